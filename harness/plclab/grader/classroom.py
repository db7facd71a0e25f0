"""`grade-class STAND TASK DIR`: grade a whole class, one submission per student, in parallel.

Each `.st` file of DIR (student = the file name without `.st`) or each folder of DIR (student =
the folder name; every `.st` file under it is one program) is one submission; for the thermo
SCADA tasks, each traffic log `.csv` (or a folder holding one) is (the task's
`RequirementSet.submission` says which files). Each is graded by
`grade()` -- exactly what `plclab grade` does for one student -- in a process of its own, so a
submission that crashes the grader or runs past the time limit costs that student a "not
graded" row and nothing else. The results go to three files an instructor and their tools read:

    results.csv   student,requirement,result,message   (one row per requirement per student)
    junit.xml     one <testsuite> per student, one <testcase> per requirement (CI, LMS import)
    report.html   one row per student, one column per requirement, failures with their traces

Results: PASS and FAIL are the grader's verdicts; ERROR means "not graded" (a grader crash or
the time limit), which is never a verdict on the student's program.
"""
from __future__ import annotations

import csv
import html
import io
import multiprocessing
import os
import threading
import time
import traceback
import urllib.parse
from collections import deque
from dataclasses import dataclass, field
from datetime import datetime, timezone
from multiprocessing.connection import wait
from pathlib import Path
from typing import Callable, Optional, Sequence

from lxml import etree

from plclab import fileio
from plclab.errors import PlcLabError

from .engine import grade, grade_sources, requirement_table
from .registry import ST_PROGRAM, Submission as SubmissionKind, requirement_set
from .report import GradeReport, Row

DEFAULT_TIME_LIMIT_S = 300.0        # one submission; normal grading takes seconds
OUTPUT_FILES = ("results.csv", "junit.xml", "report.html")
TRACES_DIR = "traces"               # OUT/traces/<student>/<stand>-<task>-<scenario>.csv|.vcd

GradeOne = Callable[[str, str, Sequence[str], Optional[str]], GradeReport]


@dataclass(frozen=True)
class Submission:
    student: str
    files: tuple[Path, ...]          # one compilation unit, in a stable order
    source: Path                     # the .st file or folder it came from


@dataclass
class StudentResult:
    """One student's outcome: the grader's report, or why there is none."""

    submission: Submission
    report: Optional[GradeReport] = None
    not_graded: str = ""             # set when the grading did not finish (crash, time limit)
    seconds: float = 0.0             # wall time of this student's grading

    @property
    def student(self) -> str:
        return self.submission.student

    @property
    def status(self) -> str:
        """PASS / FAIL as `plclab grade` says, ERROR when not graded."""
        if self.report is None:
            return "ERROR"
        return "PASS" if self.report.passed else "FAIL"

    def summary(self) -> str:
        """What the progress line says after the student's name."""
        if self.report is None:
            return f"ERROR  {self.not_graded}"
        if self.report.errors:
            what = self.report.unreadable if self.submission.files else "nothing to grade:"
            return f"FAIL   {what} {self.report.errors[0]}"
        n_pass = sum(r.passed for r in self.report.rows)
        return f"{self.status:<5}  {n_pass} of {len(self.report.rows)} requirements passed"


@dataclass
class ClassReport:
    stand: str
    task: str
    title: str
    requirements: list[tuple[str, str]]         # (id, text) in the grader's order
    results: list[StudentResult]                # sorted by student
    ignored: list[Path] = field(default_factory=list)   # entries of DIR that are no submission
    started: str = ""                           # ISO time of the run (UTC, no zone suffix)
    suffix: str = ".st"                         # the files a submission is made of (thermo: .csv)

    @property
    def complete(self) -> bool:
        """Every submission was graded (whatever the verdicts)."""
        return all(r.report is not None for r in self.results)


