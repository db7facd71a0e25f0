"""IEC 61131-3 data types as the front end checks them and the runtime stores them.

One module is shared by the checker (type rules) and the runtime (default values, wrapping),
so the two can never disagree about what an INT is.

Runtime value representation (the contract between compiler, standard library, image, traces):
  BOOL                      -> Python bool
  SINT..LINT, USINT..ULINT  -> int, wrapped to the type's width like matiec's C types
  BYTE, WORD, DWORD, LWORD  -> int (unsigned, wrapped)
  REAL                      -> float rounded to IEEE single precision on every store
  LREAL                     -> float
  TIME, DATE, TOD, DT       -> int nanoseconds (TIME signed; DATE/DT since 1970-01-01; TOD since midnight)
  STRING                    -> str (latin-1 characters, at most the declared length)
  enumerated                -> str, the value's name in upper case
  ARRAY                     -> list, flattened row-major for several dimensions
  STRUCT                    -> StructValue (attribute per field)
  FB instance               -> an object with one attribute per variable
"""
from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Any, Callable, Optional

# --------------------------------------------------------------------------- elementary


@dataclass(frozen=True, eq=False)
class Type:
    """Base of every type. Identity matters: two distinct derived types are different types."""

    name: str

    def __repr__(self) -> str:  # pragma: no cover - debugging aid
        return f"<{type(self).__name__} {self.name}>"


@dataclass(frozen=True, eq=False, repr=False)
class ElementaryType(Type):
    kind: str  # 'bool' | 'sint' | 'uint' | 'bits' | 'real' | 'time' | 'date' | 'tod' | 'dt' | 'string'
    bits: int = 0

    @property
    def is_integer(self) -> bool:
        return self.kind in ("sint", "uint")

    @property
    def is_signed(self) -> bool:
        return self.kind == "sint"

    @property
    def is_real(self) -> bool:
        return self.kind == "real"

    @property
    def is_num(self) -> bool:
        return self.kind in ("sint", "uint", "real")

    @property
    def is_bit(self) -> bool:
        return self.kind in ("bool", "bits")

    @property
    def is_date(self) -> bool:
        return self.kind in ("date", "tod", "dt")

    @property
    def min(self) -> int:
        return -(1 << (self.bits - 1)) if self.kind == "sint" else 0

    @property
    def max(self) -> int:
        if self.kind == "sint":
            return (1 << (self.bits - 1)) - 1
        return (1 << self.bits) - 1


@dataclass(frozen=True, eq=False, repr=False)
class StringType(Type):
    """STRING or STRING[n]. matiec's STRING holds at most 126 characters."""

    length: int = 126


def _mk(name: str, kind: str, bits: int = 0) -> ElementaryType:
    return ElementaryType(name, kind, bits)


BOOL = _mk("BOOL", "bool", 1)
SINT = _mk("SINT", "sint", 8)
INT = _mk("INT", "sint", 16)
DINT = _mk("DINT", "sint", 32)
LINT = _mk("LINT", "sint", 64)
USINT = _mk("USINT", "uint", 8)
UINT = _mk("UINT", "uint", 16)
UDINT = _mk("UDINT", "uint", 32)
ULINT = _mk("ULINT", "uint", 64)
BYTE = _mk("BYTE", "bits", 8)
WORD = _mk("WORD", "bits", 16)
DWORD = _mk("DWORD", "bits", 32)
LWORD = _mk("LWORD", "bits", 64)
REAL = _mk("REAL", "real", 32)
LREAL = _mk("LREAL", "real", 64)
TIME = _mk("TIME", "time", 64)
DATE = _mk("DATE", "date", 64)
TOD = _mk("TIME_OF_DAY", "tod", 64)
DT = _mk("DATE_AND_TIME", "dt", 64)
STRING = StringType("STRING", 126)

