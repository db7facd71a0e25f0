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

Results: PASS and FAIL are the grader's verdicts; NOT CHECKED marks a requirement an earlier
failure kept from being checked (no pass, no second mistake); ERROR means "not graded" (a
grader crash or the time limit), which is never a verdict on the student's program.

Hand-ins are untrusted: only regular files inside DIR are read (a link, FIFO or device where a
submission would be refuses it, unread); each student's process runs in its own process
group, dies with this one, keeps its temporary files in a folder removed whatever happens, and
is held to the time limit and a memory limit (RLIMIT_AS; reaching it is that student's FAIL).
A signal stops every child and removes every temporary folder (ClassInterrupted). The traces
are staged in a temporary folder and moved into OUT after the three result files (verdicts
first); messages are capped and results.csv fields that start like a spreadsheet formula are
quoted. `scheduler` sends the same per-student work to a Dask distributed cluster.
"""
from __future__ import annotations

import contextlib
import csv
import functools
import html
import io
import multiprocessing
import os
import pickle
import re
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
import traceback
import urllib.parse
import uuid
import weakref
from collections import deque
from dataclasses import dataclass, field
from datetime import datetime, timezone
from multiprocessing.connection import wait
from pathlib import Path
from typing import Callable, Iterator, Optional, Sequence

from lxml import etree

from plclab import fileio, limits
from plclab.errors import CompileError, PlcLabError
from plclab.frontend import read_sources
from plclab.frontend.parser import load_parser

from .engine import grade, grade_sources, requirement_table, task_title
from .explore import ExploreOptions, _fast_tmp, class_seed
from .registry import ST_PROGRAM, Submission as SubmissionKind, requirement_set
from .report import MAX_QUOTE, NOT_CHECKED, GradeReport, Row, clip

DEFAULT_TIME_LIMIT_S = 300.0        # one submission; normal grading takes seconds
DEFAULT_MEMORY_LIMIT_MIB = 1024     # address space one student's grading may add to the loaded grader's
MAX_MESSAGE_CHARS = MAX_QUOTE       # a cell's message quotes at most this much (a 1 MB identifier ...)
MAX_REPORT_CHARS = 20000            # ... and a student's report in junit.xml's <system-out>
OUTPUT_FILES = ("results.csv", "junit.xml", "report.html")
PARTIAL_RESULTS = "results.partial.csv"   # an interrupted run's verdicts so far (never results.csv)
TRACES_DIR = "traces"               # OUT/traces/<student>/<stand>-<task>-<scenario>.csv|.vcd
STOP_SIGNALS = tuple(getattr(signal, n) for n in ("SIGTERM", "SIGINT", "SIGHUP") if hasattr(signal, n))

GradeOne = Callable[[str, str, Sequence[str], Optional[str]], GradeReport]


@dataclass(frozen=True)
class Submission:
    student: str
    files: tuple[Path, ...]          # one compilation unit, in a stable order
    source: Path                     # the .st file or folder it came from
    refused: str = ""                # why it is not read (a link, a device...): a FAIL without grading


@dataclass
class StudentResult:
    """One student's outcome: the grader's report, or why there is none."""

    submission: Submission
    report: Optional[GradeReport] = None
    not_graded: str = ""             # set when the grading did not finish (crash, time limit)
    seconds: float = 0.0             # wall time of this student's grading
    staged: tuple[tuple[Path, Path], ...] = ()   # (trace file as graded, where OUT will hold it)

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
            return clip(f"ERROR  {self.not_graded}")
        if self.report.errors:
            what = self.report.unreadable if self.submission.files or self.submission.refused else \
                "nothing to grade:"
            return clip(f"FAIL   {what} {self.report.errors[0]}")
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
    staging: Optional[Path] = None              # the traces until write_class_outputs moves them to OUT
    total: int = 0                              # submissions found (more than `results` if interrupted)
    notes: list[str] = field(default_factory=list)   # e.g. why exploration was not run

    @property
    def complete(self) -> bool:
        """Every submission was graded (whatever the verdicts)."""
        return len(self.results) >= self.total and all(r.report is not None for r in self.results)


class ClassInterrupted(PlcLabError):
    """grade-class was stopped by a signal: every grading process and temporary folder is gone;
    `report` holds the students graded before it (see write_partial_results)."""

    def __init__(self, signum: int, report: ClassReport):
        self.signum = signum
        self.report = report
        super().__init__(f"grade-class: stopped by {signal.Signals(signum).name} after "
                         f"{len(report.results)} of {report.total} submissions; every grading process and "
                         f"temporary folder was removed")


# ---------------------------------------------------------------------------- submissions
def find_submissions(folder: str | Path, exclude: Sequence[str | Path] = (),
                     kind: SubmissionKind = ST_PROGRAM) -> tuple[list[Submission], list[Path]]:
    """The submissions in `folder` and the entries that are none (other files): a file with
    the `kind`'s suffix, or a folder (all such files under it: one submission).

    Hidden entries (a leading dot) are skipped silently; so is any folder that holds one of
    `exclude` (the output folder, when an instructor puts it inside the class folder).
    Nothing is followed out of the folder: a symbolic link, a FIFO or a device where a
    submission or one of its files would be (a `.st` name, or a link to a folder) makes that
    student's submission refused (a FAIL saying why, nothing read); other such entries are
    ignored. Only regular files inside the folder are ever read.
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
        mode = os.lstat(entry).st_mode
        refused = ""
        if stat.S_ISDIR(mode):
            here = entry.resolve()
            if any(e == here or here in e.parents for e in excluded):
                continue
            files, refused = _folder_files(entry, kind)
            student = entry.name
        elif stat.S_ISREG(mode) and _named_as(entry, kind):
            files, student = (entry,), entry.stem
        elif _would_be_submission(entry, mode, kind):
            files, refused = (), _refusal(entry, mode)
            student = entry.stem if _named_as(entry, kind) else entry.name
        else:
            ignored.append(entry)
            continue
        if student in submissions:
            raise PlcLabError(f"grade-class: {submissions[student].source} and {entry} are both student "
                              f"'{student}': rename one")
        submissions[student] = Submission(student, () if refused else files, entry, refused)
    if not submissions:
        raise PlcLabError(f"grade-class: no submission in {folder} (one {kind.suffix} file or one folder of "
                          f"{kind.suffix} files per student)")
    return list(submissions.values()), ignored


def _named_as(p: Path, kind: SubmissionKind) -> bool:
    """Named like a submission file: the kind's suffix; an ST program may also be handed in as
    an OpenPLC Editor project (plc.xml, ladder inside)."""
    suffix = p.suffix.lower()
    return suffix == kind.suffix or (kind is ST_PROGRAM and suffix == ".xml")


def _folder_files(folder: Path, kind: SubmissionKind) -> tuple[tuple[Path, ...], str]:
    """The submission files under a student's folder (hidden ones skipped, links never
    followed), or why the submission is refused (the first link or special file in the way)."""
    found: list[Path] = []
    for here, dirs, names in os.walk(folder, followlinks=False):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for name in sorted(names) + list(dirs):
            p = Path(here) / name
            if name.startswith("."):
                continue
            mode = os.lstat(p).st_mode
            if stat.S_ISREG(mode):
                if _named_as(p, kind):
                    found.append(p)
            elif not stat.S_ISDIR(mode) and _would_be_submission(p, mode, kind):
                return (), _refusal(p, mode)
    return tuple(sorted(found, key=lambda p: p.relative_to(folder).as_posix())), ""


def _would_be_submission(p: Path, mode: int, kind: SubmissionKind) -> bool:
    """A non-regular entry named like a submission file, or a link to a folder."""
    if _named_as(p, kind):
        return True
    return stat.S_ISLNK(mode) and p.is_dir()


def _refusal(p: Path, mode: int) -> str:
    kind = fileio.existing_kind(p) or "not a regular file"
    if stat.S_ISLNK(mode):
        kind += f" (to {os.readlink(p)})"
    return (f"{p}: {kind}: grade-class reads only regular files inside the class folder and never follows "
            f"a link; refused without reading it")


# ---------------------------------------------------------------------------- grading
def grade_class(stand: str, task: str, folder: str | Path, out_dir: str | Path,
                jobs: Optional[int] = None, time_limit_s: float = DEFAULT_TIME_LIMIT_S,
                on_result: Optional[Callable[[StudentResult, int, int], None]] = None,
                grade_one: GradeOne = grade, start_method: Optional[str] = None,
                memory_limit_mib: Optional[int] = DEFAULT_MEMORY_LIMIT_MIB,
                scheduler: Optional[str] = None, explore: Optional[int] = 0,
                reference: Optional[Sequence[str]] = None) -> ClassReport:
    """Grade every submission in `folder` on `task` of `stand`. `on_result(result, done,
    total)` is called as each student finishes (progress). `grade_one` is `grade` (tests
    substitute one that crashes or hangs); `start_method` forces how grading processes start
    (default: see `_context`). Each student is graded in a process of its own, held to
    `time_limit_s` and `memory_limit_mib` (None: no memory limit); `scheduler` (a Dask
    distributed scheduler's address) sends that work to a cluster instead of this machine.
    `explore` and `reference` are `grade`'s: each student's program is also explored against
    the task's model answer (None: the stand's budget, as `plclab grade-class` does; 0: not).

    Writes nothing in `out_dir` (it only checks it can): the traces wait in a temporary
    folder; `write_class_outputs` writes the three result files, then moves the traces. A
    SIGTERM, SIGINT or SIGHUP stops every grading process, removes every temporary folder and
    raises ClassInterrupted holding the students graded so far.
    """
    requirements = requirement_table(stand, task)         # unknown stand / task: one line, before any work
    column, note = _exploration_column(stand, task, explore, reference)
    if column is None and explore != 0:
        explore = 0                                       # nothing to explore against: the note says why
    requirements += [column] if column else []
    kind = requirement_set(stand, task).submission
    if jobs is not None and jobs < 1:
        raise PlcLabError(f"grade-class: --jobs must be at least 1 (got {jobs})")
    if not time_limit_s > 0:
        raise PlcLabError(f"grade-class: the time limit must be more than 0 s (got {time_limit_s:g})")
    if memory_limit_mib is not None and memory_limit_mib < 1:
        raise PlcLabError(f"grade-class: the memory limit must be at least 1 MiB (got {memory_limit_mib})")
    check_class_outputs(out_dir)                          # a bad --out: one line, before the work
    out = Path(out_dir).resolve()
    submissions, ignored = find_submissions(folder, exclude=[out], kind=kind)
    check_class_outputs(out_dir, probe=True)              # a read-only or full --out, too
    started = datetime.now(timezone.utc).replace(tzinfo=None, microsecond=0).isoformat()
    title = task_title(stand, task)
    staging = Path(tempfile.mkdtemp(prefix="plclab-class-"))
    report = ClassReport(stand, task, title, requirements, [], ignored, started, kind.suffix, staging,
                         len(submissions), [note] if note else [])
    cleanup = weakref.finalize(report, shutil.rmtree, str(staging), True)   # if never written out
    limits = _Limits(time_limit_s, memory_limit_mib)
    real_grader = grade_one is grade
    seed = class_seed(stand, task, str(folder)) if explore != 0 else None
    plays: Optional[str] = None
    if real_grader and (explore != 0 or reference):
        # every student under the class's scripts; the model answer's play of each shared (issue 30)
        plays = tempfile.mkdtemp(prefix="plclab-class-plays-", dir=_fast_tmp()) if explore != 0 else None
        grade_one = functools.partial(grade, reference=list(reference or ()) or None, explore=explore,
                                      explore_options=ExploreOptions(seed=seed, model_plays=plays))
    with _stop_signals_raise() as stopped:      # a second signal is ignored until the cleanup is done
        try:
            try:
                if scheduler is None:
                    if real_grader:               # builds the parser once, before forking
                        grade_sources(stand, task, [("warm-up.st", "")])
                    _run_parallel(stand, task, submissions, out, staging, jobs or os.cpu_count() or 1, limits,
                                  on_result, grade_one, _context(start_method), kind, report.results)
                else:
                    if not real_grader:
                        raise PlcLabError("grade-class: a cluster grades with the real grader only "
                                          "(grade_one is for tests)")
                    _run_on_cluster(scheduler, stand, task, submissions, out, staging, limits, on_result,
                                    kind, report.results, explore, _reference_sources(stand, task, explore, reference),
                                    seed)
            except _Stop:
                report.results.sort(key=lambda r: r.student)
                raise ClassInterrupted(stopped[0], report) from None
        except BaseException:
            cleanup()                             # interrupted or failed: no temporary folder stays
            report.staging = None
            raise
        finally:
            if plays is not None:
                shutil.rmtree(plays, ignore_errors=True)
    report.results.sort(key=lambda r: r.student)
    return report


@dataclass(frozen=True)
class _Limits:
    time_s: float
    memory_mib: Optional[int]

    def time_message(self) -> str:
        return (f"not graded: grading took longer than the time limit of {self.time_s:g} s and was stopped "
                f"(an endless or very slow program? grade it alone with `plclab grade`, or raise --time-limit)")


class _Stop(BaseException):
    """Raised by the signal handlers inside grade_class (a BaseException: no `except Exception`
    on the way may swallow it)."""


@contextlib.contextmanager
def _stop_signals_raise() -> Iterator[list[int]]:
    """While grading, SIGTERM / SIGINT / SIGHUP raise _Stop (the signal's number is put in the
    yielded list) so that the `finally` blocks stop every child and remove every temporary
    folder. Only the main thread can install handlers; elsewhere the defaults stay."""
    caught: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield caught
        return

    def handler(signum, _frame):
        if not caught:
            caught.append(signum)
            raise _Stop()

    old = {s: signal.signal(s, handler) for s in STOP_SIGNALS}
    try:
        yield caught
    finally:
        for s, h in old.items():
            signal.signal(s, h)


# ----------------------------------------------------------------- inside a grading process
def _isolate(scratch: str, memory_limit_mib: Optional[int], parent: int, time_limit_s: float) -> None:
    """First thing in a grading process: its own process group (the parent stops the group),
    killed if the parent (process `parent`) dies (Linux), default signal handlers (not the
    parent's), temporary files in `scratch` (removed by the parent whatever happens here), and
    the memory limit: `memory_limit_mib` more address space than the process has now (the
    grader, loaded, its parser's tables too: a parent's size must not eat a student's share)."""
    with contextlib.suppress(OSError):
        os.setsid()
    _die_with_parent(parent)
    for s in STOP_SIGNALS:
        signal.signal(s, signal.SIG_DFL)
    os.environ["TMPDIR"] = scratch
    tempfile.tempdir = scratch
    _dump_stack_if_stalled(time_limit_s)
    if memory_limit_mib is not None:
        load_parser()                    # the harness's tables: not the student's share
        limits.limit_memory(memory_limit_mib * 1024 * 1024)


def _die_with_parent(parent: int) -> None:
    """prctl(PR_SET_PDEATHSIG, SIGKILL): the kernel kills this process when its parent dies,
    even by SIGKILL (no handler of ours runs then); if the parent died before that, exit now.
    Linux only; elsewhere a no-op."""
    if not sys.platform.startswith("linux"):
        return
    with contextlib.suppress(Exception):
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGKILL), 0, 0, 0)   # 1 = PR_SET_PDEATHSIG
    if os.getppid() != parent:
        os._exit(1)


