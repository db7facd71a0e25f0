"""Decoding of ST literal text into runtime values (see plclab.iec.types for the representation).

Kept apart from the grammar so each literal form has one place that knows its rules and
can say precisely what is wrong with a malformed one.
"""
from __future__ import annotations

import datetime as _dt
import re

NS = {"D": 86_400 * 10**9, "H": 3_600 * 10**9, "M": 60 * 10**9, "S": 10**9,
      "MS": 10**6, "US": 10**3, "NS": 1}
_UNIT_ORDER = ["D", "H", "M", "S", "MS"]
_UNIT_MAX = {"H": 23, "M": 59, "S": 59, "MS": 999}   # limits of every part after the first (matiec)
_TIME_PART = re.compile(r"([0-9][0-9_]*(?:\.[0-9][0-9_]*)?)(MS|D|H|M|S)(?![A-Za-z])", re.I)
_EPOCH = _dt.date(1970, 1, 1)


class LiteralError(ValueError):
    """A literal whose text does not follow the IEC 61131-3 rules; str() is the message."""


def _digits(text: str) -> str:
    if "__" in text or text.endswith("_"):
        raise LiteralError(f"malformed number '{text}': underscores only between digits")
    return text.replace("_", "")


ULINT_MAX = 2**64 - 1


def _checked_int(digits: str, base: int, text: str) -> int:
    # the length test first: int() refuses very long digit strings with an unrelated message
    if len(digits.lstrip("0")) > 64 or int(digits, base) > ULINT_MAX:
        shown = text if len(text) <= 30 else text[:27] + "..."
        raise LiteralError(f"integer literal {shown} is too large (the largest is {ULINT_MAX}, ULINT)")
    return int(digits, base)


def parse_int(text: str) -> int:
    return _checked_int(_digits(text), 10, text)


def parse_based(text: str) -> int:
    base, _, digits = text.partition("#")
    if not digits or digits.startswith("_"):
        raise LiteralError(f"malformed based number '{text}'")
    return _checked_int(_digits(digits), int(base), text)


def parse_real(text: str) -> float:
    mantissa, _, exp = text.lower().partition("e")
    value = float(_digits(mantissa) + (("e" + _digits(exp)) if exp else ""))
    if value == float("inf"):
        shown = text if len(text) <= 30 else text[:27] + "..."
        raise LiteralError(f"real literal {shown} is too large even for LREAL")
    return value


def parse_time(text: str) -> int:
    """`T#1s500ms`, `TIME#-2.5s`, `t#1d_2h` -> signed nanoseconds."""
    prefix, body = text.split("#", 1)
    if prefix.upper() in ("LT", "LTIME"):
        raise LiteralError(f"'{prefix}#' (LTIME) is not supported by OpenPLC's compiler; use T#")
    sign = 1
    if body[:1] == "-":
        sign = -1
        body = body[1:]
    pos = 0
    total = 0.0
    exact = 0
    last_unit = -1
    parts = 0
    while pos < len(body):
        if body[pos] == "_" and parts:
            pos += 1
            continue
        m = _TIME_PART.match(body, pos)
        if not m:
            raise LiteralError(f"malformed time literal '{text}': expected a number and a unit "
                               f"(d, h, m, s, ms) at '{body[pos:]}'")
        number, unit = m.group(1), m.group(2).upper()
        order = _UNIT_ORDER.index(unit)
        if order <= last_unit:
            raise LiteralError(f"malformed time literal '{text}': units must go from days down to "
                               f"nanoseconds, each at most once")
        if "." in number and m.end() != len(body):
            raise LiteralError(f"malformed time literal '{text}': only the last unit may have a fraction")
        digits = _digits(number)
        if parts and unit in _UNIT_MAX and float(digits) > _UNIT_MAX[unit]:
            raise LiteralError(f"malformed time literal '{text}': after the first part, {unit.lower()} "
                               f"must be 0..{_UNIT_MAX[unit]}")
        last_unit = order
        if "." in digits:
            whole, frac = digits.split(".")
            exact += int(whole) * NS[unit] + (int(frac) * NS[unit]) // (10 ** len(frac))
        else:
            exact += int(digits) * NS[unit]
        pos = m.end()
        parts += 1
    if not parts:
        raise LiteralError(f"malformed time literal '{text}': no duration given")
    del total
    return sign * exact


def parse_date(text: str) -> int:
    """`D#2024-03-05` -> nanoseconds since 1970-01-01."""
    body = _digits_keep_sep(text.split("#", 1)[1])
    try:
        y, m, d = (int(x) for x in body.split("-"))
        day = _dt.date(y, m, d)
    except (ValueError, TypeError):
        raise LiteralError(f"malformed date literal '{text}': expected YYYY-MM-DD") from None
    return (day - _EPOCH).days * NS["D"]


def parse_tod(text: str) -> int:
    """`TOD#12:30:15.5` -> nanoseconds since midnight."""
    body = _digits_keep_sep(text.split("#", 1)[1])
    return _parse_daytime(body, text)


def parse_dt(text: str) -> int:
    """`DT#2024-03-05-12:30:00` -> nanoseconds since 1970-01-01T00:00."""
    body = _digits_keep_sep(text.split("#", 1)[1])
    parts = body.split("-")
    if len(parts) != 4:
        raise LiteralError(f"malformed date-and-time literal '{text}': expected YYYY-MM-DD-hh:mm:ss")
    date_ns = parse_date("D#" + "-".join(parts[:3]))
    return date_ns + _parse_daytime(parts[3], text)


def _digits_keep_sep(body: str) -> str:
    return body.replace("_", "")


def _parse_daytime(body: str, text: str) -> int:
    try:
        h, m, s = body.split(":")
        hh, mm = int(h), int(m)
        if "." in s:
            whole, frac = s.split(".")
            sec_ns = int(whole) * 10**9 + int(frac.ljust(9, "0")[:9])
        else:
            sec_ns = int(s) * 10**9
    except ValueError:
        raise LiteralError(f"malformed time-of-day in '{text}': expected hh:mm:ss[.fff]") from None
    if not (0 <= hh < 24 and 0 <= mm < 60 and 0 <= sec_ns < 60 * 10**9):
        raise LiteralError(f"time of day out of range in '{text}'")
    return hh * NS["H"] + mm * NS["M"] + sec_ns


_ESCAPES = {"$": "$", "'": "'", '"': '"', "L": "\n", "N": "\n", "P": "\f", "R": "\r", "T": "\t"}


def parse_string(text: str) -> str:
    """`'It$'s$N'` -> the characters, with IEC `$` escapes decoded."""
    quote = text[0]
    body = text[1:-1]
    for ch in body:
        if not " " <= ch <= "~":
            raise LiteralError(f"character {ch!r} is not allowed in a string literal (printable ASCII "
                               f"only; write $T, $N, $hh escapes)")
    out = []
    i = 0
    while i < len(body):
        c = body[i]
        if c == "$":
            nxt = body[i + 1:i + 2]
            esc = _ESCAPES.get(nxt.upper())
            if esc is not None and not (nxt in "'\"" and nxt != quote and nxt != "$"):
                out.append(esc)
                i += 2
                continue
            hexlen = 2 if quote == "'" else 4
            code = body[i + 1:i + 1 + hexlen]
            if len(code) == hexlen and all(ch in "0123456789abcdefABCDEF" for ch in code):
                out.append(chr(int(code, 16)))
                i += 1 + hexlen
                continue
            raise LiteralError(f"invalid escape '${nxt}' in string literal")
        out.append(c)
        i += 1
    return "".join(out)
