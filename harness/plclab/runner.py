"""`plclab run`: one scenario of a stand in virtual time, its timeline and its trace files.

The program is a shipped variant or a student's own ST files (`--program`): a scenario drives
either through the stand's console and I/O labels and decides from the I/O and the plant, so
it runs on a program of any structure. The stand's observables (the frame pointer...) are
shown when the program has them; the run names those it lacks, and the timeline and the trace
files show them as "absent".
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence

from plclab.errors import PlcLabError
from plclab.fileio import check_output
from plclab.frontend import check_sources, read_sources
from plclab.scenario import ScenarioFailure, Session
from plclab.stands.base import stand_spec
from plclab.trace import plot_trace, write_csv, write_vcd


@dataclass
class RunResult:
    session: Session
    timeline: list[str]
    failure: Optional[str]
    files: list[Path]

    @property
    def absent_note(self) -> Optional[str]:
        """One line naming the observables the program does not have (None: it has them all)."""
        s = self.session
        if not s.absent:
            return None
        names = ", ".join(f"{n} ({s.observables.get(n, n)})" for n in s.absent)
        return f"not in this program, shown as \"absent\" in the timeline and traces: {names}"


def run_scenario(stand: str, variant: Optional[str] = None, scenario: Optional[str] = None,
                 csv: Optional[str] = None, vcd: Optional[str] = None, plot: Optional[str] = None,
                 out_dir: str = "out", retain_dir: Optional[Path] = None,
                 program: Optional[Sequence[str]] = None, inputs: Optional[str] = None,
                 against: Optional[str] = None, reference: Optional[Sequence[str]] = None,
                 fine_cycle: Optional[int] = None) -> RunResult:
    """Run scenario `scenario` (default: the demo) of `stand` on `variant` or on the ST files
    `program` (one compilation unit, a complete program with its CONFIGURATION). A program
    that does not compile raises CompileError (its `file:line:col: error:` lines).

    `inputs`: an operator script (time_s,name,value; what a grade's exploration writes) is
    played instead of a scenario; with `against` (a task) it is played on that task's model
    answer too, and `failure` is the first difference, as the grade's row states it.

    `fine_cycle` ms (the cnc stand): PRG_CncStand runs at that fine cycle (plclab.stands.cnc)."""
    spec = stand_spec(stand)
    if fine_cycle is not None and stand != "cnc":
        raise PlcLabError(f"run: --fine-cycle is for the cnc stand (PRG_CncStand's fine cycle), not {stand}")
    if (against or reference) and not inputs:
        raise PlcLabError("run: --against and --reference compare an operator script's play: give --inputs too")
    if inputs and scenario:
        raise PlcLabError("run: give --scenario or --inputs, not both")
    if program and variant:
        raise PlcLabError("run: give --variant or --program, not both")
    for out in (csv, vcd, plot):
        if out:
            check_output(out)                # plclab.fileio: a bad output path is refused up front
    name = scenario or spec.default_scenario
    play = spec.scenario(name) if not inputs else None
    srcs, checked = None, None
    if program:
        srcs = spec.program_sources(program) if spec.program_sources else read_sources(program)
        checked = check_sources(srcs)
        if checked.config is None:
            raise PlcLabError(f"{srcs[-1][0]}: no CONFIGURATION: run the complete program (the bundle you "
                              "were given, with its CONFIGURATION Config0)")
        variant = "program"
    else:
        variant = variant or spec.stand.richest_variant   # installed: no reference solution to run
        spec.stand.variant(variant)
    retain_path = (retain_dir or Path(out_dir) / "retain") / f"{stand}-{variant}-{name}.json"
    if retain_path.exists():
        retain_path.unlink()               # a scenario starts from a fresh controller
    if fine_cycle is not None:
        from plclab.stands import cnc
        s = cnc.session(variant if srcs is None else spec.stand.richest_variant, program=srcs,
                        retain_path=retain_path, fine_ms=fine_cycle)
    elif srcs is None:
        s = spec.session(variant, retain_path=retain_path)
    else:
        s = spec.session(program=srcs, checked=checked, retain_path=retain_path)
    failure = None
    if inputs:
        from plclab.grader.explore import replay
        failure = replay(spec, s, inputs, against, reference, srcs, checked)
    else:
        try:
            play(s)
            spec.check_never(s)
        except ScenarioFailure as e:
            failure = str(e)
    if scenario is None and not inputs and not (csv or vcd or plot):
        base = Path(out_dir) / f"{stand}-{name}"
        csv, vcd, plot = f"{base}.csv", f"{base}.vcd", f"{base}.png"
    files = []
    for path, write in ((csv, write_csv), (vcd, write_vcd)):
        if path:
            write(s.trace, path)
            files.append(Path(path))
    if plot:
        signals: list = []                   # a name, or a group sharing one subplot
        for entry in spec.plot_signals:
            group = [entry] if isinstance(entry, str) else list(entry)
            present = [n for n in group if n in s.trace]
            if present:
                signals.append(present[0] if isinstance(entry, str) else tuple(present))
        plot_trace(s.trace, plot, names=signals, title=f"{spec.stand.title}: {variant}, scenario {name}")
        files.append(Path(plot))
    return RunResult(s, spec.timeline(s), failure, files)
