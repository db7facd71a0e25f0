"""`plclab grade-class` on untrusted hand-ins (issue 25 items 5-8, the memory limit; issue 21
item 6 in the class outputs): links and special files refused before reading, messages capped,
spreadsheet formulas neutralised, a read-only or full --out found before the work, verdicts
written before traces, every child and temporary folder gone with the parent on a signal, a
student's memory limit graded as that student's FAIL, and NOT CHECKED rows in every output."""
from __future__ import annotations

import contextlib
import csv
import io
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
from lxml import etree
from lxml import html as lhtml

from plclab import fileio
from plclab.cli import main
from plclab.errors import PlcLabError
from plclab.grader.classroom import (MAX_MESSAGE_CHARS, grade_class, junit_xml, report_html, results_csv,
                                     write_class_outputs)
from classroom_faults import grade_or_misbehave
from grader_helpers import FIXTURES_DIR, LARGE_DATA

BROKEN = "PROGRAM Broken\nVAR x : INT; END_VAR\nx := ;\nEND_PROGRAM\n"
HERE = Path(__file__).resolve().parent
HARNESS = HERE.parents[1] / "harness"
REFERENCE = HERE.parents[1] / "solutions"


def read_csv(path: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(path.read_text(encoding="utf-8"))))


@pytest.fixture
def own_tmp(tmp_path, monkeypatch):
    """The temporary folder every grading process and the class grader use: empty before."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    return tmp


# --------------------------------------------------------------------------- NOT CHECKED (issue 21 item 6)
def test_not_checked_rows_in_results_csv_junit_skipped_and_the_html_report(tmp_path, own_tmp):
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "sam.st").write_bytes((FIXTURES_DIR / "mp9c" / "task3_stops_at_once.st").read_bytes())
    out = tmp_path / "out"
    report = grade_class("mp9c", "task3", folder, out, jobs=1)
    write_class_outputs(report, out)
    rows = {r["requirement"]: r for r in read_csv(out / "results.csv")}
    assert rows["T3.4"]["result"] == "FAIL"
    assert rows["T3.5"]["result"] == rows["T3.6"]["result"] == "NOT CHECKED"
    assert "the scenario could not go on after T3.4 failed" in rows["T3.5"]["message"]
    suite = etree.parse(str(out / "junit.xml")).getroot().find("testsuite")
    skipped = [c.get("name").split()[0] for c in suite.findall("testcase") if c.find("skipped") is not None]
    assert skipped == ["T3.5", "T3.6"] and suite.get("skipped") == "2"
    assert suite.get("failures") == str(sum(r["result"] == "FAIL" for r in rows.values()))
    page = lhtml.fromstring((out / "report.html").read_text(encoding="utf-8"))
    header = [th.text_content() for th in page.xpath("//table/tr[1]/th")]
    cell = page.xpath("//tr[@id='sam']/td")[header.index("T3.5")]
    assert cell.get("class") == "NOT_CHECKED" and cell.text_content().startswith("NOT CHECKED")
    assert report.results[0].status == "FAIL"             # not a pass: the student's verdict stays FAIL


# --------------------------------------------------------------------------- links and special files (item 6)
def test_links_fifos_and_huge_files_in_the_class_folder_are_refused_before_reading(tmp_path, own_tmp):
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "amy.st").symlink_to("/etc/passwd")
    reference = next(REFERENCE.rglob("*.st"))
    (folder / "ben.st").symlink_to(reference)                          # the model answer, by a link
    (folder / "cat").mkdir()
    (folder / "cat" / "main.st").symlink_to(reference)
    (folder / "dan").symlink_to(REFERENCE)                             # a link to a folder of programs
    os.mkfifo(folder / "eve.st")                                       # would block a reader forever
    with open(folder / "fay.st", "wb") as f:
        f.truncate(3 * 1024 ** 3)                                      # 3 GB, sparse: must not be read
    (folder / "gus.st").write_text(BROKEN, encoding="utf-8")           # an ordinary student, graded
    (folder / "notes.txt").symlink_to("/etc/hostname")                 # no submission: ignored, unread
    out = tmp_path / "out"
    started = time.monotonic()
    report = grade_class("mp9c", "task1", folder, out, jobs=2, time_limit_s=60)
    write_class_outputs(report, out)
    assert time.monotonic() - started < 60
    status = {r.student: r.status for r in report.results}
    assert status == dict.fromkeys(["amy", "ben", "cat", "dan", "eve", "fay", "gus"], "FAIL")
    rows = read_csv(out / "results.csv")
    text = (out / "results.csv").read_text(encoding="utf-8")
    assert "root:" not in text and "PASS" not in text
    first = {r["student"]: r["message"] for r in rows}
    for student, kind in (("amy", "a symbolic link (to /etc/passwd)"), ("ben", f"a symbolic link (to {reference})"),
                          ("dan", f"a symbolic link (to {REFERENCE})"), ("eve", "a FIFO")):
        entry = folder / (student if student == "dan" else f"{student}.st")
        assert first[student] == (f"not checked: the submission is refused: {entry}: {kind}: grade-class reads only "
                                  "regular files inside the class folder and never follows a link; refused without "
                                  "reading it"), first[student]
    assert f"{folder / 'cat' / 'main.st'}: a symbolic link" in first["cat"]
    assert first["fay"].endswith(f"{folder / 'fay.st'}:1:1: error: file too large (3221225472 bytes; the limit is "
                                 f"{8 * 1024 * 1024})")
    assert ":3:6: error: missing expression" in first["gus"]
    assert [p.name for p in report.ignored] == ["notes.txt"]


# --------------------------------------------------------------------------- message length, formulas (item 7)
def test_a_huge_identifier_is_quoted_capped_and_names_that_look_like_formulas_are_neutralised(tmp_path, own_tmp):
    folder = tmp_path / "class"
    folder.mkdir()
    huge = "a" * 200_000                 # over the 131072 characters Python's csv reader takes in a field
    program = f"PROGRAM Student1\nVAR x : INT; END_VAR\nx := {huge};\nEND_PROGRAM\n"   # undeclared: quoted
    names = ['=HYPERLINK("evil.example","x")', "@SUM(1+1)", "+1+cmd", "-2+3", "\tTAB", "plain"]
    for name in names:
        (folder / f"{name}.st").write_text(program, encoding="utf-8")
    out = tmp_path / "out"
    report = grade_class("mp9c", "task1", folder, out, jobs=2)
    write_class_outputs(report, out)
    size = (out / "results.csv").stat().st_size
    assert size < len(names) * len(report.requirements) * (MAX_MESSAGE_CHARS + 400)      # 14 MB before
    assert (out / "junit.xml").stat().st_size < 2_000_000                                  # 29 MB before
    with open(out / "results.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))                 # Python's reader: no field over 131072 characters
    assert {r["student"] for r in rows} == {"'" + n for n in names[:-1]} | {"plain"}
    assert all(len(r["message"]) <= MAX_MESSAGE_CHARS + 60 for r in rows)
    assert all("more characters not shown" in r["message"] for r in rows)
    assert all(not r[k].startswith(("=", "+", "-", "@", "\t", "\r")) for r in rows for k in r)


def test_plclab_grade_quotes_a_huge_identifier_capped_too(tmp_path, capsys):
    (tmp_path / "big.st").write_text(f"PROGRAM Student1\nVAR x : INT; END_VAR\nx := {'b' * 200_000};\nEND_PROGRAM\n",
                                     encoding="utf-8")
    assert main(["grade", "mp9c", "task1", str(tmp_path / "big.st"), "--out", str(tmp_path / "out")]) == 1
    out = capsys.readouterr().out
    assert "undeclared identifier 'bbbb" in out and "more characters not shown" in out
    assert len(out) < MAX_MESSAGE_CHARS + 1000


# --------------------------------------------------------------------------- --out before the work (item 8)
@contextlib.contextmanager
def read_only(folder: Path):
    """`folder` made unwritable: chmod for a user; for root (whom permissions do not stop) a
    read-only tmpfs mounted on it (the suite runs as root in CI, as scripts/setup does)."""
    folder.mkdir(parents=True, exist_ok=True)
    if os.geteuid() != 0:
        folder.chmod(0o555)
        try:
            yield folder
        finally:
            folder.chmod(0o755)
        return
    with mounted_tmpfs(folder, "ro,size=1m"):
        yield folder


@contextlib.contextmanager
def mounted_tmpfs(folder: Path, options: str):
    """A tmpfs with `options` mounted on `folder`, unmounted after. Needs root: never skipped,
    a machine where it cannot be mounted fails the test saying so."""
    if os.geteuid() != 0:
        pytest.fail("this test mounts a small file system: run the suite as root (as CI and scripts/setup do)")
    made = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(folder)], capture_output=True)
    if made.returncode != 0:
        pytest.fail(f"cannot mount a tmpfs on {folder} as root: {made.stderr.decode().strip()}")
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], check=True)


def test_a_read_only_out_is_refused_before_any_student_is_graded(tmp_path, own_tmp, capsys):
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "hal.st").write_text("(* classroom test: hang *)\n" + BROKEN, encoding="utf-8")
    graded = []
    with read_only(tmp_path / "out") as out:
        with pytest.raises(fileio.OutputError, match=rf"^{out}: cannot write: "):
            grade_class("mp9c", "task1", folder, out, jobs=1, time_limit_s=30, grade_one=grade_or_misbehave,
                        on_result=lambda r, d, t: graded.append(r))
        assert graded == []                                       # refused at once, not after 30 s
        assert main(["grade-class", "mp9c", "task1", str(folder), "--out", str(out)]) == 1
        err = capsys.readouterr().err
        assert err.startswith(f"plclab: error: {out}: cannot write: ") and err.count("\n") == 1


@contextlib.contextmanager
def small_disk(folder: Path, size: str):
    """A tmpfs of `size` mounted on `folder` (root; unmounted after)."""
    folder.mkdir(parents=True, exist_ok=True)
    with mounted_tmpfs(folder, f"size={size}"):
        yield folder


def test_a_full_out_is_refused_before_the_work_and_verdicts_are_written_before_traces(tmp_path, own_tmp):
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "ivy.st").write_bytes((FIXTURES_DIR / "mp9c" / "task3_stops_at_once.st").read_bytes())
    with small_disk(tmp_path / "full", "1m") as full:
        (full / "filler").write_bytes(bytes(os.statvfs(full).f_bavail * os.statvfs(full).f_frsize - 8192))
        with pytest.raises(fileio.OutputError, match=rf"^{full}: cannot write: No space left on device$"):
            grade_class("mp9c", "task3", folder, full, jobs=1, grade_one=grade_or_misbehave,
                        on_result=lambda *a: pytest.fail("graded before the full --out was found"))
        (full / "filler").unlink()
        report = grade_class("mp9c", "task3", folder, full, jobs=1)
        page = os.statvfs(full).f_frsize
        verdicts = sum(-(-len(data) // page) * page for data in (results_csv(report).encode(), junit_xml(report),
                                                                 report_html(report, full).encode()))
        room = verdicts + 2 * page                       # then the disk fills: room for the verdicts only
        (full / "filler").write_bytes(bytes(os.statvfs(full).f_bavail * page - room))
        staged = sum(Path(s).stat().st_size for r in report.results for s, _ in r.staged)
        assert staged > room
        with pytest.raises(fileio.OutputError, match=r"No space left on device; the verdicts \(results.csv, "
                                                     r"junit.xml, report.html\) were written, some traces were not"):
            write_class_outputs(report, full)
        rows = read_csv(full / "results.csv")
        assert len(rows) == len(report.requirements) and {r["student"] for r in rows} == {"ivy"}
        assert etree.parse(str(full / "junit.xml")).getroot().find("testsuite").get("name") == "ivy"
        assert "ivy" in (full / "report.html").read_text(encoding="utf-8")
    assert list(own_tmp.iterdir()) == []                 # the staged traces went, moved or not


# --------------------------------------------------------------------------- signals (item 5)
DRIVER = """
import functools, sys
import plclab.grader.classroom as classroom
from plclab.cli import main
from classroom_faults import grade_or_misbehave
classroom.grade_class = functools.partial(classroom.grade_class, grade_one=grade_or_misbehave)
sys.exit(main(["grade-class", "mp9c", "task1", sys.argv[1], "--out", sys.argv[2], "--jobs", "2"]))
"""


def _gone(pid: int) -> bool:
    """The process no longer runs (a zombie waiting for a reaper counts as gone)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return True
    return state in ("Z", "X")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP, signal.SIGKILL],
                         ids=lambda s: signal.Signals(s).name)