# ---------------------------------------------------------------------------- submissions
def find_submissions(folder: str | Path, exclude: Sequence[str | Path] = (),
                     kind: SubmissionKind = ST_PROGRAM) -> tuple[list[Submission], list[Path]]:
    """The submissions in `folder` and the entries that are none (other files): a file with
    the `kind`'s suffix, or a folder (all such files under it: one submission).

    Hidden entries (a leading dot) are skipped silently; so is any folder that holds one of
    `exclude` (the output folder, when an instructor puts it inside the class folder).
    """
    root = Path(folder)
    if not root.is_dir():
        raise PlcLabError(f"grade-class: {folder}: not a folder (give the folder holding one {kind.suffix} file "
                          f"or one folder per student)")
    excluded = [Path(e).resolve() for e in exclude]
    submissions: dict[str, Submission] = {}
    ignored: list[Path] = []
    for entry in sorted(root.iterdir()):
        if entry.name.startswith("."):
            continue
        if entry.is_dir():
            here = entry.resolve()
            if any(e == here or here in e.parents for e in excluded):
                continue
            files = tuple(sorted((p for p in entry.rglob("*") if _is_a(p, kind)
                                  and not any(part.startswith(".") for part in p.relative_to(entry).parts)),
                                 key=lambda p: p.relative_to(entry).as_posix()))
            student = entry.name
        elif _is_a(entry, kind):
            files, student = (entry,), entry.stem
        else:
            ignored.append(entry)
            continue
        if student in submissions:
            raise PlcLabError(f"grade-class: {submissions[student].source} and {entry} are both student "
                              f"'{student}': rename one")
        submissions[student] = Submission(student, files, entry)
    if not submissions:
        raise PlcLabError(f"grade-class: no submission in {folder} (one {kind.suffix} file or one folder of "
                          f"{kind.suffix} files per student)")
    return list(submissions.values()), ignored


def _is_a(p: Path, kind: SubmissionKind) -> bool:
    # an ST program may also be handed in as an OpenPLC Editor project (plc.xml, ladder inside)
    suffixes = (kind.suffix, ".xml") if kind is ST_PROGRAM else (kind.suffix,)
    return p.suffix.lower() in suffixes and p.is_file()


# ---------------------------------------------------------------------------- grading
def grade_class(stand: str, task: str, folder: str | Path, out_dir: str | Path,
                jobs: Optional[int] = None, time_limit_s: float = DEFAULT_TIME_LIMIT_S,
                on_result: Optional[Callable[[StudentResult, int, int], None]] = None,
                grade_one: GradeOne = grade, start_method: Optional[str] = None) -> ClassReport:
    """Grade every submission in `folder` on `task` of `stand`; traces go to
    OUT/traces/<student>/. `on_result(result, done, total)` is called as each student finishes
    (progress). `grade_one` is `grade` (tests substitute one that crashes or hangs);
    `start_method` forces how grading processes start (default: see `_context`).

    Writes nothing but the traces; `write_class_outputs` writes the three result files.
    """
    requirements = requirement_table(stand, task)         # unknown stand / task: one line, before any work
    kind = requirement_set(stand, task).submission
    if jobs is not None and jobs < 1:
        raise PlcLabError(f"grade-class: --jobs must be at least 1 (got {jobs})")
    if not time_limit_s > 0:
        raise PlcLabError(f"grade-class: the time limit must be more than 0 s (got {time_limit_s:g})")
    check_class_outputs(out_dir)                          # a bad --out refused before the work
    out = Path(out_dir).resolve()
    submissions, ignored = find_submissions(folder, exclude=[out], kind=kind)
    started = datetime.now(timezone.utc).replace(tzinfo=None, microsecond=0).isoformat()
    title = grade_sources(stand, task, [("warm-up.st", "")]).title   # also builds the parser once, before forking
    results = _run_parallel(stand, task, title, submissions, out, jobs or os.cpu_count() or 1, time_limit_s,
                            on_result, grade_one, _context(start_method), kind)
    results.sort(key=lambda r: r.student)
    return ClassReport(stand, task, title, requirements, results, ignored, started, kind.suffix)


def _grade_in_child(conn, grade_one: GradeOne, stand: str, task: str, files: list[str],
                    out_dir: str) -> None:
    """Runs in the submission's own process: the report, or why there is none, down the pipe."""
    try:
        conn.send(("report", grade_one(stand, task, files, out_dir)))
    except PlcLabError as e:
        conn.send(("not graded", f"not graded: {e}"))
    except BaseException as e:     # a grader bug: reported in the student's row, never charged to them
        last = traceback.extract_tb(e.__traceback__)[-1:] or [None]
        where = f" at {Path(last[0].filename).name}:{last[0].lineno}" if last[0] else ""
        conn.send(("not graded", f"not graded: the grader failed on this submission ({type(e).__name__}: "
                                 f"{e}{where}); this is a harness problem, not a verdict on the program"))
    finally:
        conn.close()


