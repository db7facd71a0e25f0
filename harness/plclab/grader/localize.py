"""Where the mistake most likely is: the student's statements a failing row's output depends on,
ranked.

The output that differs from the model answer's is followed back through the scans along its
dynamic dependences (data: which assignments its value came from; control: which conditions,
and which calls, those assignments ran under): a dynamic backward slice of a traced replay
(plclab.runtime.tracing). The statements on it are ranked:

* a program that keeps the starting program's structure (the handout's: most of its POUs'
  lines are still there): only the statements the student changed from it (a line diff per
  POU, matched by POU name) are candidates, nearest to the output first (fewest dependence
  steps), then the most suspicious by their spectrum (below);
* a program rewritten from scratch: every statement on the slice, ranked by how much more
  often it ran in the scans that showed the difference than in those that did not (Ochiai:
  ef / sqrt(F * (ef + ep))), nearest first among equals.

The output's last writer stays the report's last line: what a student reads first is where
to look, what they read last is where the value was written.

Nothing here knows a robot: a caller gives a session factory, how to play its scenario on a
session and when, and which output (a label of the I/O image) to follow.
"""
from __future__ import annotations

import ast
import bisect
import difflib
import functools
import itertools
import math
import operator
import re
from dataclasses import dataclass
from typing import Any, Callable, Optional, Sequence

from plclab.runtime.retain import MemoryRetainStore
from plclab.runtime.tracing import WILD, StateReader, StopReplay, Tracer, kept_out_of_gc, paths_overlap

MAX_CANDIDATES = 3
SCRATCH_SHARE = 0.5       # under this share of the starting program's lines kept: rewritten from scratch
WINDOW_S = 60.0           # s: how far back before the failure the replay is traced


@dataclass(frozen=True)
class Candidate:
    """One ranked statement: where it is, its text, and why it is suspected."""

    file: str
    line: int
    text: str
    pou: str
    distance: int          # dependence steps from the output's value
    suspicion: float       # Ochiai score over the traced scans (0..1)
    changed: bool          # changed from the starting program
    departed: Optional[float] = None   # when its values first departed from the model answer's

    def where(self, sources: Sequence[tuple[str, str]] = ()) -> str:
        """`FILE.st:LINE `statement`` or, for a drawn (ladder / FBD) program, its rung and element."""
        from pathlib import Path

        from plclab.frontend.graphical import drawing_location
        drawn = drawing_location(sources, self.file, self.line) if sources else None
        if drawn is not None:
            return f"{Path(self.file).name}: {drawn}"
        return f"{Path(self.file).name}:{self.line} `{self.text}`"


# --------------------------------------------------------------------------- what the student changed

_POU_START = re.compile(r"^\s*(FUNCTION_BLOCK|FUNCTION|PROGRAM|TYPE|CONFIGURATION)\b\s*(\w*)", re.I)
_POU_END = re.compile(r"^\s*END_(FUNCTION_BLOCK|FUNCTION|PROGRAM|TYPE|CONFIGURATION)\b", re.I)
_COMMENT = re.compile(r"\(\*.*?\*\)|//.*$")


def pou_lines(text: str) -> dict[str, list[tuple[int, str]]]:
    """The POUs of an ST text by name: their (line number, normalized text) lines, comments and
    blank lines left out (a TYPE block is named by its first type)."""
    out: dict[str, list[tuple[int, str]]] = {}
    current: Optional[str] = None
    in_comment = False
    pending_type = False
    for n, raw in enumerate(text.splitlines(), 1):
        line = raw
        if in_comment:
            end = line.find("*)")
            if end < 0:
                continue
            line, in_comment = line[end + 2:], False
        line = _COMMENT.sub(" ", line)
        if "(*" in line:
            line, in_comment = line[:line.index("(*")], True
        norm = " ".join(line.split())
        if not norm:
            continue
        if current is None:
            m = _POU_START.match(norm)
            if m:
                kind, name = m.group(1).upper(), m.group(2)
                if kind == "CONFIGURATION":
                    current = GLOBALS
                elif kind == "TYPE" and not name:
                    pending_type, current = True, "TYPE"
                else:
                    current = name or kind
                out.setdefault(current, [])
        elif pending_type:
            name = norm.split(":")[0].strip()
            out[name] = out.pop(current, [])
            current, pending_type = name, False
        if current is not None and current != GLOBALS:
            out[current].append((n, norm))
            if _POU_END.match(norm):
                current = None
        else:                                   # globals: a GVL file, the CONFIGURATION's VAR_GLOBAL
            out.setdefault(GLOBALS, []).append((n, norm))
            if current is not None and _POU_END.match(norm):
                current = None
    return out


