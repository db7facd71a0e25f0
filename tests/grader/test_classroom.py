"""`plclab grade-class` (issue 12 part 4): a folder of submissions graded in parallel gives
the same verdicts as `plclab grade` on each, survives a submission that crashes or hangs the
grader, and writes results.csv, a JUnit XML valid under the common schema and report.html.
"""
from __future__ import annotations

import csv
import dataclasses
import io
import multiprocessing
import os
import re
import shutil
from urllib.parse import unquote
from pathlib import Path

import pytest
from lxml import etree
from lxml import html as lhtml

from plclab.cli import main
from plclab.grader import grade
from plclab.grader.classroom import (find_submissions, grade_class, junit_xml, report_html,
                                     results_csv, row_message, write_class_outputs)
from plclab.stands import get_stand, sources
from classroom_faults import grade_or_misbehave
from graded import graded_fixture
from grader_helpers import FIXTURES_DIR, fixtures

BROKEN = "PROGRAM Broken\nVAR x : INT; END_VAR\nx := ;\nEND_PROGRAM\n"   # a syntax error, line 3


def read_csv(path: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(path.read_text(encoding="utf-8"))))


# --------------------------------------------------------------------------- a class of the fixtures
@pytest.fixture(scope="module")
def mp9c_class(tmp_path_factory):
    """The MP-9C Task 2 wrong-solution fixtures as students, plus the reference solution as a
    folder of the plc/ files (carol), a program that does not compile (bob),
    a folder with no .st file (dave) and a file that is no submission; graded with 2 jobs."""
    root = tmp_path_factory.mktemp("class")
    folder = root / "submissions"
    folder.mkdir()
    for name, task, _ in fixtures("mp9c"):
        if task == "task2":
            shutil.copy(FIXTURES_DIR / "mp9c" / name, folder / name)
    stand = get_stand("mp9c")
    carol = folder / "carol"
    for name, text in sources(stand, "task2"):
        edited = re.fullmatch(r"<mp9c task2: (\w+\.st)>", name)     # a starting file with Task 2's changes
        rel = Path(*Path(name).parts[-2:]) if Path(name).exists() else \
            Path("POUs", edited.group(1)) if edited else Path("config.st")
        (carol / rel).parent.mkdir(parents=True, exist_ok=True)
        (carol / rel).write_text(text, encoding="utf-8")
    (folder / "bob.st").write_text(BROKEN, encoding="utf-8")
    (folder / "dave").mkdir()
    (folder / "dave" / "readme.txt").write_text("forgot the program\n", encoding="utf-8")
    (folder / "grades.xlsx").write_bytes(b"PK\x03\x04")
    out = root / "out"
    progress = []
    report = grade_class("mp9c", "task2", folder, out, jobs=2,
                         on_result=lambda r, done, total: progress.append((r.student, done, total)))
    written = write_class_outputs(report, out)
    return folder, out, report, progress, written


def test_class_gives_the_verdicts_of_grading_one_by_one(mp9c_class, tmp_path):
    """Every student of the class gets the rows `plclab grade` gives their files alone: the
    wrong-solution fixtures (the run's one grading of each, graded.py), carol's folder and
    bob's program that does not compile (graded here); dave's empty folder fails."""
    folder, out, report, _, _ = mp9c_class
    submissions, _ = find_submissions(folder)
    assert sorted(r.student for r in report.results) == sorted(s.student for s in submissions)
    fixture_names = {Path(name).stem: name for name, task, _ in fixtures("mp9c") if task == "task2"}
    known = {}
    for sub in submissions:
        if sub.student in fixture_names:
            known[sub.student] = graded_fixture("mp9c", "task2", FIXTURES_DIR / "mp9c" / fixture_names[sub.student])
        elif sub.files:
            known[sub.student] = grade("mp9c", "task2", [str(f) for f in sub.files], out_dir=str(tmp_path / sub.student))
    assert {"carol", "bob"} <= set(known) and "dave" not in known
    assert_class_is_one_by_one("mp9c", "task2", report, read_csv(out / "results.csv"), tmp_path, known)


# MP-9C Task 2's fixtures are the class of mp9c_class above
ROBOT_CLASSES = [(stand, task) for stand in ("mp9c", "tur10") for task in sorted({t for _, t, _ in fixtures(stand)})
                 if (stand, task) != ("mp9c", "task2")]


