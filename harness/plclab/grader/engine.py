"""`grade STAND TASK FILE.st...`: run a task's requirement checks against a student's program.

The student's files are one compilation unit forming a complete OpenPLC program (normally
the bundle they were handed, modified). It is judged by its I/O behaviour alone: each
scenario of the task's requirement set runs it on a fresh stand in virtual time, through the
located I/O (the console and wiring labels); the student's internal names are never read.
The submission is parsed, checked and compiled once per grade; every scenario runs that
compiled program on a fresh PLC (plclab.scenario.compiled_once). Trace files go through
plclab.fileio like every output: a bad --out is refused, one line, before any scenario runs.

The grader never charges the student for its own bug: an unexpected exception in a scenario
or a check (anything but ScenarioFailure) turns that scenario's unfinished requirements into
"grader error" rows (exit code 2), and the other scenarios still run.
"""
from __future__ import annotations

import contextlib
import dataclasses
from pathlib import Path
from typing import Callable, ContextManager, Optional, Sequence, TypeVar

from plclab.errors import CompileError, PlcLabError
from plclab.fileio import check_output
from plclab.frontend import check_sources, read_sources
from plclab.runtime.retain import MemoryRetainStore
from plclab.scenario import ScenarioFailure, Session, compiled_once
from plclab.trace import write_csv, write_vcd

from .explore import ExploreOptions, exploration_rows
from .registry import EVERY, Checks, Requirement, RequirementSet, requirement_set
from .report import GradeReport, Row

T = TypeVar("T")


def grade(stand: str, task: str, files: Sequence[str], out_dir: Optional[str] = None,
          reference: Optional[Sequence[str]] = None, explore: Optional[int] = 0,
          explore_options: Optional[ExploreOptions] = None, lines: Optional[bool] = None) -> GradeReport:
    """Grade the ST `files` (one program) on `task` of `stand`; trace files go to `out_dir`.
    Besides the scenarios, a robot's task is explored against its model answer (the checkout's
    solutions/, or the `reference` files): `explore` random scripts (None: the stand's budget,
    what `plclab grade` uses; 0, the default of this function: none); plclab.grader.explore.
    `explore_options`: processes, seed and shared model-answer plays of that exploration.
    `lines`: each failing scripted row names the student's statements where the mistake most
    likely is (plclab.grader.localize; its scenario is played again on the student's program
    and the model answer); None: when exploring (explore != 0).

    Raises PlcLabError only for a stand or task the grader does not know, or trace files it
    must not write; a program that does not compile or does not run is a report that fails.
    """
    req = requirement_set(stand, task)               # unknown stand / task: one-line error
    try:
        sources = read_sources(files)
    except CompileError as e:
        return GradeReport(stand, task, req.title, [str(f) for f in files],
                           errors=[str(d) for d in e.diagnostics], noun=req.submission.noun,
                           unreadable=req.submission.unreadable)
    return grade_sources(stand, task, sources, out_dir, reference, explore, explore_options, lines)


def grade_sources(stand: str, task: str, sources: Sequence[tuple[str, str]],
                  out_dir: Optional[str] = None, reference: Optional[Sequence[str]] = None,
                  explore: Optional[int] = 0, explore_options: Optional[ExploreOptions] = None,
                  lines: Optional[bool] = None) -> GradeReport:
    """Like `grade`, with the program given as (file name, text) pairs."""
    req = requirement_set(stand, task)
    _check_trace_outputs(req, out_dir)               # a bad --out: one line, before the work
    sources = list(sources)
    report = GradeReport(stand, task, req.title, [name for name, _ in sources], noun=req.submission.noun,
                         unreadable=req.submission.unreadable)
    if not sources:
        report.errors = [f"grade: no {req.submission.suffix} file given"]
        return report
    try:
        checked = check_sources(sources) if req.submission.read is None else req.submission.read(sources)
    except CompileError as e:
        report.errors = [str(d) for d in e.diagnostics]
        return report
    except PlcLabError as e:                         # a submission that is no program: its reader's line
        report.errors = [str(e)]
        return report
    if req.submission.read is None and checked.config is None:
        report.errors = [f"{sources[-1][0]}:1:1: error: no CONFIGURATION: hand in the complete program "
                         "(the bundle you were given, with its CONFIGURATION Config0)"]
        return report
    checks = Checks(req.requirements)
    with compiled_once(checked), _scenario_path(req, explore):
        for scenario in req.scenarios:
            checks.scenario = scenario.name
            retain = MemoryRetainStore() if scenario.needs_retain else None
            try:
                s = req.make_session(sources, retain, checked)
            except PlcLabError as e:                 # compiles, but cannot be loaded as a program
                report.errors = [f"{sources[0][0]}:1:1: error: the program cannot run: {e}"]
                return report
            try:
                scenario.run(s, checks)
            except ScenarioFailure as e:
                checks.stop(str(e), s.now)
            except Exception as e:                   # a bug of the grader, not of the program
                checks.grader_error(e, s.now)
            for hook in req.every:
                try:
                    hook(s, checks)
                except Exception as e:
                    checks.grader_error(e, s.now)
            if out_dir is not None:
                report.traces[scenario.name] = _write_traces(s, req, scenario.name, Path(out_dir))
    report.rows = _rows(req, checks)
    if lines if lines is not None else explore != 0:
        report.rows = _with_lines(req, report.rows, sources, checked, reference)
    rows, notes, files = exploration_rows(req, sources, checked, reference, explore, out_dir, explore_options)
    if rows:
        e1, named = rows[0], rows[1] if len(rows) > 1 else None
        at = next((i for i, r in enumerate(report.rows) if named and r.id == named.id), None)
        if named is not None and at is not None and report.rows[at].passed:
            # the difference is named by the requirement it breaks; E1 points there
            report.rows[at] = named
            e1 = dataclasses.replace(e1, expected="", observed=f"the difference breaks {named.id}: see its row",
                                     steps=(), lines=(), written="")
        report.rows.append(e1)
    report.notes += notes
    report.traces.update(files)
    return report


