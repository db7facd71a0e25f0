"""A dependence tracer for a compiled program: which generated statements ran, in which scan,
what storage each read and wrote, and which condition (or call) each one ran under.

Why here: a grader that asks "where did this output's value come from?" must follow the
program's dynamic data and control dependences back through the scans (a dynamic slice). Only
the runtime knows how ST storage looks in the generated Python (`self.X`, a local `v_X` that
mirrors `self.X` until the POU returns, `G.X` for globals, a standard FB whose body runs
outside the compiled code), so the tracer lives beside the compiler and speaks of generated
lines and storage keys only; what a line means in ST is `CompiledProgram.where`. It knows
nothing of stands or of grading.

Storage keys: `(id(object), path)`, the object reached from a name through plain attributes
(`v_ROBOT.SEQUENCER.FAULT` and `self.FAULT` inside that sequencer are one key), the path what
is left ('FAULT', '[].PAUSE' for an array element: any element, a weak key). `'*'` stands for
every field of a standard FB (its body reads its inputs and state and writes its outputs).
A local temporary of one call is `('L', call, name)`, the value a call returns `('R', call)`.
"""
from __future__ import annotations

import ast
import contextlib
import gc
import keyword
import sys
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, Callable, Iterator, Optional, Sequence

from plclab.runtime.gencode import define

_PRIMITIVE = (bool, int, float, str, bytes, type(None))
WILD = "*"
STABLE, PER_CALL = 1, 2       # how long a storage key holds (Tracer._resolve)


@dataclass(frozen=True)
class LineShape:
    """What one generated line does, read once from the generated source."""

    reads: tuple[tuple[str, str], ...]       # (root name, path) it reads
    writes: tuple[tuple[str, str], ...]      # (root name, path) it assigns
    std_calls: tuple[tuple[str, str], ...]   # (root, path) of an FB whose `_body()` it calls
    header: Optional[int]                    # the line of the IF/WHILE/FOR/CASE test it runs under
    is_return: bool = False


def _chain(node: ast.AST) -> Optional[tuple[str, str, list[ast.AST]]]:
    """`v_CP.FRAMES[i].PAUSE` -> ('v_CP', 'FRAMES[].PAUSE', [i]): root, path, index expressions."""
    parts: list[str] = []
    indexes: list[ast.AST] = []
    while True:
        if isinstance(node, ast.Attribute):
            parts.append("." + node.attr)
            node = node.value
        elif isinstance(node, ast.Subscript):
            parts.append("[]")
            indexes.append(node.slice)
            node = node.value
        elif isinstance(node, ast.Name):
            path = "".join(reversed(parts)).lstrip(".")
            return node.id, path, indexes
        else:
            return None


class _Reads(ast.NodeVisitor):
    def __init__(self) -> None:
        self.reads: list[tuple[str, str]] = []
        self.writes: list[tuple[str, str]] = []
        self.std: list[tuple[str, str]] = []

    def visit_NamedExpr(self, node: ast.NamedExpr) -> None:
        self.writes.append((node.target.id, ""))
        self.visit(node.value)

    def visit_Call(self, node: ast.Call) -> None:
        f = node.func
        if isinstance(f, ast.Attribute) and f.attr in ("_body", "_run"):
            c = _chain(f.value)
            if c is not None and f.attr == "_body":
                self.std.append((c[0], c[1]))
            if c is not None:
                for i in c[2]:
                    self.visit(i)
        elif not isinstance(f, ast.Name):
            self.visit(f)
        for a in node.args:
            self.visit(a)
        for k in node.keywords:
            self.visit(k.value)

    def _access(self, node: ast.AST) -> None:
        c = _chain(node)
        if c is None:
            self.generic_visit(node)
            return
        self.reads.append((c[0], c[1]))
        for i in c[2]:
            self.visit(i)

    visit_Attribute = _access
    visit_Subscript = _access
    visit_Name = _access


def _target(t: ast.AST, into: _Reads) -> None:
    if isinstance(t, (ast.Tuple, ast.List)):
        for e in t.elts:
            _target(e, into)
        return
    c = _chain(t)
    if c is None:
        into.visit(t)
        return
    into.writes.append((c[0], c[1]))
    for i in c[2]:
        into.visit(i)


