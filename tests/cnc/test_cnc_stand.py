"""The CNC stand: PRG_CncStand runs a part program's frames on the step/direction table in
virtual time; the tool path is checked against each method's bound, and the console
(single block, feed override, emergency stop) and the drives' limits behave as docs/cnc.md
says."""
from __future__ import annotations

import pytest

from plclab.cnc.gcode import parse
from plclab.cnc.toolpath import check_blocks
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