def test_a_signal_to_grade_class_takes_every_child_and_temporary_folder_with_it(sig, tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "a_quick.st").write_text(BROKEN, encoding="utf-8")
    for student in ("b_slow", "c_slow"):
        (folder / f"{student}.st").write_text("(* classroom test: slow *)\n" + BROKEN, encoding="utf-8")
    out = tmp_path / "out"
    out.mkdir()
    (out / "results.csv").write_text("student,requirement,result,message\nold,T1.1,PASS,\n", encoding="utf-8")
    tmp, pids = tmp_path / "tmp", tmp_path / "pids"
    tmp.mkdir()
    pids.mkdir()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HARNESS), str(HERE)]), "TMPDIR": str(tmp),
           "CLASSROOM_TEST_PIDS": str(pids)}
    parent = subprocess.Popen([sys.executable, "-c", DRIVER, str(folder), str(out)], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while len(list(pids.iterdir())) < 2 and time.monotonic() < deadline and parent.poll() is None:
            time.sleep(0.1)
        children = [int(p.name) for p in pids.iterdir()]
        assert len(children) == 2, parent.communicate(timeout=5)
        assert all(Path(p.read_text()).is_dir() for p in pids.iterdir())        # their temporary folders
        parent.send_signal(sig)
        stdout, stderr = parent.communicate(timeout=30)
    finally:
        if parent.poll() is None:
            parent.kill()
    deadline = time.monotonic() + 10
    while not all(_gone(pid) for pid in children) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert [pid for pid in children if not _gone(pid)] == []
    assert (out / "results.csv").read_text(encoding="utf-8").endswith("old,T1.1,PASS,\n")   # the old run, kept
    assert not (out / "traces").exists()
    if sig == signal.SIGKILL:              # no handler runs: the kernel ends the children (PR_SET_PDEATHSIG)
        return
    assert parent.returncode == 128 + sig, stderr
    assert stderr.splitlines() == [
        f"plclab: grade-class: stopped by {signal.Signals(sig).name} after 1 of 3 submissions; every grading "
        "process and temporary folder was removed",
        f"wrote {out / 'results.partial.csv'} (the verdicts so far; results.csv, junit.xml, report.html and traces/ "
        "were left as they were)"]
    assert "[1/3] a_quick: FAIL" in stdout
    assert list(tmp.iterdir()) == []                                          # every temporary folder gone
    partial = read_csv(out / "results.partial.csv")
    assert {r["student"] for r in partial} == {"a_quick"}


def test_a_student_stopped_at_the_time_limit_leaves_no_temporary_folder(tmp_path, own_tmp):
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "sly.st").write_text("(* classroom test: slow *)\n" + BROKEN, encoding="utf-8")
    report = grade_class("mp9c", "task1", folder, tmp_path / "out", jobs=1, time_limit_s=2.0,
                         grade_one=grade_or_misbehave)
    assert report.results[0].status == "ERROR" and "time limit of 2 s" in report.results[0].not_graded
    write_class_outputs(report, tmp_path / "out")
    assert list(own_tmp.iterdir()) == []