GLOBALS = ""       # pou_lines' name for the lines outside any POU (compared as a set, not in order)


def changed_lines(student: Sequence[tuple[str, str]], start: Sequence[tuple[str, str]]) -> tuple[set, float]:
    """The student's (file, line) pairs that are not in the starting program's POU of the same
    name (a POU the starting program has not: all its lines; where lines were taken out, the
    lines around the gap), and the share of the starting program's lines the student kept
    (near 0: rewritten from scratch)."""
    start_pous: dict[str, list[str]] = {}
    for _name, text in start:
        for pou, lines in pou_lines(text).items():
            start_pous.setdefault(pou.upper(), [t for _n, t in lines])
    changed: set[tuple[str, int]] = set()
    kept = 0
    for name, text in student:
        for pou, lines in pou_lines(text).items():
            base = start_pous.get(pou.upper())
            if pou == GLOBALS:
                pool = set(base or ())
                kept += sum(t in pool for _n, t in lines)
                changed.update((name, n) for n, t in lines if t not in pool)
                continue
            if base is None:
                changed.update((name, n) for n, _t in lines)
                continue
            sm = difflib.SequenceMatcher(None, base, [t for _n, t in lines], autojunk=False)
            for op, _a1, _a2, b1, b2 in sm.get_opcodes():
                if op == "equal":
                    kept += b2 - b1
                elif op == "delete":        # lines taken out: the statements around the gap changed
                    changed.update((name, lines[k][0]) for k in (b1 - 1, b1) if 0 <= k < len(lines))
                else:
                    changed.update((name, lines[k][0]) for k in range(b1, b2))
    total = sum(len(v) for v in start_pous.values())
    return changed, (kept / total if total else 0.0)


# --------------------------------------------------------------------------- the slice

@dataclass
class Slice:
    """The events on the dependence path of the criterion: event id -> dependence steps, and the
    storage still wanted where the trace begins (values from before it: initial values)."""

    steps: dict[int, int]
    before: dict[tuple, int]


def backward_slice(tracer: Tracer, criterion: Sequence[tuple], mapped: Callable[[int], bool]) -> Slice:
    """The dynamic backward slice of the storage `criterion` (keys) as the trace ends: events are
    visited last-completed first; one that writes wanted storage, or that a sliced event ran
    under, joins the slice and wants what it read and the test (or call) it ran under. A
    whole-value write to exactly the wanted storage ends the want (a strong update); an array
    element or a standard FB's state only adds (a weak one). `mapped(line)`: whether a generated
    line is a student's statement (the plumbing between them adds no steps)."""
    wanted: dict[Any, dict[Any, int]] = {}          # object id (or 'L'/'R' key) -> path -> steps

    def want(k: tuple, d: int) -> None:
        if len(k) == 2 and not isinstance(k[0], str):
            paths = wanted.setdefault(k[0], {})
            if paths.get(k[1], 1 << 30) > d:
                paths[k[1]] = d
        else:
            paths = wanted.setdefault(k, {})
            if paths.get("", 1 << 30) > d:
                paths[""] = d

    for k in criterion:
        want(k, 0)
    want_events: dict[int, int] = {}
    steps: dict[int, int] = {}
    events = tracer.events
    for eid in reversed(tracer.order):
        e = events[eid]
        d = want_events.pop(eid, None)
        for k, strong in e.writes:
            if len(k) == 2 and not isinstance(k[0], str):
                paths = wanted.get(k[0])
                if not paths:
                    continue
                for p in list(paths):
                    if p == k[1] or paths_overlap(k[1], p):
                        d = paths[p] if d is None else min(d, paths[p])
                        if strong and p == k[1]:
                            del paths[p]
            else:
                paths = wanted.get(k)
                if paths:
                    d = paths[""] if d is None else min(d, paths[""])
                    if strong:
                        del wanted[k]
        if d is None:
            continue
        steps[eid] = d
        nd = d + (1 if mapped(e.line) else 0)
        for k in e.reads:
            want(k, nd)
        if e.parent is not None and want_events.get(e.parent, 1 << 30) > nd:
            want_events[e.parent] = nd
    before = {(o, p): d for o, paths in wanted.items() if not isinstance(o, (str, tuple)) for p, d in paths.items()}
    return Slice(steps, before)


