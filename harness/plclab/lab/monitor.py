"""Online monitoring for the lab's page: the program's ST, POU by POU, with where each
variable is used (so the page can show its live value beside it, as CODESYS's online mode
does), and the live values of one POU instance.

The listing comes from the checked program (each POU's file and lines, its symbols); the uses
are found by a small scanner that skips comments and strings and takes dotted chains
(`Robot.Sequencer.Ptr`) whose first name is one of the POU's variables or a global, with
their array indexes when every index is an integer constant or a variable chain
(`Cp.Frames[Cp.Count].Data[1]`, `Valves[i]`). Values are read through paths resolved once
per PLC (a restart or a load re-resolves them); an indexed use is resolved at every read from
its indexes' live values in the same instance, and shows nothing when an index is out of
range or cannot be read (never the value of another element).
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Optional

from plclab.errors import PlcLabError
from plclab.iec import types as T

MAX_REFS = 2000           # variable uses listed per POU (a longer POU: the first ones)
MAX_INDEXED = 200         # indexed uses read per instance (each is resolved at every read)
_TOKENS = re.compile(r"\(\*[\s\S]*?\*\)|//[^\n]*|'(?:\$.|[^'$])*'|\"(?:\$.|[^\"$])*\"|"
                     r"(?<![\w#.])([A-Za-z_]\w*(?:[ \t]*\.[ \t]*[A-Za-z_]\w*)*)(?![\w#])")
_INDEX = re.compile(r"[ \t]*\[([^\]\[\n()'\"]*)\]")          # one `[...]` on the same line, no nesting
_FIELDS = re.compile(r"[ \t]*\.[ \t]*[A-Za-z_]\w*(?:[ \t]*\.[ \t]*[A-Za-z_]\w*)*(?![\w#])")
_INT = re.compile(r"[+-]?\d(?:_?\d)*$")
_CHAIN = re.compile(r"[A-Za-z_]\w*(?:\s*\.\s*[A-Za-z_]\w*)*$")


def display_name(file: str) -> str:
    """A source's name as a student recognises it (`FB_Mp9cManual.st`, `mp9c.st`)."""
    if file.startswith("<") and file.endswith(">"):
        return file[1:-1].split(": ", 1)[-1]
    return Path(file).name


def listing(plc: Any, sources: list[tuple[str, str]]) -> list[dict]:
    """Every POU of the program with a body in the sources: its lines, the variables it uses
    where (line, first column, last column, the chain as written, 'local' or 'global') and
    the instance paths whose values can be shown beside it."""
    from plclab.lab.ladder import drawings
    texts = dict(sources)
    instances = fb_instances(plc)
    ladders = drawings(sources)
    out = []
    for key, pou in plc.checked.pous.items():
        if not hasattr(pou, "decls") or pou.file not in texts:
            continue
        lines = texts[pou.file].splitlines()
        first, last = pou.line, pou.end_line or len(lines)
        if pou.kind == "PROGRAM":
            paths = [i.name for i in plc.instances if type(i.obj)._ST_NAME.upper() == key]
        else:
            paths = instances.get(key, [])
        out.append({"name": pou.name, "kind": pou.kind, "file": pou.file, "display": display_name(pou.file),
                    "line": first, "lines": lines[first - 1:last], "instances": paths,
                    "refs": _refs(pou, plc.checked.globals, lines, first, last)})
        if key in ladders:                   # an LD POU of a plc.xml: drawn as rungs, power flow live
            out[-1]["ladder"] = ladders[key]
        elif getattr(texts[pou.file], "xml", None):   # FBD (or ST) in a plc.xml: the ST it becomes
            out[-1]["generated"] = True
    out.sort(key=lambda p: (p["kind"] != "PROGRAM", p["kind"] != "FUNCTION_BLOCK", p["name"].upper()))
    return out