@pytest.mark.parametrize("stand, task", ROBOT_CLASSES, ids=[f"{s}-{t}" for s, t in ROBOT_CLASSES])
def test_every_tasks_fixtures_as_a_class_get_the_verdicts_of_grading_one_by_one(stand, task, tmp_path):
    """Every wrong-solution fixture of every task of both robots (whatever fixtures/<stand>/
    holds: their first lines name the task; MP-9C Task 2's are mp9c_class), graded as a
    class with 2 jobs, gets exactly the rows `plclab grade` gives it alone (the run's one
    grading of each fixture, graded.py), and fails the row its header names."""
    folder = tmp_path / "class"
    folder.mkdir()
    mine = [(name, rid) for name, t, rid in fixtures(stand) if t == task]
    for name, _ in mine:
        shutil.copy(FIXTURES_DIR / stand / name, folder / name)
    out = tmp_path / "out"
    report = grade_class(stand, task, folder, out, jobs=2)
    write_class_outputs(report, out)
    alone = {Path(name).stem: graded_fixture(stand, task, FIXTURES_DIR / stand / name) for name, _ in mine}
    assert_class_is_one_by_one(stand, task, report, read_csv(out / "results.csv"), tmp_path / "alone", alone)
    rows = {(r["student"], r["requirement"]): r["result"] for r in read_csv(out / "results.csv")}
    for name, rid in mine:
        assert rows[(Path(name).stem, rid)] == "FAIL", (name, rid)
    assert_valid_junit(out / "junit.xml")


def assert_class_is_one_by_one(stand: str, task: str, report, rows: list[dict[str, str]], alone_dir: Path,
                               known: dict | None = None) -> None:
    """Each student's results.csv rows are the rows of `grade` on their files alone: same
    requirements, same PASS/FAIL/ERROR, the same expected/observed/scenario in the message.
    (The gradings alone are independent `grade` calls, two at a time: the machine has 2 cores.)
    `known`: the students' reports alone where the run has them already (a fixture's one
    grading, graded.py: its failing rows carry their ranked lines, which a class that does not
    explore leaves out of the message, so they are left out of the comparison)."""
    assert report.complete
    graded = [r for r in report.results if r.submission.files]
    if known is not None:
        by_student = {r.student: known[r.student] for r in graded}
    else:
        with multiprocessing.get_context("fork").Pool(2) as pool:
            alones = pool.starmap(grade, [(stand, task, [str(f) for f in r.submission.files],
                                           str(alone_dir / r.student)) for r in graded])
        by_student = {r.student: alone for r, alone in zip(graded, alones)}
    for result in report.results:
        mine = [r for r in rows if r["student"] == result.student]
        if not result.submission.files:            # an empty folder: nothing `plclab grade` could be given
            assert result.status == "FAIL"
            assert all(r["result"] == "FAIL" and r["message"].endswith(" file in this folder") for r in mine), mine
            continue
        alone = by_student[result.student]
        assert result.status == ("PASS" if alone.passed else "FAIL"), alone.text()
        if alone.errors:
            why = f"not checked: {alone.unreadable} " + "; ".join(alone.errors)
            assert [(r["result"], r["message"]) for r in mine] == [("FAIL", why)] * len(report.requirements)
            continue
        assert [(r["requirement"], r["result"]) for r in mine] == [(row.id, row.result) for row in alone.rows]
        for csv_row, row in zip(mine, alone.rows):
            assert csv_row["message"] == row_message(dataclasses.replace(row, lines=(), written=""))


def test_each_fixture_fails_the_row_its_header_names_in_the_class(mp9c_class):
    _, out, report, _, _ = mp9c_class
    rows = {(r["student"], r["requirement"]): r for r in read_csv(out / "results.csv")}
    expected = [(Path(name).stem, rid) for name, task, rid in fixtures("mp9c") if task == "task2"]
    assert len(expected) >= 4
    for student, rid in expected:
        assert rows[(student, rid)]["result"] == "FAIL", rows[(student, rid)]
        assert rows[(student, rid)]["message"].startswith("expected: ")
    statuses = {r.student: r.status for r in report.results}
    assert statuses["carol"] == "PASS"
    assert statuses["bob"] == statuses["dave"] == "FAIL"
    assert rows[("bob", "T2.1")]["message"] == ("not checked: the program does not compile: "
                                                 f"{folder_of(report, 'bob')}:3:6: error: "
                                                 "missing expression after ':=' (before ';')")
    assert "no .st file in this folder" in rows[("dave", "G1")]["message"]
    assert [p.name for p in report.ignored] == ["grades.xlsx"]


