"""Corrections of textbook 4.2.2 in the soft PLC: tool radius at corners (eq. 26-27) and on
arcs (eq. 24-25), the blank's installation from two base points (eq. 28), backlash on
reversal (4.2.2.3)."""
from __future__ import annotations

import math

import pytest
from hypothesis import assume, given, settings, strategies as st

from cnc_st import Runner, pou

_cache: dict[str, Runner] = {}


def fb(name: str, call: str) -> Runner:
    """A PROGRAM that calls one instance `B` of FB `name` when Go is set (inputs: B.*)."""
    if name not in _cache:
        _cache[name] = Runner(pou(name) + f"""
PROGRAM main
VAR
    B : {name};
    Go : BOOL;
END_VAR
IF Go THEN
    Go := FALSE;
    {call}
END_IF;
END_PROGRAM
""")
    return _cache[name]


def call(name: str, **inputs):
    run = fb(name, "B();")
    return run.run(**{f"B.{k}": v for k, v in inputs.items()})


coord = st.floats(-100, 100).filter(lambda v: abs(v) > 1e-3)


@settings(max_examples=40, deadline=None)
@given(dx1=coord, dy1=coord, dx2=coord, dy2=coord, radius=st.floats(0.5, 10), g41=st.booleans())
def test_corner_point_lies_on_both_offset_lines(dx1, dy1, dx2, dy2, radius, g41):
    l1, l2 = math.hypot(dx1, dy1), math.hypot(dx2, dy2)
    turn = (dx1 * dy2 - dy1 * dx2) / (l1 * l2)
    assume(abs(turn) > 0.05)                         # a real corner (not nearly straight / reversed)
    r = call("FB_CncToolCorner", DX1=dx1, DY1=dy1, DX2=dx2, DY2=dy2, Radius=radius, G41=g41)
    assert not r["B.Error"]
    ax, ay = r["B.AX"], r["B.AY"]
    side = 1 if g41 else -1
    # signed distance to the left of each programmed line through the corner = +R (G41) / -R (G42)
    for dx, dy, length in ((dx1, dy1, l1), (dx2, dy2, l2)):
        left = (dx * ay - dy * ax) / length
        assert left == pytest.approx(side * radius, abs=1e-9 * (1 + math.hypot(ax, ay)))
    # B and C: the normals of length R at the corner (eq. 26)
    assert math.hypot(r["B.PointBX"], r["B.PointBY"]) == pytest.approx(radius)
    assert (r["B.PointBX"] * dx1 + r["B.PointBY"] * dy1) == pytest.approx(0, abs=1e-9 * l1 * radius)


def test_corner_of_a_square_and_a_straight_line():
    # G41 along +X then +Y (a left turn): the tool is inside, at (-R, R)... i.e. the corner (-2, 2)
    r = call("FB_CncToolCorner", DX1=10.0, DY1=0.0, DX2=0.0, DY2=10.0, Radius=2.0, G41=True)
    assert (r["B.AX"], r["B.AY"]) == pytest.approx((-2.0, 2.0))
    r = call("FB_CncToolCorner", DX1=10.0, DY1=0.0, DX2=0.0, DY2=10.0, Radius=2.0, G41=False)
    assert (r["B.AX"], r["B.AY"]) == pytest.approx((2.0, -2.0))       # G42: outside
    r = call("FB_CncToolCorner", DX1=5.0, DY1=0.0, DX2=7.0, DY2=0.0, Radius=2.0, G41=True)
    assert (r["B.AX"], r["B.AY"]) == pytest.approx((0.0, 2.0)) and not r["B.Error"]
    r = call("FB_CncToolCorner", DX1=5.0, DY1=0.0, DX2=-7.0, DY2=0.0, Radius=2.0, G41=True)
    assert r["B.Error"]


@pytest.mark.parametrize("ccw, g41, grows", [(False, True, True), (True, False, True),
                                             (True, True, False), (False, False, False)])
