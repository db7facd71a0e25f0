"""The grade report: one row per requirement, rendered as the table a student reads.

A row says what was checked in a sentence, PASS or FAIL, and for a failure what was
expected, what the program did instead and at which plant time, with the scenario whose
trace shows it. A program that does not compile has no rows: the report carries the
checker's `file:line:col: error: ...` lines instead.
"""
from __future__ import annotations

import textwrap
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

WIDTH = 100          # the table fits a terminal of this width
ID_WIDTH = 6
NOT_CHECKED = "NOT CHECKED"
RESULT_WIDTH = len(NOT_CHECKED)   # the widest result


MAX_QUOTE = 2000     # a message quotes at most this many characters of what it shows


def clip(text: str, limit: int = MAX_QUOTE) -> str:
    """`text` cut to `limit` characters, saying how much was left out: a message never
    repeats a student's 1 MB identifier whole."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text) - limit} more characters not shown)"


@dataclass(frozen=True)
class Row:
    """The verdict on one requirement."""

    id: str
    text: str                        # what is checked, as the student reads it
    passed: bool
    expected: str = ""               # for a failure: what the requirement wants ...
    observed: str = ""               # ... and what the program did
    time: Optional[float] = None     # plant time of the observation (s)
    scenario: str = ""               # which scenario (trace) shows it
    internal: bool = False           # not checked because the grader failed: not the student's fault
    unchecked: bool = False          # not checked because an earlier failure stopped its scenario
    steps: tuple[str, ...] = ()      # exploration: the shortest console history that shows it
    lines: tuple[str, ...] = ()      # the student's statements where the mistake most likely is, ranked
    written: str = ""                # where the differing output was last written (the message's last line)

    @property
    def result(self) -> str:
        """PASS; FAIL (the program's mistake); NOT CHECKED (an earlier failure stopped the
        scenario before this check: not a pass, not a second mistake); ERROR (the grader failed)."""
        if self.passed:
            return "PASS"
        return "ERROR" if self.internal else NOT_CHECKED if self.unchecked else "FAIL"


@dataclass
class GradeReport:
    stand: str
    task: str
    title: str                                       # e.g. "MP-9C pneumatic robot, Task 1: ..."
    files: list[str]
    rows: list[Row] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)  # compile errors: file:line:col: error: ... (or the log's)
    traces: dict[str, list[Path]] = field(default_factory=dict)   # scenario -> files written
    noun: str = "program"                            # what `files` are (the thermo SCADA tasks: "traffic log")
    unreadable: str = "the program does not compile:"   # heading over `errors` (a traffic log: "cannot be read")
    notes: list[str] = field(default_factory=list)   # lines after the verdict (how much exploration ran)

    @property
    def passed(self) -> bool:
        """True only if the program compiled and every requirement passed."""
        return not self.errors and bool(self.rows) and all(r.passed for r in self.rows)

    @property
    def grader_failed(self) -> bool:
        """Some requirement could not be judged because the grader itself failed."""
        return any(r.internal for r in self.rows)

    @property
    def exit_code(self) -> int:
        """0 all passed, 1 the program failed a requirement, 2 the grader failed (report it)."""
        return 0 if self.passed else 2 if self.grader_failed else 1

    def failed(self) -> list[Row]:
        return [r for r in self.rows if not r.passed]

    def row(self, rid: str) -> Row:
        for r in self.rows:
            if r.id == rid:
                return r
        raise KeyError(f"no requirement {rid!r} in this report (one of {', '.join(r.id for r in self.rows)})")

    def text(self) -> str:
        """The report as printed by `plclab grade`."""
        out = [self.title, f"{self.noun}: " + " ".join(self.files)]
        if self.errors:
            out.append(self.unreadable)
            out.extend(clip(e) for e in self.errors)
            out.append("FAIL")
            return "\n".join(out) + "\n"
        text_width = WIDTH - ID_WIDTH - RESULT_WIDTH - 4
        out.append("")
        out.append(f"{'id':<{ID_WIDTH}}  {'requirement':<{text_width}}  result")
        out.append(f"{'-' * ID_WIDTH}  {'-' * text_width}  {'-' * RESULT_WIDTH}")
        indent = " " * (ID_WIDTH + 2)
        for r in self.rows:
            lines = textwrap.wrap(r.text, text_width) or [""]
            out.append(f"{r.id:<{ID_WIDTH}}  {lines[0]:<{text_width}}  {r.result}")
            out.extend(indent + line for line in lines[1:])
            if not r.passed:
                detail_width = WIDTH - len(indent) - 10
                for label, value in (("expected", clip(r.expected)), ("observed", clip(r.observed))):
                    if value:
                        wrapped = textwrap.wrap(value, detail_width) or [""]
                        out.append(f"{indent}{label}: {wrapped[0]}")
                        out.extend(f"{indent}{' ' * (len(label) + 2)}{w}" for w in wrapped[1:])
                where = []
                if r.time is not None:
                    where.append(f"at t = {r.time:.2f} s")
                if r.scenario:
                    files = self.traces.get(r.scenario)
                    trace = f" ({', '.join(p.name for p in files)})" if files else ""
                    where.append(f"scenario '{r.scenario}'{trace}")
                if where:
                    out.append(f"{indent}{', '.join(where)}")
                if r.steps:
                    out.append(f"{indent}shortest console history that shows it:")
                    for step in r.steps:
                        wrapped = textwrap.wrap(step, detail_width) or [""]
                        out.append(f"{indent}  {wrapped[0]}")
                        out.extend(f"{indent}     {w}" for w in wrapped[1:])
                out.extend(_where_to_look(r, indent, detail_width))
        out.append("")
        n_pass = sum(r.passed for r in self.rows)
        verdict = "PASS" if self.passed else "FAIL"
        out.append(f"{n_pass} of {len(self.rows)} requirements passed: {verdict}")
        n_unchecked = sum(r.result == NOT_CHECKED for r in self.rows)
        if n_unchecked:
            out.append(f"{n_unchecked} requirement(s) NOT CHECKED: an earlier failure stopped their scenario; "
                       "fix the failures above and grade again")
        if self.grader_failed:
            n = sum(r.internal for r in self.rows)
            out.append(f"the grader itself failed on {n} requirement(s) (ERROR): not a mistake of your "
                       "program; please report it")
        out.extend(self.notes)
        written = [p for files in self.traces.values() for p in files]
        if written:
            folders = sorted({str(p.parent) for p in written})
            out.append(f"traces (CSV + VCD per scenario) in {', '.join(folders)}")
        return "\n".join(out) + "\n"


def _where_to_look(r: Row, indent: str, width: int) -> list[str]:
    """The ranked statements (plclab.grader.localize) and, last, the output's last writer."""
    out = []
    if r.lines:
        out.append(f"{indent}where to look, most likely first:")
        for n, line in enumerate(r.lines, 1):
            wrapped = textwrap.wrap(clip(line, 300), width) or [""]
            out.append(f"{indent}  {n}. {wrapped[0]}")
            out.extend(f"{indent}     {w}" for w in wrapped[1:])
    if r.written:
        wrapped = textwrap.wrap(clip(r.written, 300), width) or [""]
        out.append(f"{indent}{wrapped[0]}")
        out.extend(f"{indent}  {w}" for w in wrapped[1:])
    return out


def requirements_text(title: str, table: list[tuple[str, str]]) -> str:
    """What a task's grader checks, before any grading: the report's id and requirement
    columns, so a student reads the acceptance criteria in the words of the later rows."""
    width = WIDTH - ID_WIDTH - 2
    lines = [title, "", f"{'id':<{ID_WIDTH}}  requirement", f"{'-' * ID_WIDTH}  {'-' * width}"]
    for rid, text in table:
        wrapped = textwrap.wrap(text, width) or [""]
        lines.append(f"{rid:<{ID_WIDTH}}  {wrapped[0]}")
        lines += [f"{'':<{ID_WIDTH}}  {more}" for more in wrapped[1:]]
    return "\n".join(lines) + "\n"
