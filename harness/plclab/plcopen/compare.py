"""Are two checked ST units the same program? Used to prove that a PLCopen XML project reads
back to the bundle it was made from.

The comparison is structural: every AST field that carries meaning (names, sections,
qualifiers, types, initial values, locations, statements, tasks, instances), none that
records where it was written (line, column, file) or what the checker derived from it.
Comments and layout are not part of a program.
"""
from __future__ import annotations

import dataclasses
from typing import Any, Optional

from plclab.frontend import ast as A
from plclab.frontend.checked import CheckedUnit

# fields that say where a node is, or that the checker filled in (see frontend/ast.py)
_SKIP = {"line", "col", "file", "key", "ty", "sym", "pou", "std", "arg_types", "fb_type", "call", "param",
         "lo_value", "hi_value", "operand_ty", "init_value", "global_decl", "ret_ty", "symbols", "end_line",
         "interval_ns", "task_decl", "fb_init", "ret_decl", "eno_decl", "bound_params",
         "group_size"}     # group_size: `a, b : INT` is layout (TC6 lists one variable each)

_TYPE_ALIASES = {"TIME_OF_DAY": "TOD", "DATE_AND_TIME": "DT"}


def shape(node: Any) -> Any:
    """A node as a dict of its meaningful fields ("@": its class), lists as tuples: comparable with ==."""
    if isinstance(node, (list, tuple)):
        return tuple(shape(n) for n in node)
    if isinstance(node, A.EnumTypeRef):
        return {"@": "EnumTypeRef", "values": tuple(name for name, _l, _c in node.values)}
    if isinstance(node, A.NamedType):   # TOD and TIME_OF_DAY are one type (TC6 knows only TOD)
        return {"@": "NamedType", "name": _TYPE_ALIASES.get(node.key, node.name)}
    if isinstance(node, A.StructInit):
        return {"@": "StructInit", "fields": tuple((name, shape(v)) for name, _l, _c, v in node.fields)}
    if isinstance(node, A.Node):
        out = {"@": type(node).__name__}
        out.update((f.name, shape(getattr(node, f.name))) for f in dataclasses.fields(node) if f.name not in _SKIP)
        if isinstance(node, A.VarBlock):   # NON_RETAIN is kept only in the parser's qualifier list
            out["qualifiers"] = tuple(sorted(set(getattr(node, "qualifiers", []))))
        return out
    return node


def program_shape(checked: CheckedUnit) -> dict:
    """The whole program: types, POUs and configurations, in declaration order."""
    u = checked.unit
    return {"@": "program", "types": shape(u.types), "pous": shape(u.pous), "configurations": shape(u.configs),
            "global lists": shape(u.gvls)}


def first_difference(a: CheckedUnit, b: CheckedUnit) -> Optional[str]:
    """None when `a` and `b` are the same program, else where they first differ, e.g.
    `pous[3] FB_Mp9cManual .blocks[0] .decls[1] Reset .init: None vs ...`."""
    return _diff(program_shape(a), program_shape(b), "")


def _diff(x: Any, y: Any, path: str) -> Optional[str]:
    if x == y:
        return None
    if isinstance(x, dict) and isinstance(y, dict) and x["@"] == y["@"]:
        for key in x:
            d = _diff(x[key], y.get(key), f"{path}.{key}")
            if d:
                return d
    elif isinstance(x, tuple) and isinstance(y, tuple):
        for i, (xi, yi) in enumerate(zip(x, y)):
            name = xi.get("name") if isinstance(xi, dict) else None
            d = _diff(xi, yi, f"{path}[{i}]" + (f" {name} " if isinstance(name, str) else ""))
            if d:
                return d
        return f"{path or '/'}: {len(x)} items vs {len(y)}"
    return f"{path or '/'}: {_short(x)} vs {_short(y)}"


def _short(v: Any, limit: int = 120) -> str:
    text = repr(v)
    return text if len(text) <= limit else text[:limit] + "..."
