"""Requirement sets: what the grader checks for one task of one stand.

A requirement set is a list of requirements (id, the sentence a student reads) and the
scenarios that check them. A scenario drives a fresh stand (a Session running the student's
program) like the lab instructions and reports observations through `Checks`; a requirement
may be checked by one scenario or by every scenario (`EVERY`, e.g. "never a valve conflict").
Stands register their sets from `plclab.grader.<stand>` (imported on first use), so adding a
stand is adding one module:

    register(RequirementSet(stand="tur10", task="task1", title=..., requirements=[...],
                            scenarios=[Scenario("axes", run_axes)], make_session=...))
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional, Sequence

from plclab.errors import PlcLabError
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

    A scenario calls `check` for each observation (a False one is a `fail`) and `ok` once a
    requirement has been checked completely. The first failure is the requirement's verdict;
    a requirement neither failed nor completed was not checked to the end (its scenario
    stopped first), which is a failure too.
    """

    def __init__(self, requirements: Sequence[Requirement]):
        self.requirements = {r.id: r for r in requirements}
        self.passed: set[str] = set()
        self.failures: dict[str, tuple[Failure, str]] = {}
        self.scenario = ""
        self.stopped: dict[str, tuple[str, Optional[float]]] = {}   # scenario -> (reason, time)

    def _known(self, rid: str) -> None:
        if rid not in self.requirements:
            raise KeyError(f"grader: no requirement {rid!r} in this set")

    def ok(self, rid: str) -> None:
        """Requirement `rid` has been checked to the end (it passes unless something failed)."""
        self._known(rid)
        self.passed.add(rid)

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

    def failed(self, rid: str) -> bool:
        return rid in self.failures

    def stop(self, reason: str, time: Optional[float]) -> None:
        """The current scenario could not go on (a PLC fault, a step that never happened)."""
        self.stopped.setdefault(self.scenario, (reason, time))


@dataclass(frozen=True)
class Scenario:
    name: str
    run: Callable[[Session, Checks], None]
    needs_retain: bool = False     # the session gets a retain file (PLC restarts)


SessionFactory = Callable[[list[tuple[str, str]], Optional[Path]], Session]


@dataclass(frozen=True)
class RequirementSet:
    stand: str
    task: str
    title: str
    requirements: tuple[Requirement, ...]
    scenarios: tuple[Scenario, ...]
    make_session: SessionFactory                              # (sources, retain_path) -> Session
    every: tuple[Callable[[Session, Checks], None], ...] = ()  # run after each scenario
    trace_names: Optional[Callable[[Session], list[str]]] = None   # signals for the trace files

    def __post_init__(self) -> None:
        names = {s.name for s in self.scenarios}
        ids = [r.id for r in self.requirements]
        if len(set(ids)) != len(ids):
            raise ValueError(f"{self.stand} {self.task}: duplicate requirement ids")
        for r in self.requirements:
            if r.scenario != EVERY and r.scenario not in names:
                raise ValueError(f"{self.stand} {self.task}: requirement {r.id} names unknown "
                                 f"scenario {r.scenario!r}")


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


def tasks(stand: str) -> list[str]:
    """The tasks the grader knows for `stand`."""
    _load(stand)
    return sorted(task for s, task in _REGISTRY if s == stand)


def requirement_set(stand: str, task: str) -> RequirementSet:
    _load(stand)
    found = _REGISTRY.get((stand, task))
    if found is None:
        known = tasks(stand)
        if not known:
            raise PlcLabError(f"grade: no requirements for stand '{stand}' yet")
        raise PlcLabError(f"grade: stand '{stand}' has no task '{task}' (one of {', '.join(known)})")
    return found


def registered() -> list[tuple[str, str]]:
    return sorted(_REGISTRY)
