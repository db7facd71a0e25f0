"""Helpers shared by tests/grader/test_grader_*.py: a stand's wrong-solution fixtures and the
checks every stand's grade reports must pass.

Imported by its plain name: tests/conftest.py puts this directory on sys.path (as
tests/runtime/st_helpers.py).
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Sequence

from plclab.grader import GradeReport

FIXTURES_DIR = Path(__file__).resolve().parent / "fixtures"

# A real program's extra file that makes its grading need megabytes more memory than the loaded
# grader: 2 MB of declared data (the limit is 4 MiB). What an ordinary program needs beyond the
# grader depends on what the grader process has loaded and freed already (the parser's tables,
# the program's native library), down to under 1 MiB: a memory limit's test cannot hang on that.
LARGE_DATA = ("GVL_Samples.st", "VAR_GLOBAL\n    Samples : ARRAY[0..499999] OF DINT;\nEND_VAR\n")
# A function block of 300 statements beside a program (declared, never called): the generated
# Python is large enough that compiling it needs a few MiB, where a grading's other steps need
# less than one beyond the grader (its parser's tables are loaded before the limit is set).
LARGE_CODE = ("FB_Large.st", "FUNCTION_BLOCK FB_Large\nVAR\n" + "".join(f"    x{i} : DINT;\n" for i in range(50))
              + "END_VAR\n" + "".join(f"    x{i % 50} := x{(i * 7) % 50} + {i};\n" for i in range(300))
              + "END_FUNCTION_BLOCK\n")
HEADER = re.compile(r"plclab grader fixture: (task\d), expected to FAIL (\S+)\. Mistake: (.*)")
TASKS = ("task1", "task2", "task3")


def failed_ids(report: GradeReport) -> list[str]:
    return [r.id for r in report.failed()]


def fixtures(stand: str) -> list[tuple[str, str, str]]:
    """(file name, task, the requirement that must fail) of each wrong solution in
    fixtures/<stand>, as its first line says."""
    out = []
    for path in sorted((FIXTURES_DIR / stand).glob("*.st")):
        m = HEADER.search(path.read_text(encoding="utf-8").splitlines()[0])
        assert m, f"{path.name}: first line must say which task and requirement"
        out.append((path.name, m.group(1), m.group(2)))
    return out


def fixtures_per_task(stand: str) -> dict[str, list[str]]:
    return {task: [name for name, t, _ in fixtures(stand) if t == task] for task in TASKS}


def assert_fails_exactly(report: GradeReport, rids: list[str]) -> None:
    """The program runs but fails exactly the requirements `rids`, each row saying what it saw."""
    assert not report.passed and report.exit_code == 1
    assert failed_ids(report) == rids, report.text()
    for row in report.failed():
        assert row.observed
    assert "FAIL" in report.text()


def assert_fails_with(report: GradeReport, rid: str) -> None:
    """A wrong solution runs and fails `rid` with a row that says why: what was expected, what
    was seen instead and when (not a requirement left unchecked)."""
    assert not report.passed and report.exit_code == 1
    assert not report.errors, report.errors
    assert rid in failed_ids(report), report.text()
    row = report.row(rid)
    assert row.expected and row.observed and row.time is not None, row
    assert not row.observed.startswith("not checked")


def assert_traces_written(report: GradeReport, out: Path, scenarios: Sequence[str]) -> dict[str, str]:
    """Each scenario wrote a CSV and a VCD trace to `out`, as the report names them; returns the
    CSV texts by scenario (for a stand's own checks of what is traced)."""
    texts = {}
    for scenario in scenarios:
        csv = out / f"{report.stand}-{report.task}-{scenario}.csv"
        vcd = out / f"{report.stand}-{report.task}-{scenario}.vcd"
        texts[scenario] = csv.read_text(encoding="utf-8")
        assert texts[scenario].startswith("time_s,name,value\n")
        assert vcd.read_text(encoding="utf-8").startswith("$")
        assert report.traces[scenario] == [csv, vcd]
    return texts


def assert_row_names_mistake(report: GradeReport, rid: str, words: str, only: list[str] | None) -> None:
    """Row `rid` fails and says `words` (in what it expected or observed); with `only`, those
    are the only failing rows (the mistake is not charged to other requirements)."""
    row = report.row(rid)
    assert not row.passed and words in row.expected + " | " + row.observed, row
    if only is not None:
        assert failed_ids(report) == only, report.text()


def assert_fault_stop_named(report: GradeReport, task_prefix: str, watchdog: str) -> None:
    """A program stopped by its own frame watchdog: every task row that failed on it says so
    and points at the watchdog requirement, instead of blaming the task's input."""
    rows = [r for r in report.failed() if r.id.startswith(task_prefix) and not r.observed.startswith("not checked")]
    assert rows and all("stopped with a fault" in r.observed and f"see {watchdog}" in r.observed for r in rows), rows
    assert not report.row(watchdog).passed