STALL_DUMP_ENV = "PLCLAB_STALL_DUMP"
"""A folder: a grading process still running near the end of its time limit (_stall_after)
writes every thread's Python stack there (stall-PID.txt), for finding out where a grading that
ran out of time was (the test suite sets it and shows the file with the failing test)."""
_stall_file = None               # kept open for faulthandler's watchdog, which writes to it


def _stall_after(time_limit_s: float) -> float:
    """When a grading process dumps its stack: a second before its time limit (90 % of a limit
    under 10 s, half of one under 2 s), so the dump is written before the parent stops it."""
    return max(time_limit_s * 0.5, min(time_limit_s * 0.9, time_limit_s - 1.0))


def _dump_stack_if_stalled(time_limit_s: float) -> None:
    """Arm faulthandler's watchdog (a C thread: it writes even while the main thread holds the
    GIL in C code) when STALL_DUMP_ENV names a folder. Before the memory limit: the thread's
    stack is the grader's, not the student's share."""
    global _stall_file
    folder = os.environ.get(STALL_DUMP_ENV)
    if not folder or time_limit_s <= 0:
        return
    import faulthandler
    with contextlib.suppress(OSError):
        _stall_file = open(os.path.join(folder, f"stall-{os.getpid()}.txt"), "w", encoding="utf-8")
        after = _stall_after(time_limit_s)
        _stall_file.write(f"a grading process (pid {os.getpid()}) still running {after:g} s into its time limit "
                          f"of {time_limit_s:g} s:\n")
        _stall_file.flush()
        faulthandler.dump_traceback_later(after, file=_stall_file)


