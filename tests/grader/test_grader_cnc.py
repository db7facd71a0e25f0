"""The CNC grader (plclab.grader.cnc): Task 4, the students' FB_CncEvalLinear. The reference
program passes every row, the hand-out's stub fails with rows saying what the table did, and
every wrong solution in fixtures/cnc fails the requirement its first line names."""
from __future__ import annotations

import functools

import pytest


from plclab.cli import main
from plclab.grader import GradeReport, grade, grade_sources
from plclab.grader import cnc as cnc_grader
from plclab.handout import handout_files
from plclab.stands import bundle, pou_path
from plclab.stands.cnc import STAND
from grader_helpers import FIXTURES_DIR, assert_fails_with, assert_traces_written, fixtures


@functools.lru_cache(maxsize=None)
def graded(variant: str) -> GradeReport:
    return grade_sources("cnc", "task4", [(f"{variant}.st", bundle(STAND, variant))])


def test_reference_program_passes_every_row(tmp_path):
    path = tmp_path / "cnc.st"
    path.write_text(bundle(STAND, "full"), encoding="utf-8")
    report = grade("cnc", "task4", [str(path)], out_dir=str(tmp_path / "out"))
    assert report.passed and report.exit_code == 0, report.text()
    assert [r.id for r in report.rows] == ["E1", "E2", "E3", "E4"]
    csvs = assert_traces_written(report, tmp_path / "out", ("segments",))
    assert "STEP_X" in csvs["segments"] or "%QX0.0" in csvs["segments"]


def test_handed_out_stub_fails_and_the_row_says_the_table_did_not_move():
    report = graded("baseline")
    assert not report.passed and report.exit_code == 1
    row = report.row("E1")
    assert not row.passed and "exactly (tolerance 0)" in row.expected
    assert "-37, -11 steps off" in row.observed and row.time is not None


def test_the_handout_carries_the_stub_not_the_solution():
    handed = handout_files("cnc")["cnc.st"]
    solution = pou_path("FB_CncEvalLinear", reference=True).read_text(encoding="utf-8")
    assert "solutions" in str(pou_path("FB_CncEvalLinear", reference=True))
    assert "FUNCTION_BLOCK FB_CncEvalLinear" in handed and "Write your interpolator here" in handed
    body = solution.split("END_VAR")[-1]
    for line in ("F[Other] := F[Other] - Inc[Other];", "F[Other] := F[Other] + Inc[Lead];"):
        assert line in body and line not in handed


@pytest.mark.parametrize("name,task,rid", fixtures("cnc"))
def test_wrong_solution_fails_with_the_row_that_says_why(name, task, rid):
    assert task == "task4"
    report = grade("cnc", task, [str(FIXTURES_DIR / "cnc" / name)])
    assert_fails_with(report, rid)
    row = report.row(rid)
    assert "segment DX" in row.expected and "tolerance" in report.row("E1").expected + report.row("E2").expected


def test_fixtures_cover_every_requirement():
    assert sorted(rid for _n, _t, rid in fixtures("cnc")) == ["E1", "E2", "E3", "E4"]


def test_requirement_texts_quote_the_thresholds():
    assert f"within {cnc_grader.PATH_BOUND:g} step" in cnc_grader.E2.text
    assert f"{len(cnc_grader.SEGMENTS)} segments" in cnc_grader.E1.text
    quadrants = {(dx > 0, dy > 0) for dx, dy in cnc_grader.SEGMENTS if dx and dy}
    assert len(quadrants) == 4
    assert any(dx == 0 for dx, _ in cnc_grader.SEGMENTS) and any(dy == 0 for _, dy in cnc_grader.SEGMENTS)


def test_cli_grades_the_cnc_task(tmp_path, capsys):
    path = tmp_path / "cnc.st"
    path.write_text(handout_files("cnc")["cnc.st"], encoding="utf-8")
    assert main(["grade", "cnc", "task4", str(path)]) == 1
    out = capsys.readouterr().out
    assert "E1" in out and "FAIL" in out
    assert main(["grade", "cnc", "task9", str(path)]) != 0
    assert "task4" in capsys.readouterr().err