def _context(start_method: Optional[str] = None):
    """Fork (cheap: the parent has the grader loaded and warm) when that is safe, i.e. the
    parent runs no other thread; otherwise spawn, a fresh interpreter per submission (which
    gets the parent's sys.path, so a `grade_one` from any importable module works)."""
    if start_method is None:
        fork_ok = "fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1
        start_method = "fork" if fork_ok else "spawn"
    return multiprocessing.get_context(start_method)


@dataclass
class _Running:
    submission: Submission
    process: Optional[multiprocessing.process.BaseProcess]     # None: nothing to run
    conn: object
    started: float


def _run_parallel(stand: str, task: str, title: str, submissions: list[Submission], out: Path, jobs: int,
                  time_limit_s: float, on_result, grade_one: GradeOne, ctx,
                  handed_in: SubmissionKind = ST_PROGRAM) -> list[StudentResult]:
    pending = deque(submissions)
    running: list[_Running] = []
    results: list[StudentResult] = []

    def finish(job: _Running, report: Optional[GradeReport], not_graded: str) -> None:
        running.remove(job)
        if job.process is not None:
            job.process.join(timeout=5)
            if job.process.is_alive():           # sent its report but does not exit
                job.process.kill()
                job.process.join()
            job.conn.close()
        result = StudentResult(job.submission, report, not_graded, time.monotonic() - job.started)
        results.append(result)
        if on_result is not None:
            on_result(result, len(results), len(submissions))

    try:
        while pending or running:
            while pending and len(running) < jobs:
                sub = pending.popleft()
                if not sub.files:                    # nothing to run: a verdict without a process
                    empty = GradeReport(stand, task, title, [], noun=handed_in.noun, unreadable=handed_in.unreadable,
                                        errors=[f"{sub.source}: no {handed_in.suffix} file in this folder"])
                    running.append(_Running(sub, None, None, time.monotonic()))
                    finish(running[-1], empty, "")
                    continue
                receive, send = ctx.Pipe(duplex=False)
                trace_dir = out / TRACES_DIR / sub.student
                p = ctx.Process(target=_grade_in_child, name=f"grade-{sub.student}", daemon=True,
                                args=(send, grade_one, stand, task, [str(f) for f in sub.files], str(trace_dir)))
                p.start()
                send.close()
                running.append(_Running(sub, p, receive, time.monotonic()))
            if not running:
                continue
            next_deadline = min(j.started for j in running) + time_limit_s
            wait([j.conn for j in running] + [j.process.sentinel for j in running],
                 timeout=max(0.0, next_deadline - time.monotonic()))
            for job in list(running):
                if job.conn.poll():
                    try:
                        kind, value = job.conn.recv()
                    except (EOFError, OSError):
                        finish(job, None, _died(job.process))
                        continue
                    finish(job, value if kind == "report" else None, "" if kind == "report" else value)
                elif not job.process.is_alive():
                    finish(job, None, _died(job.process))
                elif time.monotonic() - job.started > time_limit_s:
                    job.process.kill()
                    finish(job, None, f"not graded: grading took longer than the time limit of "
                                      f"{time_limit_s:g} s and was stopped (an endless or very slow "
                                      f"program? grade it alone with `plclab grade`, or raise --time-limit)")
    finally:
        for job in running:                      # interrupted: stop what we started
            if job.process is not None:
                job.process.kill()
                job.process.join()
    return results


def _died(process) -> str:
    process.join(timeout=5)
    code = process.exitcode
    how = f"killed by signal {-code}" if code is not None and code < 0 else f"exit code {code}"
    return (f"not graded: the grading process died ({how}) before reporting; this is a harness "
            f"problem, not a verdict on the program")


# ---------------------------------------------------------------------------- one row per requirement
@dataclass(frozen=True)
class Cell:
    """One student's verdict on one requirement, as every output shows it."""

    requirement: str
    result: str                      # PASS / FAIL / ERROR
    message: str                     # empty for a pass
    traces: tuple[Path, ...] = ()    # the trace files of the scenario that shows a failure


def row_message(row: Row) -> str:
    """A failing row in one line: what was expected, what was observed, when and where."""
    if row.passed:
        return ""
    parts = [f"expected: {row.expected}"] if row.expected else []
    parts.append(f"observed: {row.observed}")
    if row.time is not None:
        parts.append(f"at t = {row.time:.2f} s")
    if row.scenario:
        parts.append(f"scenario '{row.scenario}'")
    return "; ".join(parts)