def _grade_isolated(grade_one: GradeOne, stand: str, task: str, files: list[str],
                    out_dir: str) -> tuple[str, object]:
    """The grading itself, in the submission's own process: ("report", report), ("memory",
    None) when the memory limit was reached, or ("not graded", why)."""
    try:
        return _outcome(grade_one, stand, task, files, out_dir)
    except MemoryError:      # at the limit, telling what went wrong ran out of memory too
        return "memory", None


def _outcome(grade_one: GradeOne, stand: str, task: str, files: list[str], out_dir: str) -> tuple[str, object]:
    try:
        report = grade_one(stand, task, files, out_dir)
        return ("memory", None) if _ran_out_of_memory(report) else ("report", report)
    except MemoryError:
        return "memory", None
    except PlcLabError as e:
        return "not graded", f"not graded: {e}"
    except BaseException as e:     # a grader bug: reported in the student's row, never charged to them
        if limits.at_memory_limit():     # ... unless C code failed an allocation at the limit (a SystemError)
            return "memory", None
        last = traceback.extract_tb(e.__traceback__)[-1:] or [None]
        where = f" at {Path(last[0].filename).name}:{last[0].lineno}" if last[0] else ""
        return "not graded", (f"not graded: the grader failed on this submission ({type(e).__name__}: {e}{where}); "
                              f"this is a harness problem, not a verdict on the program")


