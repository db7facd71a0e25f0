"""What a stand declares once, for everything that runs or shows it.

`plclab run`, the grader, `plclab lab` (a browser view of a stand) and every future stand
(CNC is next) need the same facts about a stand; each stand module fills in one `StandSpec`
named `SPEC`, and nothing else reads a stand module's loose names:

    SPEC = StandSpec(
        stand=STAND,                          # program variants, GVL, tasks (plclab.stands.Stand)
        console=("SA1", "SA2", ..., "SB1"),   # operator inputs, in the console's order
        lamps=("HL1",), sensors=("SQ1", ...), actuators=("L1", ...),
        faults=(Fault("jammed", "a cylinder stops where it is",
                      (FaultParam("mechanism", "lift|rotation|extension|gripper"),)), ...),
        observables={"FramePtr": "Main.Robot.Sequencer.Ptr", ...},
        scenarios={"demo": demo, ...}, timeline=timeline, check_never=check_never,
        plot_signals=("SB1", ..., "FramePtr"))

Console, lamps, sensors and actuators are labels of the stand's GVL (`labels()` maps them to
addresses). Observables are the named values of the program's inside that scenarios,
timelines, plots and golden traces may read: each name maps to the ST path of the shipped
programs in this one place (a variant may override a path), so renaming an FB instance
changes one line here. A session records an observable under its name, reads it with
`s.value(name)`, and a student's program that lacks one simply does not record it.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Optional, Sequence, Union

from plclab.errors import PlcLabError
from plclab.scenario import Session
from plclab.stands import Stand, gvl_labels, sources

ScenarioFn = Callable[[Session], None]
PlotEntry = Union[str, tuple[str, ...]]      # a signal, or signals sharing one subplot

REQUIRED = object()                          # FaultParam.default: the parameter must be given


@dataclass(frozen=True)
class FaultParam:
    """One parameter of an injectable plant fault: its name, what it takes, its default."""

    name: str
    doc: str
    default: Any = REQUIRED

    @property
    def required(self) -> bool:
        return self.default is REQUIRED


@dataclass(frozen=True)
class Fault:
    """A plant fault a scenario or a view may inject (`Session.inject(name, **params)`)."""

    name: str
    doc: str
    params: tuple[FaultParam, ...] = ()


@dataclass(frozen=True)
class StartPress:
    """How the operator starts automatic playback, in console terms only, so a view can say
    why a start press did nothing (the lab): what the press is, which outputs a start
    changes, and the console inputs a program may require (mode switches, spare inputs),
    each with the words the console prints for its two positions. Nothing of a program's
    inside: any program of the stand is judged by its I/O."""

    button: str                                  # the push button that starts playback ('SB1')
    mode: tuple[str, int]                        # the switch and its level in automatic mode ('SA1', 1)
    reads: tuple[tuple[str, str, str], ...]      # (console input, word when off, word when on)
    outputs: tuple[str, ...]                     # outputs a start changes (valve coils, drive outputs)
    within: float = 1.0                          # plant seconds after the release a start shows in


@dataclass(frozen=True)
class StandSpec:
    """Everything a runner, a grader or a view needs of one stand (see the module docstring)."""

    stand: Stand
    console: tuple[str, ...]                 # operator inputs (switches, buttons), console order
    lamps: tuple[str, ...]                   # indicator outputs
    sensors: tuple[str, ...]                 # plant-side inputs (limit switches, ADC, bus bits)
    actuators: tuple[str, ...]               # outputs that move the plant (valves, drives, heater)
    faults: tuple[Fault, ...]
    observables: dict[str, str]              # name -> ST path in the shipped programs
    scenarios: dict[str, ScenarioFn]
    timeline: Callable[[Session], list[str]]
    check_never: Callable[[Session], None]   # raises ScenarioFailure: what no scenario may show
    plot_signals: tuple[PlotEntry, ...]
    setup: Optional[Callable[[Session], None]] = None   # extra wiring of a fresh session (SCADA client)
    default_scenario: str = "demo"
    # a student's `--program FILES` -> the sources to run (default: the files as they are, a
    # complete program); a stand may let one block of a task stand in for its stub (cnc)
    program_sources: Optional[Callable[[Sequence[str]], list[tuple[str, str]]]] = None
    # the grader's exploration: operator-script generators, what is compared, tolerances and
    # freedoms (plclab.stands.operators.Exploration); None: the stand is graded by scenarios alone
    explore: Any = None
    # how automatic playback is started (a view says why a press did nothing); None: no playback
    start: Optional[StartPress] = None

    @property
    def name(self) -> str:
        return self.stand.name

    def labels(self) -> dict[str, str]:
        """Console and wiring labels -> addresses, from the stand's GVL (the one source)."""
        return gvl_labels(self.stand)

    def observables_for(self, variant: Optional[str]) -> dict[str, str]:
        """The observables' ST paths in `variant` (its overrides over the stand's paths)."""
        paths = dict(self.observables)
        if variant is not None:
            paths.update(self.stand.variant(variant).observables)
        return paths

    def fault(self, name: str) -> Fault:
        for f in self.faults:
            if f.name == name:
                return f
        raise PlcLabError(f"{self.name}: unknown fault '{name}' (one of {', '.join(f.name for f in self.faults)})")

    def scenario(self, name: Optional[str]) -> ScenarioFn:
        name = name or self.default_scenario
        if name not in self.scenarios:
            raise PlcLabError(f"{self.name}: unknown scenario '{name}' (one of {', '.join(self.scenarios)})")
        return self.scenarios[name]

    def session(self, variant: Optional[str] = None, program: Optional[Sequence[tuple[str, str]]] = None,
                retain_path: Optional[Path] = None, watch_internals: bool = True, checked: Any = None,
                **plant_params: Any) -> Session:
        """A fresh stand: the shipped `variant` (or a student's `program` sources, which need not
        have every observable, and `checked`, the program as the front end checked it) and a
        plant at power-up (`plant_params` set it up)."""
        variant = variant or self.stand.richest_variant
        srcs = list(program) if program is not None else sources(self.stand, variant)
        paths = self.observables_for(variant if program is None else None) if watch_internals else {}
        s = Session(srcs, self.stand.make_plant(**plant_params), self.labels(), watch=list(paths),
                    observables=paths, retain_path=retain_path, strict_watch=program is None, checked=checked,
                    name=f"{self.name} {variant if program is None else 'program'}")
        if self.setup is not None:
            self.setup(s)
        return s


def stand_spec(name: str) -> StandSpec:
    """The declared spec of stand `name` (one clear error for an unknown stand)."""
    from plclab.stands import stand_module
    spec = getattr(stand_module(name), "SPEC", None)
    if not isinstance(spec, StandSpec):
        raise PlcLabError(f"stand '{name}' declares no StandSpec (SPEC)")
    return spec


__all__ = ["Fault", "FaultParam", "PlotEntry", "REQUIRED", "ScenarioFn", "StandSpec", "StartPress", "stand_spec"]