@functools.lru_cache(maxsize=64)
def declaration_lines(source: str) -> dict[tuple[str, str], int]:
    """(generated class name, attribute) -> the generated line that gives it its initial value
    (`__init__`, or `_init_globals` for the globals object's class '_Globals'). Once per
    source text, read only."""
    out: dict[tuple[str, str], int] = {}
    tree = ast.parse(source)
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            for f in node.body:
                if isinstance(f, ast.FunctionDef) and f.name == "__init__":
                    for s in f.body:
                        if isinstance(s, ast.Assign) and isinstance(s.targets[0], ast.Attribute):
                            out.setdefault((node.name, s.targets[0].attr), s.lineno)
        elif isinstance(node, ast.FunctionDef) and node.name == "_init_globals":
            for s in node.body:
                if isinstance(s, ast.Assign) and isinstance(s.targets[0], ast.Attribute):
                    out.setdefault(("_Globals", s.targets[0].attr), s.lineno)
    return out


# --------------------------------------------------------------------------- two runs' states

class StateLog:
    """The program's state (plclab.runtime.tracing.state_walk) as each scan begins, kept as
    changes: path -> [(t, value)]; and the path of every object seen."""

    def __init__(self) -> None:
        self.changes: dict[str, list[tuple[float, Any]]] = {}
        self.paths: dict[int, str] = {}
        self._norm: Optional[dict[str, list[str]]] = None
        self._reader = StateReader()
        self._walks = -1                 # the reader's walk the names and values below are of
        self._names: list[str] = []
        self._values: list[Any] = []

    def record(self, t: float, plc: Any) -> None:
        reader = self._reader
        values = reader.values(plc)
        if reader.walks != self._walks:       # other objects (a restart...): compared by path
            self._walks = reader.walks
            self.paths.update(reader.paths)
            last = dict(zip(self._names, self._values))
            self._names = [path for _c, _k, path in reader.leaves]
            for k, v in zip(self._names, values):
                if k not in last or last[k] != v or type(last[k]) is not type(v):
                    self.changes.setdefault(k, []).append((t, v))
            self._norm = None
        elif values != self._values:
            # most scans change a few values of hundreds: a value still the same object is
            # unchanged (found in C), only the others are compared here
            old = self._values
            for n in itertools.compress(range(len(values)), map(operator.is_not, old, values)):
                a, v = old[n], values[n]
                if a != v or type(a) is not type(v):
                    self.changes.setdefault(self._names[n], []).append((t, v))
        self._values = values

    def value_at(self, path: str, t: float) -> Any:
        """The value `path` held at `t` (the last change at or before it; _MISSING before any).
        A change list is in time order, so the lookup bisects it (a ranking asks thousands of
        times, of lists as long as the scans of the window)."""
        changes = self.changes.get(path)
        if not changes:
            return _MISSING
        n = bisect.bisect_right(changes, t + 1e-9, key=_time_of)
        return changes[n - 1][1] if n else _MISSING

    def matching(self, pattern: str) -> list[str]:
        """The paths `pattern` names: itself, any element for '[]', and what lies under it."""
        if self._norm is None:
            self._norm = {}
            for p in self.changes:
                self._norm.setdefault(re.sub(r"\[\d+\]", "[]", p), []).append(p)
        out = []
        for norm, ps in self._norm.items():
            if norm == pattern or norm.startswith(pattern + ".") or norm.startswith(pattern + "["):
                out.extend(ps)
        return out


_MISSING = object()


def _time_of(change: tuple[float, Any]) -> float:
    return change[0]


