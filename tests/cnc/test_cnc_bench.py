"""`plclab bench`'s CNC figures (plclab.cnc.bench): they count what the run did and stay above
a recorded floor -- a tenth of what this project's 2-core machine measured with the other
suites running beside it (2026-12-01: dda, step drive, 2357 simulated steps per wall second,
6.8x real time). The goal itself (100,000 simulated steps/s) is the bench's to report."""
from __future__ import annotations

import pytest

from plclab.cnc.bench import GOAL_SPEEDUP, GOAL_STEPS_PER_S, bench_cnc, report_cnc

STEPS_PER_WALL_S_FLOOR = 235.0
SPEEDUP_FLOOR = 0.68


@pytest.mark.parametrize("drive", ["step", "pulse"])
def test_bench_counts_the_circle_and_stays_above_the_floor(drive):
    b = bench_cnc(radius_mm=1.5, drive=drive, runs=1)
    # the line to the circle, 150 steps, and the full circle of R 1.5 mm: |dx| + |dy| = 8 R / h
    assert b["steps"] == 150 + 8 * 150 and b["drive"] == drive
    assert b["steps_per_wall_s"] == pytest.approx(b["steps"] / b["wall_s"])
    assert b["goal_ratio"] == pytest.approx(b["steps_per_wall_s"] / (GOAL_STEPS_PER_S * GOAL_SPEEDUP))
    assert b["interpolation_cycles_per_wall_s"] == pytest.approx(b["fine_cycles_per_wall_s"] / 4)
    assert b["steps_per_wall_s"] >= STEPS_PER_WALL_S_FLOOR and b["speedup"] >= SPEEDUP_FLOOR, b


def test_report_lines_name_the_goal():
    lines = []
    report_cnc(lines.append, quick=True)
    assert len(lines) == 2 and all("goal 100000 steps/s" in line and "of it" in line for line in lines)