@lru_cache(maxsize=64)
def line_shapes(source: str) -> dict[int, LineShape]:
    """Every statement line of the generated `source`: what it reads and writes, and the
    test line it is control dependent on (None: the function's entry, i.e. its call).
    Worked out once per source text (a parse of the whole generated program: a grading
    traces the same student's program for each failing row); the answer is read only."""
    shapes: dict[int, LineShape] = {}

    def add(line: int, r: _Reads, header: Optional[int], is_return: bool = False) -> None:
        old = shapes.get(line)
        reads, writes, std = tuple(r.reads), tuple(r.writes), tuple(r.std)
        if old is not None:
            reads, writes, std = old.reads + reads, old.writes + writes, old.std_calls + std
        shapes[line] = LineShape(reads, writes, std, header, is_return or (old is not None and old.is_return))

    def walk(stmts: list[ast.stmt], header: Optional[int]) -> None:
        for s in stmts:
            r = _Reads()
            if isinstance(s, (ast.FunctionDef, ast.ClassDef)):
                walk(s.body, None)
                continue
            if isinstance(s, ast.If) or isinstance(s, ast.While):
                r.visit(s.test)
                add(s.lineno, r, header)
                walk(s.body, s.lineno)
                walk(s.orelse, s.lineno)
            elif isinstance(s, ast.For):
                r.visit(s.iter)
                _target(s.target, r)
                add(s.lineno, r, header)
                walk(s.body, s.lineno)
                walk(s.orelse, s.lineno)
            elif isinstance(s, ast.Try):
                walk(s.body, header)
                for h in s.handlers:
                    walk(h.body, header)
                walk(s.orelse, header)
                walk(s.finalbody, header)
            elif isinstance(s, ast.Assign):
                r.visit(s.value)
                for t in s.targets:
                    _target(t, r)
                add(s.lineno, r, header)
            elif isinstance(s, (ast.AugAssign, ast.AnnAssign)):
                if s.value is not None:
                    r.visit(s.value)
                _target(s.target, r)
                if isinstance(s, ast.AugAssign):
                    r.visit(s.target)
                add(s.lineno, r, header)
            elif isinstance(s, ast.Return):
                if s.value is not None:
                    r.visit(s.value)
                add(s.lineno, r, header, True)
            else:
                r.visit(s)
                add(s.lineno, r, header)

    walk(ast.parse(source).body, None)
    return shapes


@dataclass(slots=True)
class Event:
    """One execution of one generated line."""

    line: int
    scan: int                                  # index into Tracer.scan_times
    reads: tuple                               # storage keys
    writes: tuple                              # (key, strong)
    parent: Optional[int]                      # the event it ran under (a test, or its call)
    call: int = 0


class StopReplay(BaseException):
    """Raised into a replay as the first scan after `Tracer.stop_at` begins: what was to be
    seen has been (a BaseException, so that a scenario's own `except Exception` lets it by)."""


@dataclass(frozen=True)
class _LineKeys:
    """A line's storage keys as the same `me` (under the same globals `g`) always has them;
    a call's temporaries ('L' keys) are renumbered for the call that runs the line."""

    me: Any
    g: Any
    reads: tuple
    writes: tuple                     # (key, strong)
    per_call: bool                    # some key is a call's temporary

    def in_call(self, call: int) -> tuple[tuple, tuple]:
        if not self.per_call:
            return self.reads, self.writes
        return (tuple([_in_call(k, call) for k in self.reads]),
                tuple([(_in_call(k, call), strong) for k, strong in self.writes]))


def _in_call(key: tuple, call: int) -> tuple:
    return ("L", call, key[2]) if key[0] == "L" else key


class _Call:
    """One traced call of generated code: its number, the event it was called from (`parent`),
    the last event of each test line it ran (`headers`), its statement not yet completed
    (`pending`), its caller's _Call, its `self` and the storage keys of that `self`'s lines
    (line -> _LineKeys, shared by every call on the same object)."""

    __slots__ = ("call", "parent", "headers", "pending", "caller", "me", "keys")

    def __init__(self, call: int, parent: Optional[int], caller: Optional["_Call"], me: Any, keys: dict) -> None:
        self.call, self.parent, self.caller, self.me, self.keys = call, parent, caller, me, keys
        self.headers: dict[int, int] = {}
        self.pending: Optional[int] = None


