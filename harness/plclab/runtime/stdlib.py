"""IEC 61131-3 standard functions with the run-time semantics of OpenPLC v3's matiec library.

The reference is the C library OpenPLC compiles every program with
(`webserver/core/lib/iec_std_lib.h`, `iec_std_functions.h`, the same as
`utils/matiec_src/lib/C/` in `thiagoralves/OpenPLC_v3`) and the C that matiec's `iec2c`
generates for ST operators (`stage4/generate_c/generate_c_st.cc`). Where that library differs
from the letter of IEC 61131-3 (TIME conversions count seconds, FIND has an off-by-one bug,
string comparisons only look at the common prefix...) this module follows OpenPLC, because
that is what a student's program does on the real runtime. `docs/openplc-stdlib-notes.md`
lists every such fact with its source.

Values follow the contract of `plclab.iec.types`: BOOL -> bool, integers and bit strings ->
int wrapped to the type's width, REAL -> float rounded to single precision, LREAL -> float,
TIME/DATE/TOD/DT -> int nanoseconds, STRING -> str (at most 126 characters).

Undefined behaviour in C is modelled as gcc on x86-64 (OpenPLC's usual Linux/Docker target)
does it: an out-of-range double -> integer conversion gives the "integer indefinite" value
(-2**31 for <= 32-bit targets, -2**63 for 64-bit ones), a shift count is masked to 5 bits
(6 for 64-bit operands), `INT_MIN / -1` on DINT/LINT traps. Cases that would crash OpenPLC's
runtime process (a trap, a memcpy of a negative size) raise `PlcRuntimeFault` here.

Public API
----------
lookup(name, arg_types, result_type) -> callable
    A Python callable for one instantiation of a standard function, e.g.
    `lookup("ADD", [INT, INT, INT], INT)(30000, 2767, 1) == -32768`. Arguments are passed
    positionally in declaration order (SEL: G, IN0, IN1; MUX: K, IN0, IN1...; LIMIT: MN, IN,
    MX; MID: IN, L, P...). Extensible functions take any number of inputs. Explicitly typed
    names (`ADD_INT`, `SEL_STRING`, `GT_TIME`) and conversions (`REAL_TO_INT`,
    `UINT_TO_BCD_WORD`, `WORD_BCD_TO_UINT`, `TRUNC`) work the same way. Results are cached.
    Raises NoSuchFunction when OpenPLC's library has no such function for those types.

lookup_operator(op, arg_types, result_type) -> callable
    The same for ST operators, which matiec compiles to C operators or to library helpers
    (`+ - * / MOD = <> < <= > >= AND OR XOR NOT NEG`; `**` is refused by the
    front end: the C it becomes does not build in OpenPLC).

The signatures the type checker uses (which functions exist, their parameters and generic
types) are in plclab.frontend.stdsigs: one table, so the checker and the runtime cannot
disagree on what exists (tests/test_library_consistency.py checks that every function it
accepts has an implementation here).

PlcRuntimeFault(kind, message)
    kind is "division_by_zero" (integer `/` by zero), "division_overflow" (DINT/LINT
    minimum divided by -1, which traps on x86) or "memory_fault" (a string function call that
    makes OpenPLC's library copy a negative or out-of-buffer number of bytes).
    Deliberately *not* faults, because OpenPLC's library defines a result: MOD by zero
    (operator and function) -> 0, the DIV function by zero -> 0 (the `/` operator faults),
    MUX with K out of range -> the type's initial value, *_BCD_TO_* of an invalid BCD -> 0.
"""
from __future__ import annotations

import math
import re
from functools import lru_cache
from typing import Any, Callable, Optional, Sequence

from plclab.iec import types as T
from plclab.iec.types import ElementaryType, StringType, Type, base_of, to_f32, wrapper_for
from plclab.runtime.faults import PlcFault

Fn = Callable[..., Any]

STR_MAX_LEN = 126            # iec_types.h: STR_MAX_LEN; the length field is an int8_t
NS = T.NS_PER_S
_M64 = (1 << 64) - 1


# --------------------------------------------------------------------------- errors


# A run-time error of the PLC program (OpenPLC's runtime would crash or trap here): the
# runtime's one fault class. `kind` is "division_by_zero", "division_overflow" or
# "memory_fault" here; the runtime adds the POU and source line and puts the PLC in FAULT.
PlcRuntimeFault = PlcFault


class NoSuchFunction(LookupError):
    """The library has no such function for these argument types (OpenPLC would not build)."""


# --------------------------------------------------------------------------- C emulation


def _wrap_bits(v: int, bits: int, signed: bool) -> int:
    v &= (1 << bits) - 1
    if signed and v >> (bits - 1):
        v -= 1 << bits
    return v


def _i8(v: int) -> int:
    """A value stored into matiec's `__strlen_t` (int8_t)."""
    return _wrap_bits(v, 8, True)


def _i32(v: int) -> int:
    return _wrap_bits(v, 32, True)


def _i64(v: int) -> int:
    return _wrap_bits(v, 64, True)


def _cvtt(x: float, bits: int) -> int:
    """x86 cvttsd2si: truncate toward zero; NaN or out of range -> the 'integer indefinite'."""
    limit = 1 << (bits - 1)
    if x != x or not (-limit <= x < limit):  # the range test also rejects +-inf
        return -limit
    return int(x)


def c_double_to(x: float, t: ElementaryType) -> int:
    """C's `(T)x` for a double x and integer type T, as gcc compiles it for x86-64."""
    bits, kind = t.bits, t.kind
    if kind == "sint":
        v = _cvtt(x, 64) if bits == 64 else _cvtt(x, 32)
        return _wrap_bits(v, bits, True)
    if bits <= 16:                      # unsigned char/short: via a 32-bit conversion
        return _cvtt(x, 32) & ((1 << bits) - 1)
    if bits == 32:                      # unsigned int: via a 64-bit conversion
        return _cvtt(x, 64) & 0xFFFFFFFF
    if x != x:                          # unsigned long: gcc splits at 2**63
        return 1 << 63
    if x < 2.0 ** 63:
        return _cvtt(x, 64) & _M64
    return (_cvtt(x - 2.0 ** 63, 64) ^ (1 << 63)) & _M64


def _cdiv(a: int, b: int) -> int:
    """C integer division (truncates toward zero). b != 0."""
    q = abs(a) // abs(b)
    return q if (a < 0) == (b < 0) else -q


def _cmod(a: int, b: int) -> int:
    """C `%`: the remainder has the sign of the dividend. b != 0."""
    return a - b * _cdiv(a, b)


def _fdiv(a: float, b: float) -> float:
    """IEEE 754 division as C does it (Python raises on a zero divisor)."""
    if b == 0.0:
        if a != a or a == 0.0:
            return math.nan
        neg = (a < 0) != (math.copysign(1.0, b) < 0)
        return -math.inf if neg else math.inf
    return a / b


