"""Comparing a trace with a golden one: the first place they disagree, as one CI log line.

Signals are compared change by change: the k-th change of a signal in one trace pairs with the
k-th change in the other. They agree when the values are equal (NaN equals NaN, BOOL True
equals 1) and the times are at most `tolerance_ns` apart; timing checks use one scan, so an
edge that moved by a scan is not a failure but a missing, extra or wrong-valued change is.
The reported difference is the earliest over all signals (ties: the name that sorts first),
at the earlier of the two paired times. The values shown are what each trace had reached in
its own sequence of changes (the one that changed first shows its new value, the other the
value it still held): with zero tolerance that is exactly the first instant where the two
traces disagree and both traces' values there.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable, Optional

from .csvio import format_value
from .times import format_seconds, ns_to_s
from .trace import Trace, same_value

MISSING: Any = type("Missing", (), {"__repr__": lambda self: "MISSING"})()
"""The value shown for a signal one of the traces does not have."""


@dataclass(frozen=True)
class Difference:
    """The first divergence: which signal, when, and what each trace had there."""

    name: str
    time_ns: int
    expected: Any       # value in the first trace (the golden one); MISSING or None if absent
    got: Any            # value in the second trace
    kind: str = "int"   # how to print the values

    @property
    def time_s(self) -> float:
        return ns_to_s(self.time_ns)

    def __str__(self) -> str:
        return (f"first difference at t={format_seconds(self.time_ns, min_decimals=3)} s: "
                f"{self.name} expected {self._show(self.expected)}, got {self._show(self.got)}")

    def _show(self, value: Any) -> str:
        if value is MISSING:
            return "no such signal"
        if value is None:
            return "no value yet"
        if self.kind == "str":
            return repr(value)
        return format_value(self.kind, value)


def diff(expected: Trace, actual: Trace, tolerance_ns: int = 0,
         names: Optional[Iterable[str]] = None) -> Optional[Difference]:
    """None if the traces agree, else the first Difference.

    `names` limits the comparison (a golden file may hold only the outputs); by default every
    signal of either trace is compared and a signal missing from one side is a difference at
    its first time.
    """
    if tolerance_ns < 0:
        raise ValueError("tolerance_ns must not be negative")
    wanted = sorted(set(expected.signals()) | set(actual.signals()) if names is None
                    else set(names))
    best: Optional[Difference] = None
    for name in wanted:
        found = _diff_signal(expected, actual, name, tolerance_ns)
        if found is not None and (best is None or found.time_ns < best.time_ns):
            best = found     # names are visited in sorted order: ties keep the first name
    return best


def _diff_signal(a: Trace, b: Trace, name: str, tol: int) -> Optional[Difference]:
    in_a, in_b = name in a, name in b
    if not (in_a and in_b):
        if not (in_a or in_b):
            raise LookupError(f"no signal {name!r} in either trace")
        present = a if in_a else b
        t, v = present.changes(name)[0]
        kind = present.info(name).kind
        return Difference(name, t, v if in_a else MISSING, v if in_b else MISSING, kind)
    kind = a.info(name).kind
    ca, cb = a.changes(name), b.changes(name)

    def before(changes: list[tuple[int, Any]], k: int) -> Any:
        """The value a trace holds just before its k-th change, in its own (shifted) timeline."""
        return changes[k - 1][1] if k > 0 else None

    for k in range(max(len(ca), len(cb))):
        if k >= len(ca):
            return Difference(name, cb[k][0], before(ca, k), cb[k][1], kind)
        if k >= len(cb):
            return Difference(name, ca[k][0], ca[k][1], before(cb, k), kind)
        (ta, va), (tb, vb) = ca[k], cb[k]
        if abs(ta - tb) > tol:
            # one trace changed and the other had not yet (even allowing the tolerance)
            if ta < tb:
                return Difference(name, ta, va, before(cb, k), kind)
            return Difference(name, tb, before(ca, k), vb, kind)
        if not same_value(va, vb):
            return Difference(name, min(ta, tb), va, vb, kind)
    return None