@dataclass
class Tracer:
    """Records dependence events of the compiled program `compiled` while installed
    (`start()` .. `stop()`, through sys.settrace). `clock()` gives the time of the scan that
    begins whenever the compiled code is entered from outside (a new scan)."""

    compiled: Any
    clock: Callable[[], float]
    events: dict[int, Event] = field(default_factory=dict)
    order: list[int] = field(default_factory=list)        # event ids in completion order
    scan_times: list[float] = field(default_factory=list)
    types: dict[int, type] = field(default_factory=dict)  # id(object) -> its class (declarations)
    sample: Optional[Callable[[], Any]] = None             # called as each scan begins
    samples: list = field(default_factory=list)            # what it returned
    lines: bool = True                                     # False: scans and samples only
    since: float = 0.0                                     # lines traced (and samples) from this time on
    stop_at: Optional[float] = None                        # a scan that begins after it raises StopReplay

    def __post_init__(self) -> None:
        self.shapes = line_shapes(self.compiled.source)
        self._filename = self.compiled.filename
        self._calls = 0
        self._frames: dict[int, _Call] = {}            # id(frame) -> its call
        self._old: Any = None
        self._gc_was_on = False
        self._slotsets: dict[type, frozenset] = {}
        # id(self) -> line -> the keys of a line whose keys are all stable (Tracer._resolve)
        self._line_keys: dict[int, dict[int, _LineKeys]] = {}

    # ---------------------------------------------------------------- storage keys
    def _obj_key(self, obj: Any, path: str) -> tuple:
        self.types[id(obj)] = type(obj)
        return (id(obj), path)

    def _slotset(self, cls: type) -> frozenset:
        got = self._slotsets.get(cls)
        if got is None:
            got = self._slotsets[cls] = frozenset(_slots(cls)) if hasattr(cls, "__slots__") else frozenset()
        return got

    def key(self, frame: Any, st: "_Call", root: str, path: str, write: bool) -> Optional[tuple]:
        """The storage key of `root.path` in `frame` (None: a constant, a function, a module's
        own name). A POU's `v_X` mirrors `self.X` (an object: the same one), so `self` is
        enough to name it and the frame's locals are read only in a function (FC)."""
        return self._resolve(frame, st, root, path, write)[0]

    def _resolve(self, frame: Any, st: "_Call", root: str, path: str, write: bool) -> tuple[Optional[tuple], int]:
        """`key` and how long it holds: STABLE (the same for every execution of the line by the
        same `self` under the same globals: IEC storage is fixed, so only a VAR_IN_OUT, which
        each call binds anew, can put another object on the way), PER_CALL (a temporary of the
        call: the same but for the call's number) or 0 (worked out again each time)."""
        me = st.me
        if root == "self":
            obj, fixed = me, True
        elif root.startswith("v_") and me is not None and root[2:] in self._slotset(type(me)):
            obj = getattr(me, root[2:], None)
            if not path and (write or isinstance(obj, _PRIMITIVE)):
                return self._obj_key(me, root[2:]), STABLE if write or obj is not None else 0
            fixed = root[2:] not in getattr(type(me), "_IN_OUT", ())
        elif root.startswith("_") and not path:
            return ("L", st.call, root), PER_CALL
        elif root == "G" or (not root.startswith("v_") and root in frame.f_globals):
            obj = frame.f_globals.get(root)
            if not path or obj is None or isinstance(obj, _PRIMITIVE) or callable(obj) and not hasattr(obj, "__dict__"):
                return None, 0
            fixed = root == "G"
        else:
            loc = frame.f_locals
            if root not in loc:
                return (("L", st.call, root) if write or root.startswith(("_", "v_")) else None), 0
            obj = loc[root]
            if not path and (write or isinstance(obj, _PRIMITIVE)):
                return ("L", st.call, root), 0
            fixed = False
        if obj is None:
            return ("L", st.call, root), 0
        if not path:
            return self._obj_key(obj, ""), STABLE if fixed else 0
        # walk plain attributes down to the last object
        rest = path
        while rest and not rest.startswith("["):
            head, dot, tail = rest.partition(".")
            if "[" in head:
                break
            nxt = getattr(obj, head, None)
            if nxt is None:
                fixed = False             # nothing bound there now: something may be later
                break
            if isinstance(nxt, _PRIMITIVE) or not tail and write:
                break
            fixed = fixed and head not in getattr(type(obj), "_IN_OUT", ())
            obj, rest = nxt, tail
        stable = STABLE if fixed else 0
        if not rest:
            return self._obj_key(obj, ""), stable
        return self._obj_key(obj, rest), stable

    # ---------------------------------------------------------------- sys.settrace
    def start(self) -> None:
        """Install the tracer. The cyclic garbage collector is off while it is: a trace is
        hundreds of thousands of events that all stay alive, and every full collection would
        walk them all again (a third of a traced replay's time). A replay makes little cyclic
        garbage, and what it makes is collected once the tracer is stopped."""
        self._old = sys.gettrace()
        self._gc_was_on = gc.isenabled()
        gc.disable()
        sys.settrace(self._global)

    def stop(self) -> None:
        sys.settrace(self._old)
        if self._gc_was_on:
            if _KEPT_OUT[0]:
                gc.freeze()            # the trace out of the collector's walks (kept_out_of_gc)
            gc.enable()
        for st in list(self._frames.values()):
            self._finish(st)
        self._frames.clear()

    def _finish(self, st: "_Call") -> None:
        if st.pending is not None:
            self.order.append(st.pending)
            st.pending = None

    def _global(self, frame: Any, event: str, _arg: Any) -> Any:
        if frame.f_code.co_filename != self._filename:
            return None
        back = frame.f_back
        if back is None or back.f_code.co_filename != self._filename:    # from the scan loop: a scan
            now = self.clock()
            if self.stop_at is not None and now > self.stop_at + 1e-9:
                raise StopReplay(now)
            if now < self.since - 1e-9:
                return None
            if not self.scan_times or self.scan_times[-1] != now:
                self.scan_times.append(now)
                if self.sample is not None:
                    self.samples.append(self.sample())
        if not self.lines or not self.scan_times:
            return None
        caller = self._frames.get(id(back)) if back is not None else None
        self._calls += 1
        me = frame.f_locals.get("self")
        keys = self._line_keys.get(id(me))
        if keys is None:
            keys = self._line_keys[id(me)] = {}
        st = _Call(self._calls, caller.pending if caller else None, caller, me, keys)
        self._frames[id(frame)] = st
        return self._local_for(st, frame.f_globals.get("G"))

    CACHE_LINES = True     # False: every line's keys worked out anew (the tests compare both)

    def _line_keys_of(self, frame: Any, st: "_Call", shape: LineShape) -> tuple[tuple, tuple, bool, bool]:
        """A line's read keys and (write key, strong) pairs, whether all of them are stable (or
        per call) so that the next execution by the same `self` may reuse them, and whether
        one is per call."""
        hows: list[int] = []

        def keys(items: tuple, write: bool) -> list:
            out = []
            for r, p in items:
                k, how = self._resolve(frame, st, r, p, write)
                hows.append(how)
                if k is not None:
                    out.append(k)
            return out

        reads = keys(shape.reads, False)
        writes = [(k, "[" not in (k[1] if len(k) == 2 else "")) for k in keys(shape.writes, True)]
        for k in keys(shape.std_calls, False):
            if len(k) == 2 and k[1] == "":
                reads.append((k[0], WILD))
                writes.append(((k[0], WILD), False))
        return tuple(reads), tuple(writes), all(hows), PER_CALL in hows

    def _local_for(self, st: "_Call", g: Any) -> Callable[[Any, str, Any], Any]:
        """The line tracer of one call (sys.settrace's local function): it holds its call's
        state, so that each line costs no look-up of it. Each executed statement line becomes
        an Event: its storage keys (from the per-object cache where they are stable), the
        scan, and the test line or call it ran under. What holds for the whole call is worked
        out once, not per line: its scan (a call of the compiled code begins and ends inside
        one scan) and its globals `g` (a frame's globals never change)."""
        shapes, events, order = self.shapes, self.events, self.order
        keys_of_me, headers = st.keys, st.headers
        cache = self.CACHE_LINES
        me, call = st.me, st.call
        scan = len(self.scan_times) - 1

        def local(frame: Any, event: str, _arg: Any) -> Any:
            if event == "line":
                if st.pending is not None:
                    order.append(st.pending)
                    st.pending = None
                lineno = frame.f_lineno
                shape = shapes.get(lineno)
                if shape is None:
                    return frame.f_trace
                eid = len(events)                   # ids in execution order from 0: none is removed
                known = keys_of_me.get(lineno) if cache else None
                if known is not None and known.me is me and known.g is g:
                    reads, writes = known.in_call(call) if known.per_call else (known.reads, known.writes)
                else:
                    reads, writes, stable, per_call = self._line_keys_of(frame, st, shape)
                    if stable and cache:
                        keys_of_me[lineno] = _LineKeys(me, g, reads, writes, per_call)
                header = shape.header
                if shape.is_return:
                    writes = writes + ((("R", call), True),)
                    caller = st.caller
                    if caller is not None and caller.pending is not None:
                        ce = events[caller.pending]
                        ce.reads = ce.reads + (("R", call),)
                events[eid] = Event(lineno, scan, reads, writes,
                                    headers.get(header) if header is not None else st.parent, call)
                st.pending = eid
                headers[lineno] = eid
            elif event == "return":
                self._finish(st)
                self._frames.pop(id(frame), None)
            # the frame's own tracer (this function), not the name `local`: a closure that names
            # itself is a reference cycle, and through it every trace would wait for the cyclic
            # collector (hundreds of MB of events between full collections) instead of being
            # freed as its replay is dropped
            return frame.f_trace

        return local


