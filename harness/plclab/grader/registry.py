"""Requirement sets: what the grader checks for one task of one stand.

How an instructor adds a requirement (one file, `plclab.grader.<stand>`, no engine code):

1. Declare it once, next to the constants its sentence quotes, so text and check cannot
   disagree:

       FRAME_TIMEOUT = 10.0
       G10 = Requirement("G10", f"A frame not done within {FRAME_TIMEOUT:g} s stops execution.",
                         "timeout")                         # id, sentence, scenario (or EVERY)

2. Check it inside its scenario (a function `(Session, Checks) -> None` that drives the
   stand like the lab instructions) in a `with c.requirement(G10) as rid:` block. Inside,
   `c.check(rid, condition, expected, observed, time)` records an observation (a False one
   is the requirement's failure, with what was expected, what was seen and when) and
   `c.fail(...)` records a failure outright. Leaving the block normally -- also by `return`
   -- passes the requirement unless a failure was recorded; an exception (ScenarioFailure:
   the stand could not go on) leaves it "not checked". No forgotten `ok()`. A check that
   cannot be made because of an earlier failure says so: `c.not_checked(rid, why, time)`.
   A requirement not checked after another one failed in its scenario is reported NOT
   CHECKED (not a pass, and not a second mistake); not checked with no failure to explain it,
   it is a FAIL naming why the scenario stopped.

3. List it in the task's requirement set with its scenario:

       register(RequirementSet(stand="mp9c", task="task3", title=..., requirements=(G10, ...),
                               scenarios=(Scenario("timeout", sc_timeout),), make_session=...))

A requirement may be checked by every scenario (`EVERY`, e.g. "never a valve conflict"): its
check is an `every` hook run after each scenario. A scenario that plays another one in a
second mode (`Scenario("pauses_step", ..., repeats="pauses")`: the same flow in step mode)
must check each of that scenario's requirements to the end too: a requirement passes only if
it passed in its scenario and in every scenario that repeats it. Stands register their sets from
`plclab.grader.<stand>` (imported on first use), so adding a stand is adding one module.
"""
from __future__ import annotations

import importlib
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator, Optional, Sequence, Union

from plclab.errors import PlcLabError
from plclab.runtime.retain import MemoryRetainStore
from plclab.scenario import Session

EVERY = "*"           # Requirement.scenario: checked after every scenario (`RequirementSet.every`)


@dataclass(frozen=True)
class Requirement:
    id: str           # "T1.3", "G5"
    text: str         # what is checked, a sentence a student understands
    scenario: str     # the scenario that checks it, or EVERY


@dataclass(frozen=True)
class Failure:
    expected: str
    observed: str
    time: Optional[float]


class Checks:
    """Observations of one grading run, requirement by requirement.

    A scenario checks a requirement inside `with c.requirement(req) as rid:` and calls
    `check` for each observation (a False one is a `fail`); leaving the block normally
    completes the requirement (`ok`). The first failure is the requirement's verdict; a
    requirement neither failed nor completed was not checked to the end (its scenario stopped
    first): never a pass (see engine._rows for NOT CHECKED).
    """

    def __init__(self, requirements: Sequence[Requirement]):
        self.requirements = {r.id: r for r in requirements}
        self.passed_in: dict[str, set[str]] = {}                     # requirement -> scenarios
        self.failures: dict[str, tuple[Failure, str]] = {}
        self.scenario = ""
        self.stopped: dict[str, tuple[str, Optional[float]]] = {}   # scenario -> (reason, time)
        self.internal: dict[str, tuple[str, Optional[float]]] = {}  # scenario -> (grader error, time)
        self.unchecked: dict[str, tuple[Failure, str]] = {}          # requirement -> (why, scenario)

    def _known(self, rid: str) -> None:
        if rid not in self.requirements:
            raise KeyError(f"grader: no requirement {rid!r} in this set")

    @contextmanager
    def requirement(self, *reqs: Union[Requirement, str]) -> Iterator[Any]:
        """Check `reqs` in the block: on a normal exit (also a `return`) each passes unless a
        failure was recorded; an exception leaves them not checked. Yields the id (the ids
        when several are checked together)."""
        ids = [r.id if isinstance(r, Requirement) else r for r in reqs]
        for rid in ids:
            self._known(rid)
        yield ids[0] if len(ids) == 1 else tuple(ids)
        for rid in ids:
            self.ok(rid)

    def ok(self, rid: str) -> None:
        """Requirement `rid` has been checked to the end in the current scenario (it passes
        unless something failed)."""
        self._known(rid)
        self.passed_in.setdefault(rid, set()).add(self.scenario)

    @property
    def passed(self) -> set[str]:
        """The requirements checked to the end in at least one scenario."""
        return set(self.passed_in)

    def fail(self, rid: str, expected: str, observed: str, time: Optional[float]) -> None:
        self._known(rid)
        if rid not in self.failures:
            at = None if time is None else round(time, 6)
            self.failures[rid] = (Failure(expected, observed, at), self.scenario)

    def check(self, rid: str, condition: bool, expected: str, observed: str,
              time: Optional[float]) -> bool:
        """One observation: a `fail` unless `condition`; returns `condition` so a scenario can
        stop early."""
        self._known(rid)
        if not condition:
            self.fail(rid, expected, observed, time)
        return bool(condition)

    def not_checked(self, rid: str, why: str, time: Optional[float]) -> None:
        """`rid` cannot be checked because of an earlier failure (`why` names it): reported
        NOT CHECKED, never a pass. A failure of `rid` itself, recorded before or after, wins."""
        self._known(rid)
        if rid not in self.unchecked:
            at = None if time is None else round(time, 6)
            self.unchecked[rid] = (Failure("", f"not checked: {why}", at), self.scenario)

    def failed(self, rid: str) -> bool:
        return rid in self.failures

    def stop(self, reason: str, time: Optional[float]) -> None:
        """The current scenario could not go on (a PLC fault, a step that never happened)."""
        self.stopped.setdefault(self.scenario, (reason, time))

    def grader_error(self, error: BaseException, time: Optional[float]) -> None:
        """The grader itself failed in the current scenario (a bug of the harness): its
        unfinished requirements are reported as grader errors, never charged to the student."""
        self.internal.setdefault(self.scenario, (f"{type(error).__name__}: {error}", time))