def cells(result: StudentResult, requirements: Sequence[tuple[str, str]]) -> list[Cell]:
    """One cell per requirement, whatever happened to the submission."""
    report = result.report
    if report is None:
        return [Cell(rid, "ERROR", result.not_graded) for rid, _ in requirements]
    if report.errors:
        why = "not checked: " + ("" if result.submission.files == () else f"{report.unreadable} ") \
            + "; ".join(report.errors)
        return [Cell(rid, "FAIL", why) for rid, _ in requirements]
    by_id = {r.id: r for r in report.rows}
    out = []
    for rid, _ in requirements:
        row = by_id.get(rid)
        if row is None:
            out.append(Cell(rid, "ERROR", f"not graded: the grader's report has no row {rid}"))
        else:
            out.append(Cell(rid, row.result, row_message(row),
                            tuple(report.traces.get(row.scenario, ())) if not row.passed else ()))
    return out


# ---------------------------------------------------------------------------- the three outputs
def results_csv(report: ClassReport) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["student", "requirement", "result", "message"])
    for r in report.results:
        for c in cells(r, report.requirements):
            w.writerow([r.student, c.requirement, c.result, c.message])
    return buf.getvalue()


def junit_xml(report: ClassReport, hostname: str = "localhost") -> bytes:
    """JUnit XML as Ant's XMLJUnitResultFormatter writes it (the form Jenkins, GitLab and LMS
    importers read): <testsuites> of one <testsuite> per student, each with <properties>, one
    <testcase> per requirement (a <failure> for FAIL, an <error> for not graded), <system-out>
    holding the student's grade table and <system-err>."""
    suites = etree.Element("testsuites", name=f"plclab grade-class {report.stand} {report.task}")
    totals = {"tests": 0, "failures": 0, "errors": 0}
    for i, r in enumerate(report.results):
        row_cells = cells(r, report.requirements)
        n_fail = sum(c.result == "FAIL" for c in row_cells)
        n_err = sum(c.result == "ERROR" for c in row_cells)
        suite = etree.SubElement(suites, "testsuite", {
            "name": r.student, "package": f"{report.stand}.{report.task}", "id": str(i),
            "hostname": hostname, "timestamp": report.started or "1970-01-01T00:00:00",
            "tests": str(len(row_cells)), "failures": str(n_fail), "errors": str(n_err), "skipped": "0",
            "time": f"{r.seconds:.3f}"})
        etree.SubElement(suite, "properties")
        texts = dict(report.requirements)
        for c in row_cells:
            case = etree.SubElement(suite, "testcase", {
                "name": f"{c.requirement} {texts[c.requirement]}",
                "classname": f"{report.stand}.{report.task}.{r.student}", "time": "0"})
            if c.result == "FAIL":
                etree.SubElement(case, "failure", message=_xml_safe(c.message),
                                 type="requirement failed").text = _xml_safe(c.message)
            elif c.result == "ERROR":
                etree.SubElement(case, "error", message=_xml_safe(c.message),
                                 type="not graded").text = _xml_safe(c.message)
        etree.SubElement(suite, "system-out").text = _xml_safe(r.report.text() if r.report else r.not_graded)
        etree.SubElement(suite, "system-err")
        totals["tests"] += len(row_cells)
        totals["failures"] += n_fail
        totals["errors"] += n_err
    for k, v in totals.items():
        suites.set(k, str(v))
    suites.set("time", f"{sum(r.seconds for r in report.results):.3f}")
    return etree.tostring(suites, xml_declaration=True, encoding="UTF-8", pretty_print=True)


def _xml_safe(text: str) -> str:
    """XML 1.0 cannot carry most control characters (a student's file may hold any byte)."""
    return "".join(ch if ch in "\t\n\r" or ord(ch) >= 0x20 and ch not in "\ufffe\uffff" else "\ufffd"
                   for ch in text)


_CSS = """
body { font-family: sans-serif; margin: 1.5em; }
table { border-collapse: collapse; }
th, td { border: 1px solid #999; padding: 0.3em 0.5em; vertical-align: top; }
th { background: #eee; }
td.PASS { background: #d9f2d9; text-align: center; }
td.FAIL { background: #f8d4d4; max-width: 22em; font-size: 0.85em; }
td.ERROR { background: #f4e2b8; font-size: 0.85em; }
td.student { font-weight: bold; white-space: nowrap; }
.verdict { font-weight: bold; }
dt { font-weight: bold; float: left; width: 4em; }
"""