def folder_of(report, student: str) -> Path:
    return next(r.submission.source for r in report.results if r.student == student)


def test_progress_is_one_line_per_finished_student(mp9c_class):
    _, _, report, progress, _ = mp9c_class
    assert sorted(s for s, _, _ in progress) == sorted(r.student for r in report.results)
    assert [done for _, done, _ in progress] == list(range(1, len(report.results) + 1))
    assert {total for _, _, total in progress} == {len(report.results)}


def test_csv_has_one_row_per_requirement_per_student(mp9c_class):
    _, out, report, _, written = mp9c_class
    assert written == [out / "results.csv", out / "junit.xml", out / "report.html"]
    rows = read_csv(out / "results.csv")
    assert list(rows[0]) == ["student", "requirement", "result", "message"]
    ids = [rid for rid, _ in report.requirements]
    assert ids[:3] == ["T2.1", "T2.2", "T2.3"]
    assert len(rows) == len(ids) * len(report.results)
    assert {r["result"] for r in rows} == {"PASS", "FAIL", "NOT CHECKED"}      # NOT CHECKED: after a FAIL


# The conventions CI servers and LMS importers read, as Ant's XMLJUnitResultFormatter writes
# them and the common JUnit XSDs (Ant/windyroad, Jenkins junit-10) require: every attribute
# named below is required; a <testsuite> holds <properties>, its <testcase>s, <system-out> and
# <system-err> in this order; a <testcase> holds at most one <failure>, <error> or (Jenkins'
# junit-10.xsd, for NOT CHECKED) <skipped>.
JUNIT_XSD = b"""<?xml version="1.0" encoding="UTF-8"?>
<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema" elementFormDefault="qualified">
  <xs:simpleType name="timestamp">
    <xs:restriction base="xs:dateTime">
      <xs:pattern value="[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}"/>
    </xs:restriction>
  </xs:simpleType>
  <xs:simpleType name="nonblank">
    <xs:restriction base="xs:token"><xs:minLength value="1"/></xs:restriction>
  </xs:simpleType>
  <xs:complexType name="problem" mixed="true">
    <xs:attribute name="message" type="xs:string" use="required"/>
    <xs:attribute name="type" type="xs:string" use="required"/>
  </xs:complexType>
  <xs:element name="testsuites">
    <xs:complexType>
      <xs:sequence>
        <xs:element name="testsuite" minOccurs="0" maxOccurs="unbounded">
          <xs:complexType>
            <xs:sequence>
              <xs:element name="properties">
                <xs:complexType><xs:sequence>
                  <xs:element name="property" minOccurs="0" maxOccurs="unbounded">
                    <xs:complexType>
                      <xs:attribute name="name" type="nonblank" use="required"/>
                      <xs:attribute name="value" type="xs:string" use="required"/>
                    </xs:complexType>
                  </xs:element>
                </xs:sequence></xs:complexType>
              </xs:element>
              <xs:element name="testcase" minOccurs="0" maxOccurs="unbounded">
                <xs:complexType>
                  <xs:choice minOccurs="0">
                    <xs:element name="error" type="problem"/>
                    <xs:element name="failure" type="problem"/>
                    <xs:element name="skipped">
                      <xs:complexType><xs:attribute name="message" type="xs:string"/></xs:complexType>
                    </xs:element>
                  </xs:choice>
                  <xs:attribute name="name" type="nonblank" use="required"/>
                  <xs:attribute name="classname" type="nonblank" use="required"/>
                  <xs:attribute name="time" type="xs:decimal" use="required"/>
                </xs:complexType>
              </xs:element>
              <xs:element name="system-out" type="xs:string"/>
              <xs:element name="system-err" type="xs:string"/>
            </xs:sequence>
            <xs:attribute name="name" type="nonblank" use="required"/>
            <xs:attribute name="timestamp" type="timestamp" use="required"/>
            <xs:attribute name="hostname" type="nonblank" use="required"/>
            <xs:attribute name="tests" type="xs:nonNegativeInteger" use="required"/>
            <xs:attribute name="failures" type="xs:nonNegativeInteger" use="required"/>
            <xs:attribute name="errors" type="xs:nonNegativeInteger" use="required"/>
            <xs:attribute name="skipped" type="xs:nonNegativeInteger" use="required"/>
            <xs:attribute name="time" type="xs:decimal" use="required"/>
            <xs:attribute name="id" type="xs:nonNegativeInteger" use="required"/>
            <xs:attribute name="package" type="nonblank" use="required"/>
          </xs:complexType>
        </xs:element>
      </xs:sequence>
      <xs:attribute name="name" type="xs:string"/>
      <xs:attribute name="tests" type="xs:nonNegativeInteger" use="required"/>
      <xs:attribute name="failures" type="xs:nonNegativeInteger" use="required"/>
      <xs:attribute name="errors" type="xs:nonNegativeInteger" use="required"/>
      <xs:attribute name="time" type="xs:decimal"/>
    </xs:complexType>
  </xs:element>
</xs:schema>
"""


