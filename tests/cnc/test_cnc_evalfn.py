"""The evaluation-function interpolators (textbook 4.2.1.1) in the soft PLC, against the
theory's bounds: every visited point within one step h of the ideal contour, unit steps
only, the end point exactly."""
from __future__ import annotations

import math

from hypothesis import given, settings, strategies as st

from cnc_st import eval_circular, eval_linear

increments = st.integers(min_value=-400, max_value=400)


def unit_steps(points):
    for a, b in zip(points, points[1:]):
        d = [abs(q - p) for p, q in zip(a, b)]
        assert max(d) == 1 and all(x <= 1 for x in d), f"{a} -> {b} is not one unit step per axis"


@settings(max_examples=40, deadline=None)
@given(dx=increments, dy=increments, diagonal=st.booleans())
def test_linear_two_axes_within_one_step_of_the_line(dx, dy, diagonal):
    pts = eval_linear().run(DX=dx, DY=dy, DZ=0, Diagonal=diagonal).points("PX", "PY", "PZ")
    assert pts[-1] == (dx, dy, 0)
    unit_steps(pts)
    length = math.hypot(dx, dy)
    for x, y, z in pts:
        assert z == 0
        if length:
            distance = abs(dx * y - dy * x) / length
            assert distance < 1.0, f"point ({x}, {y}) is {distance:.3f} h from the line to ({dx}, {dy})"
    lead, other = max(abs(dx), abs(dy)), min(abs(dx), abs(dy))
    # plain method: one axis per iteration; diagonal: the leading axis every iteration
    assert len(pts) - 1 == (lead if diagonal or other == 0 else lead + other)


@settings(max_examples=25, deadline=None)
@given(dx=increments, dy=increments, dz=increments, diagonal=st.booleans())
def test_linear_three_axes_each_within_one_step_at_the_leading_coordinate(dx, dy, dz, diagonal):
    pts = eval_linear().run(DX=dx, DY=dy, DZ=dz, Diagonal=diagonal).points("PX", "PY", "PZ")
    end = (dx, dy, dz)
    assert pts[-1] == end
    unit_steps(pts)
    lead = max(range(3), key=lambda i: abs(end[i]))
    plain_pair = not diagonal and sum(1 for v in end if v) < 3     # two moving axes: the plain method
    length = math.sqrt(sum(v * v for v in end))
    for p in pts:
        if plain_pair and length:
            # its guarantee is the distance from the line (F keeps within one step of it)
            along = sum(a * b for a, b in zip(p, end)) / length
            distance = math.sqrt(max(0.0, sum(v * v for v in p) - along * along))
            assert distance < 1.0 and all(p[i] == 0 for i in range(3) if end[i] == 0), (p, end)
            continue
        for i in range(3):
            if end[i] == 0:
                assert p[i] == 0, f"axis {i} has no increment but moved to {p[i]}"
                continue
            ideal = end[i] * p[lead] / end[lead]
            assert abs(p[i] - ideal) < 1.0, f"{p}: axis {i} at {p[i]}, ideal {ideal:.3f} at the same alpha"


def test_linear_first_steps_follow_the_textbook_rule():
    # alpha_k = 5, beta_k = 2 (Fig. 12): F = 0 steps alpha, then F = -2 < 0 steps beta, ...
    pts = eval_linear().run(DX=5, DY=2, DZ=0, Diagonal=False).points("PX", "PY")
    assert pts[:5] == [(0, 0), (1, 0), (1, 1), (2, 1), (3, 1)]
    # diagonal (eq. 4): F <= 0 steps both at once
    pts = eval_linear().run(DX=5, DY=2, DZ=0, Diagonal=True).points("PX", "PY")
    assert pts == [(0, 0), (1, 1), (2, 1), (3, 1), (4, 2), (5, 2)]


def arc_sweep(start, end, ccw):
    """The arc's angle from start to end in the direction of motion, (0, 2 pi]."""
    a = math.atan2(end[1], end[0]) - math.atan2(start[1], start[0])
    a = a if ccw else -a
    a %= 2 * math.pi
    return a if a > 1e-12 else 2 * math.pi


def travelled(points, ccw):
    """The angle swept by the visited points, signed in the direction of motion."""
    total = 0.0
    for (x0, y0), (x1, y1) in zip(points, points[1:]):
        d = math.atan2(x0 * y1 - y0 * x1, x0 * x1 + y0 * y1)
        total += d if ccw else -d
    return total


@settings(max_examples=40, deadline=None)
@given(radius=st.integers(min_value=3, max_value=250),
       a0=st.floats(min_value=0, max_value=2 * math.pi),
       sweep=st.floats(min_value=0.05, max_value=2 * math.pi),
       ccw=st.booleans(), diagonal=st.booleans())
def test_circular_radial_error_at_most_one_step_in_every_quadrant(radius, a0, sweep, ccw, diagonal):
    i, j = round(radius * math.cos(a0)), round(radius * math.sin(a0))
    r = math.hypot(i, j)
    a1 = a0 + (sweep if ccw else -sweep)
    xe, ye = round(r * math.cos(a1)), round(r * math.sin(a1))
    run = eval_circular().run(I=i, J=j, XE=xe, YE=ye, Ccw=ccw, Diagonal=diagonal)
    pts = run.points("PX", "PY")
    assert not run["Error"]
    assert pts[-1] == (xe, ye), f"ended at {pts[-1]}, not at the end point {(xe, ye)}"
    unit_steps(pts)
    for x, y in pts:
        err = abs(math.hypot(x, y) - r)
        assert err <= 1.0 + 1e-9, f"point ({x}, {y}): radial error {err:.3f} h > h (R = {r:.3f})"
    expected = arc_sweep((i, j), (xe, ye), ccw)
    assert travelled(pts, ccw) == __import__("pytest").approx(expected, abs=2.5 / r), \
        "the path does not go round the arc in the programmed direction"


def test_circular_full_circle_and_quadrant_changes():
    run = eval_circular().run(I=100, J=0, XE=100, YE=0, Ccw=True, Diagonal=False)
    pts = run.points("PX", "PY")
    assert pts[-1] == (100, 0) and len(pts) > 700
    quadrants = {(x > 0, y > 0) for x, y in pts if x and y}
    assert quadrants == {(True, True), (False, True), (False, False), (True, False)}


def test_circular_centre_as_start_is_an_error():
    run = eval_circular().run(I=0, J=0, XE=5, YE=0, Ccw=True, Diagonal=False)
    assert run["Error"] and run["N"] == 0