def report_html(report: ClassReport, out_dir: str | Path) -> str:
    """A static page (no script, no outside resource): one row per student, one column per
    requirement; a failing cell shows its message and links to its traces (relative to
    `out_dir`, where the page is written)."""
    out = Path(out_dir).resolve()
    e = html.escape
    ids = [rid for rid, _ in report.requirements]
    lines = ["<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
             f"<title>Class results: {e(report.title)}</title>", f"<style>{_CSS}</style>", "</head>",
             "<body>", f"<h1>{e(report.title)}</h1>"]
    n = len(report.results)
    counts = {s: sum(r.status == s for r in report.results) for s in ("PASS", "FAIL", "ERROR")}
    lines.append(f"<p>{n} submissions: {counts['PASS']} pass, {counts['FAIL']} fail, "
                 f"{counts['ERROR']} not graded. Graded {e(report.started)} UTC.</p>")
    lines.append("<table>")
    head = "".join(f'<th title="{e(text)}">{e(rid)}</th>' for rid, text in report.requirements)
    lines.append(f"<tr><th>student</th><th>result</th>{head}</tr>")
    for r in report.results:
        row_cells = cells(r, report.requirements)
        n_pass = sum(c.result == "PASS" for c in row_cells)
        tr = [f'<tr id="{e(r.student, quote=True)}"><td class="student">{e(r.student)}</td>',
              f'<td class="{r.status} verdict">{r.status} ({n_pass}/{len(row_cells)})</td>']
        if r.report is None or r.report.errors:      # one message for the whole row
            cls = "ERROR" if r.report is None else "FAIL"
            if r.report is None:
                text = r.not_graded
            else:
                what = r.report.unreadable if r.submission.files else "nothing to grade:"
                text = what + "\n" + "\n".join(r.report.errors)
            tr.append(f'<td class="{cls}" colspan="{len(ids)}"><pre>{e(text)}</pre></td>')
        else:
            for c in row_cells:
                if c.result == "PASS":
                    tr.append('<td class="PASS">PASS</td>')
                    continue
                links = " ".join(f'<a href="{e(_link(p, out), quote=True)}">{e(p.suffix[1:])}</a>'
                                 for p in c.traces)
                trace = f"<br>traces: {links}" if links else ""
                tr.append(f'<td class="{c.result}"><b>{c.result}</b> {e(c.message)}{trace}</td>')
        lines.append("".join(tr) + "</tr>")
    passed_by = "".join(
        f"<td>{sum(c.result == 'PASS' for r in report.results for c in cells(r, report.requirements) if c.requirement == rid)}/{n}</td>"
        for rid in ids)
    lines.append(f"<tr><th>passed by</th><td></td>{passed_by}</tr>")
    lines.append("</table>")
    lines.append("<h2>Requirements</h2><dl>")
    lines.extend(f"<dt>{e(rid)}</dt><dd>{e(text)}</dd>" for rid, text in report.requirements)
    lines.append("</dl>")
    if report.ignored:
        lines.append("<p>Not a submission (ignored): " + ", ".join(e(p.name) for p in report.ignored) + "</p>")
    lines.extend(["</body>", "</html>"])
    return "\n".join(lines) + "\n"


def _link(path: Path, out: Path) -> str:
    """A relative URL from the page to a trace file (a student's name may hold '#', '?', spaces)."""
    p = Path(path).resolve()
    try:
        return urllib.parse.quote(p.relative_to(out).as_posix())
    except ValueError:
        return p.as_uri()


def write_class_outputs(report: ClassReport, out_dir: str | Path) -> list[Path]:
    """Write results.csv, junit.xml and report.html into `out_dir` (created if missing), each
    atomically through plclab.fileio (nothing else there is replaced, renamed or removed)."""
    out = Path(out_dir)
    contents = {"results.csv": results_csv(report).encode("utf-8"),
                "junit.xml": junit_xml(report),
                "report.html": report_html(report, out).encode("utf-8")}
    targets = check_class_outputs(out)
    for t in targets:
        fileio.write_bytes(t, contents[t.name])
    return targets


def check_class_outputs(out_dir: str | Path) -> list[Path]:
    """The three result files in `out_dir`, each refused (one line) if it exists and is not a
    regular file: a bad --out is reported before a class is graded, not after."""
    targets = [Path(out_dir) / name for name in OUTPUT_FILES]
    for t in targets:
        fileio.check_output(t)
    return targets


__all__ = ["ClassReport", "Cell", "StudentResult", "Submission", "cells", "find_submissions", "grade_class",
           "junit_xml", "report_html", "results_csv", "row_message", "write_class_outputs"]