def assert_valid_junit(path: Path) -> etree._Element:
    schema = etree.XMLSchema(etree.fromstring(JUNIT_XSD))
    doc = etree.parse(str(path))
    assert schema.validate(doc), schema.error_log
    return doc.getroot()


def test_junit_has_one_testcase_per_requirement_per_student(mp9c_class):
    _, out, report, _, _ = mp9c_class
    root = assert_valid_junit(out / "junit.xml")
    rows = read_csv(out / "results.csv")
    suites = root.findall("testsuite")
    assert [s.get("name") for s in suites] == [r.student for r in report.results]
    assert int(root.get("tests")) == len(rows)
    assert int(root.get("failures")) == sum(r["result"] == "FAIL" for r in rows)
    for suite in suites:
        cases = suite.findall("testcase")
        mine = [r for r in rows if r["student"] == suite.get("name")]
        assert [c.get("name").split()[0] for c in cases] == [r["requirement"] for r in mine]
        for case, row in zip(cases, mine):
            failure = case.find("failure")
            assert (failure is not None) == (row["result"] == "FAIL")
            if failure is not None:
                assert failure.get("message") == row["message"]
        assert int(suite.get("failures")) == sum(r["result"] == "FAIL" for r in mine)
    short = next(s for s in suites if s.get("name") == "task2_short_pause_1s")
    assert "13 of 14 requirements passed: FAIL" in short.findtext("system-out")


def test_html_report_has_a_row_per_student_and_links_to_failing_traces(mp9c_class):
    _, out, report, _, _ = mp9c_class
    text = (out / "report.html").read_text(encoding="utf-8")
    page = lhtml.fromstring(text)
    assert not page.xpath("//script") and not page.xpath("//link")
    assert not [u for u in page.xpath("//@href | //@src") if "://" in u]     # self-contained
    table = page.xpath("//table")[0]
    header = [th.text_content() for th in table.xpath("./tr[1]/th")]
    assert header == ["student", "result"] + [rid for rid, _ in report.requirements]
    body = {tr.get("id"): tr for tr in table.xpath("./tr[@id]")}
    assert sorted(body) == sorted(r.student for r in report.results)
    swapped = body["task2_pauses_swapped"]
    cell = swapped.xpath("./td")[header.index("T2.1")]
    assert "FAIL" in cell.text_content() and "expected:" in cell.text_content()
    links = cell.xpath(".//a/@href")
    assert links and all((out / unquote(href)).is_file() for href in links)
    assert {Path(h).suffix for h in links} == {".csv", ".vcd"}
    assert "does not compile" in body["bob"].text_content()
    assert body["carol"].xpath("./td")[1].text_content().startswith("PASS")


