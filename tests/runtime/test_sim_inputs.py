"""`plclab sim --inputs`: every value is read as the type of what it sets; a bad file or value
is one `FILE:LINE: error:` line (exit 1), never a wrapped value or an internal error."""
from __future__ import annotations

from pathlib import Path

import pytest

from plclab.cli import main
from plclab.trace import read_csv

PROGRAM = """
PROGRAM main
VAR level AT %IW0 : INT; raw AT %IW1 : WORD; start AT %IX0.0 : BOOL; END_VAR
VAR r : REAL; n : DINT; mode : (IDLE, RUNNING); END_VAR
VAR out AT %QW0 : INT; END_VAR
out := level;
END_PROGRAM
"""


@pytest.fixture
def st(tmp_path: Path) -> Path:
    p = tmp_path / "prog.st"
    p.write_text(PROGRAM)
    return p


def sim(st: Path, inputs: Path, *extra: str) -> int:
    return main(["sim", str(st), "--duration", "0.1", "--inputs", str(inputs), *extra])


def one_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("plclab: error:") and "internal error" not in err[0]
    return err[0]


@pytest.mark.parametrize("row, message", [
    ("main.r,abc", "in.csv:3: error: bad value 'abc' for REAL main.r: not a number"),
    ("%IW0,40000", "in.csv:3: error: value 40000 is out of range for INT %IW0 (-32768..32767)"),
    ("%IW1,-1", "in.csv:3: error: value -1 is out of range for WORD %IW1 (0..65535)"),
    ("main.n,99999999999999999999", "in.csv:3: error: value 99999999999999999999 is out of range for DINT main.n"),
    ("%IW5,70000", "in.csv:3: error: value 70000 is out of range for %IW5 (a 16-bit image cell)"),
    ("main.n," + "9" * 5000, "in.csv:3: error: value '99999999999999"),
    ("%IX0.0,2", "in.csv:3: error: bad value '2' for BOOL %IX0.0: expected 0 or 1"),
    ("main.mode,FAST", "in.csv:3: error: bad value 'FAST' for"),
    ("main.r,1e39", "in.csv:3: error: value '1e39' is out of range for REAL main.r"),
    ("main.nothing,1", "in.csv:3: error: "),
])
def test_a_bad_value_is_one_line_naming_file_and_line(st, tmp_path, capsys, row, message):
    inputs = tmp_path / "in.csv"
    inputs.write_text(f"time_s,name,value\n0,%IX0.0,0\n0.05,{row}\n")
    assert sim(st, inputs) == 1
    assert message in one_line(capsys)


def test_values_in_range_are_applied_as_their_type(st, tmp_path):
    inputs = tmp_path / "in.csv"
    inputs.write_text("time_s,name,value\n0,%IW0,-32768\n0,%IW1,65535\n0,main.r,2.5\n0,main.mode,RUNNING\n"
                      "0.04,%IW0,32767\n")
    out = tmp_path / "out.csv"
    assert sim(st, inputs, "--csv", str(out), "--watch", "main.r") == 0
    trace = read_csv(out)
    assert trace.changes("%QW0") == [(0, -32768), (40_000_000, 32767)]
    assert trace.changes("main.r") == [(0, 2.5)]


@pytest.mark.parametrize("data, message", [
    ("time_s,name,value\n0,%IX0.0,1\n".encode("utf-16"), "in.csv:1: error: the file is UTF-16"),
    (b"time_s,name,value\n0,%IX0.0,1\n0.1,%IX0.0,\xff\n", "in.csv:3: error: byte 0xff is not UTF-8"),
    (b"\x7fELF\x02\x01\x01\x00\x00\x00", "in.csv:1: error: a NUL byte: this is a binary file"),
    (b"", "in.csv:1: error: empty file"),
    (b"time_s,name,value\n" + b"x" * 100 + b",%IX0.0,1\n", "in.csv:2: error: "),
])
def test_a_file_that_is_not_utf8_text_is_one_line(st, tmp_path, capsys, data, message):
    inputs = tmp_path / "in.csv"
    inputs.write_bytes(data)
    assert sim(st, inputs) == 1
    assert message in one_line(capsys)


def test_an_input_script_that_is_a_directory_is_one_line(st, tmp_path, capsys):
    assert sim(st, tmp_path) == 1
    assert "is a directory" in one_line(capsys)
