"""ST checker, expressions: names and lvalues, literals and their types, operators, function calls
and the overloads of the standard functions, and assignability (no implicit conversion)."""
from __future__ import annotations

import sys
from typing import Optional

from plclab.frontend import ast as A
from plclab.frontend.check_base import (
    CheckerBase, DEFAULT_INT, DEFAULT_REAL, _GENERIC_RESULT_DEFAULT, _Scope, fold, short_address_message
)
from plclab.frontend.s7names import word_address_hint
from plclab.frontend.suggest import did_you_mean
from plclab.frontend.checked import INT_LIT, REAL_LIT, EnumValue, LiteralType
from plclab.frontend.stdsigs import FUNCTION_BLOCKS, FUNCTIONS, NO_BOOL_OVERLOAD, FBSig, FuncSig
from plclab.iec import types as T


class ExpressionChecks(CheckerBase):
    """Expressions, function calls and standard-function overloads, assignability."""

    def call(self, c: A.Call, scope: _Scope, expected: Optional[T.Type]) -> Optional[T.Type]:
        if not c.args:
            self.error(c, f"'{c.name}()' without arguments is rejected by OpenPLC's compiler")
            return None
        if c.key in self.pous and self.pous[c.key].kind == "FUNCTION":
            return self._user_call(c, self.pous[c.key], scope)
        if c.key in FUNCTIONS:
            return self._std_call(c, FUNCTIONS[c.key], scope, expected)
        if c.key in self.pous or c.key in FUNCTION_BLOCKS or c.key in self.fb_types:
            self.error(c, f"'{c.name}' is not a function; a function block is called through an instance")
        elif c.key in scope.names:
            self.error(c, f"'{c.name}' is a variable, not a function; a function block instance is called as a statement")
        else:
            self.error(c, f"unknown function '{c.name}'")
        for a in c.args:
            self.expr(a.value, scope, None)
        return None

    def _user_call(self, c: A.Call, pou: A.PouDecl, scope: _Scope) -> Optional[T.Type]:
        c.pou = pou
        self.user_calls.append((scope.pou, c))
        if scope.pou is pou:
            self.error(c, f"recursive call of '{pou.name}' (IEC 61131-3 forbids recursion)")
        params = [d for d in pou.decls if d.section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT")]
        by_key = {d.key: d for d in params}
        formal = [a for a in c.args if a.name is not None]
        positional = [a for a in c.args if a.name is None]
        if formal and positional:
            self.error(positional[0], "mixing formal (name := value) and positional arguments in one call")
            return pou.ret_ty
        if len(positional) > len(params):
            self.error(c, f"'{pou.name}' has {len(params)} parameter(s), {len(positional)} given")
            return pou.ret_ty
        seen = set()
        # positional arguments go to the parameters in declaration order, outputs included (matiec)
        for a, d in zip(positional, params):
            a.param = d
            seen.add(d.key)
            if d.section == "VAR_OUTPUT":
                a.is_output = True
                self._bind_output(a, d, scope)
            else:
                self._bind_input(a, d, scope, pou.name)
        for a in formal:
            if a.key in ("EN", "ENO"):
                self._en_eno_arg(a, scope)
                continue
            d = by_key.get(a.key)
            if d is None:
                self.error(a, f"function '{pou.name}' has no parameter '{a.name}'")
                continue
            if a.key in seen:
                self.error(a, f"parameter '{a.name}' given twice")
                continue
            seen.add(a.key)
            a.param = d
            if a.is_output:
                if d.section != "VAR_OUTPUT":
                    self.error(a, f"'{a.name}' is an input: use ':='")
                    continue
                self._bind_output(a, d, scope)
            else:
                if d.section == "VAR_OUTPUT":
                    self.error(a, f"'{a.name}' is an output: use '=>'")
                    continue
                self._bind_input(a, d, scope, pou.name)
        for d in params:
            if d.section == "VAR_IN_OUT" and d.key not in seen:
                self.error(c, f"VAR_IN_OUT parameter '{d.name}' of '{pou.name}' must be given")
        return pou.ret_ty

    def _bind_output(self, a: A.Arg, d: A.VarDecl, scope: _Scope) -> None:
        if not self._is_variable(a.value, d.name, "VAR_OUTPUT"):
            return
        tt = self.lvalue(a.value, scope)
        if a.negated:
            self.error(a, negated_output_message(a))
        elif tt is not None and d.ty is not None and not self._decl_types_match(T.base_of(tt), T.base_of(d.ty)):
            self.error(a.value, f"output '{d.name}' is {d.ty.name}; it cannot be stored in {self._tname(tt)}")

    def _en_eno_arg(self, a: A.Arg, scope: _Scope) -> None:
        """`EN := cond` and `ENO => flag`, which matiec gives every function and FB call."""
        if a.key == "EN" and not a.is_output:
            t = self.expr(a.value, scope, T.BOOL)
            if t is not None:
                self.assignable(T.BOOL, a.value, t, what="EN")
        elif a.key == "ENO" and a.is_output:
            t = self.lvalue(a.value, scope)
            if t is not None and T.base_of(t) is not T.BOOL:
                self.error(a.value, f"ENO is BOOL; it cannot be stored in {self._tname(t)}")
        else:
            self.error(a, f"{a.name} is {'an input: use :=' if a.key == 'EN' else 'an output: use =>'}")

    def _bind_input(self, a: A.Arg, d: A.VarDecl, scope: _Scope, fname: str) -> None:
        if d.ty is None:
            self.expr(a.value, scope, None)
            return
        if d.section == "VAR_IN_OUT":
            if not self._is_variable(a.value, d.name):
                return
            tt = self.lvalue(a.value, scope)
            if tt is not None and not self._decl_types_match(T.base_of(tt), T.base_of(d.ty)):
                self.error(a.value, f"VAR_IN_OUT '{d.name}' of '{fname}' is {d.ty.name}, not {self._tname(tt)}")
            return
        vt = self.expr(a.value, scope, d.ty)
        if vt is not None:
            self.assignable(d.ty, a.value, vt, what=f"parameter '{d.name}'")

    def _std_call(self, c: A.Call, sig: FuncSig, scope: _Scope, expected: Optional[T.Type]) -> Optional[T.Type]:
        c.std = sig.name
        args = [a for a in c.args if a.key not in ("EN", "ENO")]
        for a in c.args:
            if a.key == "EN":
                t = self.expr(a.value, scope, T.BOOL)
                if t is not None:
                    self.assignable(T.BOOL, a.value, t, what="EN")
            elif a.key == "ENO":
                self.lvalue(a.value, scope)
        formal = [a for a in args if a.name is not None]
        positional = [a for a in args if a.name is None]
        if formal and positional:
            self.error(positional[0], "mixing formal and positional arguments in one call")
            return None
        names = [p[0] for p in sig.params]
        ptypes = dict(sig.params)
        bound: list[tuple[str, str, A.Arg]] = []
        if positional:
            n = len(positional)
            if n < len(sig.params) or (n > len(sig.params) and not sig.extensible):
                want = f"at least {len(sig.params)}" if sig.extensible else str(len(sig.params))
                self.error(c, f"{sig.name} takes {want} argument(s), {n} given")
                for a in args:
                    self.expr(a.value, scope, None)
                return None
            for i, a in enumerate(positional):
                if i < len(names):
                    pname = names[i]
                else:
                    last = names[-1]
                    stem = last.rstrip("0123456789")
                    pname = f"{stem}{i - (0 if sig.name == 'MUX' else 0) + (0 if last[-1:] == '0' else 1) - (1 if sig.name in ('MUX',) else 0)}"
                gen = ptypes.get(names[min(i, len(names) - 1)])
                bound.append((pname, gen, a))
        else:
            seen = set()
            for a in formal:
                key = a.key
                if a.is_output:
                    self.error(a, f"{sig.name} has no output parameter '{a.name}'")
                    return None
                if key in seen:
                    self.error(a, f"parameter '{a.name}' given twice")
                    return None
                seen.add(key)
                if key in ptypes:
                    bound.append((key, ptypes[key], a))
                elif sig.extensible and key.rstrip("0123456789") == names[-1].rstrip("0123456789") \
                        and key[len(names[-1].rstrip("0123456789")):].isdigit():
                    bound.append((key, ptypes[names[-1]], a))
                else:
                    self.error(a, f"{sig.name} has no parameter '{a.name}'")
                    return None
            missing = [n for n in names if n not in seen]
            if missing:
                self.error(c, f"{sig.name}: parameter '{missing[0]}' is missing")
                return None
        generic_names = set(sig.generic_params)
        if sig.extensible and sig.params:
            last_stem = names[-1].rstrip("0123456789")
            if names[-1] in generic_names:
                for pname, _g, _a in bound:
                    if pname.rstrip("0123456789") == last_stem:
                        generic_names.add(pname)
        # type the generic group together: the first concretely typed argument decides
        gen_args = [(pn, g, a) for pn, g, a in bound if pn in generic_names]
        other = [(pn, g, a) for pn, g, a in bound if pn not in generic_names]
        gen_t: Optional[T.Type] = None
        raw: list[tuple[A.Arg, T.Type, str]] = []
        for pn, g, a in gen_args:
            t = self.expr(a.value, scope, None)
            if t is None:
                return None
            raw.append((a, t, g))
            if not isinstance(t, LiteralType) and gen_t is None:
                gen_t = t
        if gen_args and gen_t is None:
            if sig.result == "T" and expected is not None and not isinstance(expected, LiteralType):
                gen_t = expected
            else:
                kinds = {t.kind for _a, t, _g in raw}
                gen_t = DEFAULT_REAL if "real" in kinds else DEFAULT_INT
        if sig.name in NO_BOOL_OVERLOAD and gen_t is not None and T.base_of(gen_t) is T.BOOL:
            self.error(c, f"OpenPLC's library has no {sig.name} for BOOL (its C code would not compile)")
            return None
        for a, t, g in raw:
            if not T.in_generic(gen_t, g) and not (g in T.ELEMENTARY and T.same_type(gen_t, T.ELEMENTARY[g])):
                self.error(a.value, f"{sig.name} does not accept {self._tname(gen_t)} (needs {g})")
                return None
            if not self.assignable(gen_t, a.value, t, what=f"{sig.name} argument"):
                return None
        for pn, g, a in other:
            target = T.ELEMENTARY.get(g)
            t = self.expr(a.value, scope, target)
            if t is None:
                return None
            if target is not None:
                if not self.assignable(target, a.value, t, what=f"{sig.name} argument '{pn}'"):
                    return None
            else:
                t = self.settle(a.value, t)
                if not T.in_generic(t, g):
                    self.error(a.value, f"{sig.name} argument '{pn}' must be {g}, not {self._tname(t)}")
                    return None
        c.arg_types = [a.value.ty for _pn, _g, a in bound]
        c.bound_params = [pn for pn, _g, _a in bound]
        if sig.result == "T":
            return gen_t
        if sig.result in T.GENERICS:
            # TRUNC, UINT_TO_BCD...: the result type comes from where the call is used
            if expected is not None and not isinstance(expected, LiteralType) and T.in_generic(expected, sig.result):
                return expected
            return _GENERIC_RESULT_DEFAULT[sig.result]
        return T.ELEMENTARY[sig.result]

    # ------------------------------------------------------------------ lvalues
    def _is_variable(self, e: A.Expr, param: str, section: str = "VAR_IN_OUT") -> bool:
        """A VAR_IN_OUT is passed by reference, an output is stored: the argument must be a variable."""
        if isinstance(e, (A.Name, A.Member, A.Index)):
            return True
        why = "is passed by reference" if section == "VAR_IN_OUT" else "is stored into its argument"
        self.error(e, f"{section} '{param}' {why}: give it a variable, not an expression or a literal")
        return False

    def lvalue(self, e: A.Expr, scope: _Scope) -> Optional[T.Type]:
        t = self.expr(e, scope, None)
        if t is None:
            return None
        root = e
        path_has_member = False
        while isinstance(root, (A.Member, A.Index)):
            if isinstance(root, A.Member):
                path_has_member = True
                fb_t = root.base.ty if isinstance(root.base, (A.Name, A.Member, A.Index)) else None
                if isinstance(fb_t, T.FBType):
                    sec = self._fb_member_section(fb_t, root.key)
                    if sec == "VAR_OUTPUT":
                        self.error(e, f"'{self._path_text(e)}' is an output of {fb_t.name}: it cannot be "
                                      f"written from outside the function block")
                        return None
                    if sec not in ("VAR_INPUT", "VAR_IN_OUT", None):
                        self.error(e, f"'{self._path_text(e)}' is internal to {fb_t.name}")
                        return None
            root = root.base
        if not isinstance(root, A.Name):
            self.error(e, "cannot assign to this expression")
            return None
        sym = root.sym
        if isinstance(sym, EnumValue):
            self.error(e, f"'{root.name}' is an enumerated value, not a variable")
            return None
        if root.key.startswith("%"):
            self.error(e, f"{root.name} is written by its address: OpenPLC's compiler stops with an internal error "
                          f"on that; give the located variable a name (VAR q AT {root.name} : ...) and write the name")
            return None
        if isinstance(sym, A.VarDecl):
            if sym.constant or (sym.global_decl is not None and sym.global_decl.constant):
                self.error(e, f"'{root.name}' is a CONSTANT: it cannot be assigned")
                return None
            if sym.constant_in_openplc:
                self.error(e, f"'{root.name}' is declared in a VAR block after a VAR CONSTANT block of this "
                              f"FUNCTION, which OpenPLC's compiler takes as constant too: declare it before the "
                              f"VAR CONSTANT block")
                return None
            if root.key in scope.for_vars and root is e:
                self.error(e, f"'{root.name}' is the control variable of an enclosing FOR loop: "
                              f"it cannot be assigned in the loop body")
                return None
            if sym.location is not None and sym.location.area == "I":
                self.error(e, f"'{root.name}' is an input (AT {sym.location.text}): it cannot be written")
                return None
        if isinstance(t, T.FBType) and not path_has_member and isinstance(e, (A.Name, A.Index, A.Member)):
            self.error(e, "a function block instance cannot be assigned")
            return None
        return t

    def _fb_member_section(self, fb: T.FBType, key: str) -> Optional[str]:
        if isinstance(fb.pou, FBSig):
            if any(n == key for n, _ in fb.pou.inputs):
                return "VAR_INPUT"
            if any(n == key for n, _ in fb.pou.outputs):
                return "VAR_OUTPUT"
            return None
        d = (fb.pou.symbols or {}).get(key)
        return d.section if d is not None else None

    # ------------------------------------------------------------------ expressions
    def expr(self, e: A.Expr, scope: _Scope, expected: Optional[T.Type], allow_fb: bool = False) -> Optional[T.Type]:
        """Type of `e`; untyped literals may stay LiteralType until settled by their context."""
        t = self._expr(e, scope, expected)
        if t is not None and isinstance(t, T.FBType) and not allow_fb and not isinstance(e, A.Call):
            self.error(e, f"'{self._path_text(e)}' is a function block instance, not a value")
            return None
        e.ty = t
        return t

    @staticmethod
    def _no_member(fb: T.FBType, name: str, params: list[str]) -> str:
        """`t.DONE`: the block's inputs and outputs, the closest one first if any is close."""
        return (f"function block {fb.name} has no variable '{name}'{did_you_mean(name, params)}; "
                f"its inputs and outputs: {', '.join(params)}" if params else
                f"function block {fb.name} has no variable '{name}'")

    def _expr(self, e: A.Expr, scope: _Scope, expected: Optional[T.Type]) -> Optional[T.Type]:
        if isinstance(e, A.Literal):
            return self._literal(e, expected)
        if isinstance(e, A.Name):
            return self._name(e, scope, expected)
        if isinstance(e, A.Member):
            bt = self.expr(e.base, scope, None, allow_fb=True)
            if bt is None:
                return None
            b = T.base_of(bt)
            if isinstance(b, T.StructType):
                if e.key not in b.fields:
                    self.error(e, f"'{bt.name}' has no field '{e.name}'"
                                  f"{did_you_mean(e.name, [b.field_names.get(k, k) for k in b.fields])}")
                    return None
                return b.fields[e.key][0]
            if isinstance(b, T.FBType):
                if isinstance(b.pou, FBSig):
                    for n, tn in b.pou.inputs + b.pou.outputs + (("EN", "BOOL"), ("ENO", "BOOL")):
                        if n == e.key:     # matiec gives every block EN and ENO (OpenPLC Editor's ladder reads ENO)
                            e.sym = n
                            return T.ELEMENTARY[tn]
                    self.error(e, self._no_member(b, e.name, [n for n, _t in b.pou.inputs + b.pou.outputs]))
                    return None
                d = (b.pou.symbols or {}).get(e.key)
                if d is None or d.section == "RETURN":
                    self.error(e, self._no_member(b, e.name, [v.name for v in b.pou.decls if v.section in (
                        "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT")]))
                    return None
                if d.section not in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT"):
                    self.error(e, f"'{e.name}' is internal to {b.name}: only inputs and outputs can be "
                                  f"accessed from outside")
                    return None
                e.sym = d
                return d.ty
            self.error(e, f"'{self._path_text(e.base)}' is {self._tname(bt)}, it has no fields")
            return None
        if isinstance(e, A.Index):
            bt = self.expr(e.base, scope, None)
            if bt is None:
                return None
            b = T.base_of(bt)
            if not isinstance(b, T.ArrayType):
                self.error(e, f"'{self._path_text(e.base)}' is not an array")
                return None
            if len(e.indexes) != len(b.dims):
                self.error(e, f"'{self._path_text(e.base)}' has {len(b.dims)} dimension(s), "
                              f"{len(e.indexes)} index(es) given")
                return None
            for ix, (lo, hi) in zip(e.indexes, b.dims):
                it = self.expr(ix, scope, None)
                if it is None:
                    continue
                it = self.settle(ix, it)
                ib = T.base_of(it)
                if not (isinstance(ib, T.ElementaryType) and ib.is_integer):
                    self.error(ix, f"array index must be an integer, not {self._tname(it)}")
                    continue
                v = self.const_value(ix, scope)
                if isinstance(v, int) and not isinstance(v, bool) and not lo <= v <= hi:
                    self.error(ix, f"index {v} is outside the array bounds {lo}..{hi}")
            return b.elem
        if isinstance(e, A.Unary):
            if e.op == "NOT":
                t = self.expr(e.operand, scope, expected)
                if t is None:
                    return None
                if isinstance(t, LiteralType):
                    # `w AND NOT 16#0F`: the literal takes the bit-string type the context needs
                    if expected is not None and not isinstance(expected, LiteralType) and \
                            T.in_generic(expected, "ANY_BIT"):
                        return expected if self.assignable(expected, e.operand, t, what="operand of NOT") else None
                    self.error(e, "NOT needs a BOOL or bit-string operand, not an untyped number")
                    return None
                if not T.in_generic(t, "ANY_BIT"):
                    self.error(e, f"NOT needs a BOOL or bit-string operand, not {self._tname(t)}")
                    return None
                return t
            t = self.expr(e.operand, scope, expected)
            if t is None:
                return None
            if isinstance(t, LiteralType):
                return t
            b = T.base_of(t)
            if b is T.TIME:
                self.error(e, "unary '-' on a TIME does not compile in OpenPLC (its C code is rejected): "
                              "write T#0s - ...")
                return None
            if not (isinstance(b, T.ElementaryType) and (b.kind in ("sint", "real"))):
                self.error(e, f"unary '-' needs a signed integer or a REAL, not {self._tname(t)}")
                return None
            return t
        if isinstance(e, A.Binary):
            return self._binary(e, scope, expected)
        if isinstance(e, A.Call):
            return self.call(e, scope, expected)
        self.error(e, "unsupported expression")
        return None

    def _literal(self, e: A.Literal, expected: Optional[T.Type]) -> Optional[T.Type]:
        if e.type_name is not None:
            tn = e.type_name
            if e.kind == "enum":
                et = self.types.get(tn)
                if not isinstance(et, T.EnumType) or e.value not in et.values:
                    if tn in self.types and isinstance(self.types[tn], T.EnumType):
                        self.error(e, f"'{e.value}' is not a value of '{self.types[tn].name}'")
                    else:
                        self.error(e, f"unknown enumerated type '{tn}'")
                    return None
                return et
            t = T.ELEMENTARY.get(tn)
            if t is None or not isinstance(t, T.ElementaryType):
                self.error(e, f"'{tn}#' is not an elementary type prefix")
                return None
            if e.kind == "bool":
                if t is not T.BOOL:
                    self.error(e, f"{tn}#{'TRUE' if e.value else 'FALSE'}: TRUE/FALSE are BOOL")
                    return None
                return T.BOOL
            if t is T.BOOL:
                if e.kind == "int" and e.value in (0, 1) and e.text.upper() in ("BOOL#0", "BOOL#1"):
                    e.value = bool(e.value)
                    e.kind = "bool"
                    return T.BOOL
                self.error(e, f"BOOL# takes 0, 1, TRUE or FALSE, not {e.value}")
                return None
            if e.kind == "int":
                if t.kind == "bits" and e.text[len(tn) + 1:len(tn) + 2] in "+-":
                    self.error(e, f"a {tn} literal has no sign")
                    return None
                if t.is_integer or t.kind == "bits":
                    if not t.min <= e.value <= t.max:
                        self.error(e, f"{e.value} does not fit in {t.name} ({t.min}..{t.max})")
                        return None
                    return t
                if t.is_real:
                    self.error(e, f"'{e.text}': a {tn} literal needs a decimal point (e.g. {tn}#{e.value}.0)")
                    return None
            if e.kind == "real" and t.is_real:
                if t is T.LREAL and not self._single_precision_reads(e):
                    return None
                return t
            self.error(e, f"'{e.text}' is not a valid {tn} literal")
            return None
        if e.kind == "bool":
            return T.BOOL
        if e.kind == "time":
            return T.TIME
        if e.kind == "date":
            return T.DATE
        if e.kind == "tod":
            return T.TOD
        if e.kind == "dt":
            return T.DT
        if e.kind == "string":
            if len(e.value) > 126:
                self.error(e, "string literal longer than 126 characters (OpenPLC's STRING limit)")
                return None
            if _has_dollar_l(e.text):
                # iec2c turns $L into a raw line feed inside the C string: g++ stops on it
                self.error(e, "'$L' in a string does not build in OpenPLC (its compiler writes a raw line "
                              "break into the C code): write '$N' for a new line")
                return None
            return T.STRING
        if e.kind == "wstring":
            self.error(e, "WSTRING literals are not supported by OpenPLC's compiler; use '...'")
            return None
        if e.kind == "int":
            return INT_LIT
        if e.kind == "real":
            return REAL_LIT
        return None

    def _name(self, e: A.Name, scope: _Scope, expected: Optional[T.Type]) -> Optional[T.Type]:
        sym = scope.names.get(e.key)
        if isinstance(sym, A.VarDecl):
            e.sym = sym
            return sym.ty
        values = self.enum_values.get(e.key)
        if values:
            if len(values) == 1:
                e.sym = values[0]
                return values[0].ty
            # matiec does not let the context choose ("Ambiguous enumerate value"), even where
            # only one of the types fits (`v := OPEN` with v an E_Valve)
            mine = next((v for v in values if expected is not None and v.ty is T.base_of(expected)), values[0])
            self.error(e, f"'{e.name}' is a value of several enumerated types; qualify it (e.g. "
                          f"{mine.ty.name}#{e.name}): OpenPLC's compiler refuses it unqualified")
            return None
        if e.key.startswith("%") and A.address_without_size(e.key):
            self.error(e, short_address_message(e.name, in_statement=True))
            return None
        if e.key.startswith("%"):
            named = self.named_at.get(scope.pou.key, {}).get(e.key) if scope.pou is not None else None
            if isinstance(named, A.VarDecl):
                self.error(e, f"{e.name} is '{named.name}' in this POU: write its name (OpenPLC's compiler makes C "
                              f"that has no {e.name} here, only '{named.name}')")
                return None
            self.error(e, f"{e.name} is not declared in this POU: OpenPLC's compiler needs a located "
                          f"declaration first (e.g. VAR AT {e.name} : BOOL; END_VAR)")
            return None
        if e.key == "EN":
            self.error(e, "EN cannot be read inside a function or function block (OpenPLC's compiler has no "
                          "variable EN; it only decides whether the call runs)")
            return None
        if e.key in self.globals:
            self.error(e, f"'{e.name}' is a global variable: declare it in VAR_EXTERNAL to use it here")
            return None
        if e.key in self.pous or e.key in FUNCTIONS:
            self.error(e, f"'{e.name}' is a POU, not a variable")
            return None
        known = [getattr(v, "name", "") for v in scope.names.values()] + [g.name for g in self.globals.values()]
        self.error(e, word_address_hint(e.name) or f"undeclared identifier '{e.name}'{did_you_mean(e.name, known)}")
        return None

    _CMP = {"=", "<>", "<", ">", "<=", ">="}

    def _binary(self, e: A.Binary, scope: _Scope, expected: Optional[T.Type]) -> Optional[T.Type]:
        op = e.op
        hint = None if op in self._CMP else expected
        if op == "**":
            # iec2c writes `a ** b` as __expt(a, b), which OpenPLC's C library (core/lib) lacks:
            # g++ fails on every program using it; EXPT(a, b) is EXPT__REAL__REAL__REAL there
            self.error(e, "'**' does not build in OpenPLC (the C it becomes calls __expt, which OpenPLC's "
                          "library lacks): write EXPT(base, exponent)")
            return None
        lt = self.expr(e.left, scope, hint)
        rt = self.expr(e.right, scope, hint)
        if lt is None or rt is None:
            return None
        # an untyped literal takes the other side's type
        if isinstance(lt, LiteralType) and isinstance(rt, LiteralType):
            if op in self._CMP:
                kind = "real" if "real" in (lt.kind, rt.kind) else "int"
                common = DEFAULT_REAL if kind == "real" else DEFAULT_INT
                self.settle(e.left, lt, common)
                self.settle(e.right, rt, common)
                e.operand_ty = common
                return T.BOOL
            if op in ("AND", "OR", "XOR"):
                self.error(e, f"'{op}' needs BOOL or bit-string operands, not untyped numbers")
                return None
            if op == "/" and lt.kind == rt.kind == "int" and literal_value(e.right) == 0:
                self.error(e, _ZERO_DIVISION)
                return None
            return REAL_LIT if "real" in (lt.kind, rt.kind) else INT_LIT
        if isinstance(lt, LiteralType):
            lt = self._adopt(e.left, lt, rt, op)
            if lt is None:
                return None
        elif isinstance(rt, LiteralType):
            rt = self._adopt(e.right, rt, lt, op)
            if rt is None:
                return None
        lb, rb = T.base_of(lt), T.base_of(rt)
        if op in self._CMP:
            if not self._same(lt, rt):
                self.error(e, f"cannot compare {self._tname(lt)} with {self._tname(rt)} "
                              f"(convert one side, e.g. {lb.name}_TO_{rb.name})")
                return None
            if op not in ("=", "<>") and isinstance(lb, (T.EnumType, T.ArrayType, T.StructType, T.FBType)):
                self.error(e, f"'{op}' is not defined for {self._tname(lt)}")
                return None
            if isinstance(lb, (T.ArrayType, T.StructType, T.FBType)):
                self.error(e, f"cannot compare {self._tname(lt)} values")
                return None
            e.operand_ty = lt
            return T.BOOL
        if op in ("AND", "OR", "XOR"):
            if not T.in_generic(lt, "ANY_BIT") or not T.in_generic(rt, "ANY_BIT"):
                bad = lt if not T.in_generic(lt, "ANY_BIT") else rt
                self.error(e, f"'{op}' needs BOOL or bit-string operands, not {self._tname(bad)}")
                return None
            if not self._same(lt, rt):
                self.error(e, f"'{op}' on different types {self._tname(lt)} and {self._tname(rt)}")
                return None
            e.operand_ty = lt
            return lt
        if op == "MOD":
            if not (T.in_generic(lt, "ANY_INT") and self._same(lt, rt)):
                self.error(e, f"MOD needs two integers of one type, not {self._tname(lt)} and {self._tname(rt)}")
                return None
            e.operand_ty = lt
            return lt
        # + - * /
        if isinstance(lb, T.ElementaryType) and isinstance(rb, T.ElementaryType):
            if lb.is_num and self._same(lt, rt):
                e.operand_ty = lt
                return lt if self._folds_within(e, lb) else None
            k = (lb.kind, op, rb.kind)
            time_rules = {
                ("time", "+", "time"): T.TIME, ("time", "-", "time"): T.TIME,
                ("tod", "+", "time"): T.TOD, ("dt", "+", "time"): T.DT,
                ("tod", "-", "time"): T.TOD, ("dt", "-", "time"): T.DT,
                ("date", "-", "date"): T.TIME, ("tod", "-", "tod"): T.TIME, ("dt", "-", "dt"): T.TIME,
            }
            if k in time_rules:
                e.operand_ty = lt
                return time_rules[k]
            if lb.kind == "time" and op in ("*", "/") and rb.is_num:
                e.operand_ty = rt
                return T.TIME
        self.error(e, f"'{op}' is not defined for {self._tname(lt)} and {self._tname(rt)}"
                      + ("" if self._same(lt, rt) else " (IEC has no implicit conversion: convert one side)"))
        return None

    def _folds_within(self, e: A.Binary, b: T.ElementaryType) -> bool:
        """OpenPLC's compiler folds an operation on literals (`INT#32767 + 1`) and refuses it
        when the value leaves the operation's type; it refuses an integer division by a literal
        zero whatever the dividend (`v / 0`)."""
        if e.op == "/" and b.is_integer and literal_value(e.right) == 0:     # a REAL one is infinite
            self.error(e, _ZERO_DIVISION)          # `v / 0` too: its constant divisor decides
            return False
        if literal_value(e.left) is None:
            return True
        v = literal_value(e)
        if v is None:
            return True
        if b.is_integer and not b.min <= v <= b.max:
            self.error(e, f"this constant expression is {v}, outside {b.name} ({b.min}..{b.max}): "
                          f"OpenPLC's compiler refuses it")
            return False
        if b.is_real and not abs(v) <= (T.REAL_MAX if b is T.REAL else sys.float_info.max):
            self.error(e, f"this constant expression overflows {b.name}: OpenPLC's compiler refuses it")
            return False
        return True

    def _adopt(self, lit_e: A.Expr, lit_t: LiteralType, other: T.Type, op: str) -> Optional[T.Type]:
        """An untyped literal operand takes the type of the other operand."""
        ob = T.base_of(other)
        if isinstance(ob, T.ElementaryType) and ob.kind == "time" and op in ("*", "/"):
            return self.settle(lit_e, lit_t, DEFAULT_REAL if lit_t.kind == "real" else DEFAULT_INT)
        if isinstance(other, T.SubrangeType):
            other = other.base      # arithmetic on a subrange value happens in its base type
        if not self.assignable(other, lit_e, lit_t, what=f"operand of '{op}'"):
            return None
        return lit_e.ty

    @staticmethod
    def _same(a: T.Type, b: T.Type) -> bool:
        return T.same_type(a, b) or (isinstance(T.base_of(a), T.EnumType) and T.base_of(a) is T.base_of(b))

    def settle(self, e: A.Expr, t: T.Type, target: Optional[T.Type] = None) -> T.Type:
        """Give an untyped literal expression its final type (default DINT / LREAL)."""
        if not isinstance(t, LiteralType):
            return t
        if target is None:
            target = DEFAULT_REAL if t.kind == "real" else DEFAULT_INT
        self._set_lit_type(e, target)
        return target

    def _single_precision_reads(self, e: A.Literal) -> bool:
        """OpenPLC's compiler reads every real literal with C's strtof (its constant folding
        picks strtof by mistake: `#if (real64_tX == float)` compares two undefined names), so
        an LREAL literal that single precision overflows (beyond 3.4E38) or underflows
        (nonzero below 1.2E-38) is refused: "Numerical value exceeds range for LREAL"."""
        v = abs(e.value)
        if v > _REAL_MAX_LITERAL or 0 < v < _REAL_MIN_NORMAL:
            self.error(e, f"{e.text or e.value}: OpenPLC's compiler reads real literals in single precision, "
                          f"so an LREAL literal must be 0 or within 1.2E-38..3.4E38 in size "
                          f"(compute a larger or smaller value, e.g. 1.0E20 * 1.0E20)")
            return False
        return True

    def _set_lit_type(self, e: A.Expr, target: T.Type) -> None:
        if isinstance(e, A.Literal) and e.kind == "real" and target is T.LREAL and e.type_name is None \
                and isinstance(e.ty, LiteralType):
            self._single_precision_reads(e)
        if isinstance(e.ty, LiteralType) or e.ty is None:
            e.ty = target
        if isinstance(e, A.Binary):
            e.operand_ty = target
            self._set_lit_type(e.left, target)
            self._set_lit_type(e.right, target)
        elif isinstance(e, A.Unary):
            self._set_lit_type(e.operand, target)
        elif isinstance(e, A.Literal) and e.kind == "int" and T.in_generic(target, "ANY_REAL"):
            e.value = float(e.value)

    def assignable(self, target: T.Type, e: A.Expr, t: T.Type, what: str = "assignment") -> bool:
        """Can a value of type `t` (expression `e`) be stored in `target`? Reports why not."""
        tb = T.base_of(target)
        if isinstance(t, LiteralType):
            v = self.const_value(e)
            if isinstance(tb, T.ElementaryType):
                if t.kind == "int" and (tb.is_integer or tb.kind == "bits"):
                    if v is not None and not (tb.min <= v <= tb.max):
                        self.error(e, f"{v} does not fit in {tb.name} ({tb.min}..{tb.max})")
                        return False
                    if isinstance(target, T.SubrangeType) and v is not None and not target.lo <= v <= target.hi:
                        self.error(e, f"{v} is outside the subrange {target.lo}..{target.hi} of '{target.name}'")
                        return False
                    self._set_lit_type(e, target)
                    return True
                if tb.is_real and t.kind == "real":
                    if tb is T.REAL and v is not None and abs(v) > T.REAL_MAX:
                        if isinstance(e, A.Literal):      # an LREAL literal cannot be as large either
                            self.error(e, f"{e.text or v} does not fit in REAL")
                        else:
                            self.error(e, f"{v} does not fit in REAL (use LREAL)")
                        return False
                    self._set_lit_type(e, target)
                    return True
                if tb.is_real:
                    self.error(e, f"type mismatch in {what}: {self._tname(target)} cannot take an integer "
                                  f"literal (OpenPLC's compiler has no implicit conversion): write {v}.0")
                    return False
                if tb is T.BOOL and t.kind == "int" and v in (0, 1):
                    self._set_lit_type(e, target)
                    if isinstance(e, A.Literal):
                        e.value = bool(e.value)
                        e.kind = "bool"
                    return True
            hint = ""
            if tb is T.TIME and t.kind == "int":     # an S7 timer's preset is a count of 1/10/100 ms
                hint = f": write a duration, e.g. T#{v if isinstance(v, int) and v >= 0 else 500}ms"
            self.error(e, f"type mismatch in {what}: {self._tname(target)} cannot take "
                          f"{'a real' if t.kind == 'real' else 'an integer'} literal{hint}")
            return False
        if isinstance(t, T.FBType) or isinstance(tb, T.FBType):
            self.error(e, f"type mismatch in {what}: function block instances cannot be assigned")
            return False
        if self._same(target, t):
            if isinstance(target, T.SubrangeType):
                v = self.const_value(e)
                if isinstance(v, int) and not target.lo <= v <= target.hi:
                    self.error(e, f"{v} is outside the subrange {target.lo}..{target.hi} of '{target.name}'")
                    return False
            return True
        if isinstance(tb, T.ArrayType) and isinstance(T.base_of(t), T.ArrayType) and \
                self._decl_types_match(tb, T.base_of(t)):
            return True
        self.error(e, f"type mismatch in {what}: expected {self._tname(target)}, got {self._tname(t)}"
                      + self._conversion_hint(t, target))
        return False

    @staticmethod
    def _conversion_hint(src: T.Type, dst: T.Type) -> str:
        s, d = T.base_of(src), T.base_of(dst)
        if isinstance(s, (T.ElementaryType, T.StringType)) and isinstance(d, (T.ElementaryType, T.StringType)):
            short = {T.TOD: "TOD", T.DT: "DT"}
            sn = "STRING" if isinstance(s, T.StringType) else short.get(s, s.name)
            dn = "STRING" if isinstance(d, T.StringType) else short.get(d, d.name)
            if f"{sn}_TO_{dn}" in FUNCTIONS:
                return f" (use {sn}_TO_{dn})"
        return ""


_ZERO_DIVISION = "division by a literal zero: OpenPLC's compiler refuses it"
_REAL_MAX_LITERAL = 3.4028235677973366e38     # above it, strtof rounds to infinity
_REAL_MIN_NORMAL = 1.1754943508222875e-38     # below it (nonzero), strtof reports an underflow


def literal_value(e: A.Expr) -> Optional[float | int]:
    """The value matiec's constant folding gives an expression of numeric literals (a sign,
    + - * / and parentheses over INTEGER and REAL literals, typed or not), else None. Names,
    CONSTANT variables included, are not folded: OpenPLC's compiler folds literals only."""
    if isinstance(e, A.Literal):
        return e.value if e.kind in ("int", "real") and not isinstance(e.value, bool) else None
    if isinstance(e, A.Unary) and e.op == "-":
        v = literal_value(e.operand)
        return None if v is None else -v
    if isinstance(e, A.Binary) and e.op in ("+", "-", "*", "/"):
        a, b = literal_value(e.left), literal_value(e.right)
        if a is None or b is None:
            return None
        return fold(e.op, a, b)
    return None


def negated_output_message(a: A.Arg) -> str:
    """`NOT Q => x` in a call: iec2c stops on it ("Internal compiler error in file
    function_call_param_iterator.cc"), for any block or function."""
    return (f"a negated output (NOT {a.name} => ...) stops OpenPLC's compiler with an internal error: "
            f"bind {a.name} to a variable, then negate that after the call")


def _has_dollar_l(text: str) -> bool:
    """Whether a string literal as written has the escape $L (not $$ followed by an L)."""
    i = 0
    while i < len(text) - 1:
        if text[i] == "$":
            if text[i + 1] in "lL":
                return True
            i += 2
            continue
        i += 1
    return False