def _is_odd_int(y: float) -> bool:
    return math.isfinite(y) and y == math.floor(y) and math.fmod(y, 2.0) != 0.0


def _c_pow(x: float, y: float) -> float:
    """C99 pow(): domain errors give NaN, poles and overflow give +-inf (no exceptions)."""
    try:
        return math.pow(x, y)
    except OverflowError:
        return -math.inf if (x < 0 and _is_odd_int(y)) else math.inf
    except ValueError:
        if x == 0.0 and y < 0:
            return math.copysign(math.inf, x) if _is_odd_int(y) else math.inf
        return math.nan


def _c_math(f: Callable[[float], float], at_zero: Optional[float] = None) -> Callable[[float], float]:
    """Wrap a math function to return C's special values instead of raising."""
    def g(x: float) -> float:
        try:
            return f(x)
        except OverflowError:
            return math.inf
        except ValueError:
            if x == 0.0 and at_zero is not None:
                return at_zero
            return math.nan
    return g


def _int_to_f32(v: int) -> float:
    """(float)v for a 64-bit integer: one correct rounding (float(v) first could round twice)."""
    if -(1 << 53) <= v <= (1 << 53):
        return to_f32(float(v))
    a = abs(v)
    shift = a.bit_length() - 24
    q, r = divmod(a, 1 << shift)
    half = 1 << (shift - 1)
    if r > half or (r == half and q & 1):
        q += 1
    f = to_f32(float(q << shift))
    return -f if v < 0 else f


# --------------------------------------------------------------------------- TIME helpers
# matiec stores TIME/DATE/TOD/DT as a timespec {tv_sec, tv_nsec} with both fields of the
# same sign; here they are int nanoseconds, and these helpers go back and forth.


def _timespec(ns: int) -> tuple[int, int]:
    sec = _cdiv(ns, NS)
    return sec, ns - sec * NS


def _ts_ns(sec: int, nsec: int) -> int:
    return _i64(sec * NS + nsec)


def _time_mul(t: int, k: float) -> int:
    """iec_std_lib.h __time_mul: (int)(tv_nsec * k) overflows for products past 2**31 ns."""
    sec, nsec = _timespec(t)
    s_f = sec * k
    s = _cvtt(s_f, 64)
    prod = _cvtt(float(nsec) * k, 32)
    quot = _cdiv(prod, NS)
    rem = prod - quot * NS
    return _ts_ns(s + quot, _cvtt(rem + (s_f - s) * 1e9, 64))


def _time_div(t: int, k: float) -> int:
    """iec_std_lib.h __time_div (no check for k == 0: the result is garbage, not a crash)."""
    sec, nsec = _timespec(t)
    s_f = _fdiv(float(sec), k)
    s = _cvtt(s_f, 64)
    return _ts_ns(s, _cvtt(_fdiv(float(nsec), k) + (s_f - s) * 1e9, 64))


def _time_to_real(t: int) -> float:
    sec, nsec = _timespec(t)
    return float(sec) + float(nsec) / 1e9


time_to_seconds = _time_to_real     # __time_to_real: TIME_TO_LREAL, used by stdfb too
ieee_div = _fdiv                    # C float division, used by stdfb too


def _real_to_time(x: float) -> int:
    """iec_std_lib.h __real_to_time: x is a number of *seconds*."""
    sec = _cvtt(x, 64)
    return _ts_ns(sec, _cvtt((x - float(sec)) * 1e9, 64))


_MON_YDAY = ((0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334, 365),
             (0, 31, 60, 91, 121, 152, 182, 213, 244, 274, 305, 335, 366))


def _isleap(y: int) -> bool:
    return y % 4 == 0 and (y % 100 != 0 or y % 400 == 0)


def _broken_down(seconds: int) -> tuple[int, int, int, int, int, int]:
    """iec_std_lib.h convert_seconds_to_date_and_time, bug included: its month search uses
    `>` where `>=` is needed, so the first day of every month but January comes out as day
    (length of previous month + 1) of the previous month, e.g. 1970-02-01 -> 1970-01-32."""
    days = _cdiv(seconds, 86400)
    rem = seconds - days * 86400
    if rem < 0:
        rem += 86400
        days -= 1
    hour, rem = divmod(rem, 3600)
    minute, sec = divmod(rem, 60)
    year = 1970
    while days >= (366 if _isleap(year) else 365):
        days -= 366 if _isleap(year) else 365
        year += 1
    while days < 0:
        year -= 1
        days += 366 if _isleap(year) else 365
    table = _MON_YDAY[_isleap(year)]
    mon = 1
    while days > table[mon]:
        mon += 1
    return year, mon, days - table[mon - 1] + 1, hour, minute, sec


def _time_to_string(t: int) -> str:
    sec, nsec = _timespec(t)
    dq, dr = _cdiv(_i32(sec), 86400), _cmod(_i32(sec), 86400)
    if dr == 0 and nsec == 0:
        return "T#%dd" % dq
    hq, hr = _cdiv(dr, 3600), _cmod(dr, 3600)
    if hr == 0 and nsec == 0:
        return "T#%dd%dh" % (dq, hq)
    mq, mr = _cdiv(hr, 60), _cmod(hr, 60)
    if mr == 0 and nsec == 0:
        return "T#%dd%dh%dm" % (dq, hq, mq)
    if nsec == 0:
        return "T#%dd%dh%dm%ds" % (dq, hq, mq, mr)
    return ("T#%dd%dh%dm%ds%gms" % (dq, hq, mq, mr, nsec / 1e6))[:STR_MAX_LEN]


def _date_to_string(t: int) -> str:
    y, mo, d, _h, _mi, _s = _broken_down(_timespec(t)[0])
    return "D#%d-%2.2d-%2.2d" % (y, mo, d)


def _tod_to_string(t: int) -> str:
    sec, nsec = _timespec(t)
    if sec >= 86400:
        return "TOD#ERROR"
    _y, _mo, _d, h, mi, s = _broken_down(sec)
    if nsec == 0:
        return "TOD#%2.2d:%2.2d:%2.2d" % (h, mi, s)
    return "TOD#%2.2d:%2.2d:%09.6f" % (h, mi, s + nsec / 1e9)


def _dt_to_string(t: int) -> str:
    sec, nsec = _timespec(t)
    y, mo, d, h, mi, s = _broken_down(sec)
    if nsec == 0:
        return "DT#%d-%2.2d-%2.2d-%2.2d:%2.2d:%2.2d" % (y, mo, d, h, mi, s)
    return "DT#%d-%2.2d-%2.2d-%2.2d:%2.2d:%09.6f" % (y, mo, d, h, mi, s + nsec / 1e9)


def _dt_to_tod(t: int) -> int:
    sec, nsec = _timespec(t)
    return _ts_ns(_cmod(sec, 86400) + (86400 if sec < 0 else 0), nsec)


def _dt_to_date(t: int) -> int:
    sec, _nsec = _timespec(t)
    return _ts_ns(sec - _cmod(sec, 86400) - (86400 if sec < 0 else 0), 0)


