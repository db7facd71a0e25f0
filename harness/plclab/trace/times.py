"""Exact time conversions between the PLC's integer nanoseconds and the seconds people read.

The runtime counts virtual time in integer nanoseconds, so a trace stores integers and converts
only at the edges: `1.25` in a CSV file must be exactly 1 250 000 000 ns, and a time printed for
a student must not show float noise such as `0.30000000000000004`.
"""
from __future__ import annotations

import re
from decimal import Decimal, localcontext

NS_PER_S = 1_000_000_000

_SECONDS_RE = re.compile(r"[+]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?")


def s_to_ns(seconds: float) -> int:
    """Seconds (as a scenario writes them) to the nearest integer nanosecond."""
    return round(seconds * NS_PER_S)


def ns_to_s(ns: int) -> float:
    """Nanoseconds to float seconds, for arithmetic in assertions (`moved - done`)."""
    return ns / NS_PER_S


def format_seconds(ns: int, min_decimals: int = 0) -> str:
    """Exact decimal seconds from integer ns, trailing zeros trimmed (`1.25`, `0.01`, `3`).

    `min_decimals` pads the fraction for log lines that read better aligned (`1.230`).
    """
    sign = "-" if ns < 0 else ""
    whole, frac = divmod(abs(ns), NS_PER_S)
    digits = f"{frac:09d}".rstrip("0").ljust(min_decimals, "0")
    return f"{sign}{whole}.{digits}" if digits else f"{sign}{whole}"


def parse_seconds(text: str) -> int:
    """Non-negative decimal seconds (`1.25`, `0.010`, `2e-3`) to exact integer ns.

    Raises ValueError with a message fit for a user: for text that is not a number and for
    times finer than one nanosecond (rounding them silently would hide a typo).
    """
    text = text.strip()
    if not _SECONDS_RE.fullmatch(text):
        raise ValueError(f"bad time {text!r}: expected non-negative seconds such as 1.25")
    with localcontext() as ctx:
        ctx.prec = 60
        ns = Decimal(text) * NS_PER_S
        if ns != ns.to_integral_value():
            raise ValueError(f"time {text!r} is finer than 1 ns")
    return int(ns)
