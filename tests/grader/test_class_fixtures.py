"""`grade-class` on the wrong-solution fixtures gives the verdicts of grading each one alone.

Every robot task but MP-9C Task 2 (tests/grader/test_classroom.py grades that class with its
outputs): the fixtures of one task are one class, graded in parallel processes; each student's
rows (requirement, PASS/FAIL, expected, observed) are those of `plclab grade` on the same file,
and each fails the row its header names.
"""
from __future__ import annotations

import shutil

import pytest

from plclab.grader import grade
from plclab.grader.classroom import grade_class
from grader_helpers import FIXTURES_DIR, TASKS, fixtures

CLASSES = [(stand, task) for stand in ("mp9c", "tur10") for task in TASKS if (stand, task) != ("mp9c", "task2")]


@pytest.mark.parametrize("stand,task", CLASSES)
def test_class_of_fixtures_matches_grading_one_by_one(stand, task, tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    named = {}
    for name, t, rid in fixtures(stand):
        if t == task:
            shutil.copy(FIXTURES_DIR / stand / name, folder / name)
            named[name[:-3]] = rid
    report = grade_class(stand, task, folder, tmp_path / "out", jobs=2)
    assert sorted(r.student for r in report.results) == sorted(named)
    for result in report.results:
        alone = grade(stand, task, [str(folder / f"{result.student}.st")])
        assert not result.not_graded and result.report is not None, result.not_graded
        got = [(r.id, r.passed, r.expected, r.observed) for r in result.report.rows]
        assert got == [(r.id, r.passed, r.expected, r.observed) for r in alone.rows], result.student
        assert not result.report.passed and named[result.student] in [r.id for r in result.report.failed()]
