"""`plclab check FILE.st...` as a user runs it: exit codes, the exact one-line error format,
several errors in one run, several files as one compilation unit, unreadable files."""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

LINE = re.compile(r"^(?P<file>.+):(?P<line>\d+):(?P<col>\d+): error: (?P<msg>.+)$")


def _plclab() -> list[str]:
    script = Path(sys.executable).parent / "plclab"
    if script.exists():
        return [str(script)]
    found = shutil.which("plclab")
    return [found] if found else [sys.executable, "-m", "plclab.cli"]


def run_check(*files: Path | str) -> subprocess.CompletedProcess:
    return subprocess.run([*_plclab(), "check", *map(str, files)], capture_output=True, text=True, timeout=60)


def write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def test_valid_file_exits_0(tmp_path: Path) -> None:
    src = write(tmp_path, "ok.st", "PROGRAM Main\n  VAR x : INT; END_VAR\n  x := x + 1;\nEND_PROGRAM\n")
    r = run_check(src)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""
    assert r.stdout.strip() == "ok: 1 file(s) checked"


def test_error_exits_1_with_exact_format(tmp_path: Path) -> None:
    src = write(tmp_path, "bad.st", "PROGRAM Main\n  VAR x : INT; END_VAR\n  x := y + 1;\nEND_PROGRAM\n")
    r = run_check(src)
    assert r.returncode == 1
    assert r.stdout == ""
    assert r.stderr.splitlines() == [f"{src}:3:8: error: undeclared identifier 'y'"]
    assert "Traceback" not in r.stderr


def test_syntax_error_format(tmp_path: Path) -> None:
    src = write(tmp_path, "syntax.st", "PROGRAM Main\n  VAR x : INT; END_VAR\n  IF x > 0 THEN\n    x := 0;\n"
                                       "END_PROGRAM\n")
    r = run_check(src)
    assert r.returncode == 1
    (line,) = r.stderr.splitlines()
    assert line.startswith(f"{src}:5:1: error: missing END_IF before 'END_PROGRAM'")


def test_three_undeclared_identifiers_give_three_lines(tmp_path: Path) -> None:
    src = write(tmp_path, "three.st", "PROGRAM Main\n  VAR x : INT; END_VAR\n"
                                      "  x := alpha;\n  x := beta + 1;\n  IF gamma THEN x := 0; END_IF;\n"
                                      "END_PROGRAM\n")
    r = run_check(src)
    assert r.returncode == 1
    lines = r.stderr.splitlines()
    assert len(lines) == 3, r.stderr
    parsed = [LINE.match(l) for l in lines]
    assert all(parsed), lines
    assert [(m["file"], int(m["line"])) for m in parsed] == [(str(src), 3), (str(src), 4), (str(src), 5)]
    assert [m["msg"] for m in parsed] == ["undeclared identifier 'alpha'", "undeclared identifier 'beta'",
                                          "undeclared identifier 'gamma'"]


GVL = """\
VAR_GLOBAL
  level : INT;
  alarm : BOOL;
END_VAR
VAR_GLOBAL CONSTANT
  LEVEL_MAX : INT := 90;
END_VAR
"""

POU = """\
FUNCTION_BLOCK Watch
  VAR_EXTERNAL level : INT; END_VAR
  VAR_EXTERNAL CONSTANT LEVEL_MAX : INT; END_VAR
  VAR_OUTPUT high : BOOL; END_VAR
  high := level > LEVEL_MAX;
END_FUNCTION_BLOCK

PROGRAM Main
  VAR_EXTERNAL alarm : BOOL; END_VAR
  VAR w : Watch; END_VAR
  w();
  alarm := w.high;
END_PROGRAM
"""

CONFIG = """\
CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK MainTask (INTERVAL := T#20ms, PRIORITY := 0);
    PROGRAM Inst0 WITH MainTask : Main;
  END_RESOURCE
END_CONFIGURATION
"""


def test_several_files_are_one_unit(tmp_path: Path) -> None:
    gvl = write(tmp_path, "globals.st", GVL)
    pou = write(tmp_path, "pous.st", POU)
    cfg = write(tmp_path, "config.st", CONFIG)
    r = run_check(gvl, pou, cfg)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "ok: 3 file(s) checked"
    # each file alone lacks what the others declare
    alone = run_check(cfg)
    assert alone.returncode == 1
    assert alone.stderr.splitlines() == [f"{cfg}:4:13: error: unknown program 'Main'"]


def test_errors_name_the_file_they_are_in(tmp_path: Path) -> None:
    gvl = write(tmp_path, "globals.st", GVL.replace("level : INT;", "level : DINT;"))
    pou = write(tmp_path, "pous.st", POU)
    cfg = write(tmp_path, "config.st", CONFIG)
    r = run_check(gvl, pou, cfg)
    assert r.returncode == 1
    assert r.stderr.splitlines() == [
        f"{pou}:2:24: error: VAR_EXTERNAL 'level' is INT but the VAR_GLOBAL is DINT"]


def test_syntax_errors_in_two_files_are_both_reported(tmp_path: Path) -> None:
    a = write(tmp_path, "a.st", "PROGRAM A\n  VAR x : INT; END_VAR\n  x := 1\nEND_PROGRAM\n")
    b = write(tmp_path, "b.st", "PROGRAM B\n  VAR y : INT; END_VAR\n  y := 2; // no\nEND_PROGRAM\n")
    r = run_check(a, b)
    assert r.returncode == 1
    lines = r.stderr.splitlines()
    assert [l.split(": error: ")[0] for l in lines] == [f"{a}:4:1", f"{b}:3:11"]


def test_missing_file(tmp_path: Path) -> None:
    missing = tmp_path / "nope.st"
    r = run_check(missing)
    assert r.returncode == 1
    assert r.stderr.splitlines() == [f"{missing}:1:1: error: no such file"]
    assert "Traceback" not in r.stderr


def test_directory_instead_of_file(tmp_path: Path) -> None:
    r = run_check(tmp_path)
    assert r.returncode == 1
    assert r.stderr.splitlines() == [f"{tmp_path}:1:1: error: is a directory, not an ST file"]


def test_binary_file_is_a_clean_error(tmp_path: Path) -> None:
    p = tmp_path / "blob.st"
    p.write_bytes(bytes(range(256)) * 4)
    r = run_check(p)
    assert r.returncode == 1
    assert "Traceback" not in r.stderr
    assert all(LINE.match(l) for l in r.stderr.splitlines()), r.stderr


@pytest.mark.parametrize("argv", [["check"], []])
def test_usage_errors(argv: list[str]) -> None:
    r = subprocess.run([*_plclab(), *argv], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    assert "usage:" in r.stderr