_KEPT_OUT = [0]          # kept_out_of_gc blocks open


@contextlib.contextmanager
def kept_out_of_gc() -> Iterator[None]:
    """Traces stopped inside the block stay out of the cyclic garbage collector's walks until
    it ends. The first collection after a traced replay walked every event the trace holds
    (the collector counts them as new objects: a sixth of a row's localization), though they
    are all freed by their reference counts once the trace is dropped. A tracer stopped here
    moves every object of the process to the collector's permanent generation (gc.freeze);
    the block's end, after the caller has dropped its traces, gives back what is still alive
    (gc.unfreeze), so cyclic garbage made meanwhile is collected late, never lost. Not for a
    process that freezes objects of its own (none here does)."""
    _KEPT_OUT[0] += 1
    try:
        yield
    finally:
        _KEPT_OUT[0] -= 1
        if not _KEPT_OUT[0]:
            gc.unfreeze()


def matches(written: tuple, wanted: tuple) -> bool:
    """Whether a write of key `written` may change the storage `wanted` names (one holds the
    other: a whole struct and its field, any element and one element, an FB and its fields)."""
    if written == wanted:
        return True
    if len(written) != 2 or len(wanted) != 2 or written[0] != wanted[0]:
        return False
    return paths_overlap(written[1], wanted[1])