# --------------------------------------------------------------------------- the memory limit
def test_a_student_past_the_memory_limit_fails_with_that_reason_and_the_others_are_graded(tmp_path, own_tmp):
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "max.st").write_text("(* classroom test: memory *)\n" + BROKEN, encoding="utf-8")
    (folder / "ned.st").write_text(BROKEN, encoding="utf-8")
    out = tmp_path / "out"
    report = grade_class("mp9c", "task1", folder, out, jobs=2, memory_limit_mib=1024, grade_one=grade_or_misbehave)
    write_class_outputs(report, out)
    by = {r.student: r for r in report.results}
    assert by["max"].status == "FAIL" and by["max"].report.errors == [
        "memory limit of 1024 MiB exceeded (the program declares or uses more memory than a program may here; "
        "see docs/grading.md, --memory-limit)"]
    assert by["max"].summary().startswith("FAIL   the program was stopped: memory limit of 1024 MiB exceeded")
    assert by["ned"].status == "FAIL" and ":3:6: error: missing expression" in by["ned"].report.errors[0]
    rows = [r for r in read_csv(out / "results.csv") if r["student"] == "max"]
    assert {(r["result"], r["message"]) for r in rows} == {
        ("FAIL", "not checked: the program was stopped: " + by["max"].report.errors[0])}