def first_divergence(student: StateLog, model: StateLog, paths: Sequence[str], initial: bool = False) -> Optional[float]:
    """The first time any of `paths` holds another value in the student's run than in the model
    answer's (None: never, or no such path in the model answer's program). `initial`: only
    the values the runs began with (a declaration's initial value)."""
    best: Optional[float] = None
    for p in paths:
        if p not in model.changes:
            continue
        if initial:
            a, b = student.changes.get(p, [(0.0, _MISSING)])[0], model.changes[p][0]
            if not _same(a[1], b[1]):
                best = min(a[0], b[0]) if best is None else min(best, a[0], b[0])
            continue
        times = sorted({t for t, _v in student.changes.get(p, ())} | {t for t, _v in model.changes[p]})
        for t in times:
            if best is not None and t >= best:
                break
            a, b = student.value_at(p, t), model.value_at(p, t)
            if not _same(a, b):
                best = t
                break
    return best


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, bool) or isinstance(b, bool):
        return bool(a) == bool(b)
    if isinstance(a, float) or isinstance(b, float):
        return abs(a - b) <= 1e-6 * max(1.0, abs(a), abs(b))
    return a == b


# --------------------------------------------------------------------------- ranking

def ochiai(failed: int, passed: int, total_failed: int) -> float:
    """Ochiai's suspicion of a statement that ran in `failed` of `total_failed` failing units
    and in `passed` passing ones."""
    if failed == 0 or total_failed == 0:
        return 0.0
    return failed / math.sqrt(total_failed * (failed + passed))


def _pattern(base: str, path: str) -> str:
    if path == WILD or not path:
        return base
    return base + (path if path.startswith("[") else "." + path)