def _scenario_path(req: RequirementSet, explore: Optional[int]) -> ContextManager[None]:
    """The scan path of a grading's scenarios. Where no exploration follows, the Python path
    (unless PLCLAB_NATIVE=1 asks for native): the scenarios are a few seconds of work, and
    building the program's C in the background (from its second load, the next scenario)
    would cost more than it saves (a TUR-10 task: 1.0 s on the Python path, 1.35 s of CPU
    with the build). Before an exploration, which plays the program hundreds of times, the
    scenarios' loads start the build as usual, so that it is ready when the search begins."""
    from plclab.runtime import native
    from plclab.stands.base import stand_spec
    explores = explore != 0 and stand_spec(req.stand).explore is not None
    if explores or native.setting() is True:
        return contextlib.nullcontext()
    return native.python_only()


class _StopAfter:
    """A probe (Session.probes) that ends a replay as the first scan after plant time `t` is
    about to run: the program's state is then the one its last scan at or before `t` left."""

    def __init__(self, s: Session, t: float) -> None:
        self.s, self.t = s, t
        self.stopped = False

    def step(self, dt: float) -> None:
        if self.s.now > self.t + 1e-9:
            from plclab.runtime.tracing import StopReplay
            self.stopped = True
            raise StopReplay(self.s.now)


def replayed(stand: str, task: str, sources: Sequence[tuple[str, str]], scenario: str, t: float,
             read: Callable[[Session], T]) -> T:
    """`read(session)` at plant time `t` of scenario `scenario` of `task`, played again on the
    program `sources`: the graded run's state at the moment a row names (a grade keeps only
    the I/O in its traces; the scenarios run in virtual time, so the replay is that run).
    Raises PlcLabError (one line) when the state at `t` cannot be had: no such scenario, a
    program that does not run, a replay that ended before `t` or failed in the grader."""
    from plclab.runtime.tracing import StopReplay
    req = requirement_set(stand, task)
    sc = next((x for x in req.scenarios if x.name == scenario), None)
    if sc is None:
        raise PlcLabError(f"{stand} {task} has no scenario '{scenario}'")
    sources = list(sources)
    try:
        checked = check_sources(sources) if req.submission.read is None else req.submission.read(sources)
    except CompileError as e:
        raise PlcLabError(str(e.diagnostics[0]) if e.diagnostics else "the program does not compile") from None
    with compiled_once(checked):
        retain = MemoryRetainStore() if sc.needs_retain else None
        s = req.make_session(sources, retain, checked)
        stop = _StopAfter(s, t)
        s.add_probe(stop)
        try:
            sc.run(s, Checks(req.requirements))
        except (StopReplay, ScenarioFailure):
            pass
        except Exception as e:                       # noqa: BLE001 - the grader's bug, said as such
            raise PlcLabError(f"the replay of scenario {scenario} failed in the grader ({type(e).__name__})") from None
        last = s.now - s.tick
        if not stop.stopped and last < t - s.tick - 1e-9:
            raise PlcLabError(f"the replay of scenario {scenario} ended at t = {last:.2f} s, before t = {t:.2f} s")
        return read(s)


MAX_LOCALIZED = 2      # failing scripted moments (scenario, time) given their lines per grade: each costs two replays


def _with_lines(req: RequirementSet, rows: list[Row], sources: Sequence[tuple[str, str]], checked: object,
                reference: Optional[Sequence[str]]) -> list[Row]:
    """`rows` with each failing scripted row naming the student's statements where the mistake
    most likely is and the output's last writer (plclab.grader.localize), where the task has a
    model answer to replay its scenario on (the first MAX_LOCALIZED failing moments)."""
    from .explore import model_answer
    from .localize import scripted, written_text
    failing = [r for r in rows if not r.passed and not r.internal and not r.unchecked and r.time is not None
               and any(sc.name == r.scenario for sc in req.scenarios)]
    if not failing or req.submission.read is not None:
        return rows
    model, _why = model_answer(req.stand, req.task, reference)
    if model is None:
        return rows
    found: dict[tuple[str, float], object] = {}
    out = []
    for r in rows:
        if r in failing:
            key = (r.scenario, round(r.time, 6))
            if key not in found and len(found) >= MAX_LOCALIZED:
                out.append(r)
                continue
            if key not in found:
                scenario = next(sc for sc in req.scenarios if sc.name == r.scenario)
                found[key] = scripted(req, scenario, sources, checked, model, r.time, f"{r.expected} | {r.observed}")
            loc = found[key]
            if loc is not None and (loc.candidates or loc.writer):
                r = dataclasses.replace(r, lines=tuple(c.where(sources) for c in loc.candidates),
                                        written=written_text(loc.output, loc.writer, sources))
        out.append(r)
    return out


