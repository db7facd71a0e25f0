"""Type signatures of the IEC 61131-3 standard functions and function blocks, as the checker
needs them (the runtime's implementations live in plclab.runtime.stdlib / stdfb).

A parameter type is a concrete type name ('BOOL', 'TIME', ...) or a generic ('ANY_NUM', ...).
Generic parameters marked with the same letter in `same` must all have one concrete type, and
a result of 'T' is that type.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from plclab.iec import types as T

NUMERIC = ["SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "REAL", "LREAL"]
BITS = ["BOOL", "BYTE", "WORD", "DWORD", "LWORD"]
CONV_TYPES = NUMERIC + BITS + ["TIME", "DATE", "TOD", "DT", "STRING"]
_CONV_NAME = {"TOD": "TOD", "DT": "DT"}


@dataclass(frozen=True)
class FuncSig:
    """One standard function: parameters (name, type or generic), result, extensibility."""

    name: str
    params: tuple[tuple[str, str], ...]
    result: str                       # concrete type name, or 'T' (the common generic type)
    generic_params: tuple[str, ...] = ()  # names of the params sharing the generic type T
    extensible: bool = False          # more inputs like the last one (IN1, IN2, IN3...)
    min_args: int = 0


def _f(name: str, params: list[tuple[str, str]], result: str, generic: tuple[str, ...] = (),
       extensible: bool = False) -> FuncSig:
    return FuncSig(name, tuple(params), result, generic, extensible, len(params))


def _build() -> dict[str, FuncSig]:
    sigs: dict[str, FuncSig] = {}

    def add(s: FuncSig) -> None:
        sigs[s.name] = s

    # Type conversions, Table 22 (each pair is its own function in matiec's library)
    for src in CONV_TYPES:
        for dst in CONV_TYPES:
            if src == dst:
                continue
            if src in ("DATE", "TOD") and dst in ("TIME", "DATE", "TOD", "DT"):
                continue
            if src == "TIME" and dst in ("DATE", "TOD", "DT"):
                continue
            if dst in ("DATE",) and src not in ("DT", "STRING") + tuple(NUMERIC) + tuple(BITS):
                continue
            if src == "DT" and dst == "TIME":
                continue
            add(_f(f"{src}_TO_{dst}", [("IN", src)], dst))
    # The long type names appear in two conversions only (matiec's standard_function_names.c)
    add(_f("DATE_AND_TIME_TO_TIME_OF_DAY", [("IN", "DT")], "TOD"))
    add(_f("DATE_AND_TIME_TO_DATE", [("IN", "DT")], "DATE"))
    for b in ["BYTE", "WORD", "DWORD", "LWORD"]:
        for t in ["USINT", "UINT", "UDINT", "ULINT"]:
            add(_f(f"{b}_BCD_TO_{t}", [("IN", b)], t))
            add(_f(f"{t}_TO_BCD_{b}", [("IN", t)], b))
    for t in ["USINT", "UINT", "UDINT", "ULINT"]:   # the overloaded BCD conversions
        add(_f(f"BCD_TO_{t}", [("IN", "ANY_NBIT")], t))
        add(_f(f"{t}_TO_BCD", [("IN", t)], "ANY_NBIT"))
    add(_f("TRUNC", [("IN", "ANY_REAL")], "ANY_INT"))

    # Numeric, Table 23
    add(_f("ABS", [("IN", "ANY_NUM")], "T", ("IN",)))
    for n in ("SQRT", "LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN"):
        add(_f(n, [("IN", "ANY_REAL")], "T", ("IN",)))
    # Arithmetic, Table 24
    add(_f("ADD", [("IN1", "ANY_NUM"), ("IN2", "ANY_NUM")], "T", ("IN1", "IN2"), extensible=True))
    add(_f("MUL", [("IN1", "ANY_NUM"), ("IN2", "ANY_NUM")], "T", ("IN1", "IN2"), extensible=True))
    add(_f("SUB", [("IN1", "ANY_NUM"), ("IN2", "ANY_NUM")], "T", ("IN1", "IN2")))
    add(_f("DIV", [("IN1", "ANY_NUM"), ("IN2", "ANY_NUM")], "T", ("IN1", "IN2")))
    add(_f("MOD", [("IN1", "ANY_INT"), ("IN2", "ANY_INT")], "T", ("IN1", "IN2")))
    add(_f("EXPT", [("IN1", "ANY_REAL"), ("IN2", "ANY_NUM")], "T", ("IN1",)))
    add(_f("MOVE", [("IN", "ANY")], "T", ("IN",)))
    # Bit shift, Table 25; bitwise, Table 26
    for n in ("SHL", "SHR", "ROL", "ROR"):
        add(_f(n, [("IN", "ANY_BIT"), ("N", "ANY_INT")], "T", ("IN",)))
    for n in ("AND", "OR", "XOR"):
        add(_f(n, [("IN1", "ANY_BIT"), ("IN2", "ANY_BIT")], "T", ("IN1", "IN2"), extensible=True))
    add(_f("NOT", [("IN", "ANY_BIT")], "T", ("IN",)))
    # Selection, Table 27
    add(_f("SEL", [("G", "BOOL"), ("IN0", "ANY"), ("IN1", "ANY")], "T", ("IN0", "IN1")))
    add(_f("MAX", [("IN1", "ANY_ELEMENTARY"), ("IN2", "ANY_ELEMENTARY")], "T", ("IN1", "IN2"), extensible=True))
    add(_f("MIN", [("IN1", "ANY_ELEMENTARY"), ("IN2", "ANY_ELEMENTARY")], "T", ("IN1", "IN2"), extensible=True))
    add(_f("LIMIT", [("MN", "ANY_ELEMENTARY"), ("IN", "ANY_ELEMENTARY"), ("MX", "ANY_ELEMENTARY")], "T",
           ("MN", "IN", "MX")))
    add(_f("MUX", [("K", "ANY_INT"), ("IN0", "ANY"), ("IN1", "ANY")], "T", ("IN0", "IN1"), extensible=True))
    # Comparison, Table 28
    for n in ("GT", "GE", "EQ", "LE", "LT"):
        add(_f(n, [("IN1", "ANY_ELEMENTARY"), ("IN2", "ANY_ELEMENTARY")], "BOOL", ("IN1", "IN2"), extensible=True))
    add(_f("NE", [("IN1", "ANY_ELEMENTARY"), ("IN2", "ANY_ELEMENTARY")], "BOOL", ("IN1", "IN2")))
    # Strings, Table 29
    add(_f("LEN", [("IN", "STRING")], "ANY_INT"))      # LEN__<ANY_INT>__STRING: typed by the context
    add(_f("LEFT", [("IN", "STRING"), ("L", "ANY_INT")], "STRING"))
    add(_f("RIGHT", [("IN", "STRING"), ("L", "ANY_INT")], "STRING"))
    add(_f("MID", [("IN", "STRING"), ("L", "ANY_INT"), ("P", "ANY_INT")], "STRING"))
    add(_f("CONCAT", [("IN1", "STRING"), ("IN2", "STRING")], "STRING", extensible=True))
    add(_f("INSERT", [("IN1", "STRING"), ("IN2", "STRING"), ("P", "ANY_INT")], "STRING"))
    add(_f("DELETE", [("IN", "STRING"), ("L", "ANY_INT"), ("P", "ANY_INT")], "STRING"))
    add(_f("REPLACE", [("IN1", "STRING"), ("IN2", "STRING"), ("L", "ANY_INT"), ("P", "ANY_INT")], "STRING"))
    add(_f("FIND", [("IN1", "STRING"), ("IN2", "STRING")], "ANY_INT"))
    # Time, Table 30
    add(_f("ADD_TIME", [("IN1", "TIME"), ("IN2", "TIME")], "TIME"))
    add(_f("SUB_TIME", [("IN1", "TIME"), ("IN2", "TIME")], "TIME"))
    add(_f("MULTIME", [("IN1", "TIME"), ("IN2", "ANY_NUM")], "TIME"))   # not MUL_TIME / DIV_TIME
    add(_f("DIVTIME", [("IN1", "TIME"), ("IN2", "ANY_NUM")], "TIME"))
    add(_f("ADD_TOD_TIME", [("IN1", "TOD"), ("IN2", "TIME")], "TOD"))
    add(_f("ADD_DT_TIME", [("IN1", "DT"), ("IN2", "TIME")], "DT"))
    add(_f("SUB_DATE_DATE", [("IN1", "DATE"), ("IN2", "DATE")], "TIME"))
    add(_f("SUB_TOD_TIME", [("IN1", "TOD"), ("IN2", "TIME")], "TOD"))
    add(_f("SUB_TOD_TOD", [("IN1", "TOD"), ("IN2", "TOD")], "TIME"))
    add(_f("SUB_DT_TIME", [("IN1", "DT"), ("IN2", "TIME")], "DT"))
    add(_f("SUB_DT_DT", [("IN1", "DT"), ("IN2", "DT")], "TIME"))
    add(_f("CONCAT_DATE_TOD", [("IN1", "DATE"), ("IN2", "TOD")], "DT"))
    return sigs


FUNCTIONS: dict[str, FuncSig] = _build()

# Overloads the C library lacks although the generic signature allows them: there is no GT, EQ,
# MIN, LIMIT... for BOOL (only MAX_BOOL), so such a call passes matiec and fails in C.
NO_BOOL_OVERLOAD = frozenset({"GT", "GE", "EQ", "LE", "LT", "NE", "MIN", "LIMIT"})


@dataclass(frozen=True)
class FBSig:
    """A standard function block: inputs and outputs with their types."""

    name: str
    inputs: tuple[tuple[str, str], ...]
    outputs: tuple[tuple[str, str], ...]
    locals: tuple[tuple[str, str], ...] = field(default=())


def _counters() -> list[FBSig]:
    out = []
    for suffix, t in (("", "INT"), ("_DINT", "DINT"), ("_LINT", "LINT"), ("_UDINT", "UDINT"), ("_ULINT", "ULINT")):
        out.append(FBSig("CTU" + suffix, (("CU", "BOOL"), ("R", "BOOL"), ("PV", t)), (("Q", "BOOL"), ("CV", t))))
        out.append(FBSig("CTD" + suffix, (("CD", "BOOL"), ("LD", "BOOL"), ("PV", t)), (("Q", "BOOL"), ("CV", t))))
        out.append(FBSig("CTUD" + suffix, (("CU", "BOOL"), ("CD", "BOOL"), ("R", "BOOL"), ("LD", "BOOL"), ("PV", t)),
                         (("QU", "BOOL"), ("QD", "BOOL"), ("CV", t))))
    return out


FUNCTION_BLOCKS: dict[str, FBSig] = {s.name: s for s in [
    FBSig("SR", (("S1", "BOOL"), ("R", "BOOL")), (("Q1", "BOOL"),)),
    FBSig("RS", (("S", "BOOL"), ("R1", "BOOL")), (("Q1", "BOOL"),)),
    FBSig("R_TRIG", (("CLK", "BOOL"),), (("Q", "BOOL"),)),
    FBSig("F_TRIG", (("CLK", "BOOL"),), (("Q", "BOOL"),)),
    FBSig("TP", (("IN", "BOOL"), ("PT", "TIME")), (("Q", "BOOL"), ("ET", "TIME"))),
    FBSig("TON", (("IN", "BOOL"), ("PT", "TIME")), (("Q", "BOOL"), ("ET", "TIME"))),
    FBSig("TOF", (("IN", "BOOL"), ("PT", "TIME")), (("Q", "BOOL"), ("ET", "TIME"))),
    *_counters(),
]}

# Function blocks of OpenPLC's own library (webserver/lib/*.txt) that this project does not
# provide: their names are still taken, so a program using them as identifiers would not load.
OPENPLC_EXTRA_FBS = frozenset("""DERIVATIVE HYSTERESIS INTEGRAL PID RAMP RTC SEMA TCP_CONNECT TCP_SEND
TCP_RECEIVE TCP_CLOSE""".split())



def _library_names() -> tuple[frozenset[str], dict[str, str]]:
    """The [functions] and [variables] sections of openplc_library_names.txt (which says why
    a program cannot reuse them)."""
    text = (Path(__file__).with_name("openplc_library_names.txt")).read_text(encoding="utf-8")
    functions: set[str] = set()
    variables: dict[str, str] = {}
    section = ""
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        if line.startswith("["):
            section = line
        elif section == "[functions]":
            functions.add(line)
        elif section == "[variables]":
            name, pou = line.split()
            variables[name] = pou
    return frozenset(functions), variables


LIBRARY_FUNCTIONS, LIBRARY_VARIABLES = _library_names()
"""The typed functions of OpenPLC's library (ADD_INT, INT_TO_INT ...: unavailable as any name)
and its POUs' variable names, each with the library POU declaring it (unavailable as the
name of a TYPE, FUNCTION, FUNCTION_BLOCK, PROGRAM or CONFIGURATION)."""

# Names that matiec's library makes unavailable as identifiers.
# CONCAT_DAT_TOD: so spelled in matiec's list of standard function names (not callable here).
RESERVED_NAMES: frozenset[str] = frozenset(FUNCTIONS) | frozenset(FUNCTION_BLOCKS) | OPENPLC_EXTRA_FBS | \
    frozenset({"CONCAT_DAT_TOD"}) | LIBRARY_FUNCTIONS


def type_by_name(name: str) -> T.Type:
    return T.ELEMENTARY[name]