def test_html_escapes_names_and_links_survive_odd_characters(tmp_path):
    from plclab.grader import GradeReport, Row
    from plclab.grader.classroom import ClassReport, StudentResult, Submission

    out = tmp_path / "out"
    trace = out / "traces" / "<eve> #1" / "mp9c-task1-manual.csv"
    trace.parent.mkdir(parents=True)
    trace.write_text("time_s,name,value\n", encoding="utf-8")
    graded = GradeReport("mp9c", "task1", "MP-9C <Task 1>", ["eve.st"],
                         rows=[Row("T1.1", "gripper", False, "L1 = 1", "L1 = 0 & <stuck>", 1.5, "manual")],
                         traces={"manual": [trace]})
    sub = Submission("<eve> #1", (tmp_path / "x.st",), tmp_path / "x.st")
    report = ClassReport("mp9c", "task1", "MP-9C <Task 1>", [("T1.1", "gripper")], [StudentResult(sub, graded)])
    page = lhtml.fromstring(report_html(report, out))
    assert page.xpath("//h1")[0].text_content() == "MP-9C <Task 1>"
    row = page.xpath("//tr[@id]")[0]
    assert row.get("id") == "<eve> #1"
    assert "observed: L1 = 0 & <stuck>" in row.text_content()
    (href,) = row.xpath(".//a/@href")
    assert (out / unquote(href)) == trace


# --------------------------------------------------------------------------- the thermo SCADA tasks
SCADA_TASKS = ("scada1", "scada2")


@pytest.fixture(scope="module", params=SCADA_TASKS)
def scada_class(request, tmp_path_factory):
    """A class of SCADA clients' traffic logs (tests/grader/fixtures/thermo/TASK: a log per
    student, or a folder holding it), plus a corrupt file (zed), a log with a garbled line
    (yan), a folder of two logs (xia), a folder without a log (wes) and a note that is no
    submission; graded with 2 jobs."""
    task = request.param
    root = tmp_path_factory.mktemp(f"class-{task}")
    folder = root / "logs"
    shutil.copytree(FIXTURES_DIR / "thermo" / task, folder)
    (folder / "zed.csv").write_bytes(b"\x00\xffPK\x03\x04 not text\n")
    (folder / "yan.csv").write_text("time_s,unit,request,response,what\n0.5,1,0300000007,,\n1.0,1,zz,,\n",
                                    encoding="utf-8")
    (folder / "xia").mkdir()
    for name in ("monday.csv", "tuesday.csv"):
        shutil.copy(FIXTURES_DIR / "thermo" / task / "ann.csv", folder / "xia" / name)
    (folder / "wes").mkdir()
    (folder / "wes" / "notes.txt").write_text("my client config\n", encoding="utf-8")
    (folder / "grading-notes.txt").write_text("not a submission\n", encoding="utf-8")
    out = root / "out"
    report = grade_class("thermo", task, folder, out, jobs=2)
    write_class_outputs(report, out)
    return task, folder, out, report


def test_a_class_of_traffic_logs_gets_the_verdicts_of_grading_each_log_alone(scada_class, tmp_path, capsys):
    task, folder, out, report = scada_class
    rows = read_csv(out / "results.csv")
    assert_class_is_one_by_one("thermo", task, report, rows, tmp_path)
    for result in report.results:                     # and `plclab grade thermo TASK --traffic LOG` agrees
        if len(result.submission.files) == 1:
            code = main(["grade", "thermo", task, "--traffic", str(result.submission.files[0]),
                         "--out", str(tmp_path / "cli" / result.student)])
            assert code == {"PASS": 0, "FAIL": 1}[result.status], (result.student, capsys.readouterr().out)
    assert [p.name for p in report.ignored] == ["grading-notes.txt"]
    assert_valid_junit(out / "junit.xml")


def test_each_log_fails_exactly_the_rows_of_its_mistake(scada_class):
    task, _, out, report = scada_class
    from make_scada_fixtures import FIXTURES

    rows = read_csv(out / "results.csv")
    expected = {Path(f.path).parts[1].removesuffix(".csv"): f.fails for f in FIXTURES if f.task == task}
    assert len(expected) >= 5 and any(not fails for fails in expected.values())
    for student, fails in expected.items():
        mine = [r for r in rows if r["student"] == student]
        assert [r["requirement"] for r in mine if r["result"] == "FAIL"] == list(fails), (student, mine)
        assert all(r["message"].startswith("expected: ") and "observed: " in r["message"] for r in mine
                   if r["result"] == "FAIL")
        assert {r["result"] for r in mine} <= {"PASS", "FAIL"}
    traces = out / "traces" / "ann"
    assert sorted(p.name for p in traces.iterdir()) == [f"thermo-{task}-replay.csv", f"thermo-{task}-replay.vcd"]