def test_arc_radius_grows_or_shrinks_by_the_tool_radius(ccw, g41, grows):
    r = call("FB_CncToolArc", I=3.0, J=4.0, IE=-5.0, JE=0.0, Ccw=ccw, Radius=1.0, G41=g41)
    want = 6.0 if grows else 4.0
    assert r["B.R2"] == pytest.approx(want)
    assert math.hypot(r["B.I2"], r["B.J2"]) == pytest.approx(want)
    assert math.hypot(r["B.IE2"], r["B.JE2"]) == pytest.approx(want)
    assert (r["B.DX"], r["B.DY"]) == pytest.approx((r["B.IE2"] - r["B.I2"], r["B.JE2"] - r["B.J2"]))
    assert (r["B.I2"] * 4.0 - r["B.J2"] * 3.0) == pytest.approx(0.0)   # on the same radius line


def test_inner_arc_smaller_than_the_tool_cannot_be_built():
    r = call("FB_CncToolArc", I=1.0, J=0.0, IE=0.0, JE=1.0, Ccw=True, Radius=2.0, G41=True)
    assert r["B.Error"]


@settings(max_examples=30, deadline=None)
@given(alpha=st.floats(-0.3, 0.3), x0=st.floats(-50, 50), y0=st.floats(-50, 50),
       p1=st.tuples(coord, coord), p2=st.tuples(coord, coord), q=st.tuples(coord, coord))
def test_blank_installation_from_two_base_points(alpha, x0, y0, p1, p2, q):
    assume(math.dist(p1, p2) > 5)
    c, s = math.cos(alpha), math.sin(alpha)

    def machine(p):
        return x0 + p[0] * c - p[1] * s, y0 + p[0] * s + p[1] * c

    m1, m2 = machine(p1), machine(p2)
    r = call("FB_CncBlankSetup", X1=p1[0], Y1=p1[1], X2=p2[0], Y2=p2[1], M1x=m1[0], M1y=m1[1], M2x=m2[0], M2y=m2[1])
    assert r["B.Valid"] and r["B.Check"] == pytest.approx(1.0)
    assert (r["B.CosA"], r["B.SinA"], r["B.X0"], r["B.Y0"]) == pytest.approx((c, s, x0, y0), abs=1e-9)
    t = call("FB_CncBlankTransform", CosA=r["B.CosA"], SinA=r["B.SinA"], X0=r["B.X0"], Y0=r["B.Y0"],
             X=q[0], Y=q[1], DX=q[0] - p1[0], DY=q[1] - p1[1], I=q[0], J=q[1])
    assert (t["B.MX"], t["B.MY"]) == pytest.approx(machine(q), abs=1e-9)
    mq = machine(q)
    assert (t["B.MDX"], t["B.MDY"]) == pytest.approx((mq[0] - m1[0], mq[1] - m1[1]), abs=1e-9)
    assert math.hypot(t["B.MI"], t["B.MJ"]) == pytest.approx(math.hypot(*q))


def test_blank_measurement_that_does_not_fit_the_drawing_is_not_valid():
    r = call("FB_CncBlankSetup", X1=0.0, Y1=0.0, X2=100.0, Y2=0.0, M1x=10.0, M1y=10.0, M2x=110.2, M2y=10.0)
    assert not r["B.Valid"] and r["B.Check"] > 1.0


def backlash_run(commands, backlash_fb, play):
    """Drive a table with `play` steps of backlash through FB_CncBacklash; the table's positions."""
    run = fb("FB_CncBacklash", "B();")
    run.run(**{"B.Reset": True, "B.Command": commands[0], "B.Backlash": backlash_fb})
    table = motor = run["B.Drive"]
    out = []
    for cmd in commands[1:]:
        run.run(**{"B.Reset": False, "B.Command": cmd})
        motor = run["B.Drive"]
        table = min(max(table, motor), motor + play)   # the play: table within motor .. motor + play
        out.append(table)
    return out


@settings(max_examples=25, deadline=None)
@given(st.lists(st.integers(-50, 50), min_size=2, max_size=40), st.integers(1, 20))
def test_backlash_compensation_keeps_the_table_at_the_command(moves, play):
    commands = [0]
    for m in moves:
        commands.append(commands[-1] + m)
    assert backlash_run(commands, play, play) == commands[1:]


def test_without_compensation_a_reversal_loses_the_backlash():
    commands = [0, 100, 50, 120]
    assert backlash_run(commands, 0, 5) == [100, 55, 120]      # short by the play after reversing
    assert backlash_run(commands, 5, 5) == [100, 50, 120]
