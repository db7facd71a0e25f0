"""Exploration (issue 21): a mistake that only an unscripted console history shows is found by
many of the stand's scripts, not by one lucky stream (test_explore.py: how it is reported)."""
from __future__ import annotations

import pytest

import make_explore_fixtures as mf
from explore_cases import MISTAKES
from plclab.stands.base import stand_spec


RATE_SCRIPTS = 30          # scripts of fixed seeds (not the submission's) per mistake fixture


@pytest.mark.parametrize("fixture", MISTAKES, ids=lambda f: f"{f.stand}-{f.name}")
def test_a_mistake_is_found_by_many_scripts_not_by_one_lucky_stream(fixture):
    """The catch must not hang on the seed: over a fixed sample of scripts, enough show the
    mistake that the stand's default budget misses it with a chance under 1 %. A rare mistake,
    which coverage-guided exploration reaches by keeping and mutating scripts (memory full then
    a refused press), is found by the whole default budget of another seed too."""
    import catch_rates
    budget = stand_spec(fixture.stand).explore.episodes
    if fixture.rare:             # coverage-guided: another seed's whole default budget finds it too
        r = catch_rates.rate((fixture.stand, fixture.task, str(mf.path(fixture)), True, budget, 1000), stop_at=1)
        assert r["hits"] >= 1, r
        return
    # enough hits among RATE_SCRIPTS that the default budget misses the mistake with a chance
    # under 1 %; the sample stops once it has them (more hits could not change the verdict)
    needed = next(h for h in range(2, RATE_SCRIPTS + 1) if (1 - h / RATE_SCRIPTS) ** budget < 0.01)
    r = catch_rates.rate((fixture.stand, fixture.task, str(mf.path(fixture)), True, RATE_SCRIPTS, 1000),
                         stop_at=needed)
    assert r["hits"] >= needed, r
