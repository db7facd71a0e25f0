"""`plclab sim`: any program in virtual time, scripted inputs, trace files; the timing convention."""
from __future__ import annotations

import csv
from pathlib import Path

import pytest

from plclab.cli import main
from plclab.trace import read_csv

PROGRAM = """
PROGRAM main
VAR start AT %IX0.0 : BOOL; lamp AT %QX0.0 : BOOL; level AT %QW0 : INT; END_VAR
VAR t : TON; n : INT; END_VAR
t(IN := start, PT := T#100ms);
lamp := t.Q;
IF start THEN n := n + 1; END_IF;
level := n;
END_PROGRAM
CONFIGURATION Config0 RESOURCE Res0 ON PLC
TASK fast (INTERVAL := T#10ms, PRIORITY := 0);
PROGRAM inst WITH fast : main;
END_RESOURCE END_CONFIGURATION
"""


@pytest.fixture
def files(tmp_path: Path) -> dict:
    st = tmp_path / "prog.st"
    st.write_text(PROGRAM)
    inputs = tmp_path / "in.csv"
    inputs.write_text("time_s,name,value\n0.055,%IX0.0,1\n0.5,%IX0.0,0\n")
    return {"st": st, "in": inputs, "dir": tmp_path}


def test_sim_writes_trace_with_input_seen_at_next_scan_and_timer_to_the_tick(files, capsys):
    out = files["dir"] / "out.csv"
    rc = main(["sim", str(files["st"]), "--duration", "1s", "--inputs", str(files["in"]), "--csv", str(out)])
    assert rc == 0
    assert "100 scans of 10 ms" in capsys.readouterr().out
    with out.open() as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["time_s", "name", "value"]
    trace = read_csv(out)
    # the input changed at 0.055 s is seen by the first scan at or after it: 0.06 s
    assert trace.changes("%IX0.0")[1] == (60_000_000, True)
    # TON PT=100 ms started by that scan: Q on the scan at exactly 0.16 s
    assert trace.changes("%QX0.0")[1] == (160_000_000, True)
    # released at 0.5 s: Q falls on that scan
    assert trace.changes("%QX0.0")[2] == (500_000_000, False)
    # the counter counted scans 0.06 .. 0.49: 44 scans
    assert trace.value_at("%QW0", 0.99) == 44
    # every signal has its value at time 0
    assert {r[1] for r in rows[1:] if r[0] == "0"} == {"%IX0.0", "%QX0.0", "%QW0"}


def test_sim_vcd_and_png_are_written(files):
    vcd, png = files["dir"] / "o.vcd", files["dir"] / "o.png"
    assert main(["sim", str(files["st"]), "--duration", "0.3", "--inputs", str(files["in"]),
                 "--vcd", str(vcd), "--plot", str(png), "--watch", "inst.n"]) == 0
    text = vcd.read_text()
    assert "$timescale" in text and "QX0_0" in text and "n" in text
    assert png.stat().st_size > 5000


def test_sim_reports_bad_input_script_in_one_line(files, capsys):
    bad = files["dir"] / "bad.csv"
    bad.write_text("time_s,name,value\n0.1,%IX0.9,1\n")
    assert main(["sim", str(files["st"]), "--duration", "1", "--inputs", str(bad)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "%IX0.9" in err[0] and err[0].startswith("plclab: error:")


def test_sim_on_a_program_with_a_compile_error_prints_checker_lines(files, capsys):
    broken = files["dir"] / "broken.st"
    broken.write_text("PROGRAM prog\nVAR x : INT; END_VAR\nx := y;\nEND_PROGRAM\n")
    assert main(["sim", str(broken), "--duration", "1"]) == 1
    assert capsys.readouterr().err.strip() == f"{broken}:3:6: error: undeclared identifier 'y'"


def test_sim_fault_is_reported_with_location_and_exit_1(files, capsys):
    prog = files["dir"] / "div.st"
    prog.write_text("PROGRAM prog\nVAR q AT %QX0.0 : BOOL; END_VAR\nVAR d : INT; r : INT; END_VAR\nq := TRUE;\n"
                    "r := 10 / d;\nEND_PROGRAM\n")
    assert main(["sim", str(prog), "--duration", "1"]) == 1
    out = capsys.readouterr().out
    assert f"{prog}:5:" in out and "division_by_zero" in out and "in prog" in out


def test_sim_stopped_by_a_harness_bug_exits_70_asking_for_a_report(files, capsys, monkeypatch):
    from plclab.runtime import stdfb

    def harness_bug(self):
        raise AttributeError("'TON' object has no attribute 'PREV'")
    monkeypatch.setattr(stdfb.TON, "_body", harness_bug)
    monkeypatch.setenv("PLCLAB_NATIVE", "0")      # the bug is the Python path's (its TON)
    assert main(["sim", str(files["st"]), "--duration", "1"]) == 70
    out = capsys.readouterr().out
    assert f"{files['st']}:5:" in out and "internal error of plclab" in out and "please report it" in out


def test_bad_duration_is_one_line(files, capsys):
    with pytest.raises(SystemExit) as e:
        main(["sim", str(files["st"]), "--duration", "soon"])
    assert e.value.code == 2
    assert "not a duration" in capsys.readouterr().err
