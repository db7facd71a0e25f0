"""The program's variables for the lab's watch and force table: the tree a student picks
from (globals, program instances, FB instances, struct fields, array elements, as the
checker typed them), the values of the variables watched, and forces.

A force is what a PLC programming tool's force is: the forced value replaces what the field
(a located input) or the program (an output, an internal variable) put there, at the start
of every scan (after the inputs are read) and at its end (before the outputs are written),
until it is released. It is applied through the PLC's own I/O stage (`read_inputs`,
`write_outputs` of the one PLC object the lab runs), so the plant, the trace and the page
all see the forced value; the runtime itself knows nothing of forces.
"""
from __future__ import annotations

import math
from typing import Any, Callable, Optional

from plclab.errors import PlcLabError
from plclab.iec import types as T

MAX_NODES = 4000          # tree nodes sent to a page (a program's variables, arrays cut short)
MAX_ELEMENTS = 64         # array elements listed per array (the rest: type the index)
MAX_WATCH = 32
MAX_FORCES = 32


class VariableError(PlcLabError):
    """A variable the table cannot watch or force: one line."""


def variable_tree(plc: Any) -> list[dict]:
    """[{"name", "path", "type", "children"?}]: globals, then each program instance."""
    budget = [MAX_NODES]
    out = [{"name": "globals", "path": None, "type": "",
            "children": [_node(d.name, d.name, d.ty, budget) for d in plc.checked.globals.values()
                         if d.ty is not None and budget[0] > 0]}]
    for inst in plc.instances:
        pou = plc.checked.pous.get(type(inst.obj)._ST_NAME.upper())
        out.append({"name": f"{inst.name} : {pou.name if pou else '?'}", "path": None, "type": "",
                    "children": _pou_children(pou, inst.name, budget)})
    return out


def _pou_children(pou: Any, prefix: str, budget: list[int]) -> list[dict]:
    if pou is None:
        return []
    if not hasattr(pou, "decls"):        # a standard FB (TON, CTU...): its inputs and outputs
        members = [*getattr(pou, "inputs", ()), *getattr(pou, "outputs", ())]
        return [_node(name, f"{prefix}.{name}", T.ELEMENTARY[ty], budget) for name, ty in members
                if ty in T.ELEMENTARY and budget[0] > 0]
    return [_node(d.name, f"{prefix}.{d.name}", d.ty, budget) for d in pou.decls
            if d.ty is not None and d.section not in ("VAR_EXTERNAL", "VAR_TEMP") and budget[0] > 0]


def _node(name: str, path: str, ty: Any, budget: list[int]) -> dict:
    budget[0] -= 1
    base = T.base_of(ty)
    node: dict[str, Any] = {"name": name, "path": path, "type": ty.name}
    if isinstance(base, T.FBType):
        node["children"] = _pou_children(base.pou, path, budget)
        node["path"] = None
    elif isinstance(base, T.StructType):
        node["children"] = [_node(base.field_names.get(k, k), f"{path}.{base.field_names.get(k, k)}", t, budget)
                            for k, (t, _init) in base.fields.items() if budget[0] > 0]
        node["path"] = None
    elif isinstance(base, T.ArrayType):
        children = []
        for idx in _indexes(base.dims):
            if len(children) >= MAX_ELEMENTS or budget[0] <= 0:
                node["more"] = True
                break
            children.append(_node(f"[{idx}]", f"{path}[{idx}]", base.elem, budget))
        node["children"] = children
        node["path"] = None
    return node


def _indexes(dims: tuple[tuple[int, int], ...]):
    if not dims:
        yield ""
        return
    (lo, hi), rest = dims[0], dims[1:]
    for i in range(lo, hi + 1):
        for tail in _indexes(rest):
            yield f"{i}," + tail if tail else str(i)


def elementary(plc: Any, path: str) -> tuple[Any, Any, Any]:
    """(container, key, type) of an elementary variable, or a VariableError."""
    try:
        container, key, ty = plc.resolve_typed(path)
    except PlcLabError as e:
        raise VariableError(f"'{path[:80]}': {e}") from None
    if not isinstance(T.base_of(ty), T.ElementaryType):
        raise VariableError(f"'{path[:80]}' is not an elementary variable: pick one of its elements or fields")
    return container, key, ty


