"""The G-code front end: part program -> frames (mm, absolute), and one clear line for each
kind of bad input."""
from __future__ import annotations

import math

import pytest

from plclab.cnc.gcode import GcodeError, parse


def test_lines_arcs_modes_and_units():
    prog = parse("""%
O100 (program number: ignored)
N10 G21 G90 G17 ; metric, absolute
N20 G01 X10 Y0 F300 S800 M03
N30 G91 Y5            (incremental)
N40 G90 G03 X0 Y15 I-10 J0
N50 G02 X10 Y5 R10
N60 G20 G01 X1 Y1 F10 (inches)
N70 G00 Z2
""", "part.nc")
    f = prog.frames
    assert [x.kind for x in f] == [1, 1, 3, 2, 1, 0]
    assert f[0].end == (10.0, 0.0, 0.0) and f[0].feed == 300.0
    assert f[1].end == (10.0, 5.0, 0.0)                                  # G91: relative
    assert f[2].centre == (0.0, 5.0) and f[2].line == 6
    cx, cy = f[3].centre                                                   # R10 from (0, 15) to (10, 5), CW
    assert math.hypot(cx - 0, cy - 15) == pytest.approx(10) and math.hypot(cx - 10, cy - 5) == pytest.approx(10)
    assert (cx, cy) == pytest.approx((0.0, 5.0))                           # the short way round
    assert f[4].end[:2] == pytest.approx((25.4, 25.4)) and f[4].feed == pytest.approx(254.0)
    assert f[5].end[2] == pytest.approx(50.8)                               # G20 is modal
    assert any("M words ignored" in n for n in prog.notes) and any("S words" in n for n in prog.notes)


def test_r_negative_takes_the_long_way_round():
    f = parse("G01 X10 Y0 F100\nG02 X0 Y0 R-10\n").frames[1]
    short = parse("G01 X10 Y0 F100\nG02 X0 Y0 R10\n").frames[1]
    assert f.centre[1] == pytest.approx(-short.centre[1])


@pytest.mark.parametrize("text, where, message", [
    ("G01 X10 F100\nG01 X5 Q5\n", "p.nc:2:8:", "unknown word 'Q5'"),
    ("G01 X10 F100\nG05 X1\n", "p.nc:2:1:", "unknown word 'G05'"),
    ("G01 X10 Y0 F100\nG03 X0 Y10 I-10 J1\n", "p.nc:2:5:", "not on the arc's circle"),
    ("G01 X10 F0\n", "p.nc:1:9:", "feed F must be > 0"),
    ("G01 X10\n", "p.nc:1:5:", "no feed"),
    ("G01 X1 Y0 F100\nG02 X3 Y0 R0.5\n", "p.nc:2:11:", "R0.5 cannot join"),
    ("G41 D1 G01 X10 F100\n", "p.nc:1:5:", "D1 is not in the tool table"),
    ("G01 X10 (open comment F100\n", "p.nc:1:9:", "comment not closed"),
])
def test_bad_input_is_one_line_with_file_line_column(text, where, message):
    with pytest.raises(GcodeError) as e:
        parse(text, "p.nc")
    line = str(e.value)
    assert "\n" not in line
    assert line.startswith(f"{where} error: ") and message in line, line
    if "unknown word" in message:
        assert "supported:" in line


TOOLS = {1: 1.0, 2: 3.0}


def test_tool_radius_correction_is_carried_by_the_frames():
    f = parse("G01 X-3 Y-3 F100\nG41 D1 G01 X0 Y0\nX10\nG40 X12 Y-3\nG42 D2 X20 Y-3\n", "p.nc", TOOLS).frames
    assert [(x.comp, x.tool_radius) for x in f] == [(0, 0.0), (1, 1.0), (1, 1.0), (0, 0.0), (2, 3.0)]


@pytest.mark.parametrize("text, where, message", [
    ("G01 X10 F100\nG41 D1 X10.5\n", "p.nc:2:8:", "shorter than the tool radius"),
    ("G01 X10 F100\nG41 D1 G03 X0 Y10 I-10\n", "p.nc:2:12:", "switched on in a straight block"),
    ("G41 D2 G01 X10 F100\nG03 X12 Y2 I0 J2\n", "p.nc:2:5:", "inner arc of radius 2 mm is not larger"),
    ("G41 D1 G01 X10 F100\nG03 X10 Y10 I-5 J5\n", "p.nc:2:5:", "not tangent"),
    ("G41 D1 G01 X10 F100\nX5\n", "p.nc:2:1:", "reverses"),
    ("G41 G01 X10 F100\n", "p.nc:1:1:", "needs a tool radius"),
])
def test_a_radius_correction_that_cannot_be_built_is_refused(text, where, message):
    with pytest.raises(GcodeError) as e:
        parse(text, "p.nc", TOOLS)
    assert str(e.value).startswith(f"{where} error: ") and message in str(e.value), str(e.value)
