"""The grader on MP-9C (docs/instructors.md; docs/mp9c.md Tasks): requirements that discriminate.

The shipped baseline fails every task, each reference solution passes its own task (and the
full program passes all three), every wrong solution in fixtures/mp9c fails with the
requirement its first line names, a program that does not compile yields checker lines, and
a runtime fault is a failing row.
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from plclab.errors import PlcLabError
from plclab.grader import GradeReport, Row, grade, grade_sources, requirement_table, tasks
from plclab.stands import bundle, sources
from plclab.stands.mp9c import STAND
from graded import graded_fixture
from grader_helpers import (FIXTURES_DIR, TASKS, assert_fails_exactly, assert_fails_with,
                            assert_traces_written, fixtures, fixtures_per_task)

FIXTURES = FIXTURES_DIR / "mp9c"
DIAGNOSTIC = re.compile(r"^.+:\d+:\d+: error: .+$")
SCENARIOS = {"task1": ("manual", "playback", "playback_step"), "task2": ("pauses", "pauses_step"),
             "task3": ("enable", "enable_step", "last_pause", "last_pause_step")}
GENERAL_SCENARIOS = ("basics", "automatic", "restart", "timeout", "memory")


def write_bundle(tmp_path: Path, variant: str, edit=None) -> str:
    text = bundle(STAND, variant)
    if edit is not None:
        text = edit(text)
    path = tmp_path / f"{variant}.st"
    path.write_text(text, encoding="utf-8")
    return str(path)


# --------------------------------------------------------------------------- references

@pytest.mark.parametrize("task", TASKS)
def test_reference_solution_passes_its_task(task, tmp_path):
    out = tmp_path / "out"
    report = grade("mp9c", task, [write_bundle(tmp_path, task)], out_dir=str(out))
    assert report.passed, report.text()
    assert report.exit_code == 0
    assert all(r.passed for r in report.rows)
    assert [r.id for r in report.rows][0] == f"T{task[-1]}.1"
    assert_traces_written(report, out, SCENARIOS[task] + GENERAL_SCENARIOS)


@pytest.mark.parametrize("task", TASKS)
def test_full_program_passes_every_task(task, tmp_path):
    report = grade("mp9c", task, [write_bundle(tmp_path, "full")])
    assert report.passed, report.text()


def test_program_of_several_files_is_one_unit():
    report = grade_sources("mp9c", "task1", sources(STAND, "task1"))
    assert report.passed, report.text()


# --------------------------------------------------------------------------- baseline

BASELINE_FAILS = {
    "task1": ["T1.1", "T1.2", "T1.3", "T1.5"],     # SA2..SA4 ignored; the lift (T1.4) works
    "task2": ["T2.1", "T2.2"],                     # always 1 s; nothing live to detect (T2.3)
    "task3": ["T3.1", "T3.5", "T3.6", "T3.7"],     # starts with I0.7 = 0, always wraps
}


@pytest.mark.parametrize("task", TASKS)
def test_baseline_fails_each_task_by_its_own_rows(task, tmp_path):
    report = grade("mp9c", task, [write_bundle(tmp_path, "baseline")])
    assert_fails_exactly(report, BASELINE_FAILS[task])


def test_baseline_rows_say_why(tmp_path):
    report = grade("mp9c", "task2", [write_bundle(tmp_path, "baseline")])
    row = report.row("T2.2")
    assert "3.0 s pause" in row.expected and row.observed == ("1.00 s: every frame got the same 1.00 s pause, whatever "
                                                          "I0.7 was when it was recorded (1, 0, 0, 1)")
    assert row.time is not None and row.scenario == "pauses"


# --------------------------------------------------------------------------- wrong solutions

def test_at_least_three_wrong_solutions_per_task():
    per_task = fixtures_per_task("mp9c")
    assert all(len(names) >= 3 for names in per_task.values()), per_task


@pytest.mark.parametrize("name,task,rid", fixtures("mp9c"))
def test_wrong_solution_fails_with_the_row_that_says_why(name, task, rid):
    assert_fails_with(graded_fixture("mp9c", task, FIXTURES / name), rid)


# --------------------------------------------------------------------------- errors and faults

def test_program_that_does_not_compile_gives_checker_lines(tmp_path):
    path = write_bundle(tmp_path, "baseline",
                        lambda t: t.replace("\nL3 := SA5;\n", "\nL3 := SA5 + 1;\nL9 := 1;\n"))
    report = grade("mp9c", "task1", [path])
    assert not report.passed and report.exit_code == 1
    assert report.rows == []
    assert report.errors and all(DIAGNOSTIC.match(e) for e in report.errors), report.errors
    assert all(e.startswith(path + ":") for e in report.errors)
    text = report.text()
    assert "does not compile" in text and "Traceback" not in text
    for e in report.errors:
        assert e in text.splitlines()
    assert text.rstrip().endswith("FAIL")


def test_syntax_error_and_missing_file(tmp_path):
    bad = tmp_path / "bad.st"
    bad.write_text("PROGRAM P\nVAR x : INT; END_VAR\nx := ;\nEND_PROGRAM\n", encoding="utf-8")
    report = grade("mp9c", "task2", [str(bad)])
    assert report.errors and all(DIAGNOSTIC.match(e) for e in report.errors)
    assert report.errors[0].startswith(f"{bad}:3:")
    missing = grade("mp9c", "task2", [str(tmp_path / "nope.st")])
    assert missing.errors == [f"{tmp_path / 'nope.st'}:1:1: error: no such file"]


def test_program_without_configuration_is_refused(tmp_path):
    path = write_bundle(tmp_path, "task1", lambda t: t[:t.index("CONFIGURATION Config0")])
    report = grade("mp9c", "task1", [path])
    assert len(report.errors) == 1 and "no CONFIGURATION" in report.errors[0]
    assert DIAGNOSTIC.match(report.errors[0])


def test_runtime_fault_is_a_failing_row(tmp_path):
    def divide_by_zero_in_automatic_mode(text: str) -> str:
        declared = "    Robot : FB_Mp9cAutomatic;       (* automatic work mode subroutine *)\n"
        call = "Robot(Active := SA1,"
        assert text.count(declared) == 1 and text.count(call) == 1
        text = text.replace(declared, declared + "    Zero : INT;\n    Crash : INT;\n")
        return text.replace(call, "IF SA1 THEN\n    Crash := 100 / Zero;\nEND_IF;\n" + call)
    report = grade("mp9c", "task1", [write_bundle(tmp_path, "task1", divide_by_zero_in_automatic_mode)])
    assert not report.errors
    g1 = report.row("G1")
    assert not g1.passed and "PLC FAULT (division_by_zero)" in g1.observed and g1.time is not None
    assert all(report.row(rid).passed for rid in ("T1.1", "T1.2", "T1.3", "T1.4", "G3", "G4"))
    t15 = report.row("T1.5")
    assert not t15.passed and "runtime fault" in t15.observed


def test_unknown_stand_or_task_is_one_line_error(tmp_path):
    assert tasks("mp9c") == ["task1", "task2", "task3"]
    with pytest.raises(PlcLabError, match="no task 'task4'"):
        grade("mp9c", "task4", [write_bundle(tmp_path, "task1")])
    with pytest.raises(PlcLabError, match=r"stand 'thermo' has no task 'task1' \(one of scada1, scada2\)"):
        grade("thermo", "task1", [write_bundle(tmp_path, "task1")])
    with pytest.raises(PlcLabError, match=r"stand 'cnc' has no task 'task1' \(one of task4\)"):
        grade("cnc", "task1", [write_bundle(tmp_path, "task1")])


# --------------------------------------------------------------------------- report

def test_requirement_tables():
    for task, first in (("task1", "T1.1"), ("task2", "T2.1"), ("task3", "T3.1")):
        table = requirement_table("mp9c", task)
        ids = [rid for rid, _ in table]
        assert ids[0] == first and "G1" in ids and "G11" in ids
        assert all(text.endswith(".") for _, text in table)


def test_report_text_format():
    report = GradeReport("mp9c", "task2", "MP-9C pneumatic robot, Task 2", ["student.st"], rows=[
        Row("T2.1", "A frame recorded with I0.7 = 0 is followed by a 0.5 s pause.", True),
        Row("T2.2", "A frame recorded with I0.7 = 1 is followed by a 3.0 s pause.", False,
            "a 3.0 s pause after frame 1", "0.50 s", 4.47, "pauses"),
    ], traces={"pauses": [Path("out/mp9c-task2-pauses.csv"), Path("out/mp9c-task2-pauses.vcd")]})
    lines = report.text().splitlines()
    assert lines[0] == "MP-9C pneumatic robot, Task 2"
    assert lines[1] == "program: student.st"
    assert re.match(r"^id\s+requirement\s+result$", lines[3])
    assert re.match(r"^T2\.1\s+A frame recorded with I0\.7 = 0 .*\s+PASS$", lines[5])
    assert re.match(r"^T2\.2\s+A frame recorded with I0\.7 = 1 .*\s+FAIL$", lines[6])
    assert lines[7].strip() == "expected: a 3.0 s pause after frame 1"
    assert lines[8].strip() == "observed: 0.50 s"
    assert lines[9].strip() == ("at t = 4.47 s, scenario 'pauses' "
                                "(mp9c-task2-pauses.csv, mp9c-task2-pauses.vcd)")
    assert lines[-2] == "1 of 2 requirements passed: FAIL"
    assert lines[-1] == "traces (CSV + VCD per scenario) in out"
    assert max(len(line) for line in lines) <= 100
    assert not report.passed and report.exit_code == 1
    report.rows[1] = Row("T2.2", "A frame recorded with I0.7 = 1 is followed by a 3.0 s pause.", True)
    assert report.passed and report.exit_code == 0
    assert report.text().splitlines()[-2] == "2 of 2 requirements passed: PASS"


def test_trace_shows_console_inputs_the_program_does_not_declare(tmp_path):
    path = write_bundle(tmp_path, "task1", lambda t: re.sub(r"\n *I07 AT %IX0\.7 : BOOL;[^\n]*", "", t))
    assert "%IX0.7" not in Path(path).read_text(encoding="utf-8")
    out = tmp_path / "out"
    report = grade("mp9c", "task1", [path], out_dir=str(out))
    assert report.passed, report.text()
    assert "%IX0.7" in (out / "mp9c-task1-playback.csv").read_text(encoding="utf-8")
