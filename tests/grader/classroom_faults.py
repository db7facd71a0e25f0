"""A grader that misbehaves on purpose, for tests/grader/test_classroom.py: grade-class must
survive a grading process that is killed, hangs or hits a grader bug, and still grade the
other students with the real `grade()`.

A submission chooses its misbehaviour with its first line, `(* classroom test: crash *)`,
`... hang *)`, `... bug *)`, `... slow *)` (a temporary folder of its own, its process id
written into the folder named by $CLASSROOM_TEST_PIDS, then a long sleep: a slow student) or
`... memory *)` (2 GiB asked at once: no RSS without a limit, a MemoryError under one) or
`... exhausted *)` (every byte up to the limit taken, then the SystemError that C code raises
on a failed allocation: describing that error has no memory left either) or
`... memory_in_scenario *)` (graded for real, but writing a scenario's traces raises
MemoryError: from inside the engine's scenario loop); any other submission is graded for real. Lives in a module of
its own (not the test file) so a grading process started with spawn/forkserver can import it.
"""
from __future__ import annotations

import os
import re
import signal
import tempfile
import time
from pathlib import Path
from typing import Optional, Sequence

from plclab.grader import GradeReport, grade

MARK = re.compile(r"\(\* classroom test: (\w+) \*\)")


def grade_or_misbehave(stand: str, task: str, files: Sequence[str], out_dir: Optional[str]) -> GradeReport:
    first = Path(files[0]).read_text(encoding="utf-8").splitlines()[0] if files else ""
    m = MARK.match(first)
    what = m.group(1) if m else ""
    if what == "crash":                 # as the kernel's OOM killer would end it
        os.kill(os.getpid(), signal.SIGKILL)
    if what == "hang":
        time.sleep(3600)
    if what == "bug":
        return {}["no such key"]        # a grader bug: KeyError deep inside the grading
    if what == "slow":
        with tempfile.TemporaryDirectory(prefix="plclab-grade-") as tmp:
            (Path(tmp) / "retain.json").write_text("{}", encoding="utf-8")
            pids = os.environ.get("CLASSROOM_TEST_PIDS")
            if pids:
                (Path(pids) / str(os.getpid())).write_text(tmp, encoding="utf-8")
            time.sleep(3600)
    if what == "memory":
        held = bytes(2 * 1024 ** 3)     # calloc: untouched pages, so no RSS when there is no limit
        del held
    if what == "exhausted":             # C code failing an allocation with no memory left at all
        held = _exhaust_memory()      # noqa: F841 - kept while the error is handled
        raise SystemError("error return without exception set")
    if what == "memory_in_scenario":    # patched in this grading process only
        from plclab.grader import engine

        def exhausted(*_args):
            raise MemoryError()
        engine._write_traces = exhausted
    return grade(stand, task, files, out_dir)


def _exhaust_memory() -> list:
    """Allocate until nothing is left under the process's memory limit: large blocks first,
    then ever smaller ones, so no free piece of any size remains (a MemoryError would end an
    unlimited process only after the machine's memory: call it under a limit)."""
    held: list = []
    for size in (1 << 20, 1 << 16, 1 << 12, 1 << 8, 1 << 4):
        try:
            while True:
                held.append(bytearray(size))
        except MemoryError:
            pass
    return held