def rank(tracer: Tracer, sl: Slice, failing_scans: set[int], sources: Sequence[tuple[str, str]],
         changed: Optional[set], student: Optional[StateLog] = None, model: Optional[StateLog] = None,
         limit: int = MAX_CANDIDATES, inputs: frozenset = frozenset()) -> list[Candidate]:
    """The statements on slice `sl`, ranked (see the module docstring). `changed`: the
    student's changed (file, line)s, None for a program rewritten from scratch. A statement is
    changed when any of its lines is (the lines up to the next statement's). With both runs'
    states (`student`, `model`), a statement whose storage departs from the model answer's
    earlier ranks first (the first departure is the cause, the later ones its effects).
    `inputs`: storage keys the I/O image writes (a located input's declaration is never a
    candidate: what it reads is the stand's doing)."""
    compiled = tracer.compiled
    texts = {name: text.splitlines() for name, text in sources}
    first_lines: dict[str, list[int]] = {}
    for info in compiled.line_map.values():
        first_lines.setdefault(info.file, []).append(info.line)
    for v in first_lines.values():
        v.sort()

    def extent(file: str, line: int) -> range:
        lines = first_lines.get(file, [])
        i = bisect.bisect_right(lines, line)
        end = lines[i] if i < len(lines) else line + 1
        return range(line, min(end, line + 6))

    # spectrum: per statement, the scans it ran in
    by_line: dict[int, set[int]] = {}              # generated line -> scans (then by statement)
    for e in tracer.events.values():
        scans = by_line.get(e.line)
        if scans is None:
            scans = by_line[e.line] = set()
        scans.add(e.scan)
    ran: dict[tuple[str, int], set[int]] = {}
    for py_line, scans in by_line.items():
        info = compiled.where(py_line)
        if info is not None:
            ran.setdefault((info.file, info.line), set()).update(scans)
    total_failed = len(failing_scans)

    best: dict[tuple[str, int], list] = {}          # statement -> [steps, pou, written patterns, child stmts]
    obj_paths = student.paths if student is not None else {}

    def consider(py_line: int, d: int, writes: Sequence[tuple], parent_stmt: Optional[tuple]) -> Optional[tuple]:
        info = compiled.where(py_line)
        if info is None:
            return None
        k = (info.file, info.line)
        entry = best.setdefault(k, [d, info.pou, set(), set()])
        entry[0] = min(entry[0], d)
        for key in writes:
            if len(key) == 2 and key[0] in obj_paths:
                entry[2].add(_pattern(obj_paths[key[0]], key[1]))
        if parent_stmt is not None and parent_stmt != k and parent_stmt in best:
            best[parent_stmt][3].add(k)
        return k

    events = tracer.events
    for eid in sorted(sl.steps, key=lambda i: sl.steps[i], reverse=True):
        e = events[eid]
        parent = events.get(e.parent) if e.parent is not None else None
        pk = None
        if parent is not None:
            pi = compiled.where(parent.line)
            pk = (pi.file, pi.line) if pi is not None else None
        consider(e.line, sl.steps[eid], [k for k, _s in e.writes], pk)
    decls = declaration_lines(compiled.source)
    declared: set[tuple[str, int]] = set()           # declarations: judged by their initial values
    for (oid, path), d in sl.before.items():
        cls = tracer.types.get(oid)
        if (oid, path) in inputs:
            continue
        if cls is None:
            continue
        attr = re.split(r"[.\[]", path)[0] if path else ""
        line = decls.get((cls.__name__, attr))
        if line is not None:
            k = consider(line, d + 1, [(oid, attr)], None)
            if k is not None:
                declared.add(k)

    times: dict[tuple[str, int], Optional[tuple[float, int]]] = {}

    def departure(k: tuple) -> tuple[int, float, int]:
        """(0, t, own): its values depart from the model answer's at t (own 0: its storage, 1: a
        condition, by the statements it runs); (1, 0, 0): nothing to compare (a new variable);
        (2, 0, 0): it never departs."""
        if student is None or model is None:
            return 1, 0.0, 0
        if k not in times:
            times[k] = None                        # a cycle of conditions: nothing known
            patterns = best[k][2]
            if not patterns:
                known = [t for cls, t, _o in (departure(c) for c in best[k][3] if c != k) if cls == 0]
                times[k] = (min(known), 1) if known else None
            else:
                paths = [p for pat in patterns for p in student.matching(pat)]
                if any(p in model.changes for p in paths):
                    t = first_divergence(student, model, paths, initial=k in declared)
                    times[k] = (t if t is not None else float("inf"), 0)
        got = times[k]
        if got is None:
            return 1, 0.0, 0
        return (2, 0.0, 0) if got[0] == float("inf") else (0, got[0], got[1])

    out = []
    for (file, line), (d, pou, _w, _kids) in best.items():
        is_changed = changed is not None and any((file, n) in changed for n in extent(file, line))
        scans = ran.get((file, line), set())
        ef = len(scans & failing_scans)
        score = ochiai(ef, len(scans) - ef, total_failed)
        lines = texts.get(file, [])
        text = lines[line - 1].strip() if 0 < line <= len(lines) else ""
        dep = departure((file, line))
        out.append((dep, Candidate(file, line, text, pou, d, score, is_changed, dep[1] if dep[0] == 0 else None)))
    if changed is None:
        out.sort(key=lambda x: (-x[1].suspicion, x[0], x[1].distance, x[1].file, x[1].line))
        return [c for _k, c in out[:limit]]
    # departed at the same scan: a statement's own values before a condition's (which departs
    # by what it runs), the one further up the path first (values flow down it within the
    # scan); nothing to compare: nearest to the output first
    out.sort(key=lambda x: (x[0][0], x[0][1], x[0][2], -x[1].distance if x[0][0] == 0 else x[1].distance,
                            -x[1].suspicion, x[1].file, x[1].line))
    ranked = [c for _k, c in out if c.changed]
    # the first departure from the model answer, where the student left the starting program's
    # line as it was (a change the task needed and the student did not make)
    first = next((c for k, c in out if k[0] == 0), None)
    if first is not None and not first.changed:       # it comes before every changed one: the order
        ranked.insert(0, first)
    return ranked[:limit]


# --------------------------------------------------------------------------- a replay under the tracer

def starting_sources(stand: str) -> list[tuple[str, str]]:
    """The handout's starting program of `stand`: its POUs (one per file), then its globals."""
    from plclab.stands import get_stand
    s = get_stand(stand)
    gvl = [(str(p), p.read_text(encoding="utf-8")) for p in s.files(s.starting_variant)[-len(s.gvl):]] if s.gvl else []
    return s.pou_sources(s.starting_variant) + gvl


@dataclass
class Localized:
    candidates: list[Candidate]
    scratch: bool              # ranked as a program rewritten from scratch (spectrum first)
    output: str = ""           # the output label followed
    writer: Optional[tuple[str, int, str]] = None   # (file, line, statement) that last wrote it


Replay = Callable[[Any, Callable[[], None]], None]


