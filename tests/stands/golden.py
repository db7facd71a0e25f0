"""Golden traces of the stands' scenarios, shared by the stand test files.

A golden trace is the reviewed CSV of a scenario run; a test compares a fresh run with it
(tolerance: one scan) and names the first diverging signal and time. After an intended
change of behaviour regenerate with PLCLAB_UPDATE_GOLDEN=1 and review the diff.
"""
from __future__ import annotations

import os
from pathlib import Path

from plclab.trace import diff, read_csv, write_csv

GOLDEN = Path(__file__).parent / "golden"
UPDATE = os.environ.get("PLCLAB_UPDATE_GOLDEN") == "1"


def check_golden(trace, name: str, tick: float) -> None:
    path = GOLDEN / f"{name}.csv"
    if UPDATE or not path.exists():
        assert UPDATE, f"missing golden trace {path}: run with PLCLAB_UPDATE_GOLDEN=1 and review it"
        write_csv(trace, path)
        return
    difference = diff(read_csv(path), trace, tolerance_ns=round(tick * 1e9))
    assert difference is None, f"{name}: {difference}"