def test_a_failed_allocation_with_no_memory_left_is_the_limit_not_a_dead_grader(tmp_path, own_tmp):
    """C code that fails an allocation at the limit raises a SystemError; deciding that it was
    the limit (reading the process's size) then has no memory either. That MemoryError is the
    limit too: the student's FAIL, not "the grading process died"."""
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "max.st").write_text("(* classroom test: exhausted *)\n" + BROKEN, encoding="utf-8")
    report = grade_class("mp9c", "task1", folder, tmp_path / "out", jobs=1, memory_limit_mib=64,
                         grade_one=grade_or_misbehave)
    (max_,) = report.results
    assert (max_.status, max_.not_graded) == ("FAIL", ""), max_.not_graded
    assert max_.report.errors == ["memory limit of 64 MiB exceeded (the program declares or uses more memory than "
                                  "a program may here; see docs/grading.md, --memory-limit)"]


def test_a_memory_error_inside_a_scenario_is_the_limit_not_a_grader_error(tmp_path, own_tmp):
    """However deep the MemoryError (the engine would call a scenario's exception a grader bug,
    the runtime turns one into an internal fault), under the limit it is the student's FAIL.
    `memory_in_scenario` (classroom_faults) raises it from inside the scenario loop."""
    folder = tmp_path / "class"
    folder.mkdir()
    program = (FIXTURES_DIR / "mp9c" / "task1_gripper_inverted.st").read_text(encoding="utf-8")
    (folder / "ola.st").write_text("(* classroom test: memory_in_scenario *)\n" + program, encoding="utf-8")
    report = grade_class("mp9c", "task1", folder, tmp_path / "out", jobs=1, memory_limit_mib=2048,
                         grade_one=grade_or_misbehave)
    assert report.results[0].status == "FAIL"
    assert report.results[0].report.errors[0].startswith("memory limit of 2048 MiB exceeded")