# --------------------------------------------------------------------------- REAL -> integer


def _real_round(x: float) -> int:
    """iec_std_lib.h __real_round: called with x +- 0.5, it turns exact halves into the even
    neighbour ((LINT)x / 2 * 2), so REAL_TO_INT rounds half to even: 2.5 -> 2, 3.5 -> 4."""
    if math.isfinite(x) and math.fmod(x, 1.0) == 0.0:
        return _cdiv(_cvtt(x, 64), 2) * 2
    return _cvtt(x, 64)


def _real_to_sint(x: float) -> int:
    return _real_round(x + 0.5) if x >= 0 else _real_round(x - 0.5)


def _real_to_uint(x: float) -> int:
    """Negative values (and NaN) become 0 instead of wrapping (__preal_to_uint)."""
    return _real_round(x + 0.5) & _M64 if x >= 0 else 0


# --------------------------------------------------------------------------- STRING helpers


_ASCII_UPPER = str.maketrans("abcdefghijklmnopqrstuvwxyz", "ABCDEFGHIJKLMNOPQRSTUVWXYZ")


def _string_to_bool(s: str) -> bool:
    if len(s) == 1:
        return s == "1"
    return len(s) == 4 and s.translate(_ASCII_UPPER) == "TRUE"


def _int_shift32(d: int, shift: int) -> int:
    """`(int)d << shift` with x86's 5-bit count, sign-extended into a LINT."""
    return _i32(d << (shift & 31))


def _pstring_to_sint(s: str) -> int:
    """iec_std_lib.h __pstring_to_sint. Decimal strings are read from the right; any
    character >= '.' that is not a digit (a '.', '_', a letter) restarts the number, so
    '12.7' -> 12, '1_000' -> 1, '12abc' -> 12, 'abc' -> 0. '2#', '8#', '16#' prefixes select
    another base; other characters are skipped there."""
    b = s + "\0\0\0"
    res = 0
    shift = 0
    n = len(s)
    if b[0] == "2" and b[1] == "#":
        for c in reversed(s[2:]):
            if shift >= 64:
                break
            if c in "01":
                res |= _int_shift32(ord(c) - 48, shift)
                shift += 1
    elif b[0] == "8" and b[1] == "#":
        for c in reversed(s[2:]):
            if shift >= 64:
                break
            if "0" <= c <= "7":
                res |= _int_shift32(ord(c) - 48, shift)
                shift += 3
    elif b[0] == "1" and b[1] == "6" and b[2] == "#":
        for c in reversed(s[3:]):
            if shift >= 64:
                break
            d = int(c, 16) if c in "0123456789abcdefABCDEF" else -1
            if d >= 0:
                res |= d << shift
                shift += 4
    else:
        sign = -1 if b[0] == "-" else 1
        fac = sign
        for i in range(n - 1, -1, -1):
            if shift >= 20:
                break
            o = ord(s[i])
            if 48 <= o <= 57:
                res = _i64(res + (o - 48) * fac)
                fac = _i64(fac * 10)
                shift += 1
            elif 0x2E <= o < 0x80:      # char is signed on x86: bytes >= 0x80 are negative
                res, fac, shift = 0, sign, 0
    return _i64(res)


_ATOF = re.compile(r"[ \t\n\v\f\r]*([+-]?)(?:(0[xX](?:[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)"
                   r"(?:[pP][+-]?[0-9]+)?)|((?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)"
                   r"|(inf(?:inity)?)|(nan))", re.IGNORECASE)


def _atof(s: str) -> float:
    """C atof(): the longest prefix that strtod accepts, 0.0 when there is none."""
    m = _ATOF.match(s)
    if not m:
        return 0.0
    sign, hexpart, dec, inf, nan = m.groups()
    if hexpart:
        txt = hexpart if re.search("[pP]", hexpart) else hexpart + "p0"
        v = float.fromhex(txt)
    elif dec:
        v = float(dec)
    elif inf:
        v = math.inf
    else:
        v = math.nan
    return -v if sign == "-" else v


def _has_dot_after_first(s: str) -> bool:
    """The `while(--l > 0 && body[l] != '.')` search of __string_to_real: a '.' at index 0 is
    not seen; an empty string counts as 'found' (and atof("") is 0.0)."""
    if not s:
        return True
    return "." in s[1:]


def _string_to_real(s: str) -> float:
    return _atof(s) if _has_dot_after_first(s) else float(_pstring_to_sint(s))


def _string_to_time(s: str) -> int:
    """__string_to_time: whole seconds only. With a '.', the fraction is cast to long *before*
    it is scaled, so it is always lost ('1.5' -> T#1s); 'T#5s' reads as 0 (see _pstring)."""
    if _has_dot_after_first(s):
        return _ts_ns(_cvtt(_atof(s), 64), 0)
    return _ts_ns(_pstring_to_sint(s), 0)


def _str_cmp(a: str, b: str) -> int:
    """__STR_CMP: memcmp over the *shorter* length only, so 'AB' = 'ABC'."""
    n = min(len(a), len(b))
    x, y = a[:n], b[:n]
    return (x > y) - (x < y)


class _StrMem:
    """A STRING as matiec lays it out: `int8 len; uint8 body[126]`. body[-1] is the length
    byte, body past `len` holds zeros. Reads outside the struct are a memory fault."""

    __slots__ = ("mem",)

    def __init__(self, s: str) -> None:
        self.mem = chr(len(s)) + s + "\0" * (STR_MAX_LEN - len(s))

    def read(self, start: int, count: int, fn: str) -> str:
        if count < 0 or start < -1 or start + count > STR_MAX_LEN:
            raise PlcRuntimeFault(
                "memory_fault",
                f"{fn}: OpenPLC's library would copy {count} bytes from offset {start} of a "
                f"{STR_MAX_LEN}-byte string (undefined behaviour, usually a crash)")
        return self.mem[start + 1:start + 1 + count]


def _check_len(n: int, fn: str) -> None:
    if n > STR_MAX_LEN:
        raise PlcRuntimeFault("memory_fault",
                              f"{fn}: result of {n} characters overruns OpenPLC's {STR_MAX_LEN}-byte buffer")


def _left(s: str, l: int) -> str:
    if l < 0:
        return ""
    return s[:min(l, len(s))]


def _right(s: str, l: int) -> str:
    if l < 0:
        return ""
    l = min(l, len(s))
    return s[len(s) - l:]


def _mid(s: str, l: int, p: int, unsigned: bool = False) -> str:
    """MID(IN, L, P): L characters from 1-based position P. With a signed P, P = 0 reads
    the length byte that precedes the text (body[-1]) as a first character; with an unsigned
    P, `P -= 1` wraps to the type's maximum and the copy reads far outside the string."""
    if l < 0 or p < 0:
        return ""
    n = len(s)
    if p > n:
        return ""
    if p == 0 and unsigned:
        raise PlcRuntimeFault("memory_fault", "MID with an unsigned P = 0: OpenPLC's library "
                                              "reads outside the string (undefined behaviour)")
    p -= 1
    l = l if l + p <= n else n - p
    out = _StrMem(s).read(p, l, "MID")
    _check_len(len(out), "MID")
    return out