def _pickled(outcome: tuple[str, object]) -> bytes:
    """The outcome as the parent receives it; at the limit, where even that takes more memory
    than is left, the limit."""
    try:
        return pickle.dumps(outcome)
    except MemoryError:
        return pickle.dumps(("memory", None))


def _ran_out_of_memory(report: GradeReport) -> bool:
    """A MemoryError the grading turned into a row instead of raising it: the runtime records
    one in a scan as an internal fault ("PLC STOPPED by an internal error of plclab ...:
    MemoryError"), which stops the scenario; the engine records one in a check as a grader
    error. Under the process limit it is the limit. (Only these two forms: a student's
    identifier named MemoryError in a compile error is not the limit.)"""
    for r in report.rows:
        if r.passed:
            continue
        if r.internal and ("(MemoryError" in r.observed or limits.at_memory_limit()):
            return True
        if "internal error of plclab" in r.observed and (" s: MemoryError" in r.observed or limits.at_memory_limit()):
            return True
    return False


def _grade_in_child(conn, grade_one: GradeOne, stand: str, task: str, files: list[str],
                    out_dir: str, scratch: str, memory_limit_mib: Optional[int], parent: int,
                    time_limit_s: float) -> None:
    """Runs in the submission's own (forked) process: the outcome down the pipe."""
    _isolate(scratch, memory_limit_mib, parent, time_limit_s)
    try:
        conn.send_bytes(_pickled(_grade_isolated(grade_one, stand, task, files, out_dir)))
    finally:
        conn.close()


def memory_report(stand: str, task: str, files: Sequence[str], memory_limit_mib: Optional[int]) -> GradeReport:
    """The verdict on a program that reached the memory limit: a FAIL of that student."""
    req = requirement_set(stand, task)
    return GradeReport(stand, task, req.title, [str(f) for f in files], noun=req.submission.noun,
                       unreadable="the program was stopped:",
                       errors=[f"memory limit of {memory_limit_mib} MiB exceeded (the program declares or uses more "
                               f"memory than a program may here; see docs/grading.md, --memory-limit)"])


def _context(start_method: Optional[str] = None):
    """Fork (cheap: the parent has the grader loaded and warm) when that is safe, i.e. the
    parent runs no other thread; otherwise spawn, a fresh interpreter per submission (which
    gets the parent's sys.path, so a `grade_one` from any importable module works)."""
    if start_method is None:
        fork_ok = "fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1
        start_method = "fork" if fork_ok else "spawn"
    return multiprocessing.get_context(start_method)


# ----------------------------------------------------------------- this machine
@dataclass
class _Running:
    submission: Submission
    process: multiprocessing.process.BaseProcess
    conn: object
    started: float
    work: Path                       # staging/<n>: tmp/ (scratch) and traces/