def test_the_memory_limit_holds_the_real_grading_of_a_real_program(tmp_path, own_tmp):
    """No injected fault: the grading of a program with 2 MB of data, allowed 1 MiB beyond the
    grader, is stopped by the limit and reported as the student's FAIL; with the default it is
    graded."""
    folder = tmp_path / "class"
    pia = folder / "pia"                          # a student's folder: the program and its data file
    pia.mkdir(parents=True)
    (pia / "pia.st").write_bytes((FIXTURES_DIR / "mp9c" / "task1_gripper_inverted.st").read_bytes())
    (pia / LARGE_DATA[0]).write_text(LARGE_DATA[1], encoding="utf-8")
    # in a fresh interpreter, as `plclab grade-class` runs: a test process that has already
    # built the ST parser or loaded this program's native library would lend the grading what
    # it would otherwise allocate, and 1 MiB more could then be enough
    tight = subprocess.run(
        [sys.executable, "-c", "import sys; from plclab.grader.classroom import grade_class; "
         "r = grade_class('mp9c', 'task1', sys.argv[1], sys.argv[2], jobs=1, memory_limit_mib=1).results[0]; "
         "print(r.status); print(r.report.errors[0] if r.report.errors else '-')", str(folder), str(tmp_path / "out")],
        capture_output=True, text=True, timeout=300)
    status, error = tight.stdout.splitlines()[-2:]
    assert status == "FAIL", tight.stdout + tight.stderr
    assert error.startswith("memory limit of 1 MiB exceeded"), tight.stdout + tight.stderr
    normal = grade_class("mp9c", "task1", folder, tmp_path / "out", jobs=1)
    assert normal.results[0].status == "FAIL" and not normal.results[0].report.errors
    assert normal.results[0].report.row("T1.1").result == "FAIL"      # its mistake, graded


def test_memory_limit_option_and_refusal(tmp_path, capsys):
    (tmp_path / "eve.st").write_text(BROKEN, encoding="utf-8")
    assert main(["grade-class", "mp9c", "task1", str(tmp_path), "--out", str(tmp_path / "o"),
                 "--memory-limit", "-1"]) == 1
    assert capsys.readouterr().err == "plclab: error: grade-class: the memory limit must be at least 1 MiB (got -1)\n"
    assert main(["grade-class", "mp9c", "task1", str(tmp_path), "--out", str(tmp_path / "o"),
                 "--memory-limit", "0"]) == 0                     # 0: no limit
