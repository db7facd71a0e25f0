"""A wrong-solution fixture's grading, run once per test session and shared by the test files
that look at it (shared.py: the first worker to ask grades it, the others read its report).

Each fixture of fixtures/STAND is graded by four files: test_grader_STAND.py (it fails the
row its header names), test_named_rows.py (that row says the mistake in a student's words),
test_classroom.py (graded as a class, it gets the rows it gets alone) and the localization
figure (localize_rates.py: its failing rows name the changed line). It is `plclab grade`'s
scripted grading with each failing row's ranked lines (`lines=True`: the rows and their
verdicts are what they are without them), which is deterministic, so one grading answers all
four; each file still asserts its own things about it."""
from __future__ import annotations

from pathlib import Path

from plclab.grader import GradeReport, grade
from shared import key_of, once


def graded_fixture(stand: str, task: str, path: Path) -> GradeReport:
    """`path` graded on `task` as `plclab grade` grades it without exploring, with lines."""
    path = Path(path)
    return once(key_of("graded", stand, task, str(path), path.read_bytes()),
                lambda: grade(stand, task, [str(path)], explore=0, lines=True))