def _kill(process) -> None:
    """SIGKILL the grading process's group (it and anything it started), then the process."""
    with contextlib.suppress(OSError, TypeError):
        os.killpg(process.pid, signal.SIGKILL)
    with contextlib.suppress(OSError, AttributeError):
        process.kill()
    process.join()


def _run_parallel(stand: str, task: str, submissions: list[Submission], out: Path, staging: Path, jobs: int,
                  limits: _Limits, on_result, grade_one: GradeOne, ctx,
                  handed_in: SubmissionKind, results: list[StudentResult]) -> None:
    pending = deque(enumerate(submissions))
    running: list[_Running] = []

    def finish(job: _Running, kind: str, value) -> None:
        with contextlib.suppress(OSError, TypeError):
            os.killpg(job.process.pid, signal.SIGKILL)   # done: it and anything it left running
        job.process.join(timeout=5)
        if job.process.is_alive():
            _kill(job.process)
        job.conn.close()
        shutil.rmtree(job.work / "tmp", ignore_errors=True)
        running.remove(job)
        _record(results, job.submission, kind, value, job.work / "traces", out, limits, handed_in, stand, task,
                time.monotonic() - job.started, on_result, len(submissions))

    try:
        while pending or running:
            while pending and len(running) < jobs:
                n, sub = pending.popleft()
                if not sub.files:                    # nothing to run: a verdict without a process
                    _record(results, sub, "nothing", None, None, out, limits, handed_in, stand, task, 0.0,
                            on_result, len(submissions))
                    continue
                work = staging / f"{n:05d}"
                (work / "tmp").mkdir(parents=True)
                receive, send = ctx.Pipe(duplex=False)
                p = ctx.Process(target=_grade_in_child, name=f"grade-{sub.student}", daemon=True,
                                args=(send, grade_one, stand, task, [str(f) for f in sub.files],
                                      str(work / "traces"), str(work / "tmp"), limits.memory_mib, os.getpid(),
                                      limits.time_s))
                p.start()
                running.append(_Running(sub, p, receive, time.monotonic(), work))   # at once: stopped if we are
                send.close()
            if not running:
                continue
            next_deadline = min(j.started for j in running) + limits.time_s
            wait([j.conn for j in running] + [j.process.sentinel for j in running],
                 timeout=max(0.0, next_deadline - time.monotonic()))
            for job in list(running):
                if job.conn.poll():
                    try:
                        kind, value = job.conn.recv()
                    except (EOFError, OSError):
                        finish(job, "not graded", _died(job.process))
                        continue
                    finish(job, kind, value)
                elif not job.process.is_alive():
                    finish(job, "not graded", _died(job.process))
                elif time.monotonic() - job.started > limits.time_s:
                    _kill(job.process)
                    finish(job, "not graded", limits.time_message())
    finally:
        for job in running:                      # interrupted: stop what we started
            _kill(job.process)


def _record(results: list[StudentResult], sub: Submission, kind: str, value, traces: Optional[Path], out: Path,
            limits: _Limits, handed_in: SubmissionKind, stand: str, task: str, seconds: float, on_result,
            total: int) -> None:
    """One student's outcome as a StudentResult (its traces mapped to where OUT will hold
    them), appended to `results` and reported to `on_result`."""
    report: Optional[GradeReport] = None
    not_graded, staged = "", []
    if kind == "report":
        report = value
        final = out / TRACES_DIR / sub.student
        for scenario, files in report.traces.items():
            staged += [((traces or Path()) / p.name, final / p.name) for p in files]
            report.traces[scenario] = [final / p.name for p in files]
        # a note naming a trace file (exploration's replay line) names it where OUT will hold it,
        # not in the grading process's scratch folder (here or on a cluster's worker)
        for name in {dst.name for _src, dst in staged}:
            where = re.compile(r"\S*/" + re.escape(name) + r"(?=\s|$)")
            report.notes = [where.sub(str(final / name).replace("\\", "\\\\"), note) for note in report.notes]
    elif kind == "memory":
        report = memory_report(stand, task, sub.files, limits.memory_mib)
    elif kind == "nothing":
        title = task_title(stand, task)
        if sub.refused:
            report = GradeReport(stand, task, title, [], noun=handed_in.noun, unreadable="the submission is refused:",
                                 errors=[sub.refused])
        else:
            report = GradeReport(stand, task, title, [], noun=handed_in.noun, unreadable=handed_in.unreadable,
                                 errors=[f"{sub.source}: no {handed_in.suffix} file in this folder"])
    else:
        not_graded = value
    result = StudentResult(sub, report, not_graded, seconds, tuple(staged))
    results.append(result)
    if on_result is not None:
        on_result(result, len(results), total)


def _died(process) -> str:
    process.join(timeout=5)
    code = process.exitcode
    how = f"killed by signal {-code}" if code is not None and code < 0 else f"exit code {code}"
    return (f"not graded: the grading process died ({how}) before reporting; this is a harness "
            f"problem, not a verdict on the program")