def test_a_corrupt_log_costs_only_its_student_with_one_clear_message(scada_class):
    task, folder, out, report = scada_class
    rows = read_csv(out / "results.csv")
    status = {r.student: r.status for r in report.results}
    assert status["ann"] == "PASS" and report.complete      # the others were graded
    ids = [rid for rid, _ in report.requirements]
    why = {
        "zed": f"not checked: the traffic log cannot be read: {folder / 'zed.csv'}:1: error: not a text file "
               "(a plclab traffic log is UTF-8 CSV)",
        "yan": f"not checked: the traffic log cannot be read: {folder / 'yan.csv'}:3: error: unit must be a whole "
               "number and request/response hexadecimal PDUs",
        "xia": f"not checked: the traffic log cannot be read: grade: a SCADA task grades one traffic log, got 2: "
               f"{folder / 'xia' / 'monday.csv'}, {folder / 'xia' / 'tuesday.csv'}",
        "wes": f"not checked: {folder / 'wes'}: no .csv file in this folder",
    }
    for student, message in why.items():
        assert status[student] == "FAIL"
        assert [(r["requirement"], r["result"], r["message"]) for r in rows if r["student"] == student] == \
               [(rid, "FAIL", message) for rid in ids]
    page = lhtml.fromstring((out / "report.html").read_text(encoding="utf-8"))
    (cell,) = page.xpath("//tr[@id='yan']/td[@colspan]")      # one cell says it for the whole row
    assert "the traffic log cannot be read:" in cell.text_content() and ":3: error: unit" in cell.text_content()


