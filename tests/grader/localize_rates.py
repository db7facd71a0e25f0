"""How often a failing report names the student's changed line among its ranked candidates.

The one-mistake fixtures (tests/grader/fixtures/STAND/*.st from make_fixtures.py, and the
exploration mistakes of fixtures/explore/STAND from make_explore_fixtures.py) are each a
task's model answer with one mistake made by text edits: the lines those edits changed are
found by a line diff of the fixture against the bundle it was made from. Each fixture is
graded once (the scripted ones with their scenarios, the exploration ones with exploration);
a report names the line when one of its failing rows lists, among its ranked candidates
("where to look"), a statement that spans a changed line.

    .venv/bin/python tests/grader/localize_rates.py [NAME_PART...]    # per fixture, then the figure
"""
from __future__ import annotations

import difflib
import re
import sys
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import make_explore_fixtures as mef  # noqa: E402
import make_fixtures as mf  # noqa: E402
from explored import explored  # noqa: E402
from graded import graded_fixture  # noqa: E402

from plclab.stands import bundle, get_stand  # noqa: E402

ROBOTS = ("mp9c", "tur10")
_NAMED = re.compile(r":(\d+) `")
_ENDS = re.compile(r"(;|\bTHEN|\bELSE|\bDO|\bOF)\s*$", re.I)


@dataclass(frozen=True)
class Case:
    path: Path
    stand: str
    task: str
    base_text: str           # the bundle the fixture was made from
    explore: bool            # graded with exploration (a mistake only a console history shows)


def cases() -> list[Case]:
    out = []
    for f in mf.ALL_FIXTURES:
        if f.stand in ROBOTS:
            out.append(Case(mf.FIXTURES_DIR / f.stand / f"{f.name}.st", f.stand, f.task,
                            bundle(get_stand(f.stand), f.base), False))
    for f in mef.ALL:
        if not f.passes:
            out.append(Case(mef.path(f), f.stand, f.task, bundle(get_stand(f.stand), f.task), True))
    return out


def changed_lines(text: str, base: str) -> set[int]:
    """The fixture's lines (1-based) that its edits changed: not in an equal block of a line
    diff against the bundle it was made from (its header comment left out); where a line was
    only taken out, the lines before and after the gap."""
    a, b = base.splitlines(), text.splitlines()
    sm = difflib.SequenceMatcher(None, a, b, autojunk=False)
    header = next(n for n, line in enumerate(b, 1) if line.rstrip().endswith("*)"))
    out = set()
    for op, _a1, _a2, b1, b2 in sm.get_opcodes():
        if op == "delete":              # a line taken out: the statements around the gap
            out.update(n for n in (b1, b1 + 1) if n > header)
        elif op != "equal":
            out.update(n + 1 for n in range(b1, b2) if n + 1 > header and b[n].strip())
    return out


def statement_span(lines: list[str], first: int) -> range:
    """The lines of the ST statement that begins at line `first` (up to its ';' or THEN/ELSE/DO/OF)."""
    n = first
    while n < min(len(lines), first + 6):
        code = re.sub(r"\(\*.*?\*\)", "", lines[n - 1]).rstrip()
        if _ENDS.search(code):
            break
        n += 1
    return range(first, n + 1)


def measure(case: Case) -> tuple[bool, bool, str]:
    """(failed, named the changed line, what the report said).

    An exploration fixture's report is `plclab grade`'s: its scenarios' rows (with their
    candidates) and the exploration's row, whose candidates are its finding's. The exploration
    is the one the other test files make of the fixture (explored.py: once per test session)."""
    text = case.path.read_text(encoding="utf-8")
    report = graded_fixture(case.stand, case.task, case.path)
    said_rows = [(r.id, r.lines) for r in report.failed()]
    if case.explore:
        finding = explored(case.stand, case.task, case.path).finding
        if finding is not None:
            sources = [(str(case.path), text)]
            said_rows.append(("E1", tuple(c.where(sources) for c in finding.candidates)))
    if not said_rows:
        return False, False, "passed"
    changed = changed_lines(text, case.base_text)
    lines = text.splitlines()
    named = [int(m.group(1)) for _id, found in said_rows for line in found for m in [_NAMED.search(line)] if m]
    hit = any(set(statement_span(lines, n)) & changed for n in named)
    said = "; ".join(f"{rid}: " + " | ".join(found) for rid, found in said_rows if found) or "no candidates"
    return True, hit, said


def main(argv: list[str]) -> float:
    failing = hits = 0
    for case in cases():
        if argv and not any(a in str(case.path) for a in argv):
            continue
        failed, hit, said = measure(case)
        failing += failed
        hits += hit
        print(f"{'HIT ' if hit else 'MISS' if failed else 'PASS'} {case.stand}/{case.path.name}: {said}", flush=True)
    rate = hits / failing if failing else 0.0
    print(f"the changed line named in {hits} of {failing} failing reports ({100 * rate:.0f} %)", flush=True)
    return rate


if __name__ == "__main__":
    main(sys.argv[1:])
