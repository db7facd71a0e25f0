"""Conformance of the ST front end with OpenPLC's compiler (matiec), case by case.

Every file in cases/valid/ is a program OpenPLC's toolchain accepts: the front end must report
nothing. Every file in cases/invalid/ is one it rejects; its first line says where and why:

    (* expect: LINE:COL: message fragment *)

and the front end's first diagnostic (the earliest in the file) must be at exactly LINE:COL and
contain the fragment. docs/matiec-frontend-notes.md gives the matiec facts behind the cases.
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from plclab.errors import CompileError
from plclab.frontend import load_files

CASES = Path(__file__).parent / "cases"
VALID = sorted((CASES / "valid").glob("*.st"))
INVALID = sorted((CASES / "invalid").glob("*.st"))
EXPECT = re.compile(r"^\(\* expect: (\d+):(\d+): (.+?) \*\)$")


def test_enough_cases() -> None:
    assert len(VALID) >= 70
    assert len(INVALID) >= 70


@pytest.mark.parametrize("path", VALID, ids=[p.stem for p in VALID])
def test_valid_program_is_accepted(path: Path) -> None:
    try:
        load_files([path])
    except CompileError as e:
        pytest.fail(f"{path.name} should be accepted, got:\n{e}")


@pytest.mark.parametrize("path", INVALID, ids=[p.stem for p in INVALID])
def test_invalid_program_is_rejected_at_the_right_place(path: Path) -> None:
    header = path.read_text(encoding="utf-8").split("\n", 1)[0]
    m = EXPECT.match(header)
    assert m, f"{path.name}: first line must be (* expect: LINE:COL: fragment *)"
    line, col, fragment = int(m.group(1)), int(m.group(2)), m.group(3)
    with pytest.raises(CompileError) as info:
        load_files([path])
    first = info.value.diagnostics[0]
    assert first.file == str(path)
    assert (first.line, first.col) == (line, col), f"{path.name}: first diagnostic is {first}"
    assert fragment in first.message, f"{path.name}: first diagnostic is {first}"


@pytest.mark.parametrize("path", INVALID, ids=[p.stem for p in INVALID])
def test_every_diagnostic_is_one_well_formed_line(path: Path) -> None:
    with pytest.raises(CompileError) as info:
        load_files([path])
    for d in info.value.diagnostics:
        assert re.fullmatch(r".+:\d+:\d+: error: [^\n]+", str(d)), str(d)
        assert 1 <= d.line and 1 <= d.col