def test_cli_grades_a_class_of_traffic_logs(tmp_path, capsys):
    folder = tmp_path / "logs"
    shutil.copytree(FIXTURES_DIR / "thermo" / "scada2", folder)
    (folder / "zed.csv").write_text("hello\n", encoding="utf-8")
    out = tmp_path / "out"
    assert main(["grade-class", "thermo", "scada2", str(folder), "--out", str(out), "--jobs", "2"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert "[6/6] " in "\n".join(printed)
    assert "ben: FAIL   3 of 5 requirements passed" in [line.split("] ", 1)[1] for line in printed if "] " in line]
    assert (f"zed: FAIL   the traffic log cannot be read: {folder / 'zed.csv'}:1: error: not a plclab traffic "
            "log: the header must be time_s,unit,request,response,what") in [line.split("] ", 1)[1]
                                                                          for line in printed if "] " in line]
    assert "6 submissions: 1 pass, 5 fail, 0 not graded" in printed
    assert {r["student"] for r in read_csv(out / "results.csv")} == {"ann", "ben", "cat", "dan", "eli", "zed"}


# --------------------------------------------------------------------------- crash, hang, bug
def test_a_crash_a_hang_and_a_grader_bug_stop_nobody_else(tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    for student in ("a_hang", "b_crash", "c_bug"):
        what = student.split("_")[1]
        (folder / f"{student}.st").write_text(f"(* classroom test: {what} *)\n" + BROKEN, encoding="utf-8")
    (folder / "d_broken.st").write_text(BROKEN, encoding="utf-8")
    out = tmp_path / "out"
    # one job: each student after the hang is graded only once the hang was stopped
    report = grade_class("mp9c", "task1", folder, out, jobs=1, time_limit_s=2.0,
                         grade_one=grade_or_misbehave)
    write_class_outputs(report, out)
    status = {r.student: (r.status, r.not_graded) for r in report.results}
    assert status["a_hang"][0] == "ERROR" and "time limit of 2 s" in status["a_hang"][1]
    # before it was stopped, the hanging process wrote where it was (the suite's stall folder)
    stalls = [p.read_text(encoding="utf-8") for p in Path(os.environ["PLCLAB_STALL_DUMP"]).glob("stall-*.txt")]
    assert [s for s in stalls if "classroom_faults.py" in s and "in grade_or_misbehave" in s
            and "1 s into its time limit of 2 s" in s], stalls
    assert status["b_crash"][0] == "ERROR" and "killed by signal 9" in status["b_crash"][1]
    assert status["c_bug"][0] == "ERROR" and "KeyError" in status["c_bug"][1]
    assert "not a verdict on the program" in status["c_bug"][1]
    assert status["d_broken"] == ("FAIL", "")                  # graded for real after all that
    assert not report.complete
    rows = read_csv(out / "results.csv")
    assert {r["result"] for r in rows if r["student"] != "d_broken"} == {"ERROR"}
    root = assert_valid_junit(out / "junit.xml")
    hang = root.find("testsuite[@name='a_hang']")
    assert hang.get("errors") == hang.get("tests") != "0"
    assert "time limit" in hang.find("testcase/error").get("message")


def test_fresh_interpreters_grade_the_same_when_forking_is_unsafe(tmp_path):
    """With other threads running, grading processes are spawned (no fork): a crash is still
    that student's row and the others get their real verdict."""
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "a_crash.st").write_text("(* classroom test: crash *)\n" + BROKEN, encoding="utf-8")
    (folder / "b_broken.st").write_text(BROKEN, encoding="utf-8")
    report = grade_class("mp9c", "task1", folder, tmp_path / "out", jobs=2, time_limit_s=120.0,
                         grade_one=grade_or_misbehave, start_method="spawn")
    status = {r.student: (r.status, r.not_graded) for r in report.results}
    assert status["a_crash"][0] == "ERROR" and "killed by signal 9" in status["a_crash"][1]
    assert status["b_broken"] == ("FAIL", "")
    assert report.results[1].report.errors == [f"{folder / 'b_broken.st'}:3:6: error: missing expression after "
                                               "':=' (before ';')"]


def test_outputs_of_nothing_graded_are_still_valid(tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "eve.st").write_text(BROKEN, encoding="utf-8")
    report = grade_class("tur10", "task3", folder, tmp_path / "out", jobs=1)
    assert [r.status for r in report.results] == ["FAIL"]
    assert results_csv(report).count("\neve,") == len(report.requirements)
    etree.XMLSchema(etree.fromstring(JUNIT_XSD)).assertValid(etree.fromstring(junit_xml(report)))
    assert "eve" in report_html(report, tmp_path / "out")


# --------------------------------------------------------------------------- the command
def test_cli_grades_the_folder_prints_progress_and_writes_the_files(tmp_path, capsys):
    folder = tmp_path / "class"
    (folder / "zoe").mkdir(parents=True)
    (folder / "zoe" / "main.st").write_text(BROKEN, encoding="utf-8")
    (folder / "yan.st").write_text(BROKEN.replace("x := ;", "x := 1;"), encoding="utf-8")
    out = folder / "results"                 # inside the class folder: not taken for a student
    assert main(["grade-class", "mp9c", "task1", str(folder), "--out", str(out), "--jobs", "2"]) == 0
    printed = capsys.readouterr().out.splitlines()
    progress = [line for line in printed if line.startswith("[")]
    assert [line[:6] for line in progress] == ["[1/2] ", "[2/2] "]
    assert sorted(line[6:] for line in progress) == [
        f"yan: FAIL   the program does not compile: {folder / 'yan.st'}:1:1: error: no CONFIGURATION: "
        "hand in the complete program (the bundle you were given, with its CONFIGURATION Config0)",
        f"zoe: FAIL   the program does not compile: {folder / 'zoe' / 'main.st'}:3:6: error: missing "
        "expression after ':=' (before ';')"], printed
    assert "2 submissions: 0 pass, 2 fail, 0 not graded" in printed
    assert {p.name for p in out.iterdir()} >= {"results.csv", "junit.xml", "report.html"}
    assert {r["student"] for r in read_csv(out / "results.csv")} == {"yan", "zoe"}


def test_cli_refuses_to_replace_what_is_not_a_regular_file(tmp_path, capsys):
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "eve.st").write_text(BROKEN, encoding="utf-8")
    out = tmp_path / "out"
    (out / "junit.xml").mkdir(parents=True)
    (out / "junit.xml" / "keep.txt").write_text("mine", encoding="utf-8")
    assert main(["grade-class", "mp9c", "task1", str(folder), "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.strip() == f"plclab: error: {out / 'junit.xml'}: exists and is a directory; refusing to replace " \
                          "it (name a regular file)"
    assert (out / "junit.xml" / "keep.txt").read_text(encoding="utf-8") == "mine"
    assert not (out / "results.csv").exists()


@pytest.mark.parametrize("argv, message", [
    (["mp9c", "task9"], "grade: stand 'mp9c' has no task 'task9' (one of task1, task2, task3)"),
    (["mp9c", "task1", "--jobs", "0"], "grade-class: --jobs must be at least 1 (got 0)"),
    (["thermo", "task1"], "grade: stand 'thermo' has no task 'task1' (one of scada1, scada2)"),
])
def test_cli_bad_arguments_are_one_line(argv, message, tmp_path, capsys):
    (tmp_path / "eve.st").write_text(BROKEN, encoding="utf-8")
    args = ["grade-class", argv[0], argv[1], str(tmp_path), "--out", str(tmp_path / "o")] + argv[2:]
    assert main(args) == 1
    assert capsys.readouterr().err == f"plclab: error: {message}\n"


def test_cli_missing_or_empty_folder_is_one_line(tmp_path, capsys):
    assert main(["grade-class", "mp9c", "task1", str(tmp_path / "nope")]) == 1
    assert "not a folder" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert main(["grade-class", "mp9c", "task1", str(tmp_path / "empty"), "--out", str(tmp_path / "o")]) == 1
    assert capsys.readouterr().err.startswith(f"plclab: error: grade-class: no submission in {tmp_path / 'empty'}")


def test_two_entries_for_one_student_are_refused(tmp_path):
    (tmp_path / "amy").mkdir()
    (tmp_path / "amy.st").write_text(BROKEN, encoding="utf-8")
    with pytest.raises(Exception, match="are both student 'amy': rename one"):
        find_submissions(tmp_path)


EXPLORE_FIXTURES = Path(__file__).resolve().parent / "fixtures" / "explore" / "mp9c"


def test_grade_class_explores_every_program_against_the_model_answer(tmp_path):
    """`plclab grade-class` explores as `plclab grade` does: a mistake only an unscripted console
    history shows (a stop press needs the spare input) fails the class's E1 column with the
    shortest console history and the student's line; a correct program written differently
    passes it; the shrunk script is among the student's traces."""
    folder, out = tmp_path / "class", tmp_path / "out"
    for student, name in (("alice", "task3_alt_enable_flag.st"), ("bob", "task3_stop_needs_enable.st")):
        (folder / student).mkdir(parents=True)
        shutil.copy(EXPLORE_FIXTURES / name, folder / student / name)
    assert main(["grade-class", "mp9c", "task3", str(folder), "--out", str(out), "--jobs", "2"]) == 0
    rows = {(r["student"], r["requirement"]): r for r in read_csv(out / "results.csv")}
    assert rows[("alice", "E1")]["result"] == "PASS"
    bob = rows[("bob", "E1")]
    assert bob["result"] == "FAIL"
    assert "the model answer has" in bob["message"] and re.search(r"console steps: 1\. \d+\.\d\d s ", bob["message"])
    assert "task3_stop_needs_enable.st:" in bob["message"]            # the student's statement
    assert (out / "traces" / "bob" / "mp9c-task3-explore.csv").is_file()
    assert not (out / "traces" / "alice" / "mp9c-task3-explore.csv").exists()


def test_grade_class_says_in_one_line_why_it_did_not_explore(tmp_path, capsys):
    """A course's model answer that does not compile: no E1 column, one line saying why."""
    folder, out = tmp_path / "class", tmp_path / "out"
    folder.mkdir()
    shutil.copy(EXPLORE_FIXTURES / "task3_alt_enable_flag.st", folder / "alice.st")
    bad = tmp_path / "ref.st"
    bad.write_text("PROGRAM p\nx := ;\nEND_PROGRAM\n", encoding="utf-8")
    assert main(["grade-class", "mp9c", "task3", str(folder), "--out", str(out), "--reference", str(bad)]) == 0
    assert "exploration not run: the reference does not compile" in capsys.readouterr().out
    assert "E1" not in {r["requirement"] for r in read_csv(out / "results.csv")}
