"""TUR-10 stand: scenarios on every variant, never an overvoltage / bus contention / collision,
golden traces of the demo per variant, and the positioning results a student reads.

Regenerate golden traces after an intended change: PLCLAB_UPDATE_GOLDEN=1 (see test_mp9c.py).
"""
from __future__ import annotations

from pathlib import Path

import pytest

from golden import check_golden

from plclab.stands import tur10

ALL_VARIANTS = ("baseline", "task1", "task2", "task3", "full")


def run(variant: str, scenario: str, tmp_path: Path):
    s = tur10.session(variant, retain_path=tmp_path / "retain.json")
    tur10.SCENARIOS[scenario](s)
    tur10.check_never(s)
    return s


@pytest.mark.parametrize("variant", ALL_VARIANTS)
@pytest.mark.parametrize("scenario", ["demo", "reset", "retain", "dead_sensor"])
def test_scenarios_pass_on_every_variant(variant, scenario, tmp_path):
    run(variant, scenario, tmp_path)


@pytest.mark.parametrize("variant", ["task1", "full"])
def test_every_drive_jogs_at_both_speeds_where_task1_is_done(variant, tmp_path):
    run(variant, "jog", tmp_path)


@pytest.mark.parametrize("variant", ["baseline", "task2", "task3"])
def test_the_one_coordinate_programs_jog_only_drive_1(variant, tmp_path):
    with pytest.raises(tur10.ScenarioFailure, match="drive 2 moved 0 codes"):
        run(variant, "jog", tmp_path)


def test_demo_plays_every_frame_to_within_the_admissible_error(tmp_path):
    s = run("full", "demo", tmp_path)
    rows = tur10.frame_results(s)[1:]
    reached = [r for r in rows if "stopped" not in r]
    assert len(reached) == 8                        # 4 frames x 2 cycles; the last one was stopped
    for row in reached:
        errors = [int(part.split(":")[1].split("/")[0]) for part in row.split()[3:]]
        assert len(errors) == 5 and all(abs(e) < 16 for e in errors), row


def test_regulator_references_never_exceed_1500_and_pause_holds_zero(tmp_path):
    s = run("full", "demo", tmp_path)
    for d in tur10.DRIVES:
        values = [v - 65536 if v >= 32768 else v for _t, v in s.trace.changes(d)]
        assert max(abs(v) for v in values) == 1500
    # during a pause (between a frame done and the next start) every reference is 0
    spans = s.trace.pulses(tur10.IN_FRAME)
    for (_s0, end), (nxt, _e) in zip(spans, spans[1:]):
        mid = (end + nxt) / 2
        assert all(s.trace.value_at(d, mid) == 0 for d in tur10.DRIVES)


@pytest.mark.parametrize("variant", ALL_VARIANTS)
def test_demo_matches_its_golden_trace(variant, tmp_path):
    s = run(variant, "demo", tmp_path)
    check_golden(s.trace, f"tur10-{variant}-demo", s.tick)


def test_a_power_off_of_the_plc_is_not_charged_to_the_program(tmp_path):
    """With the PLC off every output is de-energised: all read enables OFF, every sensor on the
    bus. The plant says so, but check_never only judges what the running program did."""
    s = tur10.session("full", retain_path=tmp_path / "retain.json")
    s.run(0.5)
    s.restart_plc(off_time=1.0)
    s.run(0.5)
    off = [e for e in s.plant.events if e.kind == "bus_contention"]
    assert off and all(s.plc_was_off(e.time) for e in off)
    tur10.check_never(s)
    assert s.plc_off == [(pytest.approx(0.5, abs=0.011), pytest.approx(1.5, abs=0.011))]
