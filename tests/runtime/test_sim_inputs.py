"""`plclab sim --inputs`: every value is read as the type of what it sets; a bad file or value
is one `FILE:LINE: error:` line (exit 1), never a wrapped value or an internal error."""
from __future__ import annotations

from pathlib import Path

import pytest

from plclab.cli import main
from plclab.trace import read_csv

PROGRAM = """
TYPE E_Mode : (IDLE, RUNNING); END_TYPE
PROGRAM main
VAR level AT %IW0 : INT; raw AT %IW1 : WORD; start AT %IX0.0 : BOOL; END_VAR
VAR r : REAL; n : DINT; mode : E_Mode; END_VAR
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


@pytest.mark.parametrize("row, message", [
    # a typo in an address: the program never reads %IW7, the row would change nothing
    ("%IW7,5", "in.csv:3: error: %IW7 is not used by the program (it declares %IW0, %IW1)"),
    ("%IX0.1,1", "in.csv:3: error: %IX0.1 is not used by the program (it declares %IX0.0)"),
    ("%MW3,1", "in.csv:3: error: %MW3 is not used by the program (it declares no %MW address)"),
    ("%QX2.0,1", "in.csv:3: error: %QX2.0 is not used by the program (it declares no %QX address)"),
    # a name the program does not have: named, with its line
    ("main.levle,1", "in.csv:3: error: unknown variable 'main.levle'"),
    ("nothing,1", "in.csv:3: error: unknown variable 'nothing'"),
])
def test_a_row_setting_what_the_program_does_not_have_is_an_error_naming_the_line(st, tmp_path, capsys,
                                                                                  row, message):
    inputs = tmp_path / "in.csv"
    inputs.write_text(f"time_s,name,value\n0,%IX0.0,0\n0.05,{row}\n")
    assert sim(st, inputs) == 1
    assert one_line(capsys) == f"plclab: error: {inputs}:{message[len('in.csv:'):]}"


def test_an_address_spelled_otherwise_but_used_is_accepted(st, tmp_path):
    """%I0.0 is %IX0.0 (the short spelling): the program uses it, the row is applied."""
    inputs = tmp_path / "in.csv"
    inputs.write_text("time_s,name,value\n0,%I0.0,1\n0,%IW0,7\n")
    out = tmp_path / "out.csv"
    assert sim(st, inputs, "--csv", str(out)) == 0
    trace = read_csv(out)
    assert trace.changes("%IX0.0") == [(0, True)] and trace.changes("%QW0") == [(0, 7)]


def test_a_watched_name_the_program_lacks_is_one_line_naming_the_option(st, tmp_path, capsys):
    inputs = tmp_path / "in.csv"
    inputs.write_text("time_s,name,value\n0,%IX0.0,0\n")
    assert sim(st, inputs, "--watch", "main.nothing") == 1
    assert one_line(capsys) == "plclab: error: --watch main.nothing: unknown variable 'main.nothing'"