def localize(student: Any, model: Optional[Any], replay: Replay, output: Optional[str], t_fail: float,
             sources: Sequence[tuple[str, str]], start: Optional[Sequence[tuple[str, str]]],
             window: float = WINDOW_S, hints: Sequence[str] = ()) -> Optional[Localized]:
    """Replay a failing run on session `student`, traced from `window` s before `t_fail` to the
    scan at `t_fail` (`replay(session, start_tracer)` plays the run and calls `start_tracer()`
    at its start or any time up to `t_fail - window`; it is stopped by StopReplay after
    `t_fail`), slice output label `output` (None: the output that differs from the model
    answer's at `t_fail`; of those, one of `hints` first, the outputs the failing row speaks of,
    and one of them when none differs: an adaptive scenario may see the model answer's stand
    at another point then) and rank its statements. `model`: a fresh session of the model answer,
    replayed the same way: its outputs tell the failing scans (the spectrum) and its state is
    compared with the student's (None: neither). `start`: the starting program's sources
    (None: unknown, ranked as a program rewritten from scratch)."""
    compiled = student.plc.compiled
    slog, mlog = StateLog(), StateLog()
    t0 = max(t_fail - window, 0.0)
    outs: list[dict[str, Any]] = []
    labels = [k for k in student.labels if output_attr(student, k) is not None]

    bound: list = [None, []]       # the PLC's bindings, and (label, owner, attribute) by them

    def sample() -> None:
        plc = student.plc
        slog.record(student.now, plc)
        if bound[0] is not plc.bindings:     # new objects: a restart
            bound[:] = [plc.bindings, [(k, *a) for k in labels if (a := output_attr(student, k)) is not None]]
        outs.append({k: getattr(owner, attr) for k, owner, attr in bound[1]})

    tracer = Tracer(compiled, lambda: student.now, sample=sample, since=t0, stop_at=t_fail)
    _traced(student, tracer, replay)
    if model is not None:
        _sampled(model, lambda: mlog.record(model.now, model.plc), t0, t_fail, replay)
    if output is not None:
        order = [output]
    else:
        named = [k for k in hints if k in labels]
        differ = differing_outputs(student, model, labels, t_fail) if model is not None else []
        order = [k for k in differ if k in named] + [k for k in differ if k not in named] + \
            [k for k in named if k not in differ]
    order = [k for k in order if output_attr(student, k) is not None]
    if not order or not tracer.order:
        return None
    changed: Optional[set] = None
    scratch = True
    if start is not None:
        ch, kept = changed_lines(sources, start)
        if kept >= SCRATCH_SHARE:
            changed, scratch = ch, False
    inputs = frozenset((id(b.owner), b.attr) for b in student.plc.bindings if b.is_input)
    first: Optional[Localized] = None
    for label in order[:MAX_OUTPUTS]:        # the first output whose path has a candidate
        found = _ranked(tracer, student, model, label, outs, sources, changed, scratch, slog, mlog, inputs)
        if found.candidates:
            return found
        first = first or found
    return first


MAX_OUTPUTS = 4          # outputs followed, in order, until one's path has a candidate


def _ranked(tracer: Tracer, student: Any, model: Optional[Any], output: str, outs: list, sources: Sequence[tuple[str, str]],
            changed: Optional[set], scratch: bool, slog: StateLog, mlog: StateLog, inputs: frozenset) -> Localized:
    compiled = tracer.compiled
    owner, attr = output_attr(student, output)
    # the failing scans: those that leave the output other than the model answer's (the value
    # read as the next scan begins)
    failing: set[int] = set()
    if model is not None and output in model.trace:
        failing = {n for n in range(len(tracer.scan_times) - 1)
                   if output in outs[n + 1] and not _same(model.trace.value_at(output, tracer.scan_times[n + 1]),
                                                          outs[n + 1][output])}
    sl = backward_slice(tracer, [(id(owner), attr)], lambda line: compiled.where(line) is not None)
    cands = rank(tracer, sl, failing, sources, changed, slog, mlog if model is not None else None, inputs=inputs)
    writer = None
    for eid in reversed(tracer.order):                 # the last statement that wrote the output
        if sl.steps.get(eid) == 0 and (info := compiled.where(tracer.events[eid].line)) is not None:
            texts = dict(sources).get(info.file, "").splitlines()
            writer = (info.file, info.line, texts[info.line - 1].strip() if 0 < info.line <= len(texts) else "")
            break
    return Localized(cands, scratch, output, writer)