ELEMENTARY: dict[str, Type] = {
    t.name: t
    for t in (BOOL, SINT, INT, DINT, LINT, USINT, UINT, UDINT, ULINT, BYTE, WORD, DWORD, LWORD,
              REAL, LREAL, TIME, DATE, TOD, DT, STRING)
}
ELEMENTARY["TOD"] = TOD
ELEMENTARY["DT"] = DT

# Generic type names used in standard function signatures (never a variable's type).
GENERICS = ("ANY", "ANY_DERIVED", "ANY_ELEMENTARY", "ANY_MAGNITUDE", "ANY_NUM", "ANY_REAL",
            "ANY_INT", "ANY_BIT", "ANY_NBIT", "ANY_STRING", "ANY_DATE")


def in_generic(t: Type, generic: str) -> bool:
    """Is `t` a member of the IEC generic type `generic` (ANY_INT, ANY_NUM, ...)?"""
    t = base_of(t)
    if generic == "ANY":
        return True
    if isinstance(t, StringType):
        return generic in ("ANY_STRING", "ANY_ELEMENTARY")
    if not isinstance(t, ElementaryType):
        return generic == "ANY_DERIVED"
    k = t.kind
    return {
        "ANY_ELEMENTARY": True,
        "ANY_MAGNITUDE": k in ("sint", "uint", "real", "time"),
        "ANY_NUM": k in ("sint", "uint", "real"),
        "ANY_REAL": k == "real",
        "ANY_INT": k in ("sint", "uint"),
        "ANY_SINT": k == "sint",
        "ANY_UINT": k == "uint",
        "ANY_BIT": k in ("bool", "bits"),
        "ANY_NBIT": k == "bits",
        "ANY_STRING": False,
        "ANY_DATE": k in ("date", "tod", "dt"),
        "ANY_DERIVED": False,
    }.get(generic, False)


# --------------------------------------------------------------------------- derived


@dataclass(frozen=True, eq=False, repr=False)
class AliasType(Type):
    """TYPE T_Speed : INT := 500; END_TYPE - a new name for a type, with its own initial value."""

    base: Type = BOOL
    init: Any = None


@dataclass(frozen=True, eq=False, repr=False)
class SubrangeType(Type):
    """TYPE T_Pct : INT (0..100); END_TYPE - values outside the range are an error when constant."""

    base: ElementaryType = INT
    lo: int = 0
    hi: int = 0
    init: Any = None


@dataclass(frozen=True, eq=False, repr=False)
class EnumType(Type):
    """An enumerated type; its values are upper-case names, the first one is the default."""

    values: tuple[str, ...] = ()
    init: Optional[str] = None


@dataclass(frozen=True, eq=False, repr=False)
class ArrayType(Type):
    """ARRAY [lo..hi, lo..hi] OF elem; stored flattened row-major."""

    elem: Type = BOOL
    dims: tuple[tuple[int, int], ...] = ()
    init: Any = None  # flattened list of initial values, or None

    @property
    def size(self) -> int:
        n = 1
        for lo, hi in self.dims:
            n *= hi - lo + 1
        return n


@dataclass(frozen=True, eq=False, repr=False)
class StructType(Type):
    """STRUCT ... END_STRUCT; `fields` maps upper-case field name -> (type, initial value or None)."""

    fields: dict = field(default_factory=dict)
    field_names: dict = field(default_factory=dict)  # upper-case -> name as written


@dataclass(frozen=True, eq=False, repr=False)
class FBType(Type):
    """A function block type (standard or user). `pou` is the FB's declaration (AST) or None for standard FBs."""

    pou: Any = None


def base_of(t: Type) -> Type:
    """Strip aliases and subranges to the type values are stored as."""
    while True:
        if isinstance(t, AliasType):
            t = t.base
        elif isinstance(t, SubrangeType):
            t = t.base
        else:
            return t


