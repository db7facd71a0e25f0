"""A mistake fixture's exploration, run once per test session and shared by the test files
that look at it (shared.py: the first worker to ask runs it, the others read its result).

Three files need the very same exploration of one fixture: test_explore.py (its shrunk script
and line), test_explore_engine.py (found within the default budget) and the localization
figure (tests/grader/localize_rates.py: the candidates its report lists). It is the grader's
default exploration (the stand's budget, the submission's own seed), which is deterministic,
so one run answers all three; each file still asserts its own things about it.
"""
from __future__ import annotations

import io
import pickle
from pathlib import Path

from plclab.frontend import check_sources, read_sources
from plclab.grader.explore import ExploreResult, Program, explore, model_answer
from plclab.grader.registry import requirement_set
from plclab.stands.base import stand_spec
from plclab.stands.operators import Observed
from shared import key_of, once


class _Pickler(pickle.Pickler):
    """A result names the stand's compared signals (with their functions) by name only."""

    def persistent_id(self, obj: object) -> object:
        return ("observed", obj.name) if isinstance(obj, Observed) else None


class _Unpickler(pickle.Unpickler):
    def __init__(self, data: bytes, stand: str, task: str):
        super().__init__(io.BytesIO(data))
        self.signals = {o.name: o for o in stand_spec(stand).explore.compared(task)}

    def persistent_load(self, pid: object) -> object:
        return self.signals[pid[1]]


def _dumps(result: ExploreResult) -> bytes:
    out = io.BytesIO()
    _Pickler(out, protocol=pickle.HIGHEST_PROTOCOL).dump(result)
    return out.getvalue()


def _run(stand: str, task: str, path: Path) -> ExploreResult:
    model, why = model_answer(stand, task, None)
    assert model is not None, why
    srcs = read_sources([str(path)])
    return explore(stand_spec(stand).explore, stand, task, requirement_set(stand, task).make_session,
                   Program(srcs, check_sources(srcs)), model)


def explored(stand: str, task: str, path: Path) -> ExploreResult:
    """`path` explored against `task`'s model answer as `plclab grade` explores it."""
    path = Path(path)
    return once(key_of("explored", stand, task, path.name, path.read_bytes()), lambda: _run(stand, task, path),
                _dumps, lambda data: _Unpickler(data, stand, task).load())