@lru_cache(maxsize=1 << 16)
def paths_overlap(a: str, b: str) -> bool:
    """Whether storage paths `a` and `b` of one object overlap (matches, for one object): a
    program's paths are few and a slice asks about the same pairs again and again."""
    if a == WILD or b == WILD or a == "" or b == "":
        return True
    a, b = a.replace("[]", ".[]"), b.replace("[]", ".[]")
    return a.startswith(b + ".") or b.startswith(a + ".") or a == b


# --------------------------------------------------------------------------- the program's state by name

def _slots(cls: type) -> list[str]:
    out: list[str] = []
    for c in reversed(cls.__mro__):
        for s in getattr(c, "__slots__", ()):
            if s not in out:
                out.append(s)
    return out


class StateReader:
    """Every elementary value of the running program by its instance path (`MAIN.ROBOT.PAUSE.
    DURATION`, `MAIN.CP.FRAMES[3].PAUSE`, globals as `G.SA1`), read as often as each scan: the
    objects are walked once and again only when one of them was replaced (a restart, a whole
    struct assigned), their leaves kept as (container, key, path). `paths`: each object's path
    (id -> the first path that reaches a shared VAR_IN_OUT object). Two programs descended
    from one starting program share the names of what they kept of it."""

    def __init__(self, max_depth: int = 8) -> None:
        self.max_depth = max_depth
        self.leaves: list[tuple[Any, Any, str]] = []
        self.edges: list[tuple[Any, Any, Any]] = []     # (container, key, the object it held)
        self.paths: dict[int, str] = {}
        self.walks = 0                  # how many times the objects were walked (the leaves made)
        self._plc: Any = None
        self._same: Callable[[], bool] = lambda: False
        self._get_all: Callable[[], list[Any]] = list

    def values(self, plc: Any) -> list[Any]:
        """The values of `leaves`, in their order (walked again first where needed)."""
        if plc is not self._plc or not self._unchanged():
            self._plc = plc
            self._walk(plc)
        out = self._read()
        if not _PRIMITIVE_SET.issuperset(map(type, out)):    # a reference bound since
            self._walk(plc)
            out = self._read()
        return out

    def _unchanged(self) -> bool:
        try:
            return self._same()
        except (AttributeError, IndexError, KeyError, TypeError):   # a variable that went away
            return False

    def _read(self) -> list[Any]:
        try:
            return self._get_all()
        except (AttributeError, IndexError, KeyError, TypeError):
            return [_get(c, k) for c, k, _path in self.leaves]

    def _walk(self, plc: Any) -> None:
        leaves: list[tuple[Any, Any, str]] = []
        edges: list[tuple[Any, Any, Any]] = [(plc, "G", plc.G)]
        paths: dict[int, str] = {}

        def walk(obj: Any, path: str, depth: int, container: Any, key: Any) -> None:
            if isinstance(obj, _PRIMITIVE):
                leaves.append((container, key, path))
                return
            if container is not None:
                edges.append((container, key, obj))
            if id(obj) in paths or depth > self.max_depth:
                return
            if isinstance(obj, list):
                paths[id(obj)] = path
                for i, x in enumerate(obj):
                    walk(x, f"{path}[{i}]", depth + 1, obj, i)
                return
            slots = _fields(obj)
            if not slots:
                return
            paths[id(obj)] = path
            for name in slots:
                if name in ("EN", "ENO") or name.startswith("_"):
                    continue
                walk(getattr(obj, name, None), f"{path}.{name}", depth + 1, obj, name)

        walk(plc.G, "G", 0, None, None)
        for inst in plc.instances:
            edges.append((inst, "obj", inst.obj))
            walk(inst.obj, inst.name.upper(), 0, None, None)
        self.leaves, self.edges, self.paths = leaves, edges, paths
        self._same, self._get_all = _readers(leaves, edges)
        self.walks += 1


