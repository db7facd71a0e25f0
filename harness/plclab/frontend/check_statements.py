"""ST checker, statements: POU bodies, IF/CASE/FOR/WHILE/REPEAT, and function block calls with
their parameters, as matiec checks them."""
from __future__ import annotations

from typing import Any, Optional

from plclab.frontend import ast as A
from plclab.frontend.check_base import CheckerBase, _Scope
from plclab.frontend.check_expressions import negated_output_message
from plclab.frontend.check_limits import nesting_violation
from plclab.frontend.stdsigs import FUNCTION_BLOCKS, FUNCTIONS, FBSig
from plclab.iec import types as T


class StatementChecks(CheckerBase):
    """POU bodies: statements and function block calls."""

    # ------------------------------------------------------------------ bodies
    def _check_pou_body(self, pou: A.PouDecl) -> None:
        scope = _Scope(pou, pou.symbols or {})
        if not pou.body:
            self.error(pou, f"{pou.kind} '{pou.name}' has no statements: OpenPLC's compiler needs at least one")
        for s in pou.body:
            too_deep = nesting_violation(s)
            if too_deep is not None:
                self.error(*too_deep)
                continue
            try:
                self.stmt(s, scope)
            except RecursionError:
                scope.for_vars.clear()
                scope.loop_depth = 0
                self.error(s, "this statement nests IF/CASE/loops or operators too deeply (a few hundred "
                              "levels); split it into smaller statements or functions")

    def body(self, body: list[A.Stmt], scope: _Scope, where: Any, what: str) -> None:
        """A statement list that OpenPLC's compiler requires to be non-empty."""
        if not body:
            self.error(where, f"no statement after {what}: OpenPLC's compiler needs at least one")
        self.stmts(body, scope)

    def stmts(self, body: list[A.Stmt], scope: _Scope) -> None:
        for s in body:
            self.stmt(s, scope)

    def stmt(self, s: A.Stmt, scope: _Scope) -> None:
        if isinstance(s, A.Assign):
            tt = self.lvalue(s.target, scope)
            vt = self.expr(s.value, scope, tt)
            if tt is not None and vt is not None:
                self.assignable(tt, s.value, vt)
        elif isinstance(s, A.CallStmt):
            self.call_stmt(s, scope)
        elif isinstance(s, A.If):
            for cond, body in s.branches:
                kw = "IF" if cond is s.branches[0][0] else "ELSIF"
                self.condition(cond, scope, kw)
                self.body(body, scope, cond, f"{kw} ... THEN")
            if s.else_body is not None:
                self.body(s.else_body, scope, s, "ELSE")
        elif isinstance(s, A.Case):
            self.case(s, scope)
        elif isinstance(s, A.For):
            self.for_(s, scope)
        elif isinstance(s, A.While):
            self.condition(s.cond, scope, "WHILE")
            scope.loop_depth += 1
            self.body(s.body, scope, s, "WHILE ... DO")
            scope.loop_depth -= 1
        elif isinstance(s, A.Repeat):
            scope.loop_depth += 1
            self.body(s.body, scope, s, "REPEAT")
            scope.loop_depth -= 1
            self.condition(s.cond, scope, "UNTIL")
        elif isinstance(s, A.Exit):
            if scope.loop_depth == 0:
                self.error(s, "EXIT outside a FOR, WHILE or REPEAT loop")
        elif isinstance(s, A.Continue):
            if scope.loop_depth == 0:
                self.error(s, "CONTINUE outside a FOR, WHILE or REPEAT loop")
        elif isinstance(s, A.Empty):
            self.error(s, "empty statement ';': OpenPLC's compiler rejects a ';' that ends no statement")

    def condition(self, e: A.Expr, scope: _Scope, what: str) -> None:
        t = self.expr(e, scope, T.BOOL)
        if t is not None and T.base_of(t) is not T.BOOL:
            self.error(e, f"{what} condition must be BOOL, not {self._tname(t)}")

    def case(self, s: A.Case, scope: _Scope) -> None:
        st = self.expr(s.selector, scope, None)
        if st is not None:
            st = self.settle(s.selector, st)
            b = T.base_of(st)
            if not ((isinstance(b, T.ElementaryType) and b.is_integer) or isinstance(b, T.EnumType)):
                self.error(s.selector, f"CASE selector must be an integer or enumerated value, not {self._tname(st)}")
                st = None
        if not s.branches:
            self.error(s, "CASE without any branch")
        for br in s.branches:
            for lab in br.labels:
                lo = self._case_value(lab.lo, st, scope)
                hi = self._case_value(lab.hi, st, scope) if lab.hi is not None else lo
                lab.lo_value, lab.hi_value = lo, hi
                if isinstance(lo, int) and isinstance(hi, int) and hi < lo:
                    self.error(lab.lo, f"empty CASE range {lo}..{hi}")
            self.body(br.body, scope, br, "a CASE label")
        if s.else_body is not None:
            self.body(s.else_body, scope, s, "ELSE")

    def _case_value(self, e: A.Expr, st: Optional[T.Type], scope: _Scope) -> Any:
        plain_int = isinstance(e, A.Literal) and e.kind == "int" and e.type_name is None \
            and "#" not in e.text
        enum_value = (isinstance(e, A.Name) and e.key in self.enum_values) or \
            (isinstance(e, A.Literal) and e.kind == "enum")
        if not (plain_int or enum_value):
            self.error(e, "a CASE label must be a decimal integer literal, a range of them, or an "
                          "enumerated value (OpenPLC's compiler rejects typed/based literals and named constants)")
            return None
        t = self.expr(e, scope, st)
        if t is None or st is None:
            return None
        if not self.assignable(st, e, t, what="CASE label"):
            return None
        v = self.const_value(e, scope)
        if v is None:
            self.error(e, "a CASE label must be a constant")
        return v

    def for_(self, s: A.For, scope: _Scope) -> None:
        vt = self.expr(s.var, scope, None)
        if vt is not None:
            sym = s.var.sym
            b = T.base_of(vt)
            if not (isinstance(b, T.ElementaryType) and b.is_integer):
                self.error(s.var, f"FOR control variable must be an integer, not {self._tname(vt)}")
                vt = None
            elif isinstance(sym, A.VarDecl) and (sym.constant or sym.section == "VAR_INPUT" and scope.pou is not None
                                                and scope.pou.kind == "FUNCTION"):
                self.error(s.var, f"FOR control variable '{s.var.name}' cannot be a constant or input")
        for part in (s.start, s.end, s.step):
            if part is None:
                continue
            pt = self.expr(part, scope, vt)
            if pt is not None and vt is not None:
                self.assignable(vt, part, pt, what="FOR bound")
        scope.for_vars.append(s.var.key)
        scope.loop_depth += 1
        self.body(s.body, scope, s, "FOR ... DO")
        scope.loop_depth -= 1
        scope.for_vars.pop()

    # ------------------------------------------------------------------ calls
    def call_stmt(self, s: A.CallStmt, scope: _Scope) -> None:
        target = s.target
        if isinstance(target, A.Name) and target.key not in scope.names and (
                target.key in FUNCTIONS or (target.key in self.pous and self.pous[target.key].kind == "FUNCTION")):
            self.error(s, f"'{target.name}' is a function: its result must be used (OpenPLC's compiler "
                          f"rejects a function call as a statement), e.g. x := {target.name}(...);")
            return
        if isinstance(target, A.Name) and target.key not in scope.names and (
                target.key in FUNCTION_BLOCKS or target.key in self.fb_types):
            # `CTU(CU := x);` as an S7 box is drawn: the block needs an instance that keeps its state
            inst = f"{target.name[0].upper()}1"
            type_name = target.key if target.key in FUNCTION_BLOCKS else target.name
            self.error(s, f"'{target.name}' is a function block type: declare an instance (e.g. "
                          f"{inst} : {type_name};) and call it, {inst}(...)")
            return
        t = self.expr(target, scope, None, allow_fb=True)
        if t is None:
            for a in s.args:
                self.expr(a.value, scope, None)
            return
        if not isinstance(t, T.FBType):
            self.error(target, f"'{self._path_text(target)}' is not a function block instance or a function")
            return
        external = isinstance(target, A.Name) and isinstance(target.sym, A.VarDecl) \
            and target.sym.section == "VAR_EXTERNAL"
        if external and target.sym.constant:
            self.error(target, f"'{target.name}' is CONSTANT: it cannot be called")
        s.fb_type = t
        if external and s.args:
            # iec2c passes arguments of an external instance through __SET_EXTERNAL_FB and
            # `->` member reads that OpenPLC's accessor.h and g++ refuse; a bare call builds
            self.error(s.args[0], f"'{target.name}' is reached through VAR_EXTERNAL: OpenPLC builds a call of it "
                                  f"only without arguments; set its inputs ({target.name}.IN := ...) before the "
                                  f"call and read its outputs ({target.name}.Q) after it")
        self._bind_fb_args(s, t, scope)

    def _fb_params(self, fb: T.FBType) -> tuple[dict[str, tuple[str, T.Type, Any]], list[str]]:
        """Parameter name -> (section, type, decl) and the positional order of inputs."""
        params: dict[str, tuple[str, T.Type, Any]] = {}   # in declaration order
        order: list[str] = []
        if isinstance(fb.pou, FBSig):
            for n, tn in fb.pou.inputs:
                params[n] = ("VAR_INPUT", T.ELEMENTARY[tn], None)
                order.append(n)
            for n, tn in fb.pou.outputs:
                params[n] = ("VAR_OUTPUT", T.ELEMENTARY[tn], None)
            return params, order
        pou: A.PouDecl = fb.pou
        for d in pou.decls:
            if d.section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT") and d.ty is not None:
                params[d.key] = (d.section, d.ty, d)
                if d.section != "VAR_OUTPUT":
                    order.append(d.key)
        return params, order

    def _bind_fb_args(self, s: A.CallStmt, fb: T.FBType, scope: _Scope) -> None:
        params, order = self._fb_params(fb)
        formal = [a for a in s.args if a.name is not None]
        positional = [a for a in s.args if a.name is None]
        if formal and positional:
            self.error(positional[0], "mixing formal (name := value) and positional arguments in one call")
            return
        if positional:
            all_params = list(params)
            if len(positional) > len(all_params):
                self.error(positional[-1], f"{fb.name} has {len(all_params)} parameter(s), {len(positional)} given")
                return
            for a, pname in zip(positional, all_params):
                a.name, a.key = pname, pname
                if params[pname][0] == "VAR_OUTPUT":
                    a.is_output = True
            formal = positional
        seen = set()
        for a in formal:
            if a.key in ("EN", "ENO"):      # matiec gives every FB an EN input and an ENO output
                self._en_eno_arg(a, scope)
                continue
            if a.key in seen:
                self.error(a, f"parameter '{a.name}' given twice")
                continue
            seen.add(a.key)
            p = params.get(a.key)
            if p is None:
                self.error(a, f"function block {fb.name} has no parameter '{a.name}'")
                continue
            sec, pty, decl = p
            a.param = decl if decl is not None else (sec, a.key)
            if a.is_output:
                if sec != "VAR_OUTPUT":
                    self.error(a, f"'{a.name}' is an input of {fb.name}: use ':=' not '=>'")
                    continue
                tt = self.lvalue(a.value, scope)
                if tt is not None:
                    if a.negated:
                        self.error(a, negated_output_message(a))
                    elif not self._decl_types_match(T.base_of(tt), T.base_of(pty)) and not T.same_type(tt, pty):
                        self.error(a.value, f"output '{a.name}' is {pty.name}; it cannot be stored in {self._tname(tt)}")
            else:
                if sec == "VAR_OUTPUT":
                    self.error(a, f"'{a.name}' is an output of {fb.name}: read it with '=>' "
                                  f"or as {self._path_text(s.target)}.{a.name}")
                    continue
                if sec == "VAR_IN_OUT":
                    if not self._is_variable(a.value, a.name):
                        continue
                    tt = self.lvalue(a.value, scope)
                    if tt is not None and not self._decl_types_match(T.base_of(tt), T.base_of(pty)) \
                            and not T.same_type(tt, pty):
                        self.error(a.value, f"VAR_IN_OUT '{a.name}' is {pty.name}, not {self._tname(tt)}")
                    continue
                vt = self.expr(a.value, scope, pty)
                if vt is not None:
                    self.assignable(pty, a.value, vt, what=f"parameter '{a.name}'")
        for key, (sec, _pty, decl) in params.items():
            if sec == "VAR_IN_OUT" and key not in seen:
                self.error(s, f"VAR_IN_OUT parameter '{decl.name if decl else key}' of {fb.name} must be given")