def _trace_files(req: RequirementSet, scenario: str, out_dir: Path) -> list[Path]:
    """The CSV and VCD of one scenario in `out_dir` (created by the writers if missing)."""
    base = out_dir / f"{req.stand}-{req.task}-{scenario}"
    return [base.with_suffix(".csv"), base.with_suffix(".vcd")]


def _check_trace_outputs(req: RequirementSet, out_dir: Optional[str]) -> None:
    """Refuse, before any scenario runs, a trace file that exists and is no regular file or a
    directory that cannot be made (plclab.fileio's rules, one line)."""
    if out_dir is not None:
        for scenario in req.scenarios:
            for path in _trace_files(req, scenario.name, Path(out_dir)):
                check_output(path)


def _write_traces(s: Session, req: RequirementSet, scenario: str, out_dir: Path) -> list[Path]:
    names = req.trace_names(s) if req.trace_names else None
    files = _trace_files(req, scenario, out_dir)
    write_csv(s.trace, files[0], names=names)
    write_vcd(s.trace, files[1], names=names)
    return files


def _rows(req: RequirementSet, checks: Checks) -> list[Row]:
    rows = []
    for r in req.requirements:
        failure = checks.failures.get(r.id)
        unchecked = [sc for sc in req.checked_in(r) if sc not in checks.passed_in.get(r.id, ())]
        if failure is not None:
            f, scenario = failure
            rows.append(Row(r.id, r.text, False, f.expected, f.observed, f.time, scenario))
        elif r.id in checks.unchecked:               # an earlier failure made the check impossible
            f, scenario = checks.unchecked[r.id]
            rows.append(Row(r.id, r.text, False, f.expected, f.observed, f.time, scenario, unchecked=True))
        elif r.id in checks.passed and not unchecked:
            rows.append(Row(r.id, r.text, True, scenario=r.scenario if r.scenario != EVERY else ""))
        else:
            rows.append(_not_checked(r, checks, unchecked[0] if unchecked else r.scenario,
                                     partly=r.id in checks.passed))
    return rows


def _not_checked(r: Requirement, checks: Checks, scenario: str, partly: bool) -> Row:
    """The row of a requirement not checked to the end in `scenario` (`partly`: it was in
    another of its scenarios): a grader bug there, the scenario stopped, or it ended first.
    After a failure in that scenario the row is NOT CHECKED (that failure is the verdict);
    with no failure to explain the stop, the stop itself is this row's FAIL."""
    where = f" in scenario {scenario}" if partly else ""
    after_failure = any(sc == scenario for _f, sc in checks.failures.values())
    if scenario in checks.internal or (scenario == EVERY and checks.internal):
        scenario = scenario if scenario != EVERY else next(iter(checks.internal))
        error, time = checks.internal[scenario]
        return Row(r.id, r.text, False, "", f"not checked{where}: the grader failed ({error}); this is a "
                   "bug of the grader, not of your program: please report it", time, scenario, internal=True)
    if scenario in checks.stopped:
        reason, time = checks.stopped[scenario]
        return Row(r.id, r.text, False, "", f"not checked{where}: the scenario stopped first: {reason}",
                   time, scenario, unchecked=after_failure)
    earlier = [rid for rid, (_f, sc) in checks.failures.items() if sc == scenario]
    why = (f"the scenario could not go on after {earlier[0]} failed" if earlier
           else "the scenario ended before this check")
    return Row(r.id, r.text, False, "", f"not checked{where}: {why}", None, scenario, unchecked=bool(earlier))


def requirement_table(stand: str, task: str, exploration: bool = False) -> list[tuple[str, str]]:
    """(id, text) of every requirement of a task, e.g. for documentation; with `exploration`
    also the exploration row (E1) where the stand explores the task (what `plclab grade` and
    the hand-out list: the scenarios' rows, then E1)."""
    table = [(r.id, r.text) for r in requirement_set(stand, task).requirements]
    if exploration:
        from plclab.stands.base import stand_spec

        from .explore import EXPLORE_ID, row_text
        expl = stand_spec(stand).explore
        if expl is not None and task in expl.references:
            table.append((EXPLORE_ID, row_text(expl, task)))
    return table


def task_title(stand: str, task: str) -> str:
    """The task's title as the report heads it ("MP-9C pneumatic robot, Task 2: ...")."""
    return requirement_set(stand, task).title


__all__ = ["grade", "grade_sources", "replayed", "requirement_table", "task_title"]