def _concat(*parts: str) -> str:
    return "".join(parts)[:STR_MAX_LEN]


def _insert(s1: str, s2: str, p: int) -> str:
    """INSERT(IN1, IN2, P): IN2 after the first P characters of IN1."""
    if p < 0:
        return ""
    p8 = _i8(p)
    if p8 < 0:
        raise PlcRuntimeFault("memory_fault", f"INSERT: P={p} becomes {p8} in OpenPLC's int8 "
                                              "length type and makes it copy a negative size")
    k = min(p8, len(s1))
    return (s1[:k] + s2 + s1[k:])[:STR_MAX_LEN]


def _delete(s: str, l: int, p: int) -> str:
    """DELETE(IN, L, P): remove L characters from 1-based position P. P = 0 crashes OpenPLC
    (it copies P-1 = -1 bytes)."""
    if l < 0 or p < 0:
        return ""
    l8, p8, n = _i8(l), _i8(p), len(s)
    mem = _StrMem(s)
    to_copy = n if p8 > n else _i8(p8 - 1)
    res = mem.read(0, to_copy, "DELETE")
    pos = to_copy
    if n > pos + l8:
        res += mem.read(pos + l8, _i8(n - pos - l8), "DELETE")
    _check_len(len(res), "DELETE")
    return res


def _replace(s1: str, s2: str, l: int, p: int) -> str:
    """REPLACE(IN1, IN2, L, P): L characters from 1-based position P replaced by the first
    L characters of IN2 (IN2 is truncated to L). P = 0 crashes OpenPLC."""
    if l < 0 or p < 0:
        return ""
    l8, p8, n1 = _i8(l), _i8(p), len(s1)
    m1, m2 = _StrMem(s1), _StrMem(s2)
    to_copy = n1 if p8 > n1 else _i8(p8 - 1)
    res = m1.read(0, to_copy, "REPLACE")
    pos = to_copy
    to_copy = min(len(s2), l8)
    if to_copy + len(res) > STR_MAX_LEN:
        to_copy = STR_MAX_LEN - len(res)
    res += m2.read(0, to_copy, "REPLACE")
    pos = _i8(pos + l8)
    if len(res) < STR_MAX_LEN and pos < n1:
        res += m1.read(pos, _i8(n1 - pos), "REPLACE")
    _check_len(len(res), "REPLACE")
    return res


def _find(s1: str, s2: str) -> int:
    """iec_std_functions.h __pfind, bugs included: it returns `count1 + 1` unless exactly
    len(IN2)-1 characters matched at the end, so a miss returns len(IN1)+1 (not 0) when IN2 has
    2+ characters; and after a partial match it skips ahead, missing overlapping matches."""
    c1 = c2 = 0
    n1, n2 = len(s1), len(s2)
    while c1 + c2 < n1 and c2 < n2:
        if s1[c1 + c2] != s2[c2]:
            c1 += c2 + 1
            c2 = 0
        else:
            c2 += 1
    return 0 if c2 == n2 - 1 else c1 + 1


# --------------------------------------------------------------------------- BCD


def _uint_to_bcd(v: int) -> int:
    """__uint_to_bcd: one decimal digit per nibble (digits past 16 wrap the shift count)."""
    res = v % 10
    shift = 4
    v //= 10
    while v:
        res |= (v % 10) << (shift & 63)
        shift = (shift + 4) & 0xFF
        v //= 10
    return res & _M64


def _bcd_valid(v: int) -> bool:
    while v:
        if v & 0xF > 9:
            return False
        v >>= 4
    return True


def _bcd_to_uint(v: int) -> int:
    res, factor = 0, 1
    while v:
        res += (v & 0xF) * factor
        factor *= 10
        v >>= 4
    return res & _M64


# --------------------------------------------------------------------------- type helpers


_SHORT = {"TIME_OF_DAY": "TOD", "DATE_AND_TIME": "DT"}
_TIMELIKE = ("time", "date", "tod", "dt")


def short_name(t: Type) -> str:
    """matiec's name for an elementary type in function names (TOD and DT, not the long forms)."""
    return _SHORT.get(t.name, t.name)


def _kind(t: Type) -> str:
    t = base_of(t)
    if isinstance(t, StringType):
        return "string"
    if isinstance(t, ElementaryType):
        return t.kind
    return "derived"


def _default(t: Type) -> Any:
    return T.default_value(t)


def _wrapper(t: Type) -> Callable[[Any], Any]:
    w = wrapper_for(t)
    return w if w is not None else (lambda v: v)


def _is_int(t: Type) -> bool:
    return _kind(t) in ("sint", "uint")


def _is_nbit(t: Type) -> bool:
    return _kind(t) == "bits"


def _is_real(t: Type) -> bool:
    return _kind(t) == "real"


def _is_num(t: Type) -> bool:
    return _kind(t) in ("sint", "uint", "real")


def _is_timelike(t: Type) -> bool:
    return _kind(t) in _TIMELIKE


def _real_store(t: Type) -> Callable[[float], float]:
    return to_f32 if base_of(t) is T.REAL else float


# --------------------------------------------------------------------------- conversions


def _converter(src: Type, dst: Type) -> Optional[Fn]:
    """The *_TO_* conversion src -> dst of iec_std_functions.h, or None if it has none."""
    s, d = _kind(src), _kind(dst)
    src, dst = base_of(src), base_of(dst)
    intlike = ("bool", "sint", "uint", "bits")
    if src is dst:
        # BOOL_TO_BOOL and STRING_TO_STRING are declared by matiec but not defined in C
        return None if s in ("bool", "string") else (lambda v: v)
    if d == "bool":
        if s in ("sint", "uint", "bits", "real") or s in _TIMELIKE:
            return lambda v: v != 0
        if s == "string":
            return _string_to_bool
        return None
    if s in intlike:
        if d in ("sint", "uint", "bits"):
            w = _wrapper(dst)
            return lambda v: w(int(v))
        if d == "real":
            return (lambda v: _int_to_f32(int(v))) if dst is T.REAL else (lambda v: float(int(v)))
        if d in _TIMELIKE:                                  # __int_to_time: seconds
            return lambda v: _ts_ns(int(v), 0)
        if d == "string":
            if s == "bool":
                return lambda v: "TRUE" if v else "FALSE"
            if s == "bits":
                return lambda v: "16#%x" % v
            return lambda v: "%d" % v
        return None
    if s == "real":
        if d == "sint":
            w = _wrapper(dst)
            return lambda v: w(_real_to_sint(v))
        if d in ("uint", "bits"):
            w = _wrapper(dst)
            return lambda v: w(_real_to_uint(v))
        if d == "real":
            return _real_store(dst)
        if d in _TIMELIKE:
            return _real_to_time
        if d == "string":
            return lambda v: "%.10g" % v
        return None
    if s in _TIMELIKE:
        if d in ("sint", "uint", "bits"):                   # __time_to_int: tv_sec
            w = _wrapper(dst)
            return lambda v: w(_timespec(v)[0])
        if d == "real":
            store = _real_store(dst)
            return lambda v: store(_time_to_real(v))
        if d == "string":
            return {"time": _time_to_string, "date": _date_to_string,
                    "tod": _tod_to_string, "dt": _dt_to_string}[s]
        if s == "dt" and d == "date":
            return _dt_to_date
        if s == "dt" and d == "tod":
            return _dt_to_tod
        return None                                         # e.g. TOD_TO_TIME: not supported
    if s == "string":
        if d == "sint":
            w = _wrapper(dst)
            return lambda v: w(_pstring_to_sint(v))
        if d in ("uint", "bits"):
            w = _wrapper(dst)
            return lambda v: w(_pstring_to_sint(v) & _M64)
        if d == "real":
            store = _real_store(dst)
            return lambda v: store(_string_to_real(v))
        if d in _TIMELIKE:
            return _string_to_time
        return None
    return None


