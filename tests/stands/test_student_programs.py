"""Every scenario of every stand runs on students' programs of their own structure.

A scenario a student runs (`plclab run STAND --program ...`) decides from the stand's I/O and
the plant, never from the inside of the shipped program: tests/stands/programs/<stand>/<name>/
holds correct programs written with other structures (one flat program, blocks of their own,
other task splits, other regulator forms), each with the stand's GVL (plc/GVL) and a
config.st. Each scenario's own pass criteria must hold on each of them, the shipped
program's internals they lack are marked "absent" (never invented), and a broken edit of
one of them makes the scenario that checks it fail (the scenarios can fail).

A program folder may name shipped building blocks it uses (plc/POUs stems, one a line) in
shipped.txt: the CNC programs reorganise PRG_CncStand around the shipped interpolators.
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from plclab.runner import run_scenario
from plclab.stands import PLC_DIR, stand_module
from plclab.stands.base import stand_spec

PROGRAMS = Path(__file__).parent / "programs"
STANDS = ("mp9c", "tur10", "thermo", "cnc")
_POU = re.compile(r"^\s*(?:PROGRAM|FUNCTION_BLOCK|FUNCTION)\s+(\w+)", re.IGNORECASE | re.MULTILINE)


def program_dirs(stand: str) -> list[Path]:
    return sorted(p for p in (PROGRAMS / stand).iterdir() if p.is_dir()) if (PROGRAMS / stand).is_dir() else []


def program_files(stand: str, folder: Path) -> list[str]:
    """The program as `plclab run --program` takes it: types first, its POUs, the shipped
    blocks it names, the stand's GVL, its configuration last."""
    own = sorted((p for p in folder.glob("*.st") if p.name != "config.st"),
                 key=lambda p: (not p.name.startswith("T_"), p.name))
    shipped = folder / "shipped.txt"
    blocks = [PLC_DIR / "POUs" / f"{s.strip()}.st" for s in shipped.read_text().split()] if shipped.exists() else []
    gvl = [PLC_DIR / "GVL" / f"{g}.st" for g in stand_spec(stand).stand.gvl]
    return [str(p) for p in own + blocks + gvl + [folder / "config.st"]]


def run(stand: str, folder: Path, scenario: str, tmp_path: Path, files=None):
    return run_scenario(stand, scenario=scenario, program=files or program_files(stand, folder),
                        out_dir=str(tmp_path))


CASES = [(stand, folder.name, scenario) for stand in STANDS for folder in program_dirs(stand)
         for scenario in stand_spec(stand).scenarios]


def test_every_stand_has_two_programs_of_its_own_structure():
    for stand in STANDS:
        folders = program_dirs(stand)
        assert len(folders) >= 2, f"{stand}: {len(folders)} test programs"
        shipped = {name.upper() for variant in stand_spec(stand).stand.variants
                   for name in _shipped_pou_names(stand, variant)}
        for folder in folders:
            own = {n.upper() for p in folder.glob("*.st") for n in _POU.findall(p.read_text())}
            main = {n.upper() for n in re.findall(r"PROGRAM\s+\w+\s+WITH\s+\w+\s*:\s*(\w+)",
                                                 (folder / "config.st").read_text(), re.IGNORECASE)}
            assert main and not main & shipped, f"{folder}: runs a shipped main program {main & shipped}"
            # a block of a shipped name is only one the GVL itself requires (TUR-10's Sensors)
            assert own & shipped <= {"FB_TUR10SENSORS"}, f"{folder}: {own & shipped}"


def _shipped_pou_names(stand: str, variant: str) -> list[str]:
    return list(stand_spec(stand).stand.variant(variant).pous)


@pytest.mark.parametrize("stand, program, scenario", CASES)
def test_every_scenario_passes_on_a_program_of_its_own_structure(stand, program, scenario, tmp_path):
    r = run(stand, PROGRAMS / stand / program, scenario, tmp_path)
    assert r.failure is None, f"{stand} {program} {scenario}: {r.failure}"
    assert r.session.fault is None
    # what the program lacks of the shipped program's inside is marked absent, not invented
    for name in r.session.absent:
        assert r.session.trace.changes(name) == [(0, "absent")]
    assert len(r.timeline) > 1


def test_the_shipped_internals_are_absent_from_these_programs(tmp_path):
    r = run("mp9c", PROGRAMS / "mp9c" / "blocks", "demo", tmp_path)
    assert set(r.session.absent) == {"FramePtr", "FrameCount", "Running", "FrameFault"}
    assert "absent" in r.absent_note and "FramePtr (Main.Robot.Sequencer.Ptr)" in r.absent_note
    assert any("a frame starts" in row and "absent" in row for row in r.timeline)


