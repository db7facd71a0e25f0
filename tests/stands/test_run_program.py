"""`plclab run STAND --program FILE.st... [--scenario NAME]`: a stand scenario on a student's
own program (timeline, traces), with one-line errors for a program that cannot run."""
from __future__ import annotations

from plclab.cli import main
from plclab.stands import bundle
from plclab.stands.mp9c import STAND

BROKEN = """PROGRAM Main
VAR n : INT; END_VAR
n := n + ;
END_PROGRAM
"""


def test_a_students_program_runs_a_scenario_with_timeline_and_traces(tmp_path, capsys):
    mine = tmp_path / "mine.st"
    mine.write_text(bundle(STAND, "task1"), encoding="utf-8")
    csv = tmp_path / "step.csv"
    code = main(["run", "mp9c", "--program", str(mine), "--scenario", "step", "--csv", str(csv)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "scenario step passed" in out and "SB1 pressed" in out      # the timeline
    text = csv.read_text(encoding="utf-8")
    assert "%IX1.6" in text and ",FramePtr," in text                  # I/O and the observable, by name


def test_a_program_that_does_not_compile_is_one_line_per_error(tmp_path, capsys):
    bad = tmp_path / "bad.st"
    bad.write_text(BROKEN, encoding="utf-8")
    code = main(["run", "mp9c", "--program", str(bad)])
    err = capsys.readouterr().err
    assert code == 1
    assert err.startswith(f"{bad}:3:") and ": error: " in err and "Traceback" not in err


def test_a_program_without_configuration_or_with_a_variant_is_refused(tmp_path, capsys):
    part = tmp_path / "part.st"
    part.write_text("PROGRAM Main\nVAR n : INT; END_VAR\nn := n + 1;\nEND_PROGRAM\n", encoding="utf-8")
    assert main(["run", "mp9c", "--program", str(part)]) == 1
    assert "no CONFIGURATION" in capsys.readouterr().err
    assert main(["run", "mp9c", "--variant", "task1", "--program", str(part)]) == 1
    assert "--variant or --program, not both" in capsys.readouterr().err


def test_a_program_without_the_shipped_internals_runs_and_they_are_shown_absent(tmp_path, capsys):
    mine = tmp_path / "renamed.st"
    # the student renamed the frame store instance: the frame count observable is gone, the
    # scenario still decides from the console, the valves, the switches and HL1
    head, main_program = bundle(STAND, "task1").split("PROGRAM PRG_Mp9cBaseline", 1)
    main_program = main_program.replace("    Cp : ST_ControlProgram;", "    Store : ST_ControlProgram;") \
        .replace("Cp := Cp);", "Cp := Store);").replace("Empty := Cp.Count", "Empty := Store.Count")
    mine.write_text(head + "PROGRAM PRG_Mp9cBaseline" + main_program, encoding="utf-8")
    csv = tmp_path / "b.csv"
    code = main(["run", "mp9c", "--program", str(mine), "--scenario", "bounce", "--csv", str(csv)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "scenario bounce passed" in out
    assert "FrameCount" in out and "absent" in out                  # the run says what it cannot show
    rows = csv.read_text(encoding="utf-8").splitlines()
    assert '0,FrameCount,"absent"' in rows                          # marked, not invented
    assert not any(r.startswith(("0.", "1", "2", "3", "4", "5", "6", "7", "8", "9")) and ",FrameCount," in r
                   for r in rows)
    assert '0,FramePtr,"absent"' not in rows                        # the program still has that one