def _refs(pou: Any, globals_: dict, lines: list[str], first: int, last: int) -> list[list]:
    text = "\n".join(lines[first - 1:last])
    starts = [0]
    for line in lines[first - 1:last]:
        starts.append(starts[-1] + len(line) + 1)
    symbols = pou.symbols or {}
    refs: list[list] = []
    def scope_of(chain: str) -> Optional[str]:
        head = chain.split(".", 1)[0].strip().upper()
        decl = symbols.get(head)
        if decl is not None and decl.section != "VAR_EXTERNAL":
            return "local"
        return "global" if head in globals_ else None

    for m in _TOKENS.finditer(text):
        chain = m.group(1)
        if not chain:
            continue
        scope = scope_of(chain)
        if scope is None:
            continue
        pos = m.start(1)
        line = _line_of(starts, pos)
        end, indexes = _indexed(text, m.end(1), scope_of)
        if indexes:        # `Frames[Ptr].Data[1]`: the element's value, not the array's (none)
            refs.append([first + line, pos - starts[line], end - starts[line],
                         re.sub(r"\s+", "", text[pos:end]), scope, indexes])
        else:
            refs.append([first + line, pos - starts[line], m.end(1) - starts[line], re.sub(r"\s+", "", chain), scope])
        if len(refs) >= MAX_REFS:
            break
    refs.sort(key=lambda r: (r[0], r[2]))   # the page inserts values left to right, line by line
    return refs


def _indexed(text: str, at: int, scope_of: Any) -> tuple[int, list]:
    """Past a chain at `at`: where its `[i].field[2]` tail ends and each index as [text, scope]
    ('const', 'local' or 'global'); (at, []) when the chain has no index the page can compute.
    A tail is taken up to its last index that is an integer or a variable chain."""
    end, indexes = at, []
    while True:
        m = _INDEX.match(text, at)
        if not m:
            break
        items = []
        for item in m.group(1).split(","):
            item = item.strip()
            if _INT.match(item):
                items.append([item.replace("_", ""), "const"])
            elif _CHAIN.match(item) and scope_of(item):
                items.append([re.sub(r"\s+", "", item), scope_of(item)])
            else:
                return end, indexes
        indexes.extend(items)
        at = end = m.end()
        f = _FIELDS.match(text, at)
        if f:
            at = f.end()
            if not _INDEX.match(text, at):       # `[i].Pause`: the field belongs to the use
                end = at
    return end, indexes


def _line_of(starts: list[int], pos: int) -> int:
    lo, hi = 0, len(starts) - 1
    while lo < hi - 1:
        mid = (lo + hi) // 2
        if starts[mid] <= pos:
            lo = mid
        else:
            hi = mid
    return lo


def fb_instances(plc: Any) -> dict[str, list[str]]:
    """FB type (upper case) -> the paths of its instances, program by program."""
    out: dict[str, list[str]] = {}

    def walk(pou: Any, prefix: str, depth: int) -> None:
        if depth > 32 or not hasattr(pou, "decls"):
            return
        for d in pou.decls:
            base = T.base_of(d.ty) if d.ty is not None else None
            if isinstance(base, T.FBType) and d.section not in ("VAR_EXTERNAL", "VAR_IN_OUT"):
                name = getattr(base.pou, "name", base.name).upper()
                path = f"{prefix}.{d.name}"
                out.setdefault(name, []).append(path)
                walk(base.pou, path, depth + 1)
    for inst in plc.instances:
        walk(plc.checked.pous.get(type(inst.obj)._ST_NAME.upper()), inst.name, 0)
    return out