def differing_outputs(student: Any, model: Any, labels: Sequence[str], t: float, back: float = 5.0) -> list[str]:
    """The output labels a failure at `t` may be about, most likely first: those that differ
    between the two runs' traces at `t` (the longest-standing difference first: a signal that
    toggles fast, a sensor bus, differs anew at every toggle), then those that differed in the
    `back` s before (the latest first)."""
    now: list[tuple[float, str]] = []
    before: list[tuple[float, str]] = []
    for k in labels:
        if k not in student.trace or k not in model.trace:
            continue
        times = sorted({ns / 1e9 for tr in (student.trace, model.trace) for ns, _v in tr.changes(k)
                        if t - back - 1e-9 <= ns / 1e9 <= t + 1e-9} | {t, t - back})
        began, last = None, None
        for x in times:
            if not _same(student.trace.value_at(k, x), model.trace.value_at(k, x)):
                began = x if began is None else began
                last = x
            else:
                began = None
        if last is None:
            continue
        if last >= t - 1e-9 and began is not None:
            now.append((began, k))
        else:
            before.append((-last, k))
    return [k for _t, k in sorted(now)] + [k for _t, k in sorted(before)]


class _TraceFrom:
    """A probe (Session.probes) that installs `tracer` as the first scan at or after its
    `since` is about to run. A tracer installed costs every Python call of the process (the
    plant's, the scenario's) from then on, and the scans before `since` are not recorded anyway."""

    def __init__(self, session: Any, tracer: Tracer) -> None:
        self.session, self.tracer = session, tracer
        self.started = False

    def step(self, _dt: float) -> None:
        if not self.started and self.session.now >= self.tracer.since - 1e-9:
            self.started = True
            self.tracer.start()

    def close(self) -> None:
        if self.started:
            self.tracer.stop()


class _SampleFrom:
    """A probe (Session.probes) that has `sample()` called as each scan at or after `since`
    begins, once the scan has read its inputs (where the line tracer's sample is taken: at
    the program's entry), and stops the replay at the first scan to begin after `stop_at`,
    as the tracer does; a replay that needs no lines so pays no tracer on every Python call.
    It reaches the scan through the PLC's own `read_inputs` (an instance attribute, as the
    lab's forces do), moved to the PLC of a restart."""

    def __init__(self, session: Any, sample: Callable[[], Any], since: float, stop_at: float) -> None:
        self.session, self.sample, self.since, self.stop_at = session, sample, since, stop_at
        self._plc: Any = None

    def step(self, _dt: float) -> None:
        plc = self.session.plc
        if plc is self._plc:
            return
        self.close()
        self._plc = plc
        read, session = plc.read_inputs, self.session

        def read_inputs() -> None:
            read()
            if not plc.runs_a_task_now():
                return                               # no program runs in this scan: no entry
            now = session.now
            if now > self.stop_at + 1e-9:
                raise StopReplay(now)
            if now >= self.since - 1e-9:
                self.sample()
        plc.read_inputs = read_inputs

    def close(self) -> None:
        if self._plc is not None:
            self._plc.__dict__.pop("read_inputs", None)


def _replayed(session: Any, hook: Any, replay: Replay) -> None:
    """`replay` on `session` with probe `hook` stepped from the replay's start (its `step`
    starts what it does when its window begins) to the StopReplay it or its tracer raises
    after the failure; then `hook.close()`."""
    def begin() -> None:
        if hook not in session.probes:
            session.add_probe(hook)
            hook.step(0.0)          # from the start of the replay when its window begins there

    try:
        replay(session, begin)
    except StopReplay:
        pass
    finally:
        hook.close()
        session.remove_probe(hook)
    session.run(0)          # no scan: the session's trace takes what its stand recorded up to the stop


def _traced(session: Any, tracer: Tracer, replay: Replay) -> None:
    """`replay` traced by `tracer` from its `since`."""
    _replayed(session, _TraceFrom(session, tracer), replay)


def _sampled(session: Any, sample: Callable[[], Any], since: float, stop_at: float, replay: Replay) -> None:
    """`replay` on `session` with `sample()` called as each scan from `since` on begins (after
    its inputs are read), stopped after `stop_at`: what `_traced` does with a tracer that
    follows no lines, without the tracer."""
    _replayed(session, _SampleFrom(session, sample, since, stop_at), replay)