# --------------------------------------------------------------------------- builders
# A builder gets the (base) argument types and the result type of one call and returns the
# specialised callable, or None when OpenPLC's library has no such instance.

Builder = Callable[[Sequence[Type], Type], Optional[Fn]]
_BUILDERS: dict[str, Builder] = {}


def _builder(*names: str) -> Callable[[Builder], Builder]:
    def deco(f: Builder) -> Builder:
        for n in names:
            _BUILDERS[n] = f
        return f
    return deco


def _arith_kind(t: Type) -> str:
    """'int', 'real' or '' for the numeric families."""
    return "int" if _is_int(t) else "real" if _is_real(t) else ""


def _make_add_mul(name: str) -> Builder:
    is_add = name == "ADD"

    def build(args: Sequence[Type], res: Type) -> Optional[Fn]:
        t = args[0]
        if not is_add and _is_timelike(t):
            return _b_multime(args, res) if base_of(t) is T.TIME else None
        k = _arith_kind(t)
        if not k:
            return None
        w = _wrapper(t)
        if len(args) == 2:                             # the common case, without *args
            return (lambda a, b: w(a + b)) if is_add else (lambda a, b: w(a * b))
        if k == "int":
            if is_add:
                return lambda *xs: w(sum(xs))
            return lambda *xs: w(math.prod(xs))       # modular: the per-step wrap is the same
        def fold(*xs: float) -> float:                 # REAL rounds after every operation
            acc = xs[0]
            for x in xs[1:]:
                acc = w(acc + x) if is_add else w(acc * x)
            return acc
        return fold
    return build


_BUILDERS["ADD"] = _make_add_mul("ADD")
_BUILDERS["MUL"] = _make_add_mul("MUL")


@_builder("SUB")
def _b_sub(args: Sequence[Type], res: Type) -> Optional[Fn]:
    t = args[0]
    if not _arith_kind(t):
        return None
    w = _wrapper(t)
    return lambda a, b: w(a - b)


def _int_div(t: Type, *, zero_faults: bool) -> Fn:
    """Integer division: C truncation. On x86 `INT_MIN / -1` traps for 32/64-bit types
    (smaller ones are promoted to int first and just wrap)."""
    w = _wrapper(t)
    et = base_of(t)
    traps = et.kind == "sint" and et.bits >= 32
    lo = et.min

    def div(a: int, b: int) -> int:
        if b == 0:
            if zero_faults:
                raise PlcRuntimeFault("division_by_zero", "integer division by zero")
            return 0
        if traps and b == -1 and a == lo:
            raise PlcRuntimeFault("division_overflow", f"{et.name} {a} / -1 overflows (SIGFPE on x86)")
        return w(_cdiv(a, b))
    return div


def _int_mod(t: Type) -> Fn:
    """MOD: 0 when the divisor is 0 (function and operator); C remainder otherwise."""
    w = _wrapper(t)
    et = base_of(t)
    traps = et.kind == "sint" and et.bits >= 32
    lo = et.min

    def mod(a: int, b: int) -> int:
        if b == 0:
            return 0
        if traps and b == -1 and a == lo:
            raise PlcRuntimeFault("division_overflow", f"{et.name} {a} MOD -1 overflows (SIGFPE on x86)")
        return w(_cmod(a, b))
    return mod


@_builder("DIV")
def _b_div(args: Sequence[Type], res: Type) -> Optional[Fn]:
    t = args[0]
    if base_of(t) is T.TIME:
        return _b_divtime(args, res)
    k = _arith_kind(t)
    if k == "int":
        return _int_div(t, zero_faults=False)          # TEST_EN_COND(op2 == 0): returns 0
    if k == "real":
        w = _wrapper(t)
        return lambda a, b: 0.0 if b == 0 else w(a / b)
    return None


@_builder("MOD")
def _b_mod(args: Sequence[Type], res: Type) -> Optional[Fn]:
    return _int_mod(args[0]) if _is_int(args[0]) else None


@_builder("EXPT")
def _b_expt(args: Sequence[Type], res: Type) -> Optional[Fn]:
    if not (_is_real(args[0]) and _is_num(args[1])):
        return None
    if base_of(args[0]) is T.REAL and base_of(args[1]) is T.REAL:
        powf = _libm_float("powf", 2)      # C++'s pow(float, float): single precision
        return lambda a, b: powf(a, b)
    w = _wrapper(args[0])                  # pow(float, int or double) is computed in double
    return lambda a, b: w(_c_pow(float(a), float(b)))


@_builder("MOVE")
def _b_move(args: Sequence[Type], res: Type) -> Optional[Fn]:
    return lambda v: T.copy_value(v)


_UNARY_MATH: dict[str, Callable[[float], float]] = {
    "SQRT": _c_math(math.sqrt), "LN": _c_math(math.log, -math.inf),
    "LOG": _c_math(math.log10, -math.inf), "EXP": _c_math(math.exp),
    "SIN": _c_math(math.sin), "COS": _c_math(math.cos), "TAN": _c_math(math.tan),
    "ASIN": _c_math(math.asin), "ACOS": _c_math(math.acos), "ATAN": _c_math(math.atan),
}


_FLOAT_MATH = {"SIN": "sinf", "COS": "cosf", "TAN": "tanf", "ASIN": "asinf", "ACOS": "acosf",
               "ATAN": "atanf", "EXP": "expf", "LN": "logf", "LOG": "log10f"}
"""OpenPLC's library is compiled as C++, where SIN(op) of a REAL calls the float overload,
glibc's sinf: its result may be one unit in the last place away from sin() rounded to REAL
(SIN(REAL#40.395836) is 0.43033928 in OpenPLC, not 0.43033931). SQRT is exact either way."""