class Monitor:
    """The values of one POU instance's variable uses, read every snapshot (changes only)."""

    def __init__(self) -> None:
        self.pou: Optional[str] = None
        self.instance: Optional[str] = None
        self.chains: list[tuple[str, str]] = []       # (chain as the page keys it, path to read)
        self._targets: list[tuple[str, Any, Any, bool]] = []
        self.indexed: list[tuple[str, str, list[tuple[str, str]]]] = []  # (chain, path with {} per index, indexes)
        self._plc: Any = None
        self._sent: dict[str, Any] = {}

    def select(self, plc: Any, pou: dict, instance: Optional[str]) -> None:
        if instance is not None and instance not in pou["instances"]:
            raise PlcLabError(f"{pou['name']} has no instance '{str(instance)[:80]}'")
        self.pou, self.instance = pou["name"], instance
        chains: dict[str, str] = {}
        indexed: dict[str, tuple[str, list[tuple[str, str]]]] = {}
        for _line, _c0, _c1, chain, scope, *more in pou["refs"]:
            if scope == "local" and instance is None:
                continue
            path = chain if scope == "global" else f"{instance}.{chain}"
            if not more:
                chains[chain] = path
                continue
            if instance is None and any(s == "local" for _i, s in more[0]):
                continue
            if len(indexed) < MAX_INDEXED:      # each index: a constant, or its path in this instance
                indexed[chain] = (re.sub(r"\[[^\]]*\]", lambda m: "[" + ",".join(["{}"] * (m.group(0).count(",") + 1)) + "]", path),
                                  [(i, "const" if s == "const" else i if s == "global" else f"{instance}.{i}") for i, s in more[0]])
        self.chains = list(chains.items())
        self.indexed = [(chain, fmt, idx) for chain, (fmt, idx) in indexed.items()]
        self._plc = None
        self._sent = {}

    def values(self, plc: Any, full: bool) -> Optional[dict]:
        """{chain: value} of what changed (everything when `full`); None: nothing selected."""
        if self.pou is None:
            return None
        if plc is not self._plc:
            self._resolve(plc)
            full = True
        out = {}
        for chain, container, key, is_time in self._targets:
            value = _show(container[key] if isinstance(container, list) else getattr(container, key), is_time)
            if full or self._sent.get(chain, _NONE) != value:
                out[chain] = value
                self._sent[chain] = value
        for chain, fmt, indexes in self.indexed:
            value = _show(*self._element(plc, fmt, indexes))
            if full or self._sent.get(chain, _NONE) != value:
                out[chain] = value                     # "": shown as nothing (an index out of range)
                self._sent[chain] = value
        return out

    @staticmethod
    def _element(plc: Any, fmt: str, indexes: list[tuple[str, str]]) -> tuple[Any, bool]:
        """The element an indexed use names now, from its indexes' live values; (None, False)
        when an index is not an integer or out of range, or the element is not elementary."""
        try:
            idx = []
            for text, path in indexes:
                value = int(text) if path == "const" else plc.read(path)
                if isinstance(value, bool) or not isinstance(value, int):
                    return None, False
                idx.append(value)
            container, key, ty = plc.resolve_typed(fmt.format(*idx))
        except (PlcLabError, ValueError, LookupError, AttributeError, TypeError):
            return None, False             # e.g. a VAR_IN_OUT not yet bound before the first scan
        base = T.base_of(ty)
        if not isinstance(base, T.ElementaryType):
            return None, False
        value = container[key] if isinstance(container, list) else getattr(container, key)
        return value, base.kind == "time"

    def _resolve(self, plc: Any) -> None:
        self._plc = plc
        targets = []
        for chain, path in self.chains:
            try:
                container, key, ty = plc.resolve_typed(path)
            except PlcLabError:
                continue
            base = T.base_of(ty)
            if isinstance(base, T.ElementaryType):
                targets.append((chain, container, key, base.kind == "time"))
        self._targets = targets
        self._sent = {}


_NONE = object()


def _show(value: Any, is_time: bool) -> Any:
    """A value as the page prints it beside its use ("" for none)."""
    if value is None:
        return ""
    if is_time:
        return f"T#{value / 1e6:g}ms" if abs(value) < 1e9 else f"T#{value / 1e9:g}s"
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, float):
        return round(value, 4)
    return value


MAX_INSTANCES = 64        # POU instances read by `every_value` (a program with more: the first ones)


def every_value(plc: Any, sources: list[tuple[str, str]]) -> dict[str, dict[str, dict]]:
    """What the page would show beside every POU of the program, for each of its instances,
    now: {POU: {instance ('' where it has none): {"values": {chain: value}, "power": ...}}}
    (`power`: an LD POU's power flow). The values of a moment that is gone, such as the
    graded run's at a row's time (plclab.grader.replayed), read as the live ones are: one
    Monitor per instance, the same PowerFlow."""
    from plclab.lab.ladder import PowerFlow, pou_elements, time_aware
    out: dict[str, dict[str, dict]] = {}
    read = 0
    for pou in listing(plc, sources):
        shown: dict[str, dict] = {}
        for instance in pou["instances"] or [None]:
            if read >= MAX_INSTANCES:
                break
            read += 1
            m = Monitor()
            m.select(plc, pou, instance)
            entry: dict[str, Any] = {"values": m.values(plc, True) or {}}
            if "ladder" in pou:
                elements = pou_elements(sources, pou["name"])
                if elements is not None:
                    entry["power"] = PowerFlow(elements, instance, time_aware(plc)).state()
            shown[instance or ""] = entry
        out[pou["name"]] = shown
    return out
