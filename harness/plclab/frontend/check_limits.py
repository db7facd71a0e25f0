"""ST checker, limits: what a program may declare and how deeply it may nest, as a real PLC's
memory and compiler bound them.

A student's program is untrusted input. Without these limits a 19 KB file could declare
gigabytes (nested named arrays, FB types that double at each level), or nest FB instances
and statements until Python's stack or parser gives up: `check` would say ok and `grade`,
`sim` or the lab would crash later. Each limit is refused here, at the declaration or
statement that crosses it, with the figures named (docs/reliability.md lists them):

- MAX_DATA_BYTES: the data a program declares, counted as OpenPLC's C types store it (see
  `type_bytes`), per type, per POU instance (FB instances inside it included) and in all
  (VAR_GLOBALs plus every program instance of the CONFIGURATION).
- POUs that refer to themselves (an FB holding an instance of itself through a chain of FBs, a
  FUNCTION calling itself through other functions): OpenPLC's compiler refuses them too
  ("POU ... contains a self-reference and/or belongs in a circular referencing loop",
  matiec's stage3/remove_forward_dependencies.cc).
- MAX_POU_NESTING: the longest chain of FB instances and function calls.
- MAX_STATEMENT_NESTING, MAX_LOOP_NESTING, MAX_BRANCH_DEPTH and MAX_EXPRESSION_DEPTH: nested
  IF/CASE/loops, nested loops, ELSIF/CASE branches, nested operators and calls in one statement
  (the compiled Python must stay within Python's own limits).

Every walk here is iterative: the limits are checked before anything recurses over the tree.
"""
from __future__ import annotations

import dataclasses
from typing import Any, Iterator, Optional

from plclab.frontend import ast as A
from plclab.frontend.check_base import CheckerBase
from plclab.frontend.stdsigs import FBSig
from plclab.iec import types as T

MAX_DATA_BYTES = 4 * 1024 * 1024
"""4 MiB of declared data: thousands of times what a lab program needs (the shipped programs
declare a few KiB), and what a small PLC's data memory holds."""
MAX_POU_NESTING = 100
"""FB instances inside FB instances, and function calls inside functions, at most this many
levels below a POU (a PROGRAM holding FB1 holding FB2 has 2 levels below it)."""
MAX_STATEMENT_NESTING = 40
"""IF/CASE/FOR/WHILE/REPEAT inside each other at most this deep in one statement."""
MAX_LOOP_NESTING = 8
"""FOR/WHILE/REPEAT inside each other at most this deep (among the statements above): each loop
is two of the 20 nested blocks Python allows in one function."""
MAX_BRANCH_DEPTH = 1000
"""ELSIF and CASE branches before a statement, added up over the IFs and CASEs around it (and
one per loop): Python compiles an ELSIF chain as IFs nested in each other, and its compiler stops
near 3000 levels (an IF of 3000 ELSIFs passed `check` and then stopped `sim` with exit 70)."""
MAX_EXPRESSION_DEPTH = 40
"""Operators and calls nested inside each other at most this deep in one expression
(`a + b + c` is 2 deep: the first `+` is an operand of the second)."""

STRING_BYTES = 127       # OpenPLC's STRING: a length byte and 126 characters, whatever STRING[n] says
REFERENCE_BYTES = 8      # a VAR_IN_OUT or VAR_EXTERNAL holds a pointer, not the data
BOOKKEEPING_BYTES = 64   # each STRUCT value and FB instance: what the soft PLC keeps beside the fields

_ELEMENTARY_BYTES = {"bool": 1, "string": STRING_BYTES}
_ANNOTATIONS = frozenset({"ty", "sym", "pou", "param", "call", "fb_type", "operand_ty", "arg_types",
                          "global_decl", "bound_params", "lo_value", "hi_value"})
_FIELDS: dict[type, tuple[str, ...]] = {}   # AST class -> the fields that may hold nodes
_LOOPS = (A.For, A.While, A.Repeat)
_COMPOUND = (A.If, A.Case, *_LOOPS)


def mib(n: int) -> str:
    """A byte count for a message: `4 MiB`, `1.5 MiB`, `800 KiB`, `12 bytes`."""
    if n >= 1024 * 1024:
        return f"{n / (1024 * 1024):.4g} MiB"
    if n >= 1024:
        return f"{n / 1024:.4g} KiB"
    return f"{n} bytes"


