"""`plclab bench`'s CNC figures (plclab.cnc.bench): they count what the run did and stay above
a recorded floor -- about a tenth of what this project's 2-core machine measured with the
other suites running beside it (2026-12-02: the goal's circle on the pulse-count drive,
R 50 mm at 6 m/min, about 11x real time and 120,000 simulated steps per wall second; the step
drive at its 600 mm/min, about 10x real time and 12,000 steps/s). The goal itself (100,000
simulated steps/s) is the bench's to report, not a test's."""
from __future__ import annotations

import pytest

from plclab.cnc.bench import GOAL_SPEEDUP, GOAL_STEPS_PER_S, bench_cnc, report_cnc

FLOORS = {   # drive: (radius mm, feed mm/min, simulated steps per wall second, speed-up)
    "pulse": (50.0, 6000.0, 12_000.0, 1.1),      # the goal's own circle
    "step": (1.5, 600.0, 1_200.0, 1.0),
}


@pytest.mark.parametrize("drive", ["pulse", "step"])
def test_bench_counts_the_circle_and_stays_above_the_floor(drive):
    radius, feed, steps_floor, speedup_floor = FLOORS[drive]
    b = bench_cnc(radius_mm=radius, feed_mm_min=feed, drive=drive, runs=1)
    # the line to the circle, R / h steps, and the full circle: |dx| + |dy| = 8 R / h
    n = round(radius / 0.01)
    assert b["steps"] == n + 8 * n and b["drive"] == drive
    assert b["steps_per_wall_s"] == pytest.approx(b["steps"] / b["wall_s"])
    assert b["goal_ratio"] == pytest.approx(b["steps_per_wall_s"] / (GOAL_STEPS_PER_S * GOAL_SPEEDUP))
    assert b["interpolation_cycles_per_wall_s"] == pytest.approx(b["fine_cycles_per_wall_s"] / 4)
    assert b["steps_per_wall_s"] >= steps_floor and b["speedup"] >= speedup_floor, b


def test_the_pulse_drive_is_not_capped_by_the_fine_cycle():
    """6 m/min at 10 um is 10,000 steps/s along the path: the pulse counts carry it (on the
    circle |dx| + |dy| per second is 4 / pi of the feed in steps; the line and the arc's
    acceleration take a little of that back); the step drive makes at most one step per axis
    per 1 ms fine cycle."""
    pulse = bench_cnc(radius_mm=50.0, feed_mm_min=6000.0, drive="pulse", runs=1)
    assert pulse["steps_per_virtual_s"] > GOAL_STEPS_PER_S
    step = bench_cnc(radius_mm=1.0, feed_mm_min=6000.0, drive="step", runs=1)
    assert step["steps_per_virtual_s"] <= 2 * 1000


def test_report_lines_name_the_goal():
    lines = []
    report_cnc(lines.append, quick=True)
    assert len(lines) == 2 and all("goal 100000 steps/s" in line and "of it" in line for line in lines)
    assert "R 10 mm at 6000 mm/min, dda, pulse drive" in lines[0]
    assert "R 0.6 mm at 600 mm/min, dda, step drive" in lines[1]