@dataclass(frozen=True)
class Submission:
    """What a student hands in when it is not an ST program (the thermo SCADA tasks: the
    traffic log of their client). The engine reads the files as text, as it reads ST, and
    `read` turns them into what `make_session` receives as `checked`."""

    noun: str                 # "traffic log": the report's line naming the files ("program: a.st")
    suffix: str               # ".csv": the files `grade-class` takes for submissions
    unreadable: str           # the report's heading over its errors: "the traffic log cannot be read:"
    # (name, text) pairs -> what make_session gets as `checked`; raises PlcLabError (one line)
    # for a file it cannot take. None: an ST program, checked by the front end.
    read: Optional[Callable[[list[tuple[str, str]]], Any]] = None


ST_PROGRAM = Submission("program", ".st", "the program does not compile:")


@dataclass(frozen=True)
class Scenario:
    name: str
    run: Callable[[Session, Checks], None]
    needs_retain: bool = False     # the session gets a retain memory (PLC restarts)
    repeats: str = ""              # a scenario whose requirements this one checks again (step mode)


# (sources, retain, checked) -> Session: `retain` is where the PLC keeps its retained variables
# (a file, or the grader's in-memory store); `checked` is the program as the front end checked
# it, once per grade (None: check the sources)
SessionFactory = Callable[[list[tuple[str, str]], Optional[Path | MemoryRetainStore], Any], Session]


@dataclass(frozen=True)
class RequirementSet:
    stand: str
    task: str
    title: str
    requirements: tuple[Requirement, ...]
    scenarios: tuple[Scenario, ...]
    make_session: SessionFactory                              # (sources, retain, checked) -> Session
    every: tuple[Callable[[Session, Checks], None], ...] = ()  # run after each scenario
    trace_names: Optional[Callable[[Session], list[str]]] = None   # signals for the trace files
    submission: Submission = ST_PROGRAM                       # what a student hands in

    def __post_init__(self) -> None:
        names = {s.name for s in self.scenarios}
        ids = [r.id for r in self.requirements]
        if len(set(ids)) != len(ids):
            raise ValueError(f"{self.stand} {self.task}: duplicate requirement ids")
        for r in self.requirements:
            if r.scenario != EVERY and r.scenario not in names:
                raise ValueError(f"{self.stand} {self.task}: requirement {r.id} names unknown "
                                 f"scenario {r.scenario!r}")
        for s in self.scenarios:
            if s.repeats and s.repeats not in names:
                raise ValueError(f"{self.stand} {self.task}: scenario {s.name} repeats unknown scenario "
                                 f"{s.repeats!r}")

    def checked_in(self, r: Requirement) -> list[str]:
        """The scenarios that must each check `r` to the end: its own and its repeats."""
        if r.scenario == EVERY:
            return []
        return [r.scenario] + [s.name for s in self.scenarios if s.repeats == r.scenario]


_REGISTRY: dict[tuple[str, str], RequirementSet] = {}
_LOADED: set[str] = set()


def register(req_set: RequirementSet) -> RequirementSet:
    _REGISTRY[(req_set.stand, req_set.task)] = req_set
    return req_set


def _load(stand: str) -> None:
    if stand in _LOADED:
        return
    _LOADED.add(stand)
    try:
        importlib.import_module(f"plclab.grader.{stand}")
    except ModuleNotFoundError as e:
        if e.name != f"plclab.grader.{stand}":
            raise


def tasks(stand: str, submission: Optional[Submission] = ST_PROGRAM) -> list[str]:
    """The tasks of `stand` graded from a `submission` of that kind (default: an ST program,
    what the lab page can grade; None: every task the grader knows)."""
    _load(stand)
    return sorted(task for (s, task), req in _REGISTRY.items()
                  if s == stand and (submission is None or req.submission == submission))


def requirement_set(stand: str, task: str) -> RequirementSet:
    _load(stand)
    found = _REGISTRY.get((stand, task))
    if found is None:
        known = tasks(stand, None)
        if not known:
            raise PlcLabError(f"grade: no requirements for stand '{stand}' yet")
        raise PlcLabError(f"grade: stand '{stand}' has no task '{task}' (one of {', '.join(known)})")
    return found


def registered() -> list[tuple[str, str]]:
    return sorted(_REGISTRY)