def output_attr(session: Any, label: str) -> Optional[tuple[Any, str]]:
    """The object and attribute of the compiled program that hold output `label` (a console
    or wiring label of the stand's I/O image), None for a label the program does not bind."""
    from plclab.runtime.image import image_slot
    address = session.labels.get(label)
    if address is None:
        return None
    area, index = image_slot(address)
    for b in session.plc.bindings:
        if b.area == area and b.index == index and not b.is_input:
            return b.owner, b.attr
    return None




def candidates(student: Any, model: Optional[Any], replay: Replay, output: Optional[str], t_fail: float,
               sources: Sequence[tuple[str, str]], stand: Optional[str], hints: Sequence[str] = ()) -> Optional[Localized]:
    """`localize` against `stand`'s starting program; None where nothing can be said. Never
    raises: a failing row is reported whether or not its line is found, and a bug here is
    never the student's (it shows as no candidates, and the tests measure how often the
    changed line is named)."""
    start = None
    try:
        if stand is not None:
            start = starting_sources(stand)
    except Exception:                    # noqa: BLE001 - an installed package without the stand's sources
        start = None
    try:
        with kept_out_of_gc():           # the traces are dropped as localize returns
            return localize(student, model, replay, output, t_fail, sources, start, hints=hints)
    except Exception:                    # noqa: BLE001 - the row stands without its candidates
        return None


def scripted(req: Any, scenario: Any, sources: Sequence[tuple[str, str]], checked: Any, model: Any,
             t_fail: float, message: str = "") -> Optional[Localized]:
    """The candidates of a scripted row that failed at plant time `t_fail` in `scenario` (of
    requirement set `req`): the scenario is played again on the student's program (traced) and
    on the model answer (`model`: sources, checked, cache, as plclab.grader.explore.Program),
    each on a fresh stand, to the failure; the output followed is the one that differs then,
    one the row's `message` (its expected and observed texts) names first."""
    from plclab.runtime.native import python_only
    from plclab.scenario import ScenarioFailure, compiled_once

    from .registry import Checks
    # the tracer follows the generated Python: every PLC of the replays (restarts too) on that path
    with python_only():
        own: list = []                       # the student's program compiled once, restarts included

        def session(srcs: Any, chk: Any, name: str, share: list) -> Any:
            retain = MemoryRetainStore() if scenario.needs_retain else None
            with compiled_once(chk, share=share):
                return req.make_session(list(srcs), retain, chk)

        student = session(sources, checked, "student", own)
        other = session(model.sources, model.checked, "model", model.cache)

        def replay(sess: Any, begin: Callable[[], None]) -> None:
            chk, share = (checked, own) if sess is student else (model.checked, model.cache)
            begin()
            with compiled_once(chk, share=share):
                try:
                    scenario.run(sess, Checks(req.requirements))
                except ScenarioFailure:
                    pass

        return candidates(student, other, replay, None, t_fail, sources, req.stand, hints=named_outputs(message))


def written_text(output: Optional[str], writer: Optional[tuple[str, int, str]], sources: Sequence[tuple[str, str]]) -> str:
    """The message's last line: where `output` was last written (a drawn program: the rung and
    element of its drawing, never a line of the ST the editor generates)."""
    from pathlib import Path

    from plclab.frontend.graphical import drawing_location
    if writer is None:
        return ""
    file, line, stmt = writer
    drawn = drawing_location(sources, file, line)
    if drawn is not None:
        return f"{output} last written in {Path(file).name}: {drawn}"
    return f"{output} last written by {Path(file).name}:{line}" + (f" `{stmt}`" if stmt else "")


def named_outputs(message: str) -> list[str]:
    """The labels a row's message names with a value (`L2=0 L3=1 | L2=1 L3=0`), those whose
    values differ between its parts first."""
    parts = [dict(re.findall(r"\b([A-Za-z]+\d*)\s*=\s*(\w+)", part)) for part in message.split(" | ")]
    seen: list[str] = []
    for part in parts:
        seen += [k for k in part if k not in seen]
    differ = [k for k in seen if len({p.get(k) for p in parts}) > 1]
    return differ + [k for k in seen if k not in differ]
