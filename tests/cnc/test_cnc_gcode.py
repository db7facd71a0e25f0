"""The G-code front end: part program -> frames (mm, absolute), and one clear line for each
kind of bad input."""
from __future__ import annotations

import math

import pytest

from plclab.nc.gcode import GcodeError, parse


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
    ("G01 X10 F100\nG05 X1\n", "p.nc:2:1:", "G05 is not supported by the stand"),
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
    if "unknown word" in message or "not supported" in message:
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


# ------------------------------------------------------------------ read strictly (issue 24, item 5)

@pytest.mark.parametrize("text, where, code", [
    ("G01 X10 F100\nG91.1 X5\n", "p.nc:2:1:", "G91.1"),        # not G91: X would turn incremental
    ("G17.1 G01 X10 F100\n", "p.nc:1:1:", "G17.1"),
    ("G01 X10 F100\nG41.1 D1 X20\n", "p.nc:2:1:", "G41.1"),
    ("G01 X10 F100\nG1.5 X20 Y5\n", "p.nc:2:1:", "G1.5"),       # was "G02 needs I/J or R"
    ("G01 X10 F100\nG4 X1\n", "p.nc:2:1:", "G04"),
    ("G01 X10 F100\nM3.5\n", "p.nc:2:1:", "M3.5"),
])
def test_a_code_the_stand_does_not_know_is_refused_by_its_exact_name(text, where, code):
    with pytest.raises(GcodeError) as e:
        parse(text, "p.nc", TOOLS)
    assert str(e.value).startswith(f"{where} error: {code} is not supported by the stand (supported: "), str(e.value)


@pytest.mark.parametrize("text, where, message", [
    ("G00 G01 X10 F100\n", "p.nc:1:5:", "G00 and G01 in one block: both of modal group 1 (motion)"),
    ("G01 X10 F100\nG02 G03 X0 Y0 I-5\n", "p.nc:2:5:", "G02 and G03 in one block: both of modal group 1"),
    ("G90 G91 G01 X10 F100\n", "p.nc:1:5:", "G90 and G91 in one block: both of modal group 3 (distance mode)"),
    ("G20 G21 G01 X10 F100\n", "p.nc:1:5:", "G20 and G21 in one block: both of modal group 6 (units)"),
    ("G40 G41 D1 G01 X10 F100\n", "p.nc:1:5:", "G40 and G41 in one block: both of modal group 7 (cutter "
                                             "radius compensation)"),
    ("G01 X10 F100 M02 M30\n", "p.nc:1:18:", "M02 and M30 in one block: both of modal group 4 (stopping)"),
])
def test_two_codes_of_one_modal_group_in_a_block_are_an_error(text, where, message):
    with pytest.raises(GcodeError) as e:
        parse(text, "p.nc", TOOLS)
    assert str(e.value).startswith(f"{where} error: {message}"), str(e.value)


@pytest.mark.parametrize("text, where, message", [
    ("G01 X10 Y0 R5 F100\n", "p.nc:1:12:", "R (an arc's radius) means nothing for G01"),
    ("G01 X10 Y0 F100\nX20 I5 J5\n", "p.nc:2:5:", "I (an arc's centre) means nothing for G01"),   # modal G01
    ("G00 X10 J5\n", "p.nc:1:9:", "J (an arc's centre) means nothing for G00"),
    ("G01 X10 F100\nG02 X0 Y0 I-5 R5\n", "p.nc:2:11:", "G02 with both R and I/J"),
    ("G01 X10 F100 (a (nested) comment)\n", "p.nc:1:17:", "'(' inside a comment (opened at column 14)"),
    ("G01 X10 Y0 F100\nG02 X0 Y0 Z-1 I-5\n", "p.nc:2:11:", "G02 with Z: a helix is not supported"),
    ("G01 X10 Y0 F100\nG03 X10 Y0 Z2 I-5 J0\n", "p.nc:2:12:", "G03 with Z: a helix"),
])
def test_words_that_mean_nothing_nested_comments_and_helices_are_refused(text, where, message):
    with pytest.raises(GcodeError) as e:
        parse(text, "p.nc", TOOLS)
    assert str(e.value).startswith(f"{where} error: {message}"), str(e.value)


def test_an_arc_in_the_plane_of_its_z_and_a_comment_after_a_comment_are_fine():
    f = parse("G01 X10 Y0 Z-1 F100 (first) (second)\nG02 X0 Y0 Z-1 I-5\n", "p.nc").frames
    assert [x.kind for x in f] == [1, 2] and f[1].end == (0.0, 0.0, -1.0)


@pytest.mark.parametrize("end", ["M30", "M02", "M2"])
def test_the_program_ends_at_m30_or_m02_and_blocks_after_it_do_not_run(end):
    prog = parse(f"G01 X10 F100\nX20 {end}\n\n(after the end)\nG00 X0\nG01 Y50\n", "p.nc")
    assert [f.end for f in prog.frames] == [(10.0, 0.0, 0.0), (20.0, 0.0, 0.0)]   # the end block's own move runs
    assert "p.nc:5: warning: blocks after the program end (line 2) are not run" in prog.notes
    assert not any("M words ignored" in n for n in prog.notes)
    after = parse("G01 X10 F100\nM30\n(unread (nested\nG91.1 X5\n", "p.nc")      # not read after the end
    assert len(after.frames) == 1 and after.notes == ["p.nc:3: warning: blocks after the program end (line 2) "
                                                      "are not run"]
    quiet = parse("G01 X10 F100\nM30\n%\n(a comment)\n", "p.nc")
    assert len(quiet.frames) == 1 and quiet.notes == []             # nothing after the end: nothing said


ARC_MISSING_BY_50_UM = "G01 X10 Y0 F100\nG03 X0 Y10.05 I-10 J0\n"   # the end 10.05 mm from the centre
ARC_MISSING_BY_5_UM = "G01 X10 Y0 F100\nG03 X0 Y10.005 I-10 J0\n"


def test_the_arc_end_tolerance_is_one_step_of_the_drives():
    assert len(parse(ARC_MISSING_BY_50_UM, "p.nc", step_mm=0.1).frames) == 2     # within a 0.1 mm step
    with pytest.raises(GcodeError, match=r"p.nc:2:5: error: the end point is not on the arc's circle .*"
                                         r"tolerance one step, 0.01 mm"):
        parse(ARC_MISSING_BY_50_UM, "p.nc", step_mm=0.01)
    assert len(parse(ARC_MISSING_BY_5_UM, "p.nc", step_mm=0.01).frames) == 2
    with pytest.raises(GcodeError, match=r"tolerance one step, 0.001 mm"):
        parse(ARC_MISSING_BY_5_UM, "p.nc", step_mm=0.001)
