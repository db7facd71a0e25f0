"""`plclab grade-class ... --scheduler ADDRESS` (issue 21 item 9): a class graded on a Dask
distributed cluster gets exactly the outputs of grading it on this machine, each student still
in a process of its own under the time and memory limits. The cluster is a LocalCluster with its
scheduler on 127.0.0.1 (a port the OS chooses), in a child process: Dask leaves a thread behind,
and a test process with threads makes every later class grading spawn instead of fork."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from lxml import etree

from plclab.grader.classroom import cells, grade_class, grade_on_worker, write_class_outputs
from plclab.stands import get_stand, sources
from grader_helpers import FIXTURES_DIR, LARGE_CODE, LARGE_DATA

BROKEN = "PROGRAM Broken\nVAR x : INT; END_VAR\nx := ;\nEND_PROGRAM\n"
HARNESS = Path(__file__).resolve().parents[2] / "harness"

ON_A_CLUSTER = """
import sys
from distributed import LocalCluster
from plclab.cli import main
with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, protocol="tcp://", host="127.0.0.1",
                  scheduler_port=0, dashboard_address=None) as cluster:
    code = main(["grade-class", "mp9c", "task1", sys.argv[1], "--out", sys.argv[2],
                 "--scheduler", cluster.scheduler_address, "--explore", "2"])
sys.exit(code)
"""


def _plclab(args: list[str], timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, "PYTHONPATH": str(HARNESS)})


def _junit_without_clock(path: Path) -> bytes:
    """junit.xml without the clock's attributes, its --out folder written OUT (the reports
    name where their traces are)."""
    root = etree.parse(str(path)).getroot()
    for el in [root] + root.findall("testsuite"):
        for attr in ("time", "timestamp", "hostname"):
            el.attrib.pop(attr, None)
    return etree.tostring(root).replace(str(path.parent).encode(), b"OUT")


def test_a_class_on_a_dask_cluster_gets_the_outputs_of_grading_it_here(tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    for name in ("task1_gripper_inverted.st", "task1_hl1_inverted.st"):
        shutil.copy(FIXTURES_DIR / "mp9c" / name, folder / name)
    (folder / "bob.st").write_text(BROKEN, encoding="utf-8")               # does not compile
    (folder / "eve.st").symlink_to(FIXTURES_DIR / "mp9c" / "task1_hl1_inverted.st")   # refused
    (folder / "dave").mkdir()                                              # nothing to grade
    here, there = tmp_path / "here", tmp_path / "there"
    local = grade_class("mp9c", "task1", folder, here, jobs=2, explore=2)   # explored against the model answer
                                                                             # (sent to the workers from here)
    write_class_outputs(local, here)
    remote = _plclab(["-c", ON_A_CLUSTER, str(folder), str(there)])
    assert remote.returncode == 0, remote.stderr[-3000:]
    progress = [line for line in remote.stdout.splitlines() if line.startswith("[")]
    assert sorted(line[:6] for line in progress) == [f"[{k}/5] " for k in range(1, 6)]
    assert "5 submissions: 0 pass, 5 fail, 0 not graded" in remote.stdout
    assert (there / "results.csv").read_text(encoding="utf-8") == (here / "results.csv").read_text(encoding="utf-8")
    assert _junit_without_clock(there / "junit.xml") == _junit_without_clock(here / "junit.xml")
    assert {r.status for r in local.results} == {"FAIL"}
    assert ("E1", "FAIL") in {(c.requirement, c.result) for r in local.results for c in cells(r, local.requirements)}
    traces_here = sorted(p.relative_to(here) for p in (here / "traces").rglob("*.csv"))
    traces_there = sorted(p.relative_to(there) for p in (there / "traces").rglob("*.csv"))
    assert traces_there == traces_here and len(traces_here) >= 2
    assert all((there / p).read_bytes() == (here / p).read_bytes() for p in traces_here)


def test_on_a_worker_each_student_keeps_the_time_limit(tmp_path):
    task1 = sources(get_stand("mp9c"), "task1")
    kind, value, traces = grade_on_worker("mp9c", "task1", task1, 0.2, None)
    assert kind == "not graded" and "time limit of 0.2 s" in value and traces == {}


def test_on_a_worker_each_student_keeps_the_memory_limit():
    task1 = sources(get_stand("mp9c"), "task1") + [LARGE_DATA]
    kind, value, _ = grade_on_worker("mp9c", "task1", task1, 120.0, 4)    # less than its grading needs
    assert (kind, value) == ("memory", None)
    kind, value, _ = grade_on_worker("mp9c", "task1", task1, 120.0, None)
    assert kind == "report" and value.passed, value


def test_on_a_worker_the_parsers_tables_are_not_the_students_memory():
    """The grading process loads the ST parser's tables (several MiB of lark's objects) before
    it sets the memory limit: a small limit is the program's own. With them loaded under it,
    2 MiB ran out before the model answer's check."""
    task1 = sources(get_stand("mp9c"), "task1")
    kind, value, _ = grade_on_worker("mp9c", "task1", task1, 120.0, 2)
    assert kind == "report" and value.passed and not value.errors, (kind, value)


def test_on_a_worker_a_memory_error_at_the_limit_is_never_a_diagnostic_of_the_program():
    """Close to the limit, Python's own compiler may fail to allocate while it compiles the
    program: that is the memory limit (the student's FAIL says so), never "this code nests
    too deeply", whichever part of the grading the limit stops. (Below 5 MiB the limit stops
    this program's compilation: without the compiler's check, "this code nests too deeply".)"""
    task1 = sources(get_stand("mp9c"), "task1") + [LARGE_CODE]
    for mib in range(1, 7):
        kind, value, _ = grade_on_worker("mp9c", "task1", task1, 120.0, mib)
        assert kind == "memory" or (kind == "report" and value.passed and not value.errors), (mib, kind, value)


def test_an_unreachable_scheduler_is_one_line_before_any_grading(tmp_path):
    (tmp_path / "eve.st").write_text(BROKEN, encoding="utf-8")
    run = _plclab(["-m", "plclab.cli", "grade-class", "mp9c", "task1", str(tmp_path), "--out", str(tmp_path / "o"),
                   "--scheduler", "tcp://127.0.0.1:9"], timeout=60)
    assert run.returncode == 1
    assert run.stderr.startswith("plclab: error: grade-class: --scheduler tcp://127.0.0.1:9: cannot reach the Dask "
                                 "scheduler") and run.stderr.count("\n") == 1, run.stderr
    assert not (tmp_path / "o" / "results.csv").exists()
