"""The corrections of textbook 4.2.2 wired into the CNC stand: backlash in the drives'
transmissions compensated by FB_CncBacklash (4.2.2.3), and the blank-installation
correction measured by the stand's probing cycle (FB_CncProbeHole, FB_CncBlankSetup) and
applied to the frames (FB_CncBlankTransform, eq. 28)."""
from __future__ import annotations

import math

import pytest

from plclab.nc.gcode import parse
from plclab.nc.toolpath import check_blocks
from plclab.plants.cnc import CncTable
from plclab.plants.base import PlantError
from plclab.scenario import ScenarioFailure
from plclab.stands import cnc

H = 0.01


def backlash_run(method: str, compensate: bool):
    s = cnc.session()
    s.plant.set_backlash(cnc.PLAY_STEPS)
    if compensate:
        s.plc.write("Backlash", cnc.PLAY_STEPS)
    run = cnc.run_part(s, parse(cnc.BACKLASH).frames, method)
    return s, run, check_blocks(run.executed, run.points, H, method, run.frames_start, run.origin)


@pytest.mark.parametrize("method", ["evalfn", "dda", "integration"])
def test_backlash_compensation_keeps_the_tool_on_the_contour(method):
    s, run, blocks = backlash_run(method, compensate=True)
    assert run.finished and run.missed == {"X": 0, "Y": 0, "Z": 0}
    assert all(b.ok for b in blocks), [b.row() for b in blocks if not b.ok]
    assert run.points[-1][2:] == (0, 0, 0)
    # the drives took more steps than the table moved: the play, taken up on every reversal
    x = s.plant.axes["X"]
    assert x.received > sum(abs(b[2] - a[2]) for a, b in zip(run.points, run.points[1:]))
    assert x.motor == x.steps - cnc.PLAY_STEPS             # last moved negative: the play is behind
    # never more than one step per axis per fine cycle, the extra steps included
    for a, b in zip(run.points, run.points[1:]):
        assert all(abs(q - p) <= 1 for p, q in zip(a[2:], b[2:]))


@pytest.mark.parametrize("method", ["evalfn", "dda"])
def test_without_compensation_the_play_is_lost_on_each_reversal(method):
    s, run, blocks = backlash_run(method, compensate=False)
    assert run.finished
    bad = [b for b in blocks if not b.ok]
    assert bad, "the play left the path within its bound without compensation"
    # the last X motion (the circle's end) was negative: the table stays the play short in X
    assert run.points[-1][2:4] == (cnc.PLAY_STEPS, 0)
    assert max(b.error_mm for b in blocks) >= (cnc.PLAY_STEPS - 1) * H


def test_backlash_scenario_passes_and_fails_without_the_block():
    s = cnc.session()
    cnc.backlash(s)
    cnc.check_never(s)
    s = cnc.session()
    s.plant.set_backlash(cnc.PLAY_STEPS)
    run = cnc.run_part(s, parse(cnc.BACKLASH).frames)
    with pytest.raises(ScenarioFailure, match="contour error"):
        cnc._require_on_contour(s, run, "evalfn")


def test_the_measuring_cycle_finds_the_base_holes_and_the_part_runs_on_the_blank():
    s = cnc.session()
    cnc.blank(s)                                      # raises if a frame is off the blank
    run = s.cnc_run
    for k, hole in enumerate(cnc.BASE_HOLES, start=1):
        true = cnc.blank_to_machine(hole)
        measured = (s.plc.read(f"MeasX[{k}]") * H, s.plc.read(f"MeasY[{k}]") * H)
        assert math.dist(true, measured) <= 1.0 * H, (k, true, measured)
    x0, y0, alpha = cnc.BLANK_PLACEMENT
    turn_tolerance = 2 * H / 40.0                 # a step at each hole, 40 mm apart
    assert s.plc.read("BlankCos") == pytest.approx(math.cos(alpha), abs=turn_tolerance)
    assert s.plc.read("BlankSin") == pytest.approx(math.sin(alpha), abs=turn_tolerance)
    assert (s.plc.read("BlankX0") * H, s.plc.read("BlankY0") * H) == pytest.approx((x0, y0), abs=1.5 * H)
    assert s.plc.read("BlankCheck") == pytest.approx(1.0, abs=1e-3)
    # the tool path: every visited point of frame k near the blank's (turned) frame k
    frames = parse(cnc.BLANK).frames
    for k in range(2, len(frames) + 1):
        f = frames[k - 1]
        a, b = cnc.blank_to_machine(f.start), cnc.blank_to_machine(f.end)
        for p in (p for p in run.points if p[1] == k):
            q = (p[2] * H, p[3] * H)
            assert _distance(a, b, q) <= (cnc.BLANK_TOLERANCE_STEPS + 1) * H, (k, q)