def _fields(obj: Any) -> list[str]:
    """An object's variables: its slots, and what its __dict__ holds (a struct value)."""
    names = [n for n in _slots(type(obj)) if n not in ("__dict__", "__weakref__")]
    names += [k for k in getattr(obj, "__dict__", {}) if k not in names]
    return [n for n in names if not n.startswith("_")]


def _get(container: Any, key: Any) -> Any:
    return container[key] if isinstance(key, int) else getattr(container, key, None)


_PRIMITIVE_SET = frozenset(_PRIMITIVE)


class _Generated:
    """Source of generated readers: each object they read from is named `_o[n]`, once."""

    def __init__(self) -> None:
        self.objects: list[Any] = []
        self._index: dict[int, int] = {}

    def ref(self, obj: Any) -> str:
        n = self._index.get(id(obj))
        if n is None:
            n = self._index[id(obj)] = len(self.objects)
            self.objects.append(obj)
        return f"_o[{n}]"

    def get(self, container: Any, key: Any) -> str:
        """`_get(container, key)` as an expression (an attribute not set yet reads None)."""
        if isinstance(key, int):
            return f"{self.ref(container)}[{key}]"
        if key.isidentifier() and not keyword.iskeyword(key) and hasattr(container, key):
            return f"{self.ref(container)}.{key}"
        return f"getattr({self.ref(container)}, {key!r}, None)"

    def define(self, src: str) -> dict[str, Any]:
        ns: dict[str, Any] = {"_o": self.objects}
        define(src, "<generated reader>", ns)
        return ns


def pair_reader(pairs: Sequence[tuple[Any, Any]], as_tuple: bool = False) -> Callable[[], Any]:
    """One generated function reading (container, key) pairs (as PLC.resolve gives them: an
    array element or an attribute) into a list, or a tuple: where values are read at every
    scan, one generated expression reads them several times faster than a loop of getattr.
    It raises where a container lost an attribute it had."""
    g = _Generated()
    exprs = [g.get(c, k) for c, k in pairs]
    body = "(" + "".join(e + ", " for e in exprs) + ")" if as_tuple else "[" + ", ".join(exprs) + "]"
    return g.define(f"def read():\n    return {body}\n")["read"]


def _readers(leaves: list[tuple[Any, Any, str]], edges: list[tuple[Any, Any, Any]]
             ) -> tuple[Callable[[], bool], Callable[[], list[Any]]]:
    """Two functions generated for one walk: whether every edge still holds its object, and
    the leaves' values in order (pair_reader). They raise where a variable went away (the
    caller then walks again or reads the slow way)."""
    g = _Generated()
    same = " and ".join(f"{g.get(c, k)} is {g.ref(o)}" for c, k, o in edges) or "True"
    return g.define(f"def same():\n    return {same}\n")["same"], pair_reader([(c, k) for c, k, _p in leaves])
