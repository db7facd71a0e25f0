"""The checked program: what the front end hands to the compiler (and to the PLCopen and
build tools), and the only part of the front end they import.

A CheckedUnit is the unit's AST with every fact the checker established filled into the
fields plclab.frontend.ast declares for it (each marked "checker"): the type of every
expression (`ty`), the symbol every name denotes (`sym`), each declaration's resolved type
and initial value, a FUNCTION's result and ENO variables, the parameters a standard call
binds... plus the tables below. A literal whose context does not fix its type keeps a
LiteralType, which the compiler reads as C does (an integer literal is a DINT, a real one
an LREAL).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

from plclab.errors import Diagnostic
from plclab.frontend import ast as A
from plclab.iec import types as T


@dataclass(frozen=True, eq=False)
class LiteralType(T.Type):
    """The pseudo-type of an untyped literal: it becomes a concrete type where it is used."""

    kind: str = "int"   # 'int' | 'real'


INT_LIT = LiteralType("integer literal", "int")
REAL_LIT = LiteralType("real literal", "real")
BIT_LIT = LiteralType("0/1 literal", "int")


@dataclass(eq=False)
class EnumValue:
    """A symbol for an enumerated value (`RUN` of `E_Mode`)."""

    name: str
    ty: T.EnumType


@dataclass
class CheckedUnit:
    """The checked program: the annotated AST plus the tables the compiler needs."""

    unit: A.Unit
    types: dict[str, T.Type]            # upper-case name -> declared data type
    pous: dict[str, A.PouDecl]          # upper-case name -> the POU (the first of a duplicate)
    globals: dict[str, A.VarDecl]       # upper-case name (or %address) -> global variable
    config: Optional[A.Configuration]
    diagnostics: list[Diagnostic] = field(default_factory=list)
    scope_count: int = 1     # global scopes (several GVL files of different stands, no CONFIGURATION)
    # sources made from a plc.xml (file name -> frontend.graphical GeneratedSource): a fault in their
    # code names the POU, rung and element drawn, not a line of generated text
    drawings: dict[str, Any] = field(default_factory=dict)
