"""A result several test files need, computed once per test session and shared between the
pytest-xdist workers (tests/conftest.py names the session's folder in
PLCLAB_TESTS_SHARED_DIR): the first worker to ask computes it under a lock and leaves it
(pickled) in that folder, the others wait for it and read it. The folder belongs to one test
session, so a result never outlives the code that computed it; without a folder (a script
run by hand) the result is kept in this process only.

Used by explored.py (a fixture's exploration) and graded.py (a fixture's grading)."""
from __future__ import annotations

import fcntl
import hashlib
import os
import pickle
from pathlib import Path
from typing import Any, Callable, Optional

_HERE: dict[str, Any] = {}


def key_of(*parts: str | bytes) -> str:
    """A file name for a result: the hash of what it depends on."""
    h = hashlib.sha256()
    for p in parts:
        h.update(p if isinstance(p, bytes) else p.encode())
        h.update(b"\0")
    return h.hexdigest()[:32]


def _folder() -> Optional[Path]:
    name = os.environ.get("PLCLAB_TESTS_SHARED_DIR")
    if not name:
        return None
    folder = Path(name)
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def once(key: str, compute: Callable[[], Any], dumps: Callable[[Any], bytes] = pickle.dumps,
         loads: Callable[[bytes], Any] = pickle.loads) -> Any:
    """`compute()`'s result for `key`, computed once per test session."""
    got = _HERE.get(key)
    if got is not None:
        return got
    folder = _folder()
    if folder is None:
        got = _HERE[key] = compute()
        return got
    done = folder / f"{key}.pickle"
    with open(folder / f"{key}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)          # another worker computing it: wait for its result
        try:
            if done.exists():
                got = loads(done.read_bytes())
            else:
                got = compute()
                tmp = done.with_suffix(".tmp")
                tmp.write_bytes(dumps(got))
                tmp.replace(done)
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
    _HERE[key] = got
    return got
