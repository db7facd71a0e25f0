"""MP-9C stand: every scenario passes on the variants it applies to, never a valve conflict,
and golden traces guard the demo and the five variants.

Regenerate the golden traces after an intended change of behaviour with
    PLCLAB_UPDATE_GOLDEN=1 .venv/bin/python -m pytest tests/stands/test_mp9c.py
and review the diff of tests/stands/golden/ before committing it.
"""
from __future__ import annotations

from pathlib import Path

import pytest

from golden import check_golden

from plclab.stands import mp9c

LIFT_ONLY = ("baseline", "task2", "task3")          # variants where only SA5 moves anything
ALL_VARIANTS = ("baseline", "task1", "task2", "task3", "full")


def run(variant: str, scenario: str, tmp_path: Path) -> mp9c.Session:
    s = mp9c.session(variant, retain_path=tmp_path / "retain.json")
    mp9c.SCENARIOS[scenario](s)
    mp9c.check_never(s)
    return s


@pytest.mark.parametrize("scenario", sorted(mp9c.SCENARIOS))
def test_every_scenario_passes_on_the_full_program(scenario, tmp_path):
    run("full", scenario, tmp_path)


@pytest.mark.parametrize("variant", ALL_VARIANTS)
@pytest.mark.parametrize("scenario", ["step", "reset", "bounce", "retain", "jammed", "empty", "lift"])
def test_lift_scenarios_pass_on_every_variant(variant, scenario, tmp_path):
    run(variant, scenario, tmp_path)


def test_demo_needs_task1_so_the_baseline_cannot_teach_it(tmp_path):
    with pytest.raises(mp9c.ScenarioFailure, match="gripper clamped"):
        run("baseline", "demo", tmp_path)


def test_demo_matches_its_golden_trace(tmp_path):
    s = run("full", "demo", tmp_path)
    check_golden(s.trace, "mp9c-full-demo", s.tick)


@pytest.mark.parametrize("variant", ALL_VARIANTS)
def test_each_variant_matches_its_golden_trace(variant, tmp_path):
    s = run(variant, "lift", tmp_path)
    check_golden(s.trace, f"mp9c-{variant}-lift", s.tick)


def test_variants_differ_only_where_their_task_says(tmp_path):
    """The lift scenario's traces: Task 1 moves the rotation, Task 2 changes the pauses,
    Task 3 stops after the last frame; otherwise the same as the baseline."""
    t = {v: run(v, "lift", tmp_path / v).trace for v in ALL_VARIANTS}
    rotated = {v: bool(t[v].edges("SQ5", "rising")) for v in ALL_VARIANTS}
    assert rotated == {"baseline": False, "task1": True, "task2": False, "task3": False, "full": True}
    frame_starts = {v: t[v].edges("L3", "rising", after=5.0) for v in ALL_VARIANTS}
    # baseline and task3 run the same program until I0.7 drops at 17.5 s
    assert frame_starts["baseline"][:3] == frame_starts["task3"][:3]
    # task 2: frame 1 pause 0.5 s, frame 2 pause 3 s -> a different rhythm from the baseline
    assert frame_starts["task2"][1] - frame_starts["task2"][0] != \
        pytest.approx(frame_starts["baseline"][1] - frame_starts["baseline"][0], abs=0.05)
    # task 3 and full stop after I0.7 dropped: no frame starts in the last 4 s
    for v in ("task3", "full"):
        assert t[v].next_change(["L2", "L3"], after=t[v].end_s - 4.0, default=None) is None
    for v in ("baseline", "task1", "task2"):
        assert t[v].next_change(["L2", "L3"], after=t[v].end_s - 4.0, default=None) is not None
