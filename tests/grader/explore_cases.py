"""What the exploration tests share (test_explore.py, test_explore_rates.py,
test_explore_alternatives.py: one file per part, so that pytest-xdist runs them on different
workers): the exploration fixtures (make_explore_fixtures.py) and the ways the tests explore
them."""
from __future__ import annotations

from pathlib import Path

import make_explore_fixtures as mf
from explored import explored
from plclab.frontend import check_sources, read_sources
from plclab.grader.explore import ExploreResult, Program, explore, model_answer
from plclab.grader.registry import requirement_set
from plclab.stands.base import stand_spec

HERE = Path(__file__).resolve().parent
FIXTURES = HERE / "fixtures"
MISTAKES = [f for f in mf.ALL if not f.passes]
ALTERNATIVES = [f for f in mf.ALL if f.passes]
ALT_EPISODES = {"mp9c": 20, "tur10": 10}   # every story kind several times (tests/grader/catch_rates.py plays more)


def program(path: Path) -> Program:
    """A fixture file as the explorer takes a student's program."""
    srcs = read_sources([str(path)])
    return Program(srcs, check_sources(srcs))


def explore_fixture(stand: str, task: str, path: Path, episodes=None) -> ExploreResult:
    """`path` explored against `task`'s model answer: `episodes` scripts, or (None) the
    grader's own exploration, run once per test session (explored.py)."""
    if episodes is None:
        return explored(stand, task, path)
    model, why = model_answer(stand, task, None)
    assert model is not None, why
    return explore(stand_spec(stand).explore, stand, task, requirement_set(stand, task).make_session,
                   program(path), model, episodes)
