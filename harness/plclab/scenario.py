"""Scenarios: a stand (PLC program + plant) driven like the lab instructions, in virtual time.

Modelled on cocotb and pytest (docs/contributing.md):

    s = Session.for_stand("mp9c", "full")
    s.console.set(SA1=0, SA5=1)                     # manual mode, arm down
    s.wait_until(lambda io: io.SQ2, timeout=2.0)    # the arm reached the lower stop
    s.console.press("SB1", hold=0.3)                # record a frame
    assert s.trace.first(lambda io: io.SQ2) < 1.0

Names are the console and wiring labels of the stand's GVL (`SB1`, `SQ2`, `L3`, `HL1`); times
are plant seconds. A session records a trace of every located I/O point (with the labels as
aliases) plus chosen internal variables, and a log of the console actions for the timeline.
A stand's observables (named values of the program's inside, `plclab.stands.base`) are
recorded under their names, not their ST paths, and shown only: a scenario decides from the
stand's I/O and the plant, so it runs on a student's program of any structure. An observable
the program does not have is recorded as the constant string ABSENT ("absent"), so a
timeline, a CSV, a VCD or a plot says so instead of inventing a value; `s.has(name)` and
`s.observed(name)` (None when absent) are how a timeline asks.
"""
from __future__ import annotations

import contextlib
import contextvars
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Optional, Sequence

from plclab.frontend import check_sources
from plclab.runtime.compiler import CompiledProgram, compile_unit
from plclab.runtime.image import image_slot
from plclab.runtime.plc import PLC
from plclab.runtime.retain import MemoryRetainStore, RetainStore
from plclab.runtime.sim import Simulation
from plclab.trace import Trace


ABSENT = "absent"       # the trace value of an observable the running program does not have


class ScenarioFailure(AssertionError):
    """A scenario step that did not happen as the lab instructions expect."""


@dataclass(frozen=True)
class Action:
    time: float
    text: str


class IO:
    """Current values by label (`io.SQ2`), read from the process image."""

    def __init__(self, session: "Session"):
        object.__setattr__(self, "_s", session)

    def __getattr__(self, name: str) -> Any:
        s = object.__getattribute__(self, "_s")
        return s.value(name)

    def __getitem__(self, name: str) -> Any:
        return self.__getattr__(name)


class Console:
    """The operator: switches and buttons, through the plant's console (with its bounce)."""

    def __init__(self, session: "Session"):
        self._s = session

    def set(self, **values: Any) -> None:
        """Set switches now: console.set(SA1=1, SA6=0). Seen by the next scan."""
        plant = self._s.plant
        for name, value in values.items():
            plant.set_switch(name, int(value))
        self._s.log(", ".join(f"{k}={int(v)}" for k, v in values.items()))

    def press(self, name: str = "SB1", hold: float = 0.2) -> None:
        """Press `name`, keep it pressed `hold` seconds (time runs), release it."""
        plant = self._s.plant
        plant.press(name)
        self._s.log(f"{name} pressed ({hold:g} s)")
        self._s.run(hold)
        plant.release(name)

    def hold(self, name: str = "SB1") -> None:
        """Press and keep pressed (release later with `release`)."""
        self._s.plant.press(name)
        self._s.log(f"{name} pressed")

    def release(self, name: str = "SB1") -> None:
        self._s.plant.release(name)
        self._s.log(f"{name} released")


# The program `compiled_once` shares: [checked unit, its compiled program once compiled].
_ONE_COMPILE: contextvars.ContextVar[Optional[list]] = contextvars.ContextVar("plclab_one_compile", default=None)


@contextlib.contextmanager
def compiled_once(checked: Any, share: Optional[list] = None) -> Iterator[None]:
    """Inside the block, every Session (and PLC restart) of the checked program `checked`
    loads one compiled program, compiled on first use: the grader runs one submission through
    many scenarios and compiles it once per grade. A compiled program belongs to the PLC that
    loaded it last (as after a cold restart), so the sessions of the block must run one after
    another, as the grader's scenarios do. `share` (an empty list the caller keeps) carries
    the compiled program from one block to the next: exploration alternates two programs."""
    if share is not None:
        if not share:
            share.extend([checked, None])
        token = _ONE_COMPILE.set(share)
    else:
        token = _ONE_COMPILE.set([checked, None])
    try:
        yield
    finally:
        _ONE_COMPILE.reset(token)


_UNRECORDED: contextvars.ContextVar[bool] = contextvars.ContextVar("plclab_unrecorded", default=False)


