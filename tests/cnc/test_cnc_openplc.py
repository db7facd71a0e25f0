"""The CNC stand's bundle for a real OpenPLC (`plclab build cnc VARIANT [--part PART.nc]`): the
fine cycle OpenPLC can hold with the PSM exchange, and a part program in the frame table, so
SB1 alone (the console face's) runs it. The bundle is run here in the project's soft PLC with
the plant, in virtual time, as OpenPLC would run it: nothing but SB1 is done to the PLC."""
from __future__ import annotations

import pytest

from plclab.build import build_outputs
from plclab.cli import main
from plclab.nc.gcode import parse
from plclab.cnc.openplc import OPENPLC_FINE_MS, part_tape, plant_params
from plclab.nc.toolpath import check_blocks
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


def test_the_openplc_bundle_runs_the_fine_cycle_openplc_can_hold(capsys):
    text = build_outputs("cnc", "full", xml=False).st_text
    assert f"TASK FineTask (INTERVAL := T#{OPENPLC_FINE_MS}ms, PRIORITY := 0);" in text
    assert f"FINE_MS : LREAL := {OPENPLC_FINE_MS}.0;" in text and "T#1ms" not in text
    assert "    FrameCount : INT;" in text                    # no part given: the table starts empty
    # the PSM script's pulse generator spreads a cycle's counts over the bundle's T = 4 fine cycles
    assert plant_params() == {"pulse_cycle": 4 * OPENPLC_FINE_MS / 1000}
    assert main(["psm-script", "cnc"]) == 0                    # what `plclab psm-script cnc` writes
    assert f"PLANT = {plant_params()!r}" in capsys.readouterr().out
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


# ------------------------------------------------------------------ the tape reader (console --part)

def test_a_tape_is_stored_while_no_program_runs_and_sb1_runs_it(built):
    """The shipped program stores the frames the plant's tape reader shows, one a scan, only
    while no program runs; then SB1 runs them, within every frame's bound."""
    part, _text = built
    method, frames, notes = part_tape(str(part), "dda")
    assert method == 1 and notes == []
    s = cnc.session()
    s.plant.load_tape(method, frames)
    s.run(0.02)
    assert s.plant.readouts()[-1] == len(frames) == s.plc.read("FrameCount") == 4
    table = cnc.frame_table(parse(PART).frames, s.plant.step_mm, "dda")
    for name in cnc.FRAME_ARRAYS:
        assert [s.plc.read(f"{name}[{k}]") for k in range(1, 5)] == table[name], name
    assert s.plc.read("Method") == 1
    run = cnc.PartRun(parse(PART).frames, s.plant.step_mm, start=s.now, method="dda")
    s.plant.press("SB1")
    cnc.record_until(s, run, "KM1", timeout=1.0, release=("SB1", s.now + 0.005))     # running
    s.plant.load_tape(0, frames[:2])             # a second tape while the part runs: it waits
    cnc.record_until(s, run, "ProgramEnd", timeout=30.0)
    assert s.plc.read("ProgramEnd") and run.points[-1][2:] == (0, 0, 0)
    for block in check_blocks(run.frames, run.points, s.plant.step_mm, "dda", run.start):
        assert block.ok, block.row()
    assert s.plant.readouts()[-1] == 0                       # the second tape waited
    s.run(0.02)
    assert s.plant.readouts()[-1] == 2 and s.plc.read("FrameCount") == 2 and s.plc.read("Method") == 0


@pytest.mark.parametrize("method, frames, message", [
    (0, [], "a tape holds 1..200 frames"),
    (3, [(1, 0, 0, 0, 0, 0, 500, 0, 0)], "tape method 3"),
    (0, [(7, 0, 0, 0, 0, 0, 500, 0, 0)], "tape frame 1: kind 7"),
    (0, [(1, 0, 0, 0, 0, 0, 500, 0)], "tape frame 1: 9 values"),
])
def test_the_tape_reader_refuses_a_bad_tape_in_one_line(method, frames, message):
    from plclab.plants.base import PlantError
    from plclab.plants.cnc import CncTable

    with pytest.raises(PlantError, match=message):
        CncTable().load_tape(method, frames)


def test_console_part_refuses_bad_input_before_sending_anything(tmp_path, capsys):
    bad = tmp_path / "bad.nc"
    bad.write_text("G01 X1 F100\nG00 G01 X2\n", encoding="utf-8")
    assert main(["console", "cnc", "127.0.0.1:1", "--part", str(bad)]) == 1     # port 1: never reached
    assert capsys.readouterr().err == f"{bad}:2:5: error: G00 and G01 in one block: both of modal group 1 " \
                                      f"(motion), one of each group per block\n"
    fast = tmp_path / "fast.nc"
    fast.write_text("G01 X1 F30000\n", encoding="utf-8")            # 50,000 steps/s: not a 16-bit word
    assert main(["console", "cnc", "127.0.0.1:1", "--part", str(fast)]) == 1
    assert capsys.readouterr().err == f"plclab: error: {fast}:1: FrameFeed of 50000 steps does not fit the " \
                                      f"tape reader's 16-bit words (-32768..32767)\n"
    assert main(["console", "mp9c", "127.0.0.1:1", "--part", str(bad)]) == 1
    assert capsys.readouterr().err == "plclab: error: console: --part is for the cnc stand (a G-code part " \
                                      "program), not mp9c\n"


def test_the_tape_readout_counts_a_new_tape_from_its_load_not_the_last_one_s_count():
    """The console face's `tape` readout is what `plclab console cnc --part` waits on: loading a
    tape of the same length as one the PLC stored whole must show 0 at once, not the last
    tape's count until the next PSM exchange (a fast PLC storing the new tape between two
    reads of the console would otherwise look like no exchange at all)."""
    from plclab.modbus.console import ConsoleMap
    from plclab.modbus.protocol import Table
    from plclab.plants.cnc import CncTable
    from plclab.plants.host import PlantHost

    host = PlantHost(CncTable())
    face = ConsoleMap(host)
    frames = [(1, 200, 0, 0, 0, 0, 500, 0, 0), (1, 0, 100, 0, 0, 0, 500, 0, 0)]
    tape = [len(frames), 0] + [v for frame in frames for v in frame]
    at = [name for name, _unit in CncTable.FACE.readouts].index("tape")
    for _load in range(2):
        face.write(Table.HOLDING_REGISTERS, 1, tuple(tape[1:]))
        face.write(Table.HOLDING_REGISTERS, 0, (tape[0],))          # loads the tape
        assert face.read(Table.INPUT_REGISTERS, at, 1) == [0]         # none of this tape stored yet
        ack = 0
        for _scan in range(6):                                       # the PLC stores what is shown
            ack = host.exchange({"QW4": ack}).get("IW4", ack)
        assert face.read(Table.INPUT_REGISTERS, at, 1) == [2]
