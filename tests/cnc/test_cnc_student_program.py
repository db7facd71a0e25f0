"""A student runs their own Task 4 block: `plclab cnc PART.nc --program FB_CncEvalLinear.st`
and `plclab run cnc --program FB_CncEvalLinear.st` put their file in place of the shipped
stub (or run a complete program as it is); the installed package, which has no model
answer, says so and points at --program."""
from __future__ import annotations

import re

from pathlib import Path

import pytest

import plclab.stands as stands
from plclab.cli import main

MODEL_ANSWER = stands.pou_path("FB_CncEvalLinear", reference=True)     # the checkout's solutions tree
STUB = stands.pou_path("FB_CncEvalLinear")
WRONG_QUADRANT = str(Path(__file__).resolve().parents[1] / "grader" / "fixtures" / "cnc"
                     / "task4_wrong_quadrant_sign.st")       # a whole bundle: DirY inverted
# lines in the first, second and third quadrants, back to the start
PART = "G21 G90 F600\nG01 X1 Y0.4\nG01 X-0.5 Y1\nG01 X0 Y0\n"


@pytest.fixture
def part(tmp_path):
    path = tmp_path / "tri.nc"
    path.write_text(PART, encoding="utf-8")
    return path


@pytest.fixture
def installed(monkeypatch):
    """As in an installed package: no solutions/ tree, so no model answer of FB_CncEvalLinear."""
    monkeypatch.setattr(stands, "SOLUTIONS_DIR", None)


def _rows(out: str) -> list[str]:
    return [line for line in out.splitlines() if re.match(r"\s*\d+\s+\d+\s+G\d\d ", line)]


def test_installed_package_points_evalfn_at_program(part, installed, capsys):
    assert MODEL_ANSWER != STUB
    assert main(["cnc", str(part)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("plclab: error: --method evalfn runs FB_CncEvalLinear")
    assert "--program FB_CncEvalLinear.st" in err and len(err.splitlines()) == 1
    assert main(["cnc", str(part), "--method", "dda"]) == 0        # DDA needs no student block


def test_the_students_block_replaces_the_stub(part, installed, capsys):
    assert main(["cnc", str(part), "--method", "evalfn", "--program", str(MODEL_ANSWER)]) == 0
    out = capsys.readouterr().out
    rows = _rows(out)
    # within every bound; the evaluation function's one step per 1 ms caps F600 off the axes (said)
    assert len(rows) == 3 and all(r.endswith((" ok", "  in bound, BELOW THE FEED")) for r in rows), out
    # the stub itself handed in: the table does not move, every frame misses its end point
    assert main(["cnc", str(part), "--program", str(STUB)]) == 1
    rows = _rows(capsys.readouterr().out)
    assert ["OUT OF BOUND" in r for r in rows] == [True, True, False]   # frame 3 ends at the start


def test_a_wrong_block_fails_its_contour_rows(part, capsys):
    assert main(["cnc", str(part), "--program", WRONG_QUADRANT]) == 1
    out = capsys.readouterr().out
    rows = _rows(out)
    assert len(rows) == 3 and all("OUT OF BOUND" in r for r in rows), out
    error_mm, bound_mm = (float(v) for v in rows[0].split()[5:7])
    assert error_mm > 0.5 and bound_mm == 0.01
    assert "FAILED: see the rows above" in out


def test_a_bad_file_is_one_line_and_nothing_runs(part, tmp_path, capsys):
    bad = tmp_path / "FB_CncEvalLinear.st"
    bad.write_text("FUNCTION_BLOCK FB_CncEvalLinear\nVAR_INPUT Load : BOOL; END_VAR\nX := ;\n"
                   "END_FUNCTION_BLOCK\n", encoding="utf-8")
    csv = tmp_path / "path.csv"
    assert main(["cnc", str(part), "--program", str(bad), "--csv", str(csv)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"{bad}:3:6: error:") and len(err.splitlines()) == 1
    assert not csv.exists()


def test_run_scenario_with_the_students_block(installed, tmp_path, capsys):
    csv = str(tmp_path / "sq.csv")
    assert main(["run", "cnc", "--scenario", "square", "--program", str(MODEL_ANSWER), "--csv", csv]) == 0
    assert "scenario square passed" in capsys.readouterr().out
    assert main(["run", "cnc", "--scenario", "square", "--program", str(STUB), "--csv", csv]) == 1
    assert "scenario FAILED: frame 1 (line 3): contour error 0.0000 mm (bound 0.0100 mm), end point off by " \
           "20.0000 mm" in capsys.readouterr().out


def test_the_installed_stands_scenario_names_the_stub_and_program(installed, tmp_path, capsys):
    assert main(["run", "cnc", "--scenario", "square", "--csv", str(tmp_path / "sq.csv")]) == 1
    out = capsys.readouterr().out
    assert "scenario FAILED: frame 1 (line 3)" in out
    assert "FB_CncEvalLinear in this program is the students' stub, Task 4: run yours with " \
           "--program FB_CncEvalLinear.st" in out