# ----------------------------------------------------------------- a Dask cluster
def _run_on_cluster(address: str, stand: str, task: str, submissions: list[Submission], out: Path,
                    staging: Path, limits: _Limits, on_result, handed_in: SubmissionKind,
                    results: list[StudentResult], explore: Optional[int] = 0,
                    reference: Optional[list[tuple[str, str]]] = None, seed: Optional[int] = None) -> None:
    """Each submission is one task on the Dask cluster at `address`: a worker grades it in a
    process of its own (`grade_on_worker`: the same isolation and limits as on this machine)
    and returns the report with the trace files' bytes, staged here as local grading stages
    them. The program is read here (the workers need not see the class folder) under the names
    it has here, so a cluster's report is the report of grading on this machine. So is the
    model answer exploration plays against (`reference`, read here as (name, text) pairs)."""
    try:
        from dask.distributed import Client, as_completed
    except ImportError:                             # pragma: no cover - dask is a dependency
        raise PlcLabError("grade-class: --scheduler needs dask.distributed (pip install 'plclab[cluster]')") from None
    try:
        client = Client(address, timeout="5s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as e:
        raise PlcLabError(f"grade-class: --scheduler {address}: cannot reach the Dask scheduler ({e})") from None
    futures = {}
    started: dict[int, float] = {}
    try:
        for n, sub in enumerate(submissions):
            if not sub.files:
                _record(results, sub, "nothing", None, None, out, limits, handed_in, stand, task, 0.0, on_result,
                        len(submissions))
                continue
            try:
                sources = read_sources(sub.files)
            except CompileError:                   # unreadable: the report `grade` gives, made here
                _record(results, sub, "report", grade(stand, task, [str(f) for f in sub.files]), None, out, limits,
                        handed_in, stand, task, 0.0, on_result, len(submissions))
                continue
            future = client.submit(grade_on_worker, stand, task, sources, limits.time_s, limits.memory_mib,
                                   explore, reference, seed,
                                   key=f"plclab-grade-{n}-{uuid.uuid4().hex}", pure=False)
            futures[future] = (n, sub)
            started[n] = time.monotonic()
        for future in as_completed(list(futures), loop=client.loop):
            n, sub = futures[future]
            try:
                kind, value, traces = future.result()
            except Exception as e:                  # a worker lost, a cluster problem: never the student's
                kind, value, traces = "not graded", (f"not graded: the cluster failed on this submission "
                                                     f"({type(e).__name__}: {e}); this is a harness problem, "
                                                     f"not a verdict on the program"), {}
            work = staging / f"{n:05d}" / "traces"
            work.mkdir(parents=True, exist_ok=True)
            for name, data in traces.items():
                (work / Path(name).name).write_bytes(data)
            _record(results, sub, kind, value, work, out, limits, handed_in, stand, task,
                    time.monotonic() - started[n], on_result, len(submissions))
    finally:
        with contextlib.suppress(Exception):
            client.cancel(list(futures))
        with contextlib.suppress(Exception):
            client.close(timeout=5)


def _exploration_column(stand: str, task: str, explore: Optional[int],
                        reference: Optional[Sequence[str]]) -> tuple[Optional[tuple[str, str]], str]:
    """The exploration row's column (E1, its requirement) when every student is explored, or
    None and, where exploration was asked for but cannot run, the one line saying why (the
    same reason `plclab grade` gives: no model answer in an installed package)."""
    from plclab.grader.explore import EXPLORE_ID, model_answer, row_text
    from plclab.stands.base import stand_spec
    expl = stand_spec(stand).explore
    if explore == 0 or expl is None or task not in expl.references:
        return None, ""
    model, why = model_answer(stand, task, reference)
    if model is None:
        return None, f"exploration not run: {why}"
    return (EXPLORE_ID, row_text(expl, task)), ""


def _reference_sources(stand: str, task: str, explore: Optional[int],
                       reference: Optional[Sequence[str]]) -> Optional[list[tuple[str, str]]]:
    """The model answer exploration plays against, read on this machine for a cluster's workers
    (a worker installed from the wheel has no solutions/): the course's `reference` files, else
    the checkout's model answer; None when nothing is explored or there is none here (the
    worker's report then says why exploration did not run)."""
    if explore == 0 and not reference:
        return None
    if reference:
        return read_sources(reference)
    from plclab.grader.explore import model_answer
    model, _why = model_answer(stand, task, None)
    return list(model.sources) if model is not None else None


def _write_reference(reference: list[tuple[str, str]], folder: Path) -> list[str]:
    """The model answer's (name, text) pairs as files for `grade`'s `reference` (numbered: two
    pairs may share a name such as a generated configuration's)."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for n, (name, text) in enumerate(reference):
        stem = "".join(c if c.isalnum() or c in "._-" else "_" for c in Path(name.strip("<>")).name) or "part.st"
        path = folder / f"{n:02d}_{stem if stem.endswith('.st') else stem + '.st'}"
        path.write_text(text, encoding="utf-8")
        paths.append(str(path))
    return paths


def grade_on_worker(stand: str, task: str, sources: list[tuple[str, str]], time_limit_s: float,
                    memory_limit_mib: Optional[int], explore: Optional[int] = 0,
                    reference: Optional[list[tuple[str, str]]] = None,
                    seed: Optional[int] = None) -> tuple[str, object, dict[str, bytes]]:
    """A Dask task: grade one program in a fresh process of its own on this worker (a Dask
    worker may not fork children of its own, and runs tasks in threads), held to the time and
    memory limits; returns (kind, value, trace files by name)."""
    work = Path(tempfile.mkdtemp(prefix="plclab-class-"))
    try:
        (work / "tmp").mkdir()
        payload = pickle.dumps((stand, task, sources, str(work / "traces"), str(work / "tmp"), memory_limit_mib,
                                time_limit_s, os.getpid(), explore, reference, seed))
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p), "TMPDIR": str(work / "tmp")}
        child = subprocess.Popen([sys.executable, "-c", "from plclab.grader.classroom import _worker_child; "
                                  "_worker_child()"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                 stderr=subprocess.DEVNULL, env=env, start_new_session=True)
        try:
            answer, _ = child.communicate(payload, timeout=time_limit_s)
        except subprocess.TimeoutExpired:
            return "not graded", _Limits(time_limit_s, memory_limit_mib).time_message(), {}
        finally:
            with contextlib.suppress(OSError):
                os.killpg(child.pid, signal.SIGKILL)
            child.wait()
        try:
            kind, value = pickle.loads(answer)
        except Exception:
            how = f"killed by signal {-child.returncode}" if child.returncode < 0 else f"exit code {child.returncode}"
            return "not graded", (f"not graded: the grading process died ({how}) before reporting; this is a "
                                  f"harness problem, not a verdict on the program"), {}
        traces = {}
        if kind == "report":
            traces = {p.name: p.read_bytes() for files in value.traces.values() for p in files}
        return kind, value, traces
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _worker_child() -> None:
    """The grading process a Dask worker starts: the arguments pickled on stdin, the outcome
    pickled on stdout (a report of our own grader: trusted data between our processes)."""
    (stand, task, sources, traces, scratch, memory_limit_mib, time_limit_s, parent, explore,
     reference, seed) = pickle.loads(sys.stdin.buffer.read())
    out = sys.stdout.buffer
    _isolate(scratch, memory_limit_mib, parent, time_limit_s)
    reference_files = _write_reference(reference, Path(scratch) / "reference") if reference else None

    def grade_read(stand: str, task: str, _files, out_dir) -> GradeReport:
        return grade_sources(stand, task, sources, out_dir, reference_files, explore, ExploreOptions(seed=seed))

    result = _grade_isolated(grade_read, stand, task, [name for name, _ in sources], traces)
    out.write(_pickled(result))
    out.flush()
    # the parent takes the outcome at this process's end: no interpreter teardown to wait for
    # (nothing is left to clean up here; the parent removes the scratch folder)
    os._exit(0)


# ---------------------------------------------------------------------------- one row per requirement
@dataclass(frozen=True)
class Cell:
    """One student's verdict on one requirement, as every output shows it."""

    requirement: str
    result: str                      # PASS / FAIL / NOT CHECKED / ERROR
    message: str                     # empty for a pass; at most MAX_MESSAGE_CHARS (plus the cut's note)
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
    if row.steps:                  # exploration: the shortest console history that shows it
        parts.append("console steps: " + " ".join(step.strip() for step in row.steps))
    if row.lines:                  # the student's statements where the mistake most likely is
        parts.append("where to look: " + " | ".join(f"{n}. {line}" for n, line in enumerate(row.lines, 1)))
    if row.written:
        parts.append(row.written)
    return "; ".join(parts)


def cells(result: StudentResult, requirements: Sequence[tuple[str, str]]) -> list[Cell]:
    """One cell per requirement, whatever happened to the submission."""
    report = result.report
    if report is None:
        return [Cell(rid, "ERROR", clip(result.not_graded)) for rid, _ in requirements]
    if report.errors:              # nothing was checked: the program's own failure, on every row
        heading = result.submission.files or result.submission.refused
        why = clip("not checked: " + (f"{report.unreadable} " if heading else "") + "; ".join(report.errors))
        return [Cell(rid, "FAIL", why) for rid, _ in requirements]
    by_id = {r.id: r for r in report.rows}
    out = []
    for rid, _ in requirements:
        row = by_id.get(rid)
        if row is None:
            out.append(Cell(rid, "ERROR", f"not graded: the grader's report has no row {rid}"))
        else:
            out.append(Cell(rid, row.result, clip(row_message(row)),
                            tuple(report.traces.get(row.scenario, ())) if row.result == "FAIL" else ()))
    return out


# ---------------------------------------------------------------------------- the three outputs
def results_csv(report: ClassReport) -> str:
    """One row per requirement per student. Every field that a spreadsheet would take for a
    formula (it starts with = + - @, a tab or a carriage return: a student named
    `=HYPERLINK(...)`) gets a leading single quote, as OWASP advises against CSV injection."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["student", "requirement", "result", "message"])
    for r in report.results:
        for c in cells(r, report.requirements):
            w.writerow([csv_field(r.student), csv_field(c.requirement), c.result, csv_field(c.message)])
    return buf.getvalue()


FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def csv_field(text: str) -> str:
    """`text` as a spreadsheet shows it, never runs it: a leading single quote when it starts
    like a formula (OWASP, CSV injection)."""
    return "'" + text if text.startswith(FORMULA_STARTS) else text


def junit_xml(report: ClassReport, hostname: str = "localhost") -> bytes:
    """JUnit XML as Ant's XMLJUnitResultFormatter writes it (the form Jenkins, GitLab and LMS
    importers read): <testsuites> of one <testsuite> per student, each with <properties>, one
    <testcase> per requirement (a <failure> for FAIL, an <error> for not graded, <skipped> for
    NOT CHECKED), <system-out> holding the student's grade table (cut at MAX_REPORT_CHARS) and
    <system-err>."""
    suites = etree.Element("testsuites", name=f"plclab grade-class {report.stand} {report.task}")
    totals = {"tests": 0, "failures": 0, "errors": 0}      # <testsuites> has no "skipped" (junit-10.xsd)
    for i, r in enumerate(report.results):
        row_cells = cells(r, report.requirements)
        n_fail = sum(c.result == "FAIL" for c in row_cells)
        n_err = sum(c.result == "ERROR" for c in row_cells)
        n_skip = sum(c.result == NOT_CHECKED for c in row_cells)
        suite = etree.SubElement(suites, "testsuite", {
            "name": r.student, "package": f"{report.stand}.{report.task}", "id": str(i),
            "hostname": hostname, "timestamp": report.started or "1970-01-01T00:00:00",
            "tests": str(len(row_cells)), "failures": str(n_fail), "errors": str(n_err), "skipped": str(n_skip),
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
            elif c.result == NOT_CHECKED:
                etree.SubElement(case, "skipped", message=_xml_safe(c.message))
        out_text = r.report.text() if r.report else r.not_graded
        etree.SubElement(suite, "system-out").text = _xml_safe(clip(out_text, MAX_REPORT_CHARS))
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
td.NOT_CHECKED { background: #e6e6e6; max-width: 22em; font-size: 0.85em; }
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
                 f"{counts['ERROR']} not graded. Graded {e(report.started)} UTC. NOT CHECKED: an earlier "
                 f"failure stopped the scenario before this requirement was checked (not a pass).</p>")
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
                what = r.report.unreadable if r.submission.files or r.submission.refused else "nothing to grade:"
                text = what + "\n" + "\n".join(clip(err) for err in r.report.errors[:20])
            tr.append(f'<td class="{cls}" colspan="{len(ids)}"><pre>{e(text)}</pre></td>')
        else:
            for c in row_cells:
                if c.result == "PASS":
                    tr.append('<td class="PASS">PASS</td>')
                    continue
                links = " ".join(f'<a href="{e(_link(p, out), quote=True)}">{e(p.suffix[1:])}</a>'
                                 for p in c.traces)
                trace = f"<br>traces: {links}" if links else ""
                tr.append(f'<td class="{c.result.replace(" ", "_")}"><b>{c.result}</b> {e(c.message)}{trace}</td>')
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
    atomically through plclab.fileio, then the traces into OUT/traces/<student>/: the verdicts
    first, so a disk that fills up costs traces, never verdicts. Nothing else there is
    replaced, renamed or removed. Returns the three result files; a trace that cannot be
    written is an OutputError raised after the verdicts were written."""
    out = Path(out_dir)
    contents = {"results.csv": results_csv(report).encode("utf-8"),
                "junit.xml": junit_xml(report),
                "report.html": report_html(report, out).encode("utf-8")}
    targets = check_class_outputs(out)
    for t in targets:
        fileio.write_bytes(t, contents[t.name])
    try:
        _move_traces(report)
    finally:
        if report.staging is not None:
            shutil.rmtree(report.staging, ignore_errors=True)
            report.staging = None
    return targets


