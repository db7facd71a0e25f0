"""AST pieces back to ST text: expressions, initial values and types as TC6 stores them
(`simpleValue value="T#1s"`, `dimension lower="1"`), and as the round-trip check compares them.

Literals keep the text the user wrote (`16#FF`, `T#1s500ms`), so a value survives the trip
unchanged; operators are fully parenthesised, which is always what the source meant.
"""
from __future__ import annotations

from typing import Any

from plclab.errors import PlcLabError
from plclab.frontend import ast as A


def expr(e: A.Expr) -> str:
    if isinstance(e, A.Literal):
        return e.text
    if isinstance(e, A.Name):
        return e.name
    if isinstance(e, A.Member):
        return f"{expr(e.base)}.{e.name}"
    if isinstance(e, A.Index):
        return f"{expr(e.base)}[{', '.join(expr(i) for i in e.indexes)}]"
    if isinstance(e, A.Unary):
        inner = expr(e.operand)
        if isinstance(e.operand, (A.Binary, A.Unary)):
            inner = f"({inner})"
        return f"NOT {inner}" if e.op == "NOT" else f"-{inner}"
    if isinstance(e, A.Binary):
        return f"{_operand(e.left)} {e.op} {_operand(e.right)}"
    if isinstance(e, A.Call):
        return f"{e.name}({', '.join(arg(a) for a in e.args)})"
    raise PlcLabError(f"line {e.line}: cannot write this expression as text ({type(e).__name__})")


def _operand(e: A.Expr) -> str:
    return f"({expr(e)})" if isinstance(e, A.Binary) else expr(e)


def arg(a: A.Arg) -> str:
    if a.name is None:
        return expr(a.value)
    if a.is_output:
        return f"{'NOT ' if a.negated else ''}{a.name} => {expr(a.value)}"
    return f"{a.name} := {expr(a.value)}"


def initializer(init: Any) -> str:
    """`5`, `[1, 2, 3(0)]`, `(Data := [5(0)], Pause := T#1s)`."""
    if isinstance(init, A.ArrayInit):
        items = []
        for count, value in init.items:
            if count is None:
                items.append(initializer(value))
            else:
                items.append(f"{expr(count)}({'' if value is None else initializer(value)})")
        return f"[{', '.join(items)}]"
    if isinstance(init, A.StructInit):
        return "(" + ", ".join(f"{name} := {initializer(v)}" for name, _l, _c, v in init.fields) + ")"
    return expr(init)


def type_ref(t: A.TypeRef) -> str:
    """A type as declared: `INT`, `STRING[20]`, `ARRAY[1..5] OF INT`, `(RUN, STOP)`, `INT (0..100)`."""
    if isinstance(t, A.NamedType):
        return t.name
    if isinstance(t, A.StringTypeRef):
        word = "WSTRING" if t.wide else "STRING"
        return f"{word}[{expr(t.length)}]" if t.length is not None else word
    if isinstance(t, A.ArrayTypeRef):
        dims = ", ".join(f"{expr(lo)}..{expr(hi)}" for lo, hi in t.ranges)
        return f"ARRAY[{dims}] OF {type_ref(t.elem)}"
    if isinstance(t, A.EnumTypeRef):
        return "(" + ", ".join(name for name, _l, _c in t.values) + ")"
    if isinstance(t, A.SubrangeTypeRef):
        return f"{t.base.name} ({expr(t.lo)}..{expr(t.hi)})"
    raise PlcLabError(f"line {t.line}: cannot write this type as text ({type(t).__name__})")