def show(value: Any) -> Any:
    """A value as the page shows it (JSON: booleans as TRUE / FALSE, TIME in seconds)."""
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    return value


def parse_value(ty: Any, text: Any) -> Any:
    """The value a student typed for a variable of type `ty`, checked (never wrapped)."""
    base = T.base_of(ty)
    word = str(text).strip()
    if not isinstance(base, T.ElementaryType) or base.kind not in ("bool", "sint", "uint", "bits", "real", "time"):
        raise VariableError(f"{ty.name}: only BOOL, integer, REAL and TIME variables can be forced")
    if base.kind == "bool":
        if word.upper() in ("TRUE", "1"):
            return True
        if word.upper() in ("FALSE", "0"):
            return False
        raise VariableError(f"a BOOL is forced TRUE or FALSE (1 or 0), not '{word[:40]}'")
    if base.kind == "time":
        from plclab.frontend.literals import LiteralError, parse_time
        try:
            return parse_time(word)
        except (LiteralError, ValueError) as e:
            raise VariableError(f"a TIME is forced as T#1s, T#250ms ...: {e}") from None
    if base.kind == "real":
        try:
            value = float(word)
        except ValueError:
            raise VariableError(f"a {ty.name} is forced with a number, not '{word[:40]}'") from None
        if not math.isfinite(value):
            raise VariableError(f"a {ty.name} is forced with a finite number, not '{word[:40]}'")
        return value
    try:
        value = int(word, 0) if word.lower().startswith(("0x", "-0x")) else int(word)
    except ValueError:
        raise VariableError(f"a {ty.name} is forced with a whole number, not '{word[:40]}'") from None
    signed = base.kind == "sint"
    lo, hi = (-(1 << (base.bits - 1)), (1 << (base.bits - 1)) - 1) if signed else (0, (1 << base.bits) - 1)
    if not lo <= value <= hi:
        raise VariableError(f"{value} is outside {ty.name} ({lo}..{hi})")
    return value


class Forces:
    """The forces of the lab's PLC: path -> value, applied in the PLC's I/O stage."""

    def __init__(self) -> None:
        self.values: dict[str, Any] = {}
        self._targets: list[tuple[Any, Any, Any]] = []
        self._plc: Any = None

    def attach(self, plc: Any) -> list[str]:
        """Apply the forces to `plc` (a new PLC after a restart or a load); returns the paths
        it does not have (dropped)."""
        self._plc = plc
        dropped = []
        for path in list(self.values):
            try:
                elementary(plc, path)
            except VariableError:
                dropped.append(path)
                del self.values[path]
        self._resolve()
        if not getattr(plc, "_lab_forces", False):
            read_inputs, write_outputs = plc.read_inputs, plc.write_outputs

            def read_then_force() -> None:
                read_inputs()
                self.apply()

            def force_then_write() -> None:
                self.apply()
                write_outputs()
            plc.read_inputs, plc.write_outputs = read_then_force, force_then_write
            plc._lab_forces = True
        return dropped

    def force(self, path: str, text: Any) -> Any:
        container, key, ty = elementary(self._plc, path)
        if path not in self.values and len(self.values) >= MAX_FORCES:
            raise VariableError(f"at most {MAX_FORCES} forces at once: release one first")
        value = parse_value(ty, text)
        self.values[path] = value
        self._resolve()
        self.apply()
        return value

    def release(self, path: Optional[str] = None) -> list[str]:
        released = [path] if path is not None else list(self.values)
        for p in released:
            self.values.pop(p, None)
        self._resolve()
        return released

    def _resolve(self) -> None:
        targets = []
        for path, value in self.values.items():
            container, key, ty = elementary(self._plc, path)
            wrap: Optional[Callable[[Any], Any]] = T.wrapper_for(ty)
            targets.append((container, key, wrap(value) if wrap is not None else value))
        self._targets = targets

    def apply(self) -> None:
        for container, key, value in self._targets:
            if isinstance(container, list):
                container[key] = value
            else:
                setattr(container, key, value)
