"""Exploration (issue 21): a correct program written differently from the model answer, or
written from the task alone, passes (test_explore.py: mistakes are found)."""
from __future__ import annotations

import pytest

import make_explore_fixtures as mf
from explore_cases import ALT_EPISODES, ALTERNATIVES, FIXTURES, explore_fixture
from plclab.grader import engine


@pytest.mark.parametrize("fixture", ALTERNATIVES, ids=lambda f: f"{f.stand}-{f.name}")
def test_a_correct_program_written_differently_passes(fixture):
    result = explore_fixture(fixture.stand, fixture.task, mf.path(fixture), ALT_EPISODES[fixture.stand])
    assert result.finding is None, (fixture.name, result.finding and result.finding.steps,
                                    result.finding and result.finding.first_difference)
    assert result.episodes == ALT_EPISODES[fixture.stand]


INDEPENDENT = sorted((FIXTURES / "explore" / "independent").glob("*/*.st"))


@pytest.mark.parametrize("path", INDEPENDENT, ids=lambda p: f"{p.parent.name}-{p.stem}")
def test_an_independent_correct_solution_passes_every_row(path, tmp_path):
    """A program written from the task alone, with its own choices where the task leaves them
    open (a refused press restarts the full-memory blink, SA6 taken at the end of a pause, a
    frame reached only on fresh sensor readings), passes the scenarios and exploration."""
    stand, task = path.parent.name, path.stem
    report = engine.grade(stand, task, [str(path)], out_dir=str(tmp_path), explore=ALT_EPISODES[stand])
    assert report.passed, [(r.id, r.expected, r.observed, r.steps) for r in report.rows if not r.passed]
    assert report.row("E1").passed
