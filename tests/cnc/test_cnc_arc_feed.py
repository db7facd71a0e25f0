"""Eq. (9) of textbook 4.2.1.1: on an arc the evaluation function's iteration frequency
follows the point's coordinates, so the contour speed stays the programmed feed along the
whole arc (without it the speed swings as Fig. 14 shows)."""
from __future__ import annotations

import bisect
import math

import pytest

from plclab.nc.gcode import parse
from plclab.stands import cnc

PART = "G21 G90 G17 F300\nG01 X10\nG03 X10 Y0 I-10 J0\n"       # a full circle R 10 at 5 mm/s
WINDOW = 0.25                                                  # s: a chord of 1.25 mm on R 10


def window_speeds(points, h=0.01):
    """mm/min between the ends of consecutive windows of the arc (chords, not the staircase)."""
    times = [p[0] for p in points]
    out, t = [], times[0]
    while t + WINDOW <= times[-1]:
        a, b = bisect.bisect_left(times, t), bisect.bisect_left(times, t + WINDOW) - 1
        out.append(math.dist(points[a][2:4], points[b][2:4]) * h / (times[b] - times[a]) * 60.0)
        t += WINDOW
    return out


@pytest.mark.parametrize("diagonal", [False, True])
def test_contour_speed_on_an_arc_stays_the_feed(diagonal):
    s = cnc.session()
    run = cnc.run_part(s, parse(PART).frames, "evalfn", diagonal=diagonal)
    arc = [p for p in run.points if p[1] == 2]
    speeds = window_speeds(arc)
    chord = 2 * 10 * math.sin(1.25 / 20)                      # a window's chord on the arc
    assert len(speeds) > 40
    assert min(speeds) >= 300 * chord / 1.25 * 0.97 and max(speeds) <= 300 * 1.02, (min(speeds), max(speeds))
    # the whole circle in 2 pi R / V (within a scan per quadrant)
    assert arc[-1][0] - arc[0][0] == pytest.approx(2 * math.pi * 10 / 5.0, abs=0.01)


@pytest.mark.parametrize("method", ["dda", "integration"])
def test_dda_and_integration_arcs_run_at_the_programmed_feed(method):
    s = cnc.session()
    run = cnc.run_part(s, parse("G21 G90 G17 F600\nG03 X0 Y0 I3 J0\n").frames, method)
    took = run.points[-1][0] - run.start
    ideal = 2 * math.pi * 3 / 10.0                       # 18.85 mm at 10 mm/s
    assert ideal <= took <= ideal + 0.1, took            # + acceleration and deceleration (200 mm/s^2)