def _move_traces(report: ClassReport) -> None:
    """Each staged trace file to its place under OUT/traces (fileio's rules: a target that is
    not a regular file is refused); the first failure is raised once the others were tried."""
    failed: Optional[fileio.OutputError] = None
    for r in report.results:
        for staged, final in r.staged:
            try:
                fileio.check_output(final)
                final.parent.mkdir(parents=True, exist_ok=True)
                try:
                    os.replace(staged, final)          # same file system: a rename
                except OSError:
                    fileio.write_bytes(final, Path(staged).read_bytes())
            except fileio.OutputError as e:
                failed = failed or e
            except OSError as e:
                failed = failed or fileio.OutputError(f"{final}: cannot write: {e.strerror or e}")
    if failed is not None:
        raise fileio.OutputError(f"{failed}; the verdicts (results.csv, junit.xml, report.html) were written, "
                                 f"some traces were not")


def write_partial_results(report: ClassReport, out_dir: str | Path) -> Path:
    """An interrupted run's verdicts so far, in OUT/results.partial.csv: a previous complete
    run's results.csv, junit.xml, report.html and traces stay as they were."""
    return fileio.write_bytes(Path(out_dir) / PARTIAL_RESULTS, results_csv(report).encode("utf-8"))


def check_class_outputs(out_dir: str | Path, probe: bool = False) -> list[Path]:
    """The three result files in `out_dir`, each refused (one line) if it exists and is not a
    regular file; with `probe`, also a folder that cannot be written now (read-only, full):
    a bad --out is reported before a class is graded, not after."""
    targets = [Path(out_dir) / name for name in OUTPUT_FILES + (PARTIAL_RESULTS,)]
    for t in targets + [Path(out_dir) / TRACES_DIR / "student"]:     # traces/ must be a folder too
        fileio.check_output(t)
    if probe:
        fileio.check_writable(Path(out_dir))
    return targets[:len(OUTPUT_FILES)]


__all__ = ["ClassInterrupted", "ClassReport", "Cell", "StudentResult", "Submission", "cells", "csv_field",
           "find_submissions", "grade_class", "grade_on_worker", "junit_xml", "memory_report", "report_html",
           "results_csv", "row_message", "write_class_outputs", "write_partial_results"]