def _broken(tmp_path: Path, stand: str, program: str, file: str, old: str, new: str) -> list[str]:
    """The program's files with one edit in `file` (a student's mistake)."""
    files = program_files(stand, PROGRAMS / stand / program)
    out = []
    for f in files:
        if Path(f).name == file and Path(f).parent.name == program:
            text = Path(f).read_text()
            assert old in text, (file, old)
            copy = tmp_path / file
            copy.write_text(text.replace(old, new))
            out.append(str(copy))
        else:
            out.append(f)
    return out


@pytest.mark.parametrize("stand, program, file, old, new, scenario, message", [
    # the release of the 3 s reset press records a frame
    ("mp9c", "onefile", "robot.st", "ShortEv := Opened.Q AND NOT Consumed;", "ShortEv := Opened.Q;",
     "reset", "the release recorded a frame"),
    # one press records the frame twice (what a bouncing contact would do): step playback shows it
    ("mp9c", "onefile", "robot.st", "            LongWait[Taught] := I07;\n",
     "            LongWait[Taught] := I07;\n            Taught := Taught + 1;\n"
     "            OutCode[Taught] := OutCode[Taught - 1];\n            InCode[Taught] := InCode[Taught - 1];\n",
     "bounce", "after step press 2"),
    # SB1 does not stop continuous execution
    ("mp9c", "onefile", "robot.st", "        IF PressEv AND NOT Stepping THEN", "        IF FALSE THEN",
     "demo", "a frame started after SB1 stopped"),
    # the taught frames not retained: lost at the power cycle
    ("mp9c", "blocks", "P_Mp9cBlocks.st", "VAR RETAIN\n    Memory", "VAR\n    Memory",
     "retain", "HL1 on after the restart"),
    # Task 1 not done: the gripper switch does nothing
    ("mp9c", "blocks", "P_Mp9cBlocks.st", "L1 := SA2;", "L1 := FALSE;", "demo", "gripper clamped"),
    ("tur10", "onetask", "P_Tur10Single.st", "VAR RETAIN\n    Kept", "VAR\n    Kept",
     "retain", "the frames were lost"),
    # no frame timeout: a dead sensor keeps the regulator creeping
    ("tur10", "twotasks", "FB_Tur10Sequence.st", "PT := T#20s", "PT := T#200s",
     "dead_sensor", "the frame timeout (references 0) not reached"),
    # the heater not cut with an open sensor
    ("thermo", "velocity", "P_ThermoVelocity.st", "IF Broken THEN\n    HeatCmd := 0;\nEND_IF;", "",
     "sensor_open", "with the sensor open"),
    # a regulator that takes over from 0 instead of the actuator's command: a bump
    ("thermo", "blocks", "FB_PositionPI.st", "IPart := Out - Gain * Dev;", "IPart := 0.0;",
     "modes", "jumped by"),
    # the emergency stop not read: the table goes on
    ("cnc", "axes", "P_CncAxes.st", "IF NOT SB3 OR ((SQ1", "IF FALSE AND ((SQ1", "estop", "HL2 not lit or KM1 still closed"),
    # Task 4 wrong: the evaluation function updated with the wrong sign leaves a sloped line
    # (the blank lies turned: its rectangle's sides are sloped)
    ("cnc", "split", "FB_CncLinearSteps.st", "Fn[Minor] := Fn[Minor] - Span[Minor];",
     "Fn[Minor] := Fn[Minor] + Span[Minor];", "blank", "contour error"),
])
def test_a_broken_program_fails_the_scenario_that_checks_it(tmp_path, stand, program, file, old, new,
                                                            scenario, message):
    files = _broken(tmp_path, stand, program, file, old, new)
    r = run(stand, PROGRAMS / stand / program, scenario, tmp_path, files)
    assert r.failure is not None and message in r.failure, r.failure


def test_plclab_run_on_such_a_program_names_and_marks_what_it_lacks(tmp_path, capsys):
    """The command a student types: timeline, the one line naming the missing observables,
    and CSV / VCD / plot that carry them as "absent"."""
    from plclab.cli import main

    files = program_files("tur10", PROGRAMS / "tur10" / "twotasks")
    csv, vcd, png = tmp_path / "d.csv", tmp_path / "d.vcd", tmp_path / "d.png"
    code = main(["run", "tur10", "--program", *files, "--scenario", "demo", "--csv", str(csv), "--vcd", str(vcd),
                 "--plot", str(png)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "scenario demo passed" in out
    assert 'not in this program, shown as "absent" in the timeline and traces: FramePtr (Main.Robot.Sequencer.Ptr)' in out
    assert "(absent: the program has no InFrame, FramePtr)" in out          # no positioning table invented
    assert '0,FramePtr,"absent"' in csv.read_text().splitlines()
    assert "sabsent" in vcd.read_text()
    assert png.stat().st_size > 0
    # what the program does have of the stand's globals is recorded as usual
    assert any(row.startswith("0,Position1,") and "absent" not in row for row in csv.read_text().splitlines())
