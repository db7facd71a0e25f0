"""The CNC stand: PRG_CncStand runs a part program's frames on the step/direction table in
virtual time; the tool path is checked against each method's bound, and the console
(single block, feed override, emergency stop) and the drives' limits behave as docs/cnc.md
says."""
from __future__ import annotations

import math

import pytest

from plclab.nc.gcode import parse
from plclab.nc.toolpath import check_blocks
from plclab.scenario import ScenarioFailure
from plclab.stands import cnc

PART = """(lines in three quadrants, a half circle CCW, back home)
G21 G90 F600
G01 X1.5 Y1
X-0.5 Y2
G03 X-0.5 Y-1 I0 J-1.5
G01 X0 Y0
"""


@pytest.mark.parametrize("method", ["evalfn", "dda", "integration"])
def test_every_frame_within_its_bound_and_at_its_end_point(method):
    s = cnc.session()
    frames = parse(PART).frames
    run = cnc.run_part(s, frames, method)
    assert run.finished
    assert run.missed == {"X": 0, "Y": 0, "Z": 0}
    for block in check_blocks(frames, run.points, 0.01, method, run.start):
        assert block.ok, f"{method}: {block.row()}"
    assert run.points[-1][2:] == (0, 0, 0)
    # one step per axis per fine cycle at most
    for a, b in zip(run.points, run.points[1:]):
        assert b[0] > a[0] and all(abs(q - p) <= 1 for p, q in zip(a[2:], b[2:])), (a, b)


def test_single_block_stops_after_each_frame_until_sb1():
    s = cnc.session()
    cnc.load_frames(s, parse("G01 X1 F600\nX2\n").frames)
    s.console.set(SA1=1)
    s.console.press("SB1", hold=0.005)
    s.run(0.5)
    assert s.plant.position_mm("X") == pytest.approx(1.0) and s.plc.read("Frame") == 1
    s.run(0.5)
    assert s.plant.position_mm("X") == pytest.approx(1.0), "moved on without SB1 in single block"
    s.console.press("SB1", hold=0.005)
    s.run(0.5)
    assert s.plant.position_mm("X") == pytest.approx(2.0) and s.value("ProgramEnd")


def test_feed_override_halves_the_feed():
    times = {}
    for percent in (100, 50):
        s = cnc.session()
        s.plant.set_override(percent)
        run = cnc.run_part(s, parse("G01 X3 F300\n").frames)
        times[percent] = run.points[-1][0] - run.start
    assert times[100] == pytest.approx(0.6, abs=0.005)          # 3 mm at 5 mm/s
    assert times[50] == pytest.approx(2 * times[100], abs=0.005)


def test_a_slow_drive_misses_steps_and_the_stand_reports_them():
    s = cnc.session()
    s.inject("slow_drive", axis="X", rate=200.0)
    run = cnc.run_part(s, parse("G01 X1 F600\n").frames)
    assert run.missed["X"] > 0 and run.missed["Y"] == 0
    assert s.plant.position_mm("X") < 1.0
    with pytest.raises(ScenarioFailure, match="missed steps"):
        cnc.check_never(s)


def test_emergency_stop_scenario():
    s = cnc.session()
    cnc.estop(s)                     # raises if the table moved, HL2 dark or KM1 closed
    assert not s.value("HL2") or s.value("SB3")


POCKET = """(pocket wall 3 x 2 with a rounded corner R0.5, tool D1: G41 going CCW = inside)
G21 G90 F600
G00 X-1 Y-1
G41 D1 G01 X0 Y0
X3
Y1.5
G03 X2.5 Y2 I-0.5 J0
G01 X0
Y0
G40 G01 X-1 Y-1
"""


@pytest.mark.parametrize("method, side", [("evalfn", "G41"), ("dda", "G42")])
def test_tool_radius_correction_runs_on_the_equidistant(method, side):
    from plclab.nc.toolpath import check_offsets

    text = POCKET.replace("G41", side)
    frames = parse(text, "pocket.nc", {1: 0.3}).frames
    s = cnc.session()
    run = cnc.run_part(s, frames, method)
    assert run.finished and run.prep_error == 0
    offsets = check_offsets(frames, run.executed, 0.01)
    assert len(offsets) == 5 and all(o.ok for o in offsets), [o.row() for o in offsets]
    for block in check_blocks(run.executed, run.points, 0.01, method, run.start):
        assert block.ok, block.row()
    arc = run.executed[4]
    assert math.hypot(arc.i, arc.j) == pytest.approx(0.2 if side == "G41" else 0.8, abs=0.011)
    # the tool centre keeps the tool radius from the wall: inside (G41) or outside (G42)
    wall = [p for p in run.points if p[1] == 3]          # frame 3: along X at Y 0 programmed
    assert all(abs(p[3] * 0.01 - (0.3 if side == "G41" else -0.3)) <= 0.011 for p in wall)


@pytest.mark.parametrize("method", ["evalfn", "dda"])
def test_run_part_records_every_move_from_the_first_step(method):
    """A 270-step line is 270 recorded moves, the first one step from the start (the moves
    made while SB1 was held used to be missing: 266 rows)."""
    s = cnc.session()
    run = cnc.run_part(s, parse("G01 X2.7 F300\n").frames, method)
    assert run.finished and s.plant.axes["X"].steps == 270
    assert len(run.points) == 270
    assert [p[2] for p in run.points] == list(range(1, 271))
    assert all(p[1] == 1 for p in run.points)                     # all of frame 1
    assert not s.plant.console_bits["SB1"]                        # the press was released