def same_type(a: Type, b: Type) -> bool:
    """matiec compares data types by name after resolving aliases: no implicit widening."""
    a, b = base_of(a), base_of(b)
    if a is b:
        return True
    if isinstance(a, StringType) and isinstance(b, StringType):
        return True
    if isinstance(a, ArrayType) and isinstance(b, ArrayType):
        return a.dims == b.dims and same_type(a.elem, b.elem) and a.name == b.name
    return False


# --------------------------------------------------------------------------- values


def wrap_int(value: int, t: ElementaryType) -> int:
    """Wrap an integer the way the C type matiec generates for `t` would."""
    bits = t.bits
    mask = (1 << bits) - 1
    value &= mask
    if t.kind == "sint" and value >> (bits - 1):
        value -= 1 << bits
    return value


_F32 = struct.Struct("f")
_f32_pack, _f32_unpack = _F32.pack, _F32.unpack


REAL_MAX = 3.4028234663852886e38
"""The largest finite REAL (C's FLT_MAX)."""


def to_f32(x: float) -> float:
    """Round a Python float to IEEE single precision (REAL); on the hot path of every REAL operation."""
    try:
        return _f32_unpack(_f32_pack(x))[0]
    except OverflowError:   # beyond the REAL range: C's float conversion gives +-inf
        return float("inf") if x > 0 else float("-inf")


def wrapper_for(t: Type) -> Optional[Callable[[Any], Any]]:
    """The function that normalises a value stored into a variable of type `t` (None: identity)."""
    t = base_of(t)
    if isinstance(t, ElementaryType):
        if t.kind in ("sint", "uint", "bits"):
            bits = t.bits
            mask = (1 << bits) - 1
            if t.kind == "sint":
                half = 1 << (bits - 1)
                return lambda v: ((int(v) & mask) ^ half) - half
            return lambda v: int(v) & mask
        if t is REAL:
            return to_f32
        if t is LREAL:
            return float
        if t is BOOL:
            return bool
        if t.kind in ("time", "date", "tod", "dt"):
            return lambda v: ((int(v) + (1 << 63)) & ((1 << 64) - 1)) - (1 << 63)
    return None


class StructValue:
    """A STRUCT value: one attribute per field (upper-case names)."""

    __slots__ = ("__dict__",)

    def __init__(self, **fields: Any) -> None:
        self.__dict__.update(fields)

    def copy(self) -> "StructValue":
        return StructValue(**{k: copy_value(v) for k, v in self.__dict__.items()})

    def __eq__(self, other: object) -> bool:
        return isinstance(other, StructValue) and self.__dict__ == other.__dict__

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={v!r}" for k, v in self.__dict__.items())
        return f"({inner})"


def copy_value(v: Any) -> Any:
    """Deep copy of an assignable value (arrays and structs are copied on assignment in IEC)."""
    if isinstance(v, list):
        return [copy_value(x) for x in v]
    if isinstance(v, StructValue):
        return v.copy()
    return v


def default_value(t: Type) -> Any:
    """The initial value of a variable of type `t` when its declaration gives none."""
    if isinstance(t, AliasType):
        return t.init if t.init is not None else default_value(t.base)
    if isinstance(t, SubrangeType):
        return t.init if t.init is not None else t.lo
    if isinstance(t, EnumType):
        return t.init if t.init is not None else t.values[0]
    if isinstance(t, ArrayType):
        if t.init is not None:
            return copy_value(t.init)
        return [default_value(t.elem) for _ in range(t.size)]
    if isinstance(t, StructType):
        return StructValue(**{
            k: (copy_value(init) if init is not None else default_value(ft))
            for k, (ft, init) in t.fields.items()
        })
    if isinstance(t, StringType):
        return ""
    if isinstance(t, ElementaryType):
        if t is BOOL:
            return False
        if t.kind == "real":
            return 0.0
        return 0
    raise TypeError(f"no default value for {t!r}")


NS_PER_S = 1_000_000_000
NS_PER_MS = 1_000_000