@lru_cache(maxsize=None)
def _libm_float(cname: str, arity: int = 1) -> Callable[..., float]:
    """The C library's single-precision function `cname` (sinf, powf...), as OpenPLC calls it."""
    import ctypes
    import ctypes.util
    libm = ctypes.CDLL(ctypes.util.find_library("m") or "libm.so.6")
    fn = getattr(libm, cname)
    fn.restype = ctypes.c_float
    fn.argtypes = [ctypes.c_float] * arity
    return fn


def _make_math(name: str) -> Builder:
    f = _UNARY_MATH[name]

    def build(args: Sequence[Type], res: Type) -> Optional[Fn]:
        if not _is_real(args[0]):
            return None
        if base_of(args[0]) is T.REAL and name in _FLOAT_MATH:
            return _libm_float(_FLOAT_MATH[name])
        w = _wrapper(args[0])
        return lambda x: w(f(x))
    return build


for _n in _UNARY_MATH:
    _BUILDERS[_n] = _make_math(_n)


@_builder("ABS")
def _b_abs(args: Sequence[Type], res: Type) -> Optional[Fn]:
    t = args[0]
    k = _kind(t)
    if k == "uint":
        return lambda x: x
    if k in ("sint", "real"):
        w = _wrapper(t)
        return lambda x: w(-x) if x < 0 else x           # keeps -0.0 and NaN like C
    return None


@_builder("TRUNC")
def _b_trunc(args: Sequence[Type], res: Type) -> Optional[Fn]:
    if not (_is_real(args[0]) and _is_int(res)):
        return None
    et = base_of(res)
    return lambda x: c_double_to(float(x), et)


# ---- bit strings


def _count_mask(t: Type) -> int:
    """x86 masks shift counts to 5 bits for (promoted) 32-bit operands, 6 bits for 64-bit."""
    return 63 if base_of(t).bits == 64 else 31


def _make_shift(left: bool) -> Builder:
    def build(args: Sequence[Type], res: Type) -> Optional[Fn]:
        t, n = args[0], args[1]
        if not _is_int(n):
            return None
        if _kind(t) == "bool":
            return lambda v, k: v if k == 0 else False  # SHL__BOOL__*: N>0 always gives 0
        if not _is_nbit(t):
            return None
        mask = (1 << base_of(t).bits) - 1
        cm = _count_mask(t)
        if left:
            return lambda v, k: (v << (k & cm)) & mask
        return lambda v, k: v >> (k & cm)
    return build


_BUILDERS["SHL"] = _make_shift(True)
_BUILDERS["SHR"] = _make_shift(False)


def _make_rotate(left: bool) -> Builder:
    def build(args: Sequence[Type], res: Type) -> Optional[Fn]:
        t, n = args[0], args[1]
        if not _is_int(n):
            return None
        if _kind(t) == "bool":
            return lambda v, k: v
        if not _is_nbit(t):
            return None
        width = base_of(t).bits
        mask = (1 << width) - 1
        # N %= 8*sizeof(IN) is done in size_t, i.e. a mathematical modulo for these widths
        if left:
            return lambda v, k: ((v << (k % width)) | (v >> (width - k % width))) & mask
        return lambda v, k: ((v >> (k % width)) | (v << (width - k % width))) & mask
    return build


_BUILDERS["ROL"] = _make_rotate(True)
_BUILDERS["ROR"] = _make_rotate(False)


def _make_logic(name: str) -> Builder:
    def build(args: Sequence[Type], res: Type) -> Optional[Fn]:
        k = _kind(args[0])
        if k == "bool":
            if name == "AND":
                return lambda *xs: all(xs)
            if name == "OR":
                return lambda *xs: any(xs)
            return lambda *xs: sum(1 for x in xs if x) % 2 == 1
        if k != "bits":
            return None
        if name == "AND":
            def f(*xs: int) -> int:
                acc = xs[0]
                for x in xs[1:]:
                    acc &= x
                return acc
        elif name == "OR":
            def f(*xs: int) -> int:
                acc = xs[0]
                for x in xs[1:]:
                    acc |= x
                return acc
        else:
            def f(*xs: int) -> int:
                acc = xs[0]
                for x in xs[1:]:
                    acc ^= x
                return acc
        return f
    return build


for _n in ("AND", "OR", "XOR"):
    _BUILDERS[_n] = _make_logic(_n)


@_builder("NOT")
def _b_not(args: Sequence[Type], res: Type) -> Optional[Fn]:
    k = _kind(args[0])
    if k == "bool":
        return lambda v: not v
    if k == "bits":
        mask = (1 << base_of(args[0]).bits) - 1
        return lambda v: ~v & mask
    return None


# ---- selection and comparison


def _less(t: Type) -> Optional[Callable[[Any, Any], bool]]:
    """The `<` the library uses for type t, or None if it has no ordering for it."""
    k = _kind(t)
    if k == "string":
        return lambda a, b: _str_cmp(a, b) < 0
    if k in ("bool", "sint", "uint", "bits", "real") or k in _TIMELIKE:
        return lambda a, b: a < b
    return None


@_builder("SEL")
def _b_sel(args: Sequence[Type], res: Type) -> Optional[Fn]:
    return lambda g, in0, in1: in1 if g else in0


@_builder("MUX")
def _b_mux(args: Sequence[Type], res: Type) -> Optional[Fn]:
    if not _is_int(args[0]):
        return None
    dflt = _default(args[1]) if len(args) > 1 else _default(res)

    def mux(k: int, *ins: Any) -> Any:
        if 0 <= k < len(ins):
            return ins[k]
        return T.copy_value(dflt)                # K >= count: ENO := FALSE, initial value
    return mux


def _make_extreme(is_max: bool) -> Builder:
    def build(args: Sequence[Type], res: Type) -> Optional[Fn]:
        t = args[0]
        if not is_max and _kind(t) == "bool":
            return None
        lt = _less(t)
        if lt is None:
            return None

        def extreme(*xs: Any) -> Any:
            acc = xs[0]
            for x in xs[1:]:
                if (lt(acc, x) if is_max else lt(x, acc)):
                    acc = x
            return acc
        return extreme
    return build


_BUILDERS["MAX"] = _make_extreme(True)
_BUILDERS["MIN"] = _make_extreme(False)


@_builder("LIMIT")
def _b_limit(args: Sequence[Type], res: Type) -> Optional[Fn]:
    t = args[0]
    if _kind(t) == "bool":
        return None
    lt = _less(t)
    if lt is None:
        return None
    # IN > MN ? (IN < MX ? IN : MX) : MN  -- so MN wins when MN > MX
    return lambda mn, x, mx: (x if lt(x, mx) else mx) if lt(mn, x) else mn


_CMP_TESTS: dict[str, Callable[[int], bool]] = {
    "GT": lambda c: c > 0, "GE": lambda c: c >= 0, "EQ": lambda c: c == 0,
    "LE": lambda c: c <= 0, "LT": lambda c: c < 0, "NE": lambda c: c != 0,
}


