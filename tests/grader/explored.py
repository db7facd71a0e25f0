"""A mistake fixture's exploration, run once per test session and shared by the test files
that look at it.

Three files need the very same exploration of one fixture: test_explore.py (its shrunk script
and line), test_explore_engine.py (found within the default budget) and the localization
figure (tests/grader/localize_rates.py: the candidates its report lists). It is the grader's
default exploration (the stand's budget, the submission's own seed), which is deterministic,
so one run answers all three; each file still asserts its own things about it. With
pytest-xdist the files run on different workers: the first worker to ask runs it under a lock
and leaves the result (pickled) in the session's folder, the others wait for it and read it.

The folder belongs to one test session (pytest's base temporary folder for it, named in
PLCLAB_TESTS_SHARED_DIR by tests/conftest.py), so a result never outlives the code that
computed it. Without a folder (a script run by hand) the result is kept in this process only.
"""
from __future__ import annotations

import fcntl
import hashlib
import io
import os
import pickle
from pathlib import Path
from typing import Optional

from plclab.frontend import check_sources, read_sources
from plclab.grader.explore import ExploreResult, Program, explore, model_answer
from plclab.grader.registry import requirement_set
from plclab.stands.base import stand_spec
from plclab.stands.operators import Observed

_HERE: dict[str, ExploreResult] = {}


def _folder() -> Optional[Path]:
    """The session's shared folder (tests/conftest.py names it), None outside pytest."""
    name = os.environ.get("PLCLAB_TESTS_SHARED_DIR")
    if not name:
        return None
    folder = Path(name)
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def _key(stand: str, task: str, path: Path) -> str:
    h = hashlib.sha256(f"{stand}\0{task}\0{path.name}\0".encode())
    h.update(path.read_bytes())
    return h.hexdigest()[:32]


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
    key = _key(stand, task, Path(path))
    got = _HERE.get(key)
    if got is not None:
        return got
    folder = _folder()
    if folder is None:
        got = _HERE[key] = _run(stand, task, Path(path))
        return got
    done = folder / f"{key}.pickle"
    with open(folder / f"{key}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)          # another worker running it: wait for its result
        try:
            if done.exists():
                got = _Unpickler(done.read_bytes(), stand, task).load()
            else:
                got = _run(stand, task, Path(path))
                tmp = done.with_suffix(".tmp")
                tmp.write_bytes(_dumps(got))
                tmp.replace(done)
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
    _HERE[key] = got
    return got