def type_bytes(t: T.Type, memo: dict[Any, int], fb_bytes: Any = None) -> int:
    """The bytes a value of `t` takes, counted as OpenPLC's C types store it: BOOL, SINT, BYTE 1,
    INT 2, DINT, REAL 4, LINT, LREAL, TIME and dates 8, an enumeration 4, a STRING 127, an ARRAY
    its elements, a STRUCT its fields plus BOOKKEEPING_BYTES. `fb_bytes(fb)` sizes an FB instance.
    Memoised by type: nested named types share their parts, so the walk stays linear."""
    if t in memo:
        return memo[t]
    if isinstance(t, (T.AliasType, T.SubrangeType)):
        n = type_bytes(t.base, memo, fb_bytes)
    elif isinstance(t, T.EnumType):
        n = 4
    elif isinstance(t, T.StringType):
        n = STRING_BYTES
    elif isinstance(t, T.ElementaryType):
        n = _ELEMENTARY_BYTES.get(t.kind, max(1, t.bits // 8))
    elif isinstance(t, T.ArrayType):
        n = t.size * type_bytes(t.elem, memo, fb_bytes)
    elif isinstance(t, T.StructType):
        n = BOOKKEEPING_BYTES + sum(type_bytes(ft, memo, fb_bytes) for ft, _init in t.fields.values())
    elif isinstance(t, T.FBType):
        n = fb_bytes(t) if fb_bytes is not None else BOOKKEEPING_BYTES
    else:
        n = 8
    memo[t] = n
    return n


def std_fb_bytes(sig: FBSig, memo: dict[Any, int]) -> int:
    """A standard FB instance: its inputs and outputs, EN/ENO, its internal state (a timer's
    start time, a trigger's memory) and the bookkeeping."""
    params = sum(type_bytes(T.ELEMENTARY[tn], memo) for _n, tn in (*sig.inputs, *sig.outputs))
    return params + 2 + 16 + BOOKKEEPING_BYTES


def _children(node: Any) -> Iterator[A.Node]:
    """The AST nodes directly under `node` (its fields, through lists and tuples), without the
    checker's annotations."""
    names = _FIELDS.get(type(node))
    if names is None:
        names = _FIELDS[type(node)] = tuple(f.name for f in dataclasses.fields(node)
                                            if f.name not in _ANNOTATIONS and f.name not in ("line", "col", "file"))
    for name in names:
        todo = [getattr(node, name)]
        while todo:
            v = todo.pop()
            if isinstance(v, A.Node):
                yield v
            elif isinstance(v, (list, tuple)):
                todo.extend(v)


def _branch_positions(node: A.Node) -> dict[int, int]:
    """id(child) -> the position of its branch (1: THEN or the first CASE branch, 2: the first
    ELSIF or the second branch, ...; ELSE after the last) for the statements of an IF and the
    branches of a CASE: Python compiles an ELSIF chain as IFs nested in each other's else."""
    if isinstance(node, A.If):
        parts: list = [body for _cond, body in node.branches]
    elif isinstance(node, A.Case):
        parts = [[branch] for branch in node.branches]
    else:
        return {}
    parts.append(node.else_body or [])
    return {id(child): i for i, part in enumerate(parts, start=1) for child in part}


def nesting_violation(stmt: A.Stmt) -> Optional[tuple[A.Node, str]]:
    """Where `stmt` nests statements or expressions beyond the limits, and the message; None
    when it does not. Iterative, so a statement nested 100,000 deep is measured, not a crash.
    A compound statement's depth counts the compound statements around it and itself; an
    expression's depth counts the expressions around it and itself (a call's arguments are one
    deeper than the call); a statement's branch depth adds up the positions of the IF/CASE
    branches it is in (MAX_BRANCH_DEPTH)."""
    # node, statement depth, loop depth, branch depth, expression depth
    todo: list[tuple[A.Node, int, int, int, int]] = [(stmt, 1, 1, 0, 0)]
    while todo:
        node, sdepth, ldepth, bdepth, edepth = todo.pop()
        if isinstance(node, _COMPOUND) and sdepth > MAX_STATEMENT_NESTING:
            return node, (f"statements nested more than {MAX_STATEMENT_NESTING} levels deep (IF, CASE, FOR, "
                          f"WHILE, REPEAT inside each other); move the inner part into a function or "
                          f"function block")
        if isinstance(node, _LOOPS) and ldepth > MAX_LOOP_NESTING:
            return node, (f"loops nested more than {MAX_LOOP_NESTING} levels deep (FOR, WHILE, REPEAT inside each "
                          f"other); move the inner loops into a function or function block")
        if isinstance(node, A.Stmt) and bdepth > MAX_BRANCH_DEPTH:
            return node, (f"too many ELSIF or CASE branches before this statement: counting each branch of each "
                          f"IF and CASE around it, it is {bdepth} branches deep (at most {MAX_BRANCH_DEPTH}); "
                          f"split the IF or CASE (e.g. a CASE per range of values) or move its branches into "
                          f"functions")
        if isinstance(node, A.Expr) and edepth > MAX_EXPRESSION_DEPTH:
            return node, (f"expression nested more than {MAX_EXPRESSION_DEPTH} levels deep (operators and calls "
                          f"inside each other); compute parts of it into variables first")
        inner = sdepth + 1 if isinstance(node, _COMPOUND) else sdepth
        inner_loop = ldepth + 1 if isinstance(node, _LOOPS) else ldepth
        positions = _branch_positions(node)
        branch = bdepth + 1 if isinstance(node, _LOOPS) else bdepth
        in_expr = isinstance(node, (A.Expr, A.Arg))
        for child in _children(node):
            below = branch + positions.get(id(child), 0)
            if isinstance(child, A.Expr):
                todo.append((child, inner, inner_loop, below, edepth + 1 if in_expr else 1))
            else:
                todo.append((child, inner, inner_loop, below, edepth if in_expr else 0))
    return None


class LimitChecks(CheckerBase):
    """Declared memory, POUs that refer to themselves, nesting of POUs: checked once every POU's
    declarations and body are (calls are resolved then)."""

    # ------------------------------------------------------------------ after every body
    def _check_limits(self, config: Optional[A.Node]) -> None:
        pous = [p for p in self.unit.pous if self.pous.get(p.key) is p]
        edges = self._pou_edges(pous)
        in_cycle = self._report_cycles(pous, edges)
        if in_cycle:
            return
        depth: dict[str, int] = {}
        for pou in self._topological(pous, edges):   # callees first
            below = [(depth[t.key], node) for t, node in edges[pou.key]]
            depth[pou.key] = 1 + max((d for d, _n in below), default=0)
            if depth[pou.key] - 1 > MAX_POU_NESTING:
                node = max(below, key=lambda b: b[0])[1]
                self.error(node, f"function blocks and function calls nested more than {MAX_POU_NESTING} levels "
                                 f"deep ('{pou.name}' reaches {depth[pou.key] - 1} levels of POUs below it)")
                return
        if not self.memory_refused:          # else its instances would be reported again
            self._check_instance_sizes(pous, edges, config)

    def _pou_edges(self, pous: list[A.PouDecl]) -> dict[str, list[tuple[A.PouDecl, A.Node]]]:
        """POU -> the user POUs it refers to (the type of an FB variable, also a VAR_IN_OUT or
        VAR_EXTERNAL one, as matiec counts references; a called function), each with the
        declaration or call that refers to it."""
        edges: dict[str, list[tuple[A.PouDecl, A.Node]]] = {p.key: [] for p in pous}
        for pou in pous:
            for d in pou.decls:
                if isinstance(d.ty, T.FBType) and isinstance(d.ty.pou, A.PouDecl) and d.ty.pou.key in edges:
                    edges[pou.key].append((d.ty.pou, d))
        for caller, call in self.user_calls:
            if caller is not None and caller.key in edges and call.pou is not None and call.pou.key in edges:
                edges[caller.key].append((call.pou, call))
        return edges

    def _report_cycles(self, pous: list[A.PouDecl], edges: dict[str, list[tuple[A.PouDecl, A.Node]]]) -> bool:
        """One error per loop of POUs referring to each other (`FB_A -> FB_B -> FB_A`), at the
        reference that closes it into the first POU of the loop; True if there is one. Direct
        self-references are reported where they are declared (an FB variable of its own type,
        a recursive call), not again here."""
        by_key = {p.key: p for p in pous}
        state: dict[str, int] = {}            # 1: on the current path, 2: done
        found = False
        reported: set[frozenset[str]] = set()
        for root in pous:
            if root.key in state:
                continue
            path: list[tuple[str, A.Node]] = [(root.key, root)]
            iters = [iter(edges[root.key])]
            state[root.key] = 1
            while iters:
                step = next(iters[-1], None)
                if step is None:
                    state[path[-1][0]] = 2
                    path.pop()
                    iters.pop()
                    continue
                target, node = step
                if state.get(target.key) == 1:
                    keys = [k for k, _n in path]
                    loop = path[keys.index(target.key):] + [(target.key, node)]
                    members = frozenset(k for k, _n in loop)
                    found = True
                    closing = loop[-1][1]
                    if len(loop) == 2 and isinstance(closing, A.VarDecl) and closing.section == "VAR_EXTERNAL":
                        self.error(closing, f"function block '{by_key[target.key].name}' names its own type in a "
                                            f"VAR_EXTERNAL (OpenPLC's compiler refuses a POU that refers to itself)")
                    if len(loop) > 2 and members not in reported:
                        reported.add(members)
                        names = " -> ".join(by_key[k].name for k, _n in loop)
                        kinds = {by_key[k].kind for k, _n in loop}
                        contain = all(isinstance(n, A.VarDecl) and n.section not in ("VAR_IN_OUT", "VAR_EXTERNAL")
                                      for _k, n in loop[1:])
                        what = ("function blocks contain each other" if kinds == {"FUNCTION_BLOCK"} and contain else
                                "function blocks refer to each other" if kinds == {"FUNCTION_BLOCK"} else
                                "functions call each other" if kinds == {"FUNCTION"} else "POUs refer to each other")
                        self.error(closing, f"{what} in a loop: {names} (recursion is not allowed: "
                                            f"OpenPLC's compiler refuses a POU that refers to itself)")
                elif target.key not in state:
                    state[target.key] = 1
                    path.append((target.key, node))
                    iters.append(iter(edges[target.key]))
        return found

    @staticmethod
    def _topological(pous: list[A.PouDecl], edges: dict[str, list[tuple[A.PouDecl, A.Node]]]) -> list[A.PouDecl]:
        """The POUs with every POU after the POUs it refers to (the graph has no loop)."""
        order: list[A.PouDecl] = []
        seen: set[str] = set()
        for root in pous:
            if root.key in seen:
                continue
            seen.add(root.key)
            stack = [(root, iter(edges[root.key]))]
            while stack:
                pou, it = stack[-1]
                nxt = next(it, None)
                if nxt is None:
                    order.append(pou)
                    stack.pop()
                elif nxt[0].key not in seen:
                    seen.add(nxt[0].key)
                    stack.append((nxt[0], iter(edges[nxt[0].key])))
        return order

    def _check_instance_sizes(self, pous: list[A.PouDecl], edges: dict[str, list[tuple[A.PouDecl, A.Node]]],
                              config: Optional[A.Node]) -> None:
        """Each FB and PROGRAM instance, FB instances inside it included, and the whole program
        (VAR_GLOBALs and every program instance) within MAX_DATA_BYTES."""
        size: dict[str, int] = {}
        memo = self.size_memo

        def fb_bytes(fb: T.FBType) -> int:
            if isinstance(fb.pou, FBSig):
                return std_fb_bytes(fb.pou, memo)
            return size.get(fb.pou.key, BOOKKEEPING_BYTES)

        too_big = False
        for pou in self._topological(pous, edges):
            if pou.kind == "FUNCTION":
                continue
            total = BOOKKEEPING_BYTES + 2
            for d in pou.decls:
                if d.ty is None:
                    continue
                n = REFERENCE_BYTES if d.section in ("VAR_IN_OUT", "VAR_EXTERNAL") else \
                    type_bytes(d.ty, {}, fb_bytes) if isinstance(d.ty, T.FBType) else type_bytes(d.ty, memo)
                if total + n > MAX_DATA_BYTES and not too_big:
                    kind = "function block" if pou.kind == "FUNCTION_BLOCK" else "program"
                    self.error(d, f"an instance of {kind} '{pou.name}' takes more than the {mib(MAX_DATA_BYTES)} a "
                                  f"program may declare: '{d.name}' ({d.ty.name}, {mib(n)}) brings it to "
                                  f"{mib(total + n)}")
                    too_big = True
                total += n
            size[pou.key] = total
        if too_big:
            return
        globals_bytes = sum(type_bytes(d.ty, {}, fb_bytes) for scope in self.global_scopes for d in scope.values()
                            if isinstance(d, A.VarDecl) and d.ty is not None and d.name)
        instances = self._program_instances(pous, config)
        total = globals_bytes
        for node, name, pou in instances:
            total += size.get(pou.key, 0)
            if total > MAX_DATA_BYTES:
                self.error(node, f"the program declares {mib(total)} with program instance '{name}' of "
                                 f"'{pou.name}' ({mib(size.get(pou.key, 0))}; VAR_GLOBALs {mib(globals_bytes)}), "
                                 f"more than the {mib(MAX_DATA_BYTES)} a program may declare")
                return

    def _program_instances(self, pous: list[A.PouDecl], config: Any) -> list[tuple[A.Node, str, A.PouDecl]]:
        """(where, instance name, PROGRAM) of every program instance: the CONFIGURATION's, or
        each PROGRAM once when there is none."""
        if config is None:
            return [(p, p.name, p) for p in pous if p.kind == "PROGRAM"]
        found = []
        for res in config.resources:
            for inst in res.programs:
                pou = self.pous.get(inst.type_name.upper())
                if pou is not None and pou.kind == "PROGRAM":
                    found.append((inst, inst.name, pou))
        return found