def _num_cmp(a: Any, b: Any) -> Optional[int]:
    """Three-way compare; None when unordered (a NaN), which C's operators treat as false."""
    if a < b:
        return -1
    if a > b:
        return 1
    return 0 if a == b else None


def _cmp_fn(t: Type) -> Optional[Callable[[Any, Any], Optional[int]]]:
    k = _kind(t)
    if k == "string":
        return _str_cmp
    if k in ("sint", "uint", "bits", "real", "bool") or k in _TIMELIKE:
        return _num_cmp
    return None


def _make_compare(name: str) -> Builder:
    test = _CMP_TESTS[name]

    def build(args: Sequence[Type], res: Type) -> Optional[Fn]:
        t = args[0]
        if _kind(t) == "bool":
            return None                           # no GT_BOOL etc. in the C library
        cmp = _cmp_fn(t)
        if cmp is None:
            return None

        def ok(a: Any, b: Any) -> bool:
            c = cmp(a, b)
            if c is None:                         # unordered (NaN)
                return name == "NE"
            return test(c)

        if name == "NE" or len(args) == 2:
            return ok

        def chain(*xs: Any) -> bool:              # GT(a, b, c) = a > b AND b > c
            for a, b in zip(xs, xs[1:]):
                if not ok(a, b):
                    return False
            return True
        return chain
    return build


for _n in _CMP_TESTS:
    _BUILDERS[_n] = _make_compare(_n)


# ---- strings


def _string_fn(f: Fn, nint: int, result_int: bool = False) -> Builder:
    """Builder for a Table 29 function taking strings then `nint` ANY_INT arguments."""
    def build(args: Sequence[Type], res: Type) -> Optional[Fn]:
        nstr = len(args) - nint
        if any(_kind(a) != "string" for a in args[:nstr]):
            return None
        if any(not _is_int(a) for a in args[nstr:]):
            return None
        if result_int:
            if not _is_int(res):
                return None
            w = _wrapper(res)
            return lambda *xs: w(f(*xs))
        return f
    return build


_BUILDERS["LEN"] = _string_fn(len, 0, result_int=True)
_BUILDERS["LEFT"] = _string_fn(_left, 1)
_BUILDERS["RIGHT"] = _string_fn(_right, 1)


@_builder("MID")
def _b_mid(args: Sequence[Type], res: Type) -> Optional[Fn]:
    if _string_fn(_mid, 2)(args, res) is None:
        return None
    if _kind(args[2]) == "uint":
        return lambda s, l, p: _mid(s, l, p, unsigned=True)
    return _mid


_BUILDERS["INSERT"] = _string_fn(_insert, 1)
_BUILDERS["DELETE"] = _string_fn(_delete, 2)
_BUILDERS["REPLACE"] = _string_fn(_replace, 2)
_BUILDERS["FIND"] = _string_fn(_find, 0, result_int=True)


@_builder("CONCAT")
def _b_concat(args: Sequence[Type], res: Type) -> Optional[Fn]:
    return _concat if all(_kind(a) == "string" for a in args) else None


# ---- time (Table 30)


def _time_add(a: int, b: int) -> int:
    return _i64(a + b)


def _time_sub(a: int, b: int) -> int:
    return _i64(a - b)


_TIME_FUNCS: dict[str, tuple[tuple[str, str], str, Fn]] = {
    "ADD_TIME": (("TIME", "TIME"), "TIME", _time_add),
    "ADD_TOD_TIME": (("TOD", "TIME"), "TOD", _time_add),
    "ADD_DT_TIME": (("DT", "TIME"), "DT", _time_add),
    "SUB_TIME": (("TIME", "TIME"), "TIME", _time_sub),
    "SUB_DATE_DATE": (("DATE", "DATE"), "TIME", _time_sub),
    "SUB_TOD_TIME": (("TOD", "TIME"), "TOD", _time_sub),
    "SUB_TOD_TOD": (("TOD", "TOD"), "TIME", _time_sub),
    "SUB_DT_TIME": (("DT", "TIME"), "DT", _time_sub),
    "SUB_DT_DT": (("DT", "DT"), "TIME", _time_sub),
    "CONCAT_DATE_TOD": (("DATE", "TOD"), "DT", _time_add),
}


def _make_time_fn(name: str) -> Builder:
    (a, b), _r, f = _TIME_FUNCS[name]

    def build(args: Sequence[Type], res: Type) -> Optional[Fn]:
        if short_name(base_of(args[0])) != a or short_name(base_of(args[1])) != b:
            return None
        return f
    return build


for _n in _TIME_FUNCS:
    _BUILDERS[_n] = _make_time_fn(_n)


def _b_multime(args: Sequence[Type], res: Type) -> Optional[Fn]:
    if base_of(args[0]) is not T.TIME or not _is_num(args[1]):
        return None
    return lambda t, k: _time_mul(t, float(k))


def _b_divtime(args: Sequence[Type], res: Type) -> Optional[Fn]:
    if base_of(args[0]) is not T.TIME or not _is_num(args[1]):
        return None
    return lambda t, k: _time_div(t, float(k))


_BUILDERS["MULTIME"] = _b_multime
_BUILDERS["DIVTIME"] = _b_divtime


# --------------------------------------------------------------------------- lookup


_TYPE_PART = "|".join(sorted((re.escape(n) for n in T.ELEMENTARY), key=len, reverse=True))
_RE_TO_BCD = re.compile(rf"^({_TYPE_PART})_TO_BCD(?:_({_TYPE_PART}))?$")
_RE_BCD_TO = re.compile(rf"^(?:({_TYPE_PART})_)?BCD_TO_({_TYPE_PART})$")
_RE_CONV = re.compile(rf"^({_TYPE_PART})_TO_({_TYPE_PART})$")
_RE_TYPED = re.compile(rf"^([A-Z]+)_({_TYPE_PART})$")


def _bcd_encoder(src: Type, dst: Type) -> Optional[Fn]:
    if _kind(src) != "uint" or _kind(dst) != "bits":
        return None
    mask = (1 << base_of(dst).bits) - 1
    return lambda v: _uint_to_bcd(v) & mask


def _bcd_decoder(src: Type, dst: Type) -> Optional[Fn]:
    if _kind(src) != "bits" or _kind(dst) != "uint":
        return None
    w = _wrapper(dst)
    return lambda v: w(_bcd_to_uint(v)) if _bcd_valid(v) else 0


