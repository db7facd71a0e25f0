"""What the parts of the ST checker share: the limits and tables of matiec's rules, a POU's scope,
and the checker's state and error reporting (plclab.frontend.checker assembles the parts)."""
from __future__ import annotations

import math
from typing import Any, Optional

from plclab.errors import Diagnostic
from plclab.frontend import ast as A
from plclab.frontend.checked import EnumValue
from plclab.frontend.stdsigs import LIBRARY_VARIABLES
from plclab.iec import types as T


LOCATED_AREAS = {"IX": "IX", "QX": "QX", "IW": "IW", "QW": "QW", "MW": "MW", "MD": "MD", "ML": "ML"}
LOCATED_TYPES = {
    "X": {"BOOL"},
    "W": {"INT", "UINT", "WORD"},
    "D": {"DINT", "UDINT", "DWORD", "REAL"},
    "L": {"LINT", "ULINT", "LWORD", "LREAL"},
}
AREA_LIMIT = {"X": 99, "W": 1023, "D": 1023, "L": 1023}


def short_address_message(text: str, in_statement: bool = False) -> str:
    """Why `%I0.1` (the bit address without its size letter) is refused. iec2c takes it in a
    declaration as a BOOL named `__I0_1`, apart from `%IX0.1` (`__IX0_1`), and OpenPLC's glue
    generator connects a located variable by the letter after its area: `__I0_1` has none, so
    it is never connected to the I/O (an input that never changes, an output that drives
    nothing). In a statement it is not %IX0.1 either (iec2c refuses it where no `AT %I0.1` is)."""
    area, parts = text[1].upper(), text[2:].split(".")
    full = f"%{area}X{parts[0]}.{parts[1] if len(parts) > 1 else 0}"
    instead = "OpenPLC's memory area is %MW, %MD or %ML only" if area == "M" else f"write {full}"
    if in_statement:
        return f"{text} leaves out the size letter: OpenPLC's compiler does not read it as {full}; {instead}"
    return (f"{text} leaves out the size letter: OpenPLC builds it but never connects it to the I/O "
            f"(its glue generator needs the X, W, D or L after the area); {instead}")


# Words matiec reserves that this grammar lexes as identifiers (keywords of IL/SFC/REF extensions).
RESERVED_WORDS = frozenset("""EN ENO ANY ANY_DERIVED ANY_ELEMENTARY ANY_MAGNITUDE ANY_NUM ANY_REAL ANY_INT
ANY_BIT ANY_STRING ANY_DATE VAR_CONFIG VAR_ACCESS ACTION END_ACTION TRANSITION END_TRANSITION FROM
INITIAL_STEP STEP END_STEP READ_WRITE READ_ONLY REF DREF REF_TO NULL""".split())
DEFAULT_INT = T.DINT
DEFAULT_REAL = T.LREAL
_GENERIC_RESULT_DEFAULT = {"ANY_INT": T.DINT, "ANY_NBIT": T.DWORD}


MAX_TYPE_NESTING = 100
"""A type defined through more named types than this (an alias of an alias ..., a STRUCT of a
STRUCT ...) is refused at the declaration that crosses the limit, before Python's stack does."""


def _library_variable_message(name: str, what: str) -> str:
    """Why a TYPE or POU cannot take the name of a variable of OpenPLC's library
    (stdsigs.LIBRARY_VARIABLES)."""
    pou = LIBRARY_VARIABLES[name.upper()]
    return (f"'{name}' is a variable name inside OpenPLC's standard library ({pou} declares it), and "
            f"OpenPLC's compiler reads its library with the program's type and POU names in scope: "
            f"a {what} named '{name}' makes it fail on its own library; choose another name")


class _Scope:
    """Names visible inside one POU."""

    def __init__(self, pou: Optional[A.PouDecl], names: dict[str, Any]):
        self.pou = pou
        self.names = names
        self.for_vars: list[str] = []
        self.loop_depth = 0


class CheckerBase:
    """The state every part of the checker shares, its error reporting and its text helpers."""

    def __init__(self, unit: A.Unit):
        self.unit = unit
        self.diags: list[Diagnostic] = []
        self.types: dict[str, T.Type] = {}
        self.type_decls: dict[str, A.TypeDecl] = {}
        self.enum_values: dict[str, list[EnumValue]] = {}
        # POU key -> address -> the named variable located there (its address is not a name in C)
        self.named_at: dict[str, dict[str, Any]] = {}
        self.pous: dict[str, A.PouDecl] = {}
        self.fb_types: dict[str, T.FBType] = {}
        self.globals: dict[str, A.VarDecl] = {}
        self._resolving: set[str] = set()
        self._unresolvable: set[str] = set()
        self.size_memo: dict[T.Type, int] = {}      # check_limits: bytes of each type, by identity
        self.declared_bytes = 0                     # check_limits: data declared so far (no FB instances)
        self.memory_refused = False                 # check_limits: a type or variable was too large (reported)
        self.user_calls: list[tuple[Optional[A.PouDecl], A.Call]] = []   # (caller, call) of user FUNCTIONs

    # ------------------------------------------------------------------ reporting
    def error(self, node: Any, message: str) -> None:
        self.diags.append(Diagnostic(node.file, node.line, node.col, message))

    # ------------------------------------------------------------------ text helpers
    @staticmethod
    def _tname(t: T.Type) -> str:
        return t.name

    def _path_text(self, e: A.Expr) -> str:
        if isinstance(e, A.Name):
            return e.name
        if isinstance(e, A.Member):
            return f"{self._path_text(e.base)}.{e.name}"
        if isinstance(e, A.Index):
            return f"{self._path_text(e.base)}[...]"
        if isinstance(e, A.Call):
            return f"{e.name}(...)"
        return "expression"


def _is_signed_integer(e: A.Expr) -> bool:
    """A plain decimal integer literal, optionally signed (`5`, `-5`): matiec's signed_integer."""
    return isinstance(e, A.Literal) and e.kind == "int" and e.type_name is None and "#" not in e.text


def fold(op: str, a: Any, b: Any) -> Any:
    """`a op b` for two constant numbers as the C that matiec writes computes it (integer
    division truncates toward zero, MOD takes the dividend's sign); None for another operator,
    a division by zero or an overflow."""
    try:
        if op == "+":
            return a + b
        if op == "-":
            return a - b
        if op == "*":
            return a * b
        if op == "/":
            if isinstance(a, int) and isinstance(b, int):
                q = abs(a) // abs(b)
                return q if (a < 0) == (b < 0) else -q
            return a / b
        if op == "MOD":
            return int(math.fmod(a, b))
        if op == "**":
            return float(a) ** b
    except (ZeroDivisionError, OverflowError, ValueError):
        return None
    return None
