"""The integer range of an ST expression's value, so the compiler can leave out wraps that
cannot happen.

C wraps an integer result only when it leaves its type; Python's integers never do, so the
compiled code wraps explicitly, and a wrap costs as much as the operation it guards. Most
wraps in a PLC program guard nothing: `count + 1` of an INT is computed in C's 32-bit int
and cannot leave it, `x MOD 7` always fits in an INT. Interval arithmetic over the declared
types proves this at compile time.

The invariant it rests on: a variable always holds a value of its type (every store narrows,
and so do the image copies and `PLC.write`).
"""
from __future__ import annotations

from typing import Optional

from plclab.frontend import ast as A
from plclab.frontend.checked import LiteralType
from plclab.iec import types as T

Range = tuple[int, int]

_C_INT: Range = (-(1 << 31), (1 << 31) - 1)


def concrete(t: Optional[T.Type]) -> Optional[T.Type]:
    """A literal's type as C sees it: an untyped integer literal is a DINT, a real an LREAL."""
    if isinstance(t, LiteralType):
        return T.DINT if t.kind == "int" else T.LREAL
    return t


def int_type(t: Optional[T.Type]) -> Optional[T.ElementaryType]:
    """The elementary integer or bit-string type (not BOOL) of values of type `t`, if any."""
    b = T.base_of(concrete(t)) if t is not None else None
    if isinstance(b, T.ElementaryType) and b.kind in ("sint", "uint", "bits"):
        return b
    return None


def ring_type(e: A.Expr) -> Optional[T.ElementaryType]:
    """The integer type of a + - * or unary - node (a ring operation), else None.

    Wrapping commutes with ring operations, so the compiler computes a chain of them with
    Python's exact integers and wraps once, where the value leaves the chain."""
    if (isinstance(e, A.Binary) and e.op in ("+", "-", "*")) or (isinstance(e, A.Unary) and e.op == "-"):
        return int_type(e.ty)
    return None


def type_range(b: T.ElementaryType) -> Range:
    return b.min, b.max


def promoted_range(b: T.ElementaryType) -> Range:
    """Where C computes an operation on `b`: SINT/INT/USINT/UINT/BYTE/WORD operands are
    promoted to 32-bit int, wider types stay themselves."""
    return _C_INT if b.bits < 32 else type_range(b)


def wrap_bounds(b: T.ElementaryType) -> Range:
    """Where the compiled code wraps a ring operation on `b` (Compiler.wrap): a small signed
    or unsigned integer in C's int, a bit string and a wider type in the type itself."""
    return _C_INT if b.kind in ("sint", "uint") and b.bits < 32 else type_range(b)


def within(r: Optional[Range], bounds: Range) -> bool:
    return r is not None and bounds[0] <= r[0] and r[1] <= bounds[1]


class RangeOf:
    """Ranges of expressions of one compilation (memoised per node)."""

    def __init__(self) -> None:
        self._memo: dict[int, Optional[Range]] = {}

    def value(self, e: A.Expr) -> Optional[Range]:
        """The range of the value the compiled expression yields (after any wrap it needs)."""
        key = id(e)
        if key not in self._memo:
            self._memo[key] = self._value(e)
        return self._memo[key]

    def raw(self, e: A.Expr) -> Optional[Range]:
        """For a ring operation: the range of its exact result, before the wrap."""
        b = ring_type(e)
        if b is None:
            return self.value(e)
        if isinstance(e, A.Unary):
            r = self._child(e.operand, b)
            return (-r[1], -r[0]) if r is not None else None
        lr, rr = self._child(e.left, b), self._child(e.right, b)
        if lr is None or rr is None:
            return None
        if e.op == "+":
            return lr[0] + rr[0], lr[1] + rr[1]
        if e.op == "-":
            return lr[0] - rr[1], lr[1] - rr[0]
        products = [x * y for x in lr for y in rr]
        return min(products), max(products)

    def _child(self, e: A.Expr, b: T.ElementaryType) -> Optional[Range]:
        # the compiler keeps a child of the same ring type unwrapped (Compiler._ring_child)
        return self.raw(e) if ring_type(e) is b else self.value(e)

    def _value(self, e: A.Expr) -> Optional[Range]:
        if isinstance(e, A.Literal):
            v = e.value
            return (v, v) if isinstance(v, int) and not isinstance(v, bool) else None
        b = int_type(e.ty)
        if b is None:
            return None
        if isinstance(e, (A.Name, A.Member, A.Index, A.Call)):
            return type_range(b)          # stored (or returned) values are of their type
        ring = ring_type(e)
        if ring is not None:
            r = self.raw(e)
            bounds = wrap_bounds(ring)
            return r if within(r, bounds) else bounds
        if isinstance(e, A.Binary) and e.op == "MOD":
            a = self.value(e.left)
            d = e.right.value if isinstance(e.right, A.Literal) else None
            if a is not None:
                lo, hi = min(a[0], 0), max(a[1], 0)   # C's %: |r| <= |a|, the sign of a
                if isinstance(d, int) and d > 0:
                    lo, hi = max(lo, 1 - d), min(hi, d - 1)
                return lo, hi
        if isinstance(e, A.Binary) and e.op in ("AND", "OR", "XOR"):
            lr, rr = self.value(e.left), self.value(e.right)
            if within(lr, type_range(b)) and within(rr, type_range(b)) and b.min == 0:
                return type_range(b)      # bits of two values of the type stay in it
        return promoted_range(b)