@contextlib.contextmanager
def unrecorded_sessions(on: bool = True) -> Iterator[None]:
    """Inside the block (with `on`), a Session starts without recording its I/O: its
    simulation samples no signal. For a session whose recording would be dropped at once
    (exploration's search, plclab.grader.explore.unrecorded): building the recorder is a sixth
    of making a session, and an exploration makes thousands. A PLC restart later records as
    usual."""
    token = _UNRECORDED.set(on)
    try:
        yield
    finally:
        _UNRECORDED.reset(token)


def _compiled(checked: Any) -> CompiledProgram:
    shared = _ONE_COMPILE.get()
    if shared is None or shared[0] is not checked:
        return compile_unit(checked)
    if shared[1] is None:
        shared[1] = compile_unit(checked)
    return shared[1]


class Session:
    """One stand in virtual time: PLC program, plant model, trace and console."""

    def __init__(self, sources: Sequence[tuple[str, str]], plant: Any, labels: dict[str, str],
                 watch: Iterable[str] = (), retain_path: Optional[Path | MemoryRetainStore] = None, tick_s: Optional[float] = None,
                 name: str = "stand", checked: Any = None, observables: Optional[dict[str, str]] = None,
                 strict_watch: bool = True):
        self.name = name
        self.sources = list(sources)
        self.plant = plant
        self.labels = dict(labels)                    # label -> address ('SQ2' -> '%IX0.1')
        self.observables = dict(observables or {})    # observable name -> ST path
        self.watch = list(watch)                      # observable names or ST paths to record
        self.strict_watch = strict_watch              # False: skip what the program does not have
        self._trace_names = {path: name for name, path in self.observables.items()}
        self.retain_path = retain_path
        self.tick_ns = round(tick_s * 1e9) if tick_s else None
        self.checked = checked if checked is not None else check_sources(self.sources)
        self.actions: list[Action] = []
        self.console = Console(self)
        self.io = IO(self)
        self.trace = Trace()
        self._offset_ns = 0                       # PLC restarts keep one continuous trace time
        self.plc_off: list[tuple[float, float]] = []   # (from, to) plant seconds the PLC was off
        self.probes: list[Any] = []               # stepped after the plant every tick, restarts too
        self._start_plc()

    # ------------------------------------------------------------------ set-up
    def _start_plc(self) -> None:
        if isinstance(self.retain_path, MemoryRetainStore):
            store = self.retain_path             # one memory across the session's restarts
        else:
            store = RetainStore(self.retain_path) if self.retain_path else None
        self.plc = PLC(_compiled(self.checked), tick_ns=self.tick_ns, retain=store)
        self.plc.now_ns = self.plc.ticks = 0
        paths = [self.observables.get(n, n) for n in self.watch]
        self.absent = []                      # observables this program lacks (recorded as ABSENT)
        if not self.strict_watch:             # a student's program need not have the shipped FBs
            self.absent = [n for n, p in zip(self.watch, paths) if not self._has(p)]
            paths = [p for p in paths if self._has(p)]
        # every labelled I/O point is traced, also one the program does not declare: a
        # student may drop an unused global, the trace still shows the console
        if _UNRECORDED.get():
            self.sim = Simulation(self.plc, plants=[self.plant], record_located=False)
        else:
            self.sim = Simulation(self.plc, plants=[self.plant], watch=paths,
                                  extra_addresses=list(self.labels.values()))
        self.sim.plants.extend(self.probes)
        self._merge_pending = True

    def add_probe(self, probe: Any) -> None:
        """Step `probe` (an object with step(dt)) after the plant every tick from now on, also
        after PLC restarts (which build the simulation anew)."""
        self.probes.append(probe)
        self.sim.plants.append(probe)

    def remove_probe(self, probe: Any) -> None:
        if probe in self.probes:
            self.probes.remove(probe)
        if probe in self.sim.plants:
            self.sim.plants.remove(probe)

    @property
    def tick(self) -> float:
        return self.plc.tick_ns / 1e9

    @property
    def now(self) -> float:
        return (self._offset_ns + self.plc.now_ns) / 1e9

    def log(self, text: str) -> None:
        self.actions.append(Action(self.now, text))

    # ------------------------------------------------------------------ time
    def run(self, seconds: float) -> None:
        """Let `seconds` of plant time pass (whole scans)."""
        self.sim.run(seconds)
        self._copy_trace()

    def wait(self, seconds: float) -> None:
        self.run(seconds)

    def wait_until(self, predicate: Callable[[IO], Any], timeout: float, what: str = "") -> float:
        """Scan until `predicate(io)` holds; returns the time. Fails with a clear message."""
        end = self.plc.now_ns + round(timeout * 1e9)
        while self.plc.now_ns <= end:
            self.sim.step(1)
            self._copy_trace()
            if predicate(self.io):
                return self.now - self.tick
        raise ScenarioFailure(f"t={self.now:.2f} s: {what or 'condition'} not reached within {timeout:g} s")

    def _copy_trace(self) -> None:
        """Append what the simulation recorded since the last call to the session's trace."""
        src = self.sim.trace
        if self._merge_pending:
            self._merge_pending = False
            for name in src.signals():
                out = self._trace_names.get(name, name)
                if out not in self.trace:
                    info = src.info(name)
                    self.trace.declare(out, info.kind, src.changes(name)[0][1], self._offset_ns,
                                       width=info.width)
            for label, address in self.labels.items():
                if address in self.trace and label not in self.trace:
                    self.trace.alias(label, address)
            for name in self.absent:
                if name not in self.trace:
                    self.trace.declare(name, "str", ABSENT, self._offset_ns)
            self._copied = {}
            names = src.signals()
            self._copy_names = [(name, self._trace_names.get(name, name)) for name in names]
            self._seen_versions = [-1] * len(names)
        # only what was recorded since the last copy (a change at the same instant may have
        # replaced the last entry, so that one is taken again), and only of the signals that
        # were edited since (most scans change nothing: one list comparison)
        versions = src.versions()
        seen = self._seen_versions
        if versions != seen:
            offset, copied, copy = self._offset_ns, self._copied, self.trace.changes_into
            for i, (name, out) in enumerate(self._copy_names):
                if versions[i] == seen[i]:
                    continue
                copy(out, src.changes_from(name, max(0, copied.get(name, 0) - 1)), offset)
                copied[name] = src.change_count(name)
            self._seen_versions = versions
        self.trace.advance(self._offset_ns + self.plc.now_ns - self.plc.tick_ns)

    # ------------------------------------------------------------------ state
    def value(self, name: str) -> Any:
        """A label's I/O point (`SQ2`), an observable (`FramePtr`) or an ST path, now."""
        address = self.labels.get(name, name)
        if address.startswith("%"):
            area, index = image_slot(address)
            raw = self.plc.image.areas[area][index]
            return bool(raw) if area[1] == "X" else raw
        if name in self.observables:
            path = self.observables[name]
            if not self._has(path):
                raise ScenarioFailure(f"t={self.now:.2f} s: this scenario reads {name} ({path}), which "
                                      "the program does not have")
            return self.plc.read(path)
        return self.plc.read(name)

    def has(self, name: str) -> bool:
        """Whether the running program has observable `name` (or the ST path `name`)."""
        return self._has(self.observables.get(name, name))

    def observed(self, name: str) -> Any:
        """Observable `name` now, for showing it: None when the program does not have it."""
        return self.value(name) if self.has(name) else None

    def _has(self, path: str) -> bool:
        """Whether the running program has the variable `path`."""
        from plclab.errors import PlcLabError
        try:
            self.plc.resolve(path)
        except PlcLabError:
            return False
        return True

    def inject(self, fault: str, **params: Any) -> None:
        self.plant.inject(fault, **params)
        from plclab.plants.base import fault_words
        self.log(f"fault injected: {fault_words(fault, params)}")

    def clear_faults(self) -> None:
        self.plant.clear()
        self.log("faults cleared")

    def restart_plc(self, off_time: float = 0.0) -> None:
        """Stop the PLC (retain flushed), keep the plant, start it again: a power cycle of
        the controller only. The trace goes on in the same time axis."""
        self.plc.stop()
        self.log("PLC stopped")
        self._offset_ns += self.plc.now_ns
        if off_time:
            off_from = self.plant.time
            self.plant.step({}, off_time)        # every output de-energised
            self.plc_off.append((off_from, self.plant.time))
            self._offset_ns += round(off_time * 1e9)
        self._start_plc()
        self.log("PLC restarted")

    def load_program(self, sources: Sequence[tuple[str, str]], checked: Any = None) -> None:
        """Download another program to the controller (the virtual lab's "load"): the PLC
        stops (retain flushed), the plant stays where it is, the new program starts cold in
        the same trace time. `checked` is the front end's result for `sources`, if known."""
        checked = checked if checked is not None else check_sources(sources)
        self.plc.stop()
        self._offset_ns += self.plc.now_ns
        self.sources, self.checked = list(sources), checked
        self._start_plc()
        self.log("program loaded")

    def plc_was_off(self, t: float) -> bool:
        """Whether plant time `t` falls in a power-off of the PLC (restart_plc with off_time):
        what the plant saw then is no doing of the program."""
        return any(lo <= t < hi for lo, hi in self.plc_off)

    @property
    def fault(self):
        return self.plc.fault

