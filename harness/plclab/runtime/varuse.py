"""Which variables a POU body uses, writes, mutates and passes by reference.

The compiler keeps a POU's own variables in Python locals while its body runs (a local is
several times cheaper than an attribute), which is only sound for variables no one else can
reach during the call: a variable passed by reference (VAR_IN_OUT, a function's output) must
stay in its object so the callee writes where the caller reads. This module finds them, with
how often each variable is named, so that only variables worth a local get one.
"""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Iterable, Optional

from plclab.frontend import ast as A


@dataclass
class VarUse:
    """Keyed by id() of the VarDecl (names in different scopes may share a key)."""

    count: Counter = field(default_factory=Counter)   # occurrences in the body
    written: set[int] = field(default_factory=set)    # assigned as a whole (a scalar store)
    mutated: set[int] = field(default_factory=set)    # an element or field assigned
    by_ref: set[int] = field(default_factory=set)     # passed by reference to a call


def body_use(body: Iterable[A.Stmt]) -> VarUse:
    use = VarUse()
    for s in body:
        _stmt(s, use)
    return use


def _root(e: A.Expr) -> Optional[A.Name]:
    while isinstance(e, (A.Member, A.Index)):
        e = e.base
    return e if isinstance(e, A.Name) else None


def _target(e: A.Expr, use: VarUse) -> None:
    """`e` is stored into: a whole variable is written, an element or field mutates its root."""
    _expr(e, use)
    root = _root(e)
    if root is not None and isinstance(root.sym, A.VarDecl):
        (use.written if root is e else use.mutated).add(id(root.sym))


def _by_ref(e: A.Expr, use: VarUse) -> None:
    _expr(e, use)
    root = _root(e)
    if root is not None and isinstance(root.sym, A.VarDecl):
        use.by_ref.add(id(root.sym))
        use.mutated.add(id(root.sym))


def _stmt(s: A.Stmt, use: VarUse) -> None:
    if isinstance(s, A.Assign):
        _target(s.target, use)
        _expr(s.value, use)
    elif isinstance(s, A.CallStmt):
        _expr(s.target, use)
        for a in s.args:
            if a.is_output:
                _target(a.value, use)
            elif isinstance(a.param, A.VarDecl) and a.param.section == "VAR_IN_OUT":
                _by_ref(a.value, use)
            else:
                _expr(a.value, use)
    elif isinstance(s, A.If):
        for cond, body in s.branches:
            _expr(cond, use)
            _block(body, use)
        _block(s.else_body or [], use)
    elif isinstance(s, A.Case):
        _expr(s.selector, use)
        for br in s.branches:
            _block(br.body, use)
        _block(s.else_body or [], use)
    elif isinstance(s, A.For):
        _target(s.var, use)
        for e in (s.start, s.end, s.step):
            if e is not None:
                _expr(e, use)
        _block(s.body, use)
    elif isinstance(s, A.While):
        _expr(s.cond, use)
        _block(s.body, use)
    elif isinstance(s, A.Repeat):
        _block(s.body, use)
        _expr(s.cond, use)


def _block(body: Iterable[A.Stmt], use: VarUse) -> None:
    for s in body:
        _stmt(s, use)


def _expr(e: Optional[A.Expr], use: VarUse) -> None:
    if isinstance(e, A.Name):
        if isinstance(e.sym, A.VarDecl):
            use.count[id(e.sym)] += 1
    elif isinstance(e, A.Member):
        _expr(e.base, use)
    elif isinstance(e, A.Index):
        _expr(e.base, use)
        for ix in e.indexes:
            _expr(ix, use)
    elif isinstance(e, A.Unary):
        _expr(e.operand, use)
    elif isinstance(e, A.Binary):
        _expr(e.left, use)
        _expr(e.right, use)
    elif isinstance(e, A.Call):
        for a in e.args:
            section = a.param.section if isinstance(a.param, A.VarDecl) else None
            if a.is_output or section in ("VAR_OUTPUT", "VAR_IN_OUT"):
                _by_ref(a.value, use)       # a function's outputs and ENO are set through references
            else:
                _expr(a.value, use)
