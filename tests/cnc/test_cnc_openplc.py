"""The CNC stand's bundle for a real OpenPLC (`plclab build cnc VARIANT [--part PART.nc]`): the
fine cycle OpenPLC can hold with the PSM exchange, and a part program in the frame table, so
SB1 alone (the console face's) runs it. The bundle is run here in the project's soft PLC with
the plant, in virtual time, as OpenPLC would run it: nothing but SB1 is done to the PLC."""
from __future__ import annotations

import pytest

from plclab.build import build_outputs
from plclab.cli import main
from plclab.cnc.gcode import parse
from plclab.cnc.openplc import OPENPLC_FINE_MS, plant_params
from plclab.cnc.toolpath import check_blocks
from plclab.modbus.psm import psm_script
from plclab.stands import cnc

PART = """(an L and a quarter circle back)
G21 G90 G17
G01 X2 Y0 F300
Y1
G03 X1 Y2 I-1 J0
G01 X0 Y0
M30
"""


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    part = tmp_path_factory.mktemp("part") / "part.nc"
    part.write_text(PART, encoding="utf-8")
    return part, build_outputs("cnc", "full", xml=False, part=str(part)).st_text


def test_the_openplc_bundle_runs_the_fine_cycle_openplc_can_hold():
    text = build_outputs("cnc", "full", xml=False).st_text
    assert f"TASK FineTask (INTERVAL := T#{OPENPLC_FINE_MS}ms, PRIORITY := 0);" in text
    assert f"FINE_MS : LREAL := {OPENPLC_FINE_MS}.0;" in text and "T#1ms" not in text
    assert "    FrameCount : INT;" in text                    # no part given: the table starts empty
    # the PSM script's pulse generator spreads a cycle's counts over the bundle's T = 4 fine cycles
    assert plant_params() == {"pulse_cycle": 4 * OPENPLC_FINE_MS / 1000}
    assert f"PLANT = {plant_params()!r}" in psm_script("cnc")
    assert "PLANT = {}" in psm_script("mp9c")


def test_a_part_program_in_the_bundle_runs_on_sb1_alone(built):
    part, text = built
    s = cnc.session(program=[("cnc_full.st", text)])
    assert s.tick == pytest.approx(OPENPLC_FINE_MS / 1000)
    frames = parse(PART).frames
    table = cnc.frame_table(frames, s.plant.step_mm)
    for name, value in table.items():                    # the initial values are the harness's table
        got = [s.plc.read(f"{name}[{k}]") for k in range(1, len(value) + 1)] if isinstance(value, list) \
            else s.plc.read(name)
        assert got == value, name
    run = cnc.PartRun(frames, s.plant.step_mm, start=s.now)
    s.plant.press("SB1")                                 # the operator, on the console face
    cnc.record_until(s, run, "ProgramEnd", timeout=30.0, release=("SB1", s.now + 0.02))
    assert s.plc.read("ProgramEnd") and run.points[-1][2:] == (0, 0, 0)
    assert run.points[0][2:] == (1, 0, 0)
    for block in check_blocks(frames, run.points, s.plant.step_mm, "evalfn", run.start):
        assert block.ok, block.row()
    # the feed is the program's, at most one step per 5 ms fine cycle: the 2 mm of frame 1
    # at F300 (500 steps/s) are capped at 200 steps/s: 1 s (a 1 ms FINE_MS would take 2.5 s)
    first = [p for p in run.points if p[1] == 1]
    assert first[-1][0] - run.start == pytest.approx(200 * OPENPLC_FINE_MS / 1000, abs=2 * s.tick)


def test_build_part_cli_writes_the_bundle_and_refuses_bad_input_in_one_line(built, tmp_path, capsys):
    part, text = built
    out = tmp_path / "cnc_full.st"
    assert main(["build", "cnc", "full", "--part", str(part), "-o", str(out), "--xml", str(tmp_path / "c.xml")]) == 0
    assert out.read_text(encoding="utf-8") == text
    assert f"Part program {part}: 4 frames in the frame table (GVL_CNC), method evalfn" in text
    assert capsys.readouterr().err == ""
    tail = tmp_path / "tail.nc"
    tail.write_text(PART + "G00 X50\n", encoding="utf-8")               # a block after M30: a warning
    assert main(["build", "cnc", "full", "--part", str(tail), "-o", str(tmp_path / "tail.st")]) == 0
    assert capsys.readouterr().err == f"{tail}:8: warning: blocks after the program end (line 7) are not run\n"
    bad = tmp_path / "bad.nc"
    bad.write_text("G01 X1 F100\nG91.1 X2\n", encoding="utf-8")
    capsys.readouterr()
    assert main(["build", "cnc", "full", "--part", str(bad), "-o", str(tmp_path / "bad.st")]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"{bad}:2:1: error: G91.1 is not supported by the stand") and err.count("\n") == 1
    assert not (tmp_path / "bad.st").exists()
    assert main(["build", "mp9c", "full", "--part", str(part), "-o", str(tmp_path / "m.st")]) == 1
    assert capsys.readouterr().err == "plclab: error: build: --part is for the cnc stand (a G-code part " \
                                      "program), not mp9c\n"
