"""The grader on TUR-10 (docs/instructors.md; docs/tur10.md Tasks): requirements that discriminate.

The shipped baseline fails every task, each reference solution passes its own task (and the
full program passes all three), every wrong solution in fixtures/tur10 fails with the
requirement its first line names, the timing tolerance follows the student's slowest task,
and a runtime fault is a failing row. Each program is graded once per task (about a second
of wall time for some 100 s of plant time).
"""
from __future__ import annotations

import functools

import pytest

from plclab.grader import GradeReport, grade, grade_sources, requirement_table, tasks
from plclab.grader.tur10 import POS, make_session
from plclab.stands import bundle, sources
from plclab.stands.tur10 import STAND
from graded import graded_fixture
from grader_helpers import (FIXTURES_DIR, TASKS, assert_fails_exactly, assert_fails_with,
                            assert_traces_written, fixtures, fixtures_per_task)

FIXTURES = FIXTURES_DIR / "tur10"
SCENARIOS = {"task1": ("jog",), "task2": ("pauses",), "task3": ("enable", "last_pause")}
GENERAL_SCENARIOS = ("basics", "automatic", "restart", "timeout")
GENERAL_IDS = [f"G{i}" for i in range(1, 12)]


@functools.lru_cache(maxsize=None)
def graded(task: str, variant: str) -> GradeReport:
    """The report of a shipped variant's bundle on `task` (graded once per test session)."""
    return grade_sources("tur10", task, [(f"{variant}.st", bundle(STAND, variant))])


# --------------------------------------------------------------------------- references

@pytest.mark.parametrize("task", TASKS)
def test_reference_solution_passes_its_task(task, tmp_path):
    path = tmp_path / f"{task}.st"
    path.write_text(bundle(STAND, task), encoding="utf-8")
    out = tmp_path / "out"
    report = grade("tur10", task, [str(path)], out_dir=str(out))
    assert report.passed, report.text()
    assert report.exit_code == 0
    ids = [r.id for r in report.rows]
    assert ids[0] == f"T{task[-1]}.1" and ids[-len(GENERAL_IDS):] == GENERAL_IDS
    csvs = assert_traces_written(report, out, SCENARIOS[task] + GENERAL_SCENARIOS)
    for text in csvs.values():
        assert "\n0,plant.pos1,16000\n" in text and ",%QW0," in text      # links next to references


@pytest.mark.parametrize("task", TASKS)
def test_full_program_passes_every_task(task):
    report = graded(task, "full")
    assert report.passed, report.text()


def test_program_of_several_files_is_one_unit():
    report = grade_sources("tur10", "task2", sources(STAND, "task2"))
    assert report.passed, report.text()


def test_tolerance_follows_the_slowest_task():
    """A main task of 50 ms instead of 20 ms: one scan of it is the timing tolerance."""
    text = bundle(STAND, "task3").replace("TASK MainTask (INTERVAL := T#20ms", "TASK MainTask (INTERVAL := T#50ms")
    assert "T#50ms" in text
    report = grade_sources("tur10", "task3", [("slow.st", text)])
    assert report.passed, report.text()


# --------------------------------------------------------------------------- baseline

BASELINE_FAILS = {
    "task1": ["T1.1", "T1.2"],             # drives 2-5 not jogged; none moves wrongly (T1.3, T1.4)
    "task2": ["T2.1", "T2.2"],             # always 1 s; nothing live to detect (T2.3)
    "task3": ["T3.1", "T3.5", "T3.6", "T3.7"],     # starts with I1.5 = 0, always wraps
}


@pytest.mark.parametrize("task", TASKS)
def test_baseline_fails_each_task_by_its_own_rows(task):
    assert_fails_exactly(graded(task, "baseline"), BASELINE_FAILS[task])


def test_baseline_rows_say_why():
    t1 = graded("task1", "baseline").row("T1.1")
    assert t1.expected == "SA2_FWD held with SA6 = 1: DRIVE2 = +500 within one scan"
    assert t1.observed == "DRIVE2 = 0 (drive 2 is not jogged)"
    assert t1.time is not None and t1.scenario == "jog"
    t2 = graded("task2", "baseline").row("T2.2")
    assert "3.0 s pause" in t2.expected and t2.observed.startswith("1.01 s: every frame got the same") and t2.scenario == "pauses"
    t3 = graded("task3", "baseline").row("T3.5")
    assert t3.observed.startswith("execution went on to frame 1: DRIVE1=-")


# --------------------------------------------------------------------------- wrong solutions

def test_at_least_three_wrong_solutions_per_task():
    per_task = fixtures_per_task("tur10")
    assert all(len(names) >= 3 for names in per_task.values()), per_task


@pytest.mark.parametrize("name,task,rid", fixtures("tur10"))
def test_wrong_solution_fails_with_the_row_that_says_why(name, task, rid):
    assert_fails_with(graded_fixture("tur10", task, FIXTURES / name), rid)


# --------------------------------------------------------------------------- faults, tables

def test_runtime_fault_is_a_failing_row():
    text = bundle(STAND, "task1")
    declared = "    Robot : FB_Tur10Automatic;      (* automatic work mode subroutine *)\n"
    call = "Robot(Active := SA7,"
    assert text.count(declared) == 1 and text.count(call) == 1
    text = text.replace(declared, declared + "    Zero : INT;\n    Crash : INT;\n")
    text = text.replace(call, "IF SA7 THEN\n    Crash := 100 / Zero;\nEND_IF;\n" + call)
    report = grade_sources("tur10", "task1", [("crash.st", text)])
    assert not report.errors
    g1 = report.row("G1")
    assert not g1.passed and "PLC FAULT (division_by_zero)" in g1.observed and g1.time is not None
    assert all(report.row(rid).passed for rid in ("T1.1", "T1.2", "T1.3", "T1.4", "T1.5", "G5", "G6"))
    g8 = report.row("G8")
    assert not g8.passed and "runtime fault" in g8.observed


def test_requirement_tables():
    assert tasks("tur10") == ["task1", "task2", "task3"]
    for task in TASKS:
        table = requirement_table("tur10", task)
        ids = [rid for rid, _ in table]
        assert ids[0] == f"T{task[-1]}.1" and ids[-len(GENERAL_IDS):] == GENERAL_IDS
        assert all(text.endswith(".") for _, text in table)


def test_plant_positions_are_traced_across_a_restart(tmp_path):
    s = make_session(sources(STAND, "task1"), tmp_path / "retain.json")
    s.run(0.2)
    s.console.set(SA1_FWD=1)
    s.run(0.3)
    s.console.set(SA1_FWD=0)
    s.run(0.3)
    moved = s.plant.true_code(1)
    assert moved > 17000
    assert s.trace.value_at(POS[0], s.now - s.tick) == moved
    assert s.trace.value_at(POS[1], s.now - s.tick) == 16000
    s.restart_plc()
    s.console.set(SA2_BWD=1)
    s.run(0.3)
    assert s.trace.value_at(POS[0], s.now - s.tick) == moved
    assert s.trace.value_at(POS[1], s.now - s.tick) == s.plant.true_code(2) < 15000