def test_without_the_measuring_cycle_the_part_misses_the_blank():
    s = cnc.session()
    s.plant.set_blank([cnc.blank_to_machine(p) for p in cnc.BASE_HOLES], cnc.HOLE_RADIUS)
    run = cnc.run_part(s, parse(cnc.BLANK).frames)
    end = (run.points[-1][2] * H, run.points[-1][3] * H)
    assert math.dist(end, cnc.blank_to_machine((10.0, 10.0))) > 0.5


def test_a_blank_not_where_drawn_stops_with_the_hole_named():
    s = cnc.session()
    cnc.place_blank(s, placement=(0.0, 0.0, math.radians(10.0)))   # hole 2 far from its drawn place
    run = cnc.run_part(s, parse(cnc.BLANK).frames, timeout=30.0)
    assert not run.finished
    assert s.plc.read("BlankError") == 2 and s.value("HL2") and not s.value("KM1")
    assert not [p for p in run.points if p[1] > 0], "frames ran after a failed measurement"


def test_holes_farther_apart_than_drawn_are_not_a_valid_measurement():
    s = cnc.session()
    cnc.place_blank(s)
    s.plant.set_blank([cnc.blank_to_machine(p) for p in ((0.0, 0.0), (40.5, 0.0))], cnc.HOLE_RADIUS)
    run = cnc.run_part(s, parse(cnc.BLANK).frames, timeout=30.0)
    assert not run.finished and s.plc.read("BlankError") == 3
    assert s.plc.read("BlankCheck") > 1.01


def _distance(a, b, q) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    t = max(0.0, min(1.0, ((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / (dx * dx + dy * dy)))
    return math.dist((a[0] + t * dx, a[1] + t * dy), q)


# --- the plant's side ------------------------------------------------------------------------

def _steps(table: CncTable, axis: str, n: int, negative: bool) -> None:
    from plclab.plants.cnc import DIR, ENABLE, STEP

    for _ in range(n):
        line = 1 - table.axes[axis].step_line
        table.step({STEP[axis]: line, DIR[axis]: int(negative), ENABLE: 1}, 0.001)


def test_the_drive_model_loses_the_play_on_reversal():
    table = CncTable(backlash=4)
    _steps(table, "X", 10, negative=False)
    assert table.axes["X"].steps == 10
    _steps(table, "X", 6, negative=True)
    assert table.axes["X"].steps == 8 and table.axes["X"].motor == 4    # 4 steps in the dead band
    _steps(table, "X", 3, negative=False)
    assert table.axes["X"].steps == 8                                   # back across the band
    _steps(table, "X", 2, negative=False)
    assert table.axes["X"].steps == 9
    with pytest.raises(PlantError):
        table.set_backlash(-1)


def test_the_probe_touches_at_the_hole_wall_only():
    table = CncTable()
    table.set_blank([(0.053, 0.0)], radius=0.1)
    contact = []
    for k in range(-20, 31):                    # the collar: 3 radii = 30 steps around the centre
        table.axes["X"].steps = k
        contact.append((k, table.probe_contact()))
    touching = [k for k, c in contact if c]
    assert touching == list(range(-20, -4)) + list(range(16, 31))       # at or beyond the wall
    table.axes["X"].steps = 40
    assert not table.probe_contact()            # beyond the collar: above the blank
    assert table.step({}, 0.001)["IX1.2"] == 0
    table.axes["X"].steps = 20
    assert table.step({}, 0.001)["IX1.2"] == 1              # B1 on the PLC's input


def test_console_buttons_and_the_normally_closed_emergency_stop():
    table = CncTable()
    assert table.console_bits == {"SB1": 0, "SB2": 0, "SA1": 0, "SB3": 1}
    table.press("SB3")
    table.press("SB1")
    assert table.console_bits["SB3"] == 0 and table.console_bits["SB1"] == 1
    table.release("SB3")
    assert table.console_bits["SB3"] == 1
    with pytest.raises(PlantError, match="unknown console input 'SB9'"):
        table.set_switch("SB9", 1)