def _build(name: str, args: tuple[Type, ...], res: Type) -> Fn:
    """Find the implementation of `name` for these (base) types; raise NoSuchFunction."""
    def missing() -> NoSuchFunction:
        sig = ", ".join(short_name(a) if isinstance(a, (ElementaryType, StringType)) else a.name
                        for a in args)
        return NoSuchFunction(f"OpenPLC's library has no {name}({sig})")

    if name in _BUILDERS:
        f = _BUILDERS[name](args, res)
        if f is None:
            raise missing()
        return f
    m = _RE_TO_BCD.match(name)
    if m:
        src = T.ELEMENTARY[m.group(1)]
        dst = T.ELEMENTARY[m.group(2)] if m.group(2) else res
        f = _bcd_encoder(src, dst) if (not args or T.same_type(args[0], src)) else None
        if f is None:
            raise missing()
        return f
    m = _RE_BCD_TO.match(name)
    if m:
        src = T.ELEMENTARY[m.group(1)] if m.group(1) else (args[0] if args else None)
        dst = T.ELEMENTARY[m.group(2)]
        f = _bcd_decoder(src, dst) if src is not None else None
        if f is None:
            raise missing()
        return f
    m = _RE_CONV.match(name)
    if m:
        src, dst = T.ELEMENTARY[m.group(1)], T.ELEMENTARY[m.group(2)]
        if args and not T.same_type(args[0], src):    # STRING[n] is a STRING too
            raise missing()
        f = _converter(src, dst)
        if f is None:
            raise missing()
        return f
    m = _RE_TYPED.match(name)
    if m and m.group(1) in _BUILDERS:
        typed = base_of(T.ELEMENTARY[m.group(2)])
        generic = m.group(1)
        if generic == "MUX" or not any(T.same_type(a, typed) for a in args):
            raise missing()
        return _build(generic, args, res)
    raise NoSuchFunction(f"{name} is not a standard function of OpenPLC's library")


@lru_cache(maxsize=None)
def _cached(name: str, args: tuple[Type, ...], res: Type) -> Fn:
    return _build(name, args, res)


def lookup(name: str, arg_types: Sequence[Type], result_type: Type) -> Fn:
    """The callable for one call of standard function `name` with these argument types.

    See the module docstring. `result_type` matters where the arguments do not fix it
    (LEN, FIND, TRUNC, overloaded BCD conversions).
    """
    args = tuple(base_of(t) for t in arg_types)
    return _cached(name.upper(), args, base_of(result_type))


# --------------------------------------------------------------------------- operators


def _numeric_binop(op: str, t: Type) -> Optional[Fn]:
    k = _arith_kind(t)
    if not k:
        return None
    w = _wrapper(t)
    if op == "+":
        return lambda a, b: w(a + b)
    if op == "-":
        return lambda a, b: w(a - b)
    if op == "*":
        return lambda a, b: w(a * b)
    if op == "/":
        if k == "int":
            return _int_div(t, zero_faults=True)   # C `/`: SIGFPE on OpenPLC
        return lambda a, b: w(_fdiv(a, b))        # IEEE: +-inf or NaN
    if op == "MOD":
        return _int_mod(t) if k == "int" else None
    return None


_CMP_OPS = {"=": "EQ", "<>": "NE", "<": "LT", "<=": "LE", ">": "GT", ">=": "GE"}


def _build_operator(op: str, args: tuple[Type, ...], res: Type) -> Fn:
    def missing(why: str = "") -> NoSuchFunction:
        names = " ".join(short_name(a) if isinstance(a, (ElementaryType, StringType)) else a.name
                         for a in args)
        return NoSuchFunction(f"no operator {op} for ({names}) in OpenPLC" + (f": {why}" if why else ""))

    if op in _CMP_OPS:
        a = args[0]
        k = _kind(a)
        if k == "string" or k in _TIMELIKE:
            return _build(_CMP_OPS[op], args, T.BOOL)   # matiec calls EQ_STRING, LT_TIME...
        if k == "derived":
            if op not in ("=", "<>"):
                raise missing("enumerations only compare for equality")
            return (lambda x, y: x == y) if op == "=" else (lambda x, y: x != y)
        return {"=": lambda x, y: x == y, "<>": lambda x, y: x != y, "<": lambda x, y: x < y,
                "<=": lambda x, y: x <= y, ">": lambda x, y: x > y,
                ">=": lambda x, y: x >= y}[op]
    if op in ("AND", "&", "OR", "XOR"):
        return _build({"&": "AND"}.get(op, op), args, res)
    if op == "NOT":
        return _build("NOT", args, res)
    if op == "NEG":
        k = _kind(args[0])
        if k in ("sint", "uint", "real"):
            w = _wrapper(args[0])
            return lambda x: w(-x)
        raise missing("C cannot negate this type")
    if op in ("+", "-", "*", "/", "MOD"):
        a, b = args
        if _is_timelike(res) or _is_timelike(a):
            if op == "+" and _is_timelike(a) and _is_timelike(b):
                return _time_add                       # __time_add
            if op == "-" and _is_timelike(a) and _is_timelike(b):
                return _time_sub                       # __time_sub
            if op == "*" and base_of(a) is T.TIME and _is_num(b):
                return lambda t, k: _time_mul(t, float(k))
            if op == "*" and _is_num(a):
                raise missing("matiec emits __time_mul(number, TIME), which does not compile")
            if op == "/" and base_of(a) is T.TIME and _is_num(b):
                return lambda t, k: _time_div(t, float(k))
            raise missing()
        f = _numeric_binop(op, res if _is_num(res) else a)
        if f is None:
            raise missing()
        return f
    raise NoSuchFunction(f"unknown operator {op}")


@lru_cache(maxsize=None)
def _cached_op(op: str, args: tuple[Type, ...], res: Type) -> Fn:
    return _build_operator(op, args, res)


def lookup_operator(op: str, arg_types: Sequence[Type], result_type: Type) -> Fn:
    """The callable for an ST operator as matiec compiles it for OpenPLC.

    op: "+", "-", "*", "/", "MOD", "=", "<>", "<", "<=", ">", ">=", "AND" (or "&"),
    "OR", "XOR", "NOT", "NEG" (unary minus). Facts encoded here:
      * integer `/` by zero raises PlcRuntimeFault("division_by_zero") (C `/` traps);
        REAL `/` by zero gives +-inf/NaN; MOD by zero gives 0 (matiec emits `(b == 0)?0:a%b`);
      * TIME/DATE `+ - * /` use __time_add/__time_sub/__time_mul/__time_div;
      * comparisons of TIME, DATE and STRING call the EQ/LT... library functions, so strings
        compare only over the shorter length;
    Arithmetic results are wrapped to `result_type`. NOTE: matiec emits plain C expressions
    without casts, so an *intermediate* SINT/INT/USINT/UINT result is computed in C `int`
    and only narrowed on assignment ((a + b) / 2 does not overflow for INT a, b); that is the
    compiler's business: it can use a 32-bit signed result_type for inner nodes.
    """
    args = tuple(base_of(t) for t in arg_types)
    return _cached_op(op.upper(), args, base_of(result_type))


__all__ = [
    "NoSuchFunction", "PlcRuntimeFault", "STR_MAX_LEN", "c_double_to", "ieee_div", "lookup",
    "lookup_operator", "short_name", "time_to_seconds",
]
