"""ST checker, declarations and types: names, data types, constant expressions, initial values,
variable blocks, located variables and VAR_EXTERNAL, as matiec checks them."""
from __future__ import annotations

from typing import Any, Optional

from plclab.errors import Diagnostic
from plclab.frontend import ast as A
from plclab.frontend.check_base import (
    AREA_LIMIT, CheckerBase, _is_signed_integer, _library_variable_message, LOCATED_AREAS,
    LOCATED_TYPES, MAX_TYPE_NESTING, RESERVED_WORDS, _Scope, fold, short_address_message
)
from plclab.frontend.check_limits import MAX_DATA_BYTES, mib, type_bytes
from plclab.frontend.checked import EnumValue
from plclab.frontend.stdsigs import FUNCTION_BLOCKS, LIBRARY_VARIABLES, RESERVED_NAMES
from plclab.frontend.suggest import did_you_mean, foreign_type
from plclab.iec import types as T


class DeclarationChecks(CheckerBase):
    """Declarations and data types of the unit and of each POU."""

    def _declare_name(self, node: Any, name: str, what: str) -> bool:
        key = name.upper()
        if key in RESERVED_NAMES:
            self.error(node, f"'{name}' is the name of a standard function or function block; "
                             f"it cannot name a {what}")
            return False
        if key in RESERVED_WORDS:
            self.error(node, f"'{name}' is a reserved word of OpenPLC's compiler; it cannot name a {what}")
            return False
        if key in LIBRARY_VARIABLES:
            self.error(node, _library_variable_message(name, what))
            return False
        if key in T.ELEMENTARY or key in T.GENERICS:
            self.error(node, f"'{name}' is a type name; it cannot name a {what}")
            return False
        if key in self.type_decls or key in self.pous:
            self.error(node, f"'{name}' is already declared")
            return False
        return True

    # ------------------------------------------------------------------ types
    def _resolve_type_decl(self, td: A.TypeDecl) -> Optional[T.Type]:
        if td.key in self.types:
            return self.types[td.key]
        if td.key in self._unresolvable:       # reported once, where it went wrong
            return None
        if td.key in self._resolving:
            self.error(td, f"type '{td.name}' is defined in terms of itself")
            return None
        if len(self._resolving) >= MAX_TYPE_NESTING:
            self.error(td, f"type declarations nested more than {MAX_TYPE_NESTING} levels deep "
                           f"('{td.name}' is reached through a chain of that many other types)")
            return None
        self._resolving.add(td.key)
        try:
            ty = self._make_type(td.type_ref, td.name, td.init)
        finally:
            self._resolving.discard(td.key)
        if ty is not None:
            self.types[td.key] = ty
            td.ty = ty
        else:
            self._unresolvable.add(td.key)
        return ty

    def resolve_type(self, ref: A.TypeRef, scope: Optional[_Scope] = None) -> Optional[T.Type]:
        """The Type a declaration names (anonymous types get a generated name). `scope` gives
        the constants an inline array bound or string length may use (`ARRAY[0..N-1]`)."""
        return self._make_type(ref, None, None, scope)

    def _make_type(self, ref: A.TypeRef, name: Optional[str], init: Any,
                   scope: Optional[_Scope] = None) -> Optional[T.Type]:
        if isinstance(ref, A.NamedType):
            base = self._lookup_type(ref)
            if base is None:
                return None
            if name is None:
                return base
            if isinstance(base, T.FBType):
                self.error(ref, f"a TYPE cannot be a function block ('{ref.name}')")
                return None
            depth, b = 1, base
            while isinstance(b, T.AliasType):
                depth, b = depth + 1, b.base
            if depth > MAX_TYPE_NESTING:
                self.error(ref, f"type declarations nested more than {MAX_TYPE_NESTING} levels deep "
                                f"('{name}' is an alias of an alias ... {depth} times)")
                return None
            alias = T.AliasType(name, base, None)
            if init is not None:
                value = self._init_value(init, alias)
                alias = T.AliasType(name, base, value)
            return alias
        if isinstance(ref, A.StringTypeRef):
            if ref.wide:
                self.error(ref, "WSTRING is not supported by OpenPLC's compiler; use STRING")
                return None
            if ref.length is not None:
                # iec2c takes the declaration, then calls a variable of it "not declared in this
                # scope" where the body uses it (a TYPE of it: "invalid specification")
                self.error(ref, "STRING[n] does not work in OpenPLC's compiler (a variable declared so is "
                                "'not declared' where it is used): declare STRING (up to 126 characters)")
                return None
            st = T.StringType(name or "STRING", 126)
            if name and init is not None:
                return T.AliasType(name, st, self._init_value(init, st))
            return st if name is None else T.AliasType(name, st, None)
        if isinstance(ref, A.ArrayTypeRef):
            dims = []
            for lo_e, hi_e in ref.ranges:
                bad = next((b for b in (lo_e, hi_e) if not (_is_signed_integer(b) or isinstance(b, A.Name))), None)
                if bad is not None:
                    self.error(bad, "an array bound must be an integer literal or the name of a constant "
                                    "(OpenPLC's compiler accepts no expression here)")
                    return None
                local = next((b for b in (lo_e, hi_e) if isinstance(b, A.Name) and scope is not None and
                              isinstance(scope.names.get(b.key), A.VarDecl) and
                              scope.names[b.key].section != "VAR_EXTERNAL"), None)
                if local is not None:
                    # matiec folds a global constant (VAR_EXTERNAL CONSTANT) into a bound, but
                    # not the POU's own VAR CONSTANT: "Subrange upper limit is not a constant value"
                    self.error(local, f"'{local.name}' is a constant of this POU: OpenPLC's compiler takes as an "
                                      f"array bound a literal or a global constant (VAR_GLOBAL CONSTANT, "
                                      f"here VAR_EXTERNAL CONSTANT), not a local one")
                    return None
                lo = self.const_int(lo_e, "an array bound", scope)
                hi = self.const_int(hi_e, "an array bound", scope)
                if lo is None or hi is None:
                    return None
                if hi < lo:
                    self.error(lo_e, f"empty array range {lo}..{hi}")
                    return None
                dims.append((lo, hi))
            if not isinstance(ref.elem, A.NamedType) and not (
                    isinstance(ref.elem, A.StringTypeRef) and ref.elem.length is None):
                self.error(ref.elem, "an array element type must be a type name (declare the inner "
                                     "ARRAY, STRING[n], enum or subrange as a TYPE first)")
                return None
            elem = self._make_type(ref.elem, None, None)
            if elem is None:
                return None
            if isinstance(elem, T.FBType):
                self.error(ref.elem, f"arrays of function block instances ({ref.elem.name}) are not "
                                     f"supported by OpenPLC's compiler")
                return None
            if isinstance(T.base_of(elem), T.ArrayType):
                # iec2c's C for a variable of it starts from the empty initialiser {{,}}: g++ stops
                self.error(ref.elem, f"an array of arrays ({ref.elem.name} is an array) does not build in OpenPLC: "
                                     f"use one array of several dimensions, e.g. ARRAY[1..2, 1..3] OF INT")
                return None
            size = 1
            for lo, hi in dims:
                size *= hi - lo + 1
            if size > 1_000_000:
                self.error(ref, f"array of {size} elements is too large")
                return None
            arr = T.ArrayType(name or f"ARRAY[{','.join(f'{a}..{b}' for a, b in dims)}] OF {elem.name}",
                              elem, tuple(dims))
            if self._type_too_large(ref, arr, f"{arr.name} ({size} elements of {mib(type_bytes(elem, self.size_memo))})"):
                return None
            if init is not None and self._value_too_large(ref, arr, f"the initial value of {arr.name}"):
                return None
            if init is not None:
                arr = T.ArrayType(arr.name, elem, tuple(dims), self._init_value(init, arr))
            return arr
        if isinstance(ref, A.EnumTypeRef):
            if name is None:
                # iec2c: "C code generator does not currently support anonymous enumerated
                # data types" (a variable), an internal compiler error (a structure's field)
                self.error(ref, "an enumerated type must be declared by name in a TYPE block (e.g. TYPE E_Mode : "
                                f"({', '.join(v for v, _l, _c in ref.values[:3])}); END_TYPE): OpenPLC's compiler "
                                "cannot make C for one written inline")
                return None
            seen = set()
            values = []
            for vname, line, col in ref.values:
                key = vname.upper()
                if key in seen:
                    self.diags.append(Diagnostic(ref.file, line, col, f"duplicate enumerated value '{vname}'"))
                    continue
                seen.add(key)
                values.append(key)
            enum = T.EnumType(name or "(" + ", ".join(values) + ")", tuple(values))
            for v in values:
                self.enum_values.setdefault(v, []).append(EnumValue(v, enum))
            if init is not None:
                if isinstance(init, A.Name) and init.key in values:
                    enum = T.EnumType(enum.name, enum.values, init.key)
                    for v in values:
                        self.enum_values[v][-1] = EnumValue(v, enum)
                else:
                    self.error(init, f"initial value of enumerated type '{enum.name}' must be one of its values")
            return enum
        if isinstance(ref, A.SubrangeTypeRef):
            base = self._lookup_type(ref.base)
            if base is None:
                return None
            if not (isinstance(base, T.ElementaryType) and base.is_integer):
                self.error(ref, f"a subrange needs an integer base type, not {base.name}")
                return None
            for bound in (ref.lo, ref.hi):
                if not _is_signed_integer(bound):
                    self.error(bound, "a subrange bound must be an integer literal")
                    return None
            lo = self.const_int(ref.lo, "a subrange bound")
            hi = self.const_int(ref.hi, "a subrange bound")
            if lo is None or hi is None:
                return None
            if lo > hi or lo < base.min or hi > base.max:
                self.error(ref, f"invalid subrange {lo}..{hi} of {base.name}")
                return None
            sub = T.SubrangeType(name or f"{base.name}({lo}..{hi})", base, lo, hi)
            if init is not None:
                v = self._init_value(init, sub)
                sub = T.SubrangeType(sub.name, base, lo, hi, v)
            return sub
        if isinstance(ref, A.StructTypeRef):
            fields: dict[str, tuple[T.Type, Any]] = {}
            names: dict[str, str] = {}
            for f in ref.fields:
                if isinstance(f.type_ref, A.StringTypeRef) and f.type_ref.length is not None:
                    self.error(f.type_ref, "STRING[n] is not allowed in a STRUCT by OpenPLC's compiler; "
                                           "use STRING")
                    continue
                if f.key in fields:
                    self.error(f, f"duplicate field '{f.name}'")
                    continue
                ft = self._make_type(f.type_ref, None, None)
                if ft is None:
                    continue
                if isinstance(ft, T.FBType):
                    self.error(f.type_ref, "a STRUCT field cannot be a function block instance")
                    continue
                if f.init is not None and self._value_too_large(f, ft, f"the initial value of field '{f.name}'"):
                    continue
                fv = self._init_value(f.init, ft) if f.init is not None else None
                f.ty = ft
                fields[f.key] = (ft, fv)
                names[f.key] = f.name
            struct = T.StructType(name or "STRUCT", fields, names)
            if self._type_too_large(ref, struct, f"STRUCT {name or ''}".rstrip()):
                return None
            return struct
        self.error(ref, "unsupported type")
        return None

    def _lookup_type(self, ref: A.NamedType) -> Optional[T.Type]:
        key = ref.key
        if key in T.ELEMENTARY:
            return T.ELEMENTARY[key]
        if key in self.type_decls:
            return self._resolve_type_decl(self.type_decls[key])
        if key in self.fb_types:
            return self.fb_types[key]
        if key in FUNCTION_BLOCKS:
            return self.std_fb_type(key)
        if key in self.pous:
            self.error(ref, f"'{ref.name}' is a {self.pous[key].kind.lower().replace('_', ' ')}, not a type")
            return None
        if key in T.GENERICS:
            self.error(ref, f"generic type {ref.name} can only be used by standard functions")
            return None
        known = [*T.ELEMENTARY, *(d.name for d in self.type_decls.values()), *FUNCTION_BLOCKS,
                 *(p.name for p in self.pous.values() if p.kind == "FUNCTION_BLOCK")]
        self.error(ref, f"unknown type '{ref.name}'{foreign_type(ref.name) or did_you_mean(ref.name, known)}")
        return None

    _std_fb_cache: dict[str, T.FBType] = {}

    def std_fb_type(self, key: str) -> T.FBType:
        if key not in DeclarationChecks._std_fb_cache:
            DeclarationChecks._std_fb_cache[key] = T.FBType(key, FUNCTION_BLOCKS[key])
        return DeclarationChecks._std_fb_cache[key]

    # ------------------------------------------------------------------ declared memory (check_limits)
    def _type_too_large(self, node: Any, t: T.Type, what: str) -> bool:
        """Refuse a type whose one value is larger than the program may declare, before any
        value of it is made."""
        n = type_bytes(t, self.size_memo)
        if n <= MAX_DATA_BYTES:
            return False
        self.error(node, f"{what} takes {mib(n)} ({n} bytes), more than the {mib(MAX_DATA_BYTES)} a "
                         f"program may declare in all")
        self.memory_refused = True
        return True

    def _value_too_large(self, node: Any, t: T.Type, what: str) -> bool:
        """Count a value the checker makes for a type's own initial value (a variable's is
        counted with the variable); refuse the one that takes the program past MAX_DATA_BYTES."""
        n = type_bytes(t, self.size_memo)
        if self.declared_bytes + n > MAX_DATA_BYTES:
            self.error(node, f"{what} takes {mib(n)}; with what is declared before it the program declares "
                             f"{mib(self.declared_bytes + n)}, more than the {mib(MAX_DATA_BYTES)} a program may declare")
            self.memory_refused = True
            return True
        self.declared_bytes += n
        return False

    def _declaration_too_large(self, d: A.VarDecl, t: T.Type) -> bool:
        """Count a variable's data (FB instances are counted later, per instance); refuse the one
        that takes the declarations past MAX_DATA_BYTES, before its initial value is made."""
        if isinstance(t, T.FBType):
            return False
        n = type_bytes(t, self.size_memo)
        if self.declared_bytes + n > MAX_DATA_BYTES:
            self.error(d, f"'{d.name}' ({t.name}) takes {mib(n)}; with the variables declared before it the "
                          f"program declares {mib(self.declared_bytes + n)}, more than the "
                          f"{mib(MAX_DATA_BYTES)} a program may declare")
            self.memory_refused = True
            return True
        self.declared_bytes += n
        return False

    # ------------------------------------------------------------------ constants and initial values
    def const_int(self, e: A.Expr, what: str, scope: Optional[_Scope] = None) -> Optional[int]:
        v = self.const_value(e, scope)
        if v is None or isinstance(v, bool) or not isinstance(v, int):
            self.error(e, f"{what} must be a constant integer expression")
            return None
        return v

    def const_value(self, e: A.Expr, scope: Optional[_Scope] = None) -> Any:
        """Value of a constant expression (literals, CONSTANT variables, enum values), else None."""
        if isinstance(e, A.Literal):
            return e.value
        if isinstance(e, A.Name):
            sym = e.sym
            if sym is None and scope is not None:
                sym = scope.names.get(e.key)
            if sym is None:
                sym = self.globals.get(e.key)
                if sym is not None and not sym.constant:
                    sym = None
            if isinstance(sym, EnumValue):
                return sym.name
            if isinstance(sym, A.VarDecl) and sym.constant:
                if sym.global_decl is not None:
                    sym = sym.global_decl
                return sym.init_value
            if sym is None and e.key in self.enum_values and len(self.enum_values[e.key]) == 1:
                return e.key
            return None
        if isinstance(e, A.Unary):
            v = self.const_value(e.operand, scope)
            if v is None:
                return None
            if e.op == "-" and isinstance(v, (int, float)) and not isinstance(v, bool):
                return -v
            if e.op == "NOT" and isinstance(v, bool):
                return not v
            return None
        if isinstance(e, A.Call) and e.std is not None and e.args:
            return None
        if isinstance(e, A.Binary):
            a = self.const_value(e.left, scope)
            b = self.const_value(e.right, scope)
            if a is None or b is None or isinstance(a, (str, bool)) or isinstance(b, (str, bool)):
                if isinstance(a, bool) and isinstance(b, bool):
                    return {"AND": a and b, "OR": a or b, "XOR": a != b, "=": a == b, "<>": a != b}.get(e.op)
                return None
            return fold(e.op, a, b)
        return None

    def _init_value(self, init: Any, ty: T.Type, scope: Optional[_Scope] = None, nested: bool = False) -> Any:
        """Check an initializer against `ty` and return the runtime value (None if invalid).
        `nested`: an element of an array, structure or block instance initialiser."""
        base = T.base_of(ty)
        if isinstance(init, A.ArrayInit):
            if not isinstance(base, T.ArrayType):
                self.error(init, f"an array initializer needs an ARRAY, not {ty.name}")
                return None
            values: list[Any] = []
            count = sum(1 if n_e is None else n_e.value for n_e, _item in init.items)
            if count > base.size:
                self.error(init, f"{count} initial values for an array of {base.size} elements")
                return None
            for count_e, item in init.items:
                n = 1
                if count_e is not None:
                    n = count_e.value
                if item is None:
                    v = T.default_value(base.elem)
                elif isinstance(item, A.StructInit):
                    self.error(item, "OpenPLC's compiler refuses a structure value inside an array initialiser "
                                     "(\"Initialization element identifier ... is not declared\"): give the "
                                     "structure type's fields their initial values, or set them in the program")
                    return None
                else:
                    v = self._init_value(item, base.elem, scope, nested=True)
                    if v is None:
                        return None
                values.extend(T.copy_value(v) for _ in range(n))
            values.extend(T.default_value(base.elem) for _ in range(base.size - len(values)))
            return values
        if isinstance(init, A.StructInit):
            if not isinstance(base, T.StructType):
                self.error(init, f"a structure initializer needs a STRUCT, not {ty.name}")
                return None
            value = T.default_value(base)
            for fname, line, col, fval in init.fields:
                key = fname.upper()
                if key not in base.fields:
                    self.diags.append(Diagnostic(init.file, line, col, f"'{ty.name}' has no field '{fname}'"))
                    return None
                if isinstance(fval, A.ArrayInit):
                    self.diags.append(Diagnostic(init.file, line, col, (
                        f"OpenPLC's compiler refuses an array value inside a structure initialiser (field "
                        f"'{fname}'): give it its initial value in the STRUCT's declaration, or set it in the program")))
                    return None
                probe = _field_matiec_checks(base, key)
                if probe != key and not _literal_fits(fval, base.fields[probe][0]):
                    shown = base.field_names.get(probe, probe)
                    self.diags.append(Diagnostic(init.file, line, col, (
                        f"OpenPLC's compiler checks this value against field '{shown}' instead of '{fname}' "
                        f"(it takes the first field declared whose name sorts at or after '{fname}'), and refuses "
                        f"it: declare '{fname}' before '{shown}' in '{ty.name}', or set it in the program")))
                    return None
                v = self._init_value(fval, base.fields[key][0], scope, nested=True)
                if v is None:
                    return None
                setattr(value, key, v)
            return value
        if not isinstance(init, A.Expr):
            return None
        if isinstance(base, (T.ArrayType, T.StructType)):
            self.error(init, f"'{ty.name}' needs a {'[...]' if isinstance(base, T.ArrayType) else '(field := ...)'} initializer")
            return None
        sc = scope or _Scope(None, {})
        et = self.expr(init, sc, ty)
        if et is None:
            return None
        if not self.assignable(ty, init, et):
            return None
        v = self.const_value(init, scope)
        if v is None or not self._is_literal(init, v):
            self.error(init, _not_a_literal(init))
            return None
        if nested and isinstance(base, T.EnumType):
            # enum_declaration_check.cc meets an enumerated value with no enumerated type being
            # declared around it and stops: "Internal compiler error ... line 145"
            self.error(init, "OpenPLC's compiler stops with an internal error on an enumerated value inside an "
                             "array, structure or block initialiser: give the value in the program instead")
            return None
        return self._normalise(v, ty, init)

    @staticmethod
    def _is_literal(init: A.Expr, value: Any) -> bool:
        """OpenPLC's compiler takes a literal as an initial value (`5`, `-2`, `SINT#-2`,
        `T#1s`, `'text'`, an enumerated value), not an expression, a parenthesis or a name."""
        if isinstance(init, A.Literal):
            return not init.parenthesized
        return isinstance(init, A.Name) and not isinstance(init.sym, A.VarDecl) and isinstance(value, str)

    def _normalise(self, v: Any, ty: T.Type, node: Any) -> Any:
        if isinstance(ty, T.SubrangeType) and isinstance(v, int) and not (ty.lo <= v <= ty.hi):
            self.error(node, f"value {v} outside the subrange {ty.lo}..{ty.hi} of '{ty.name}'")
            return None
        base = T.base_of(ty)
        if isinstance(base, T.ElementaryType) and base.kind == "real":
            return T.to_f32(float(v)) if base is T.REAL else float(v)
        if isinstance(base, T.StringType) and isinstance(v, str):
            return v[:base.length]
        return v

    # ------------------------------------------------------------------ declarations
    def _check_block_rules(self, block: A.VarBlock, pou: Optional[A.PouDecl]) -> None:
        quals = block.qualifiers
        for q in set(quals):
            if quals.count(q) > 1:
                self.error(block, f"{q} given twice")
        if "RETAIN" in quals and "NON_RETAIN" in quals:
            self.error(block, "RETAIN and NON_RETAIN exclude each other")
        if "CONSTANT" in quals and ("RETAIN" in quals or "NON_RETAIN" in quals):
            self.error(block, "a CONSTANT block cannot be RETAIN or NON_RETAIN")
        sec = block.section
        allowed: set[str] = set()
        if sec == "VAR":
            allowed = {"CONSTANT"} if pou is not None and pou.kind == "FUNCTION" else {"CONSTANT", "RETAIN", "NON_RETAIN"}
        elif sec == "VAR_GLOBAL":
            allowed = {"CONSTANT", "RETAIN"}
        elif sec in ("VAR_INPUT", "VAR_OUTPUT"):
            allowed = {"RETAIN", "NON_RETAIN"}
        elif sec == "VAR_EXTERNAL":
            allowed = {"CONSTANT"}
        for q in quals:
            if q not in allowed:
                self.error(block, f"{q} is not allowed on {sec}")
        if not block.decls:
            self.error(block, f"empty {sec} block: OpenPLC's compiler needs at least one declaration")
        located = [d for d in block.decls if d.location is not None]
        if located and len(located) != len(block.decls) and sec != "VAR_GLOBAL":
            plain = next(d for d in block.decls if d.location is None)
            first = located[0]
            bad = plain if plain.line > first.line or (plain.line == first.line and plain.col > first.col) else first
            self.error(bad, "a VAR block cannot mix located (AT %...) and non-located declarations "
                            "(OpenPLC's compiler rejects it): put them in separate blocks")

    def _declare_var(self, d: A.VarDecl, names: dict[str, Any], pou: Optional[A.PouDecl]) -> None:
        if d.location is not None:
            self._check_location(d, pou)
            if pou is not None and not d.name:
                # an unnamed one: the body may then read the address itself (matiec's C names
                # its member __IX0_0); for a named one that member does not exist (g++ fails)
                names.setdefault(d.location.key, d)
            elif pou is not None:
                self.named_at.setdefault(pou.key, {}).setdefault(d.location.key, d)
        if not d.name:
            d.ty = self.resolve_type(d.type_ref)
            if isinstance(d.ty, T.FBType):   # already reported by _check_location
                return
            if d.ty is not None and d.init is not None:
                d.init_value = self._init_value(d.init, d.ty)
            elif d.ty is not None:
                d.init_value = T.default_value(d.ty)
            names[f"%{id(d)}"] = d
            return
        if d.key in RESERVED_NAMES:
            self.error(d, f"'{d.name}' is the name of a standard function or function block; "
                          f"it cannot name a variable")
            # still declared below, so its uses do not add a cascade of errors
        if d.key in RESERVED_WORDS:
            self.error(d, f"'{d.name}' is a reserved word of OpenPLC's compiler; it cannot name a variable")
            # still declared below, so its uses do not add a cascade of "undeclared" errors
        if d.key in T.ELEMENTARY:
            self.error(d, f"'{d.name}' is a type name; it cannot name a variable")
            return
        if d.key in names:
            self.error(d, f"'{d.name}' is already declared")
            return
        if d.key in self.type_decls or (d.key in self.pous and (pou is None or self.pous[d.key] is not pou)):
            self.error(d, f"'{d.name}' is already the name of a type or POU")
            return
        names[d.key] = d
        if d.section == "VAR_EXTERNAL":
            self._check_external(d)
            return
        ty = self.resolve_type(d.type_ref, _Scope(pou, names))
        d.ty = ty
        if ty is None:
            return
        if d.edge is not None and (d.section != "VAR_INPUT" or T.base_of(ty) is not T.BOOL
                                   or pou is None or pou.kind != "FUNCTION_BLOCK"):
            self.error(d, f"{d.edge} is only allowed on a BOOL VAR_INPUT of a function block")
        elif d.edge is not None:
            # matiec accepts the qualifier but its C generator declares a plain BOOL: on
            # OpenPLC the input would see levels, not edges. Stricter than matiec on purpose.
            self.error(d, f"{d.edge} compiles in OpenPLC but has no effect there (the input behaves as "
                          f"a plain BOOL); use an {'R_TRIG' if d.edge == 'R_EDGE' else 'F_TRIG'} instance")
        if isinstance(ty, T.FBType):
            if pou is not None and pou.kind == "FUNCTION":
                self.error(d, "a FUNCTION cannot hold function block instances")
            if d.section in ("VAR_TEMP",):
                self.error(d, "function block instances cannot be VAR_TEMP")
            if d.init is not None:
                self._fb_init(d, ty)
            if ty.pou is pou and pou is not None:
                self.error(d, f"function block '{pou.name}' cannot contain an instance of itself")
            d.init_value = None
            return
        if (pou is not None and pou.kind == "FUNCTION" and d.section == "VAR_INPUT"
                and isinstance(T.base_of(ty), (T.ArrayType, T.StructType))):
            self.error(d, "an ARRAY or STRUCT passed by value to a FUNCTION does not compile in OpenPLC "
                          "(its C code is rejected); use a FUNCTION_BLOCK with VAR_IN_OUT")
        if d.section in ("VAR_IN_OUT", "VAR_TEMP") and d.init is not None:    # a STRING's neither (iec2c)
            self.error(d.init, f"a {d.section} cannot have an initial value in OpenPLC's compiler")
        if self._declaration_too_large(d, ty):
            return
        if d.init is not None:
            d.init_value = self._init_value(d.init, ty, _Scope(pou, names))
            if d.init_value is None:
                d.init_value = T.default_value(ty)
        else:
            d.init_value = T.default_value(ty)

    def _fb_init(self, d: A.VarDecl, fb: T.FBType) -> None:
        """`t : TON := (PT := T#1s);` sets inputs of the instance before its first call."""
        if not isinstance(d.init, A.StructInit):
            self.error(d.init, "a function block instance is initialised with (name := value, ...)")
            return
        params, _order = self._fb_params(fb)
        values = {}
        for fname, line, col, fval in d.init.fields:
            p = params.get(fname.upper())
            if p is None:
                self.diags.append(Diagnostic(d.file, line, col, f"function block {fb.name} has no input '{fname}'"))
                continue
            v = self._init_value(fval, p[1], nested=True)
            if v is not None:
                values[fname.upper()] = v
        d.fb_init = values

    def _check_location(self, d: A.VarDecl, pou: Optional[A.PouDecl]) -> None:
        loc = d.location
        group = d.group_size
        if group > 1:
            self.error(d, "only one variable can be located at an address")
        if pou is not None and pou.kind != "PROGRAM":
            self.error(loc, f"located variables (AT {loc.text}) are only allowed in a PROGRAM or VAR_GLOBAL")
            return
        if d.section not in ("VAR", "VAR_GLOBAL"):
            self.error(loc, f"located variables are not allowed in {d.section}")
            return
        area = loc.area + loc.size
        if loc.written_without_size:
            self.error(loc, short_address_message(loc.text))
            return
        if area not in LOCATED_AREAS:
            self.error(loc, f"{loc.text} is outside OpenPLC's located areas "
                            f"(%IX, %QX, %IW, %QW, %MW, %MD, %ML)")
            return
        if loc.size == "X":
            if len(loc.parts) != 2:
                self.error(loc, f"a bit address needs byte and bit: e.g. %{loc.area}X{loc.parts[0]}.0")
                return
            byte, bit = loc.parts
            if bit > 7:
                self.error(loc, f"bit number {bit} in {loc.text} is above 7 (a byte has bits 0..7)")
                return
            if byte > AREA_LIMIT["X"]:
                self.error(loc, f"{loc.text} is outside OpenPLC's buffers (byte 0..99)")
                return
        else:
            if len(loc.parts) != 1:
                self.error(loc, f"{loc.text}: a word address has one number, e.g. %{area}4")
                return
            if loc.parts[0] > AREA_LIMIT[loc.size]:
                self.error(loc, f"{loc.text} is outside OpenPLC's buffers (0..1023)")
                return
        ty = self.resolve_type(d.type_ref)
        base = T.base_of(ty) if ty is not None else None
        if base is not None and (not isinstance(base, T.ElementaryType) or base.name not in LOCATED_TYPES[loc.size]):
            self.error(d.type_ref, f"a variable at {loc.text} must be "
                                   f"{' or '.join(sorted(LOCATED_TYPES[loc.size]))}, not {ty.name}")

    def _check_external(self, d: A.VarDecl) -> None:
        if d.group_size > 1:
            self.error(d, "a VAR_EXTERNAL declaration names one variable ('A, B : BOOL' is rejected "
                          "by OpenPLC's compiler); declare each on its own line")
        if d.init is not None:
            self.error(d.init, "a VAR_EXTERNAL cannot have an initial value")
        ty = self.resolve_type(d.type_ref)       # refuses STRING[n], here as anywhere
        d.ty = ty
        g = self.globals.get(d.key)
        if g is None:
            if self.unit.configs or self.unit.gvls:
                self.error(d, f"VAR_EXTERNAL '{d.name}' has no matching VAR_GLOBAL")
            d.init_value = T.default_value(ty) if ty is not None and not isinstance(ty, T.FBType) else None
            return
        d.global_decl = g
        if ty is not None and g.ty is not None and not self._decl_types_match(ty, g.ty):
            self.error(d.type_ref, f"VAR_EXTERNAL '{d.name}' is {ty.name} but the VAR_GLOBAL is {g.ty.name}")
        if g.constant and not d.constant:
            self.error(d, f"'{d.name}' is a CONSTANT global: declare it VAR_EXTERNAL CONSTANT")
        d.init_value = g.init_value

    @staticmethod
    def _decl_types_match(a: T.Type, b: T.Type) -> bool:
        if a is b:
            return True
        if isinstance(a, T.StringType) and isinstance(b, T.StringType):
            return a.length == b.length
        if isinstance(a, T.ArrayType) and isinstance(b, T.ArrayType):
            return a.dims == b.dims and DeclarationChecks._decl_types_match(a.elem, b.elem)
        return False

    def _scope_for(self, pou: A.PouDecl) -> dict[str, A.VarDecl]:
        """The global scope whose names cover the POU's VAR_EXTERNALs (the first one if none
        does: the missing names are then reported)."""
        if len(self.global_scopes) == 1:
            return self.global_scopes[0]
        wanted = {d.key for d in pou.decls if d.section == "VAR_EXTERNAL"}
        best = max(self.global_scopes, key=lambda g: len(wanted & g.keys()))
        return best

    def _check_pou_decls(self, pou: A.PouDecl) -> None:
        names: dict[str, Any] = {}
        if pou.kind == "FUNCTION":
            ret = pou.return_type
            if not (isinstance(ret, A.NamedType) or (isinstance(ret, A.StringTypeRef) and ret.length is None)):
                self.error(ret, "a FUNCTION's return type must be a type name (declare an ARRAY, STRING[n], "
                                "enumeration or subrange as a TYPE first)")
            pou.ret_ty = self.resolve_type(ret)
            if isinstance(pou.ret_ty, T.FBType):
                self.error(pou.return_type, "a FUNCTION cannot return a function block")
                pou.ret_ty = None
        after_constant = False
        for block in pou.blocks:
            self._check_block_rules(block, pou)
            sec = block.section
            if pou.kind == "FUNCTION" and sec == "VAR":
                if "CONSTANT" in block.qualifiers:
                    after_constant = True
                elif after_constant:
                    # iec2c takes a FUNCTION's VAR block after a VAR CONSTANT block as constant
                    # too: writing its variables is "Assignment to CONSTANT variables"
                    for d in block.decls:
                        d.constant_in_openplc = True
            if sec == "VAR_GLOBAL":
                self.error(block, "VAR_GLOBAL belongs in a CONFIGURATION or RESOURCE (or a GVL file), not in a POU")
                continue
            if pou.kind == "FUNCTION" and sec in ("VAR_EXTERNAL", "VAR_TEMP"):
                self.error(block, f"{sec} is not allowed in a FUNCTION")
            for d in block.decls:
                if pou.kind == "FUNCTION" and d.key == pou.key:
                    self.error(d, f"'{d.name}' is the function's own name (its return value)")
                    continue
                self._declare_var(d, names, pou)
        if not pou.blocks:
            self.error(pou, f"{pou.kind} '{pou.name}' declares no variables: OpenPLC's compiler needs at least one "
                            f"VAR block")
        if pou.kind == "FUNCTION" and pou.ret_ty is not None:
            ret = A.VarDecl(line=pou.line, col=pou.col, file=pou.file, name=pou.name,
                            type_ref=pou.return_type, section="RETURN")
            ret.ty = pou.ret_ty
            ret.init_value = None if self._declaration_too_large(ret, pou.ret_ty) else T.default_value(pou.ret_ty)
            names[pou.key] = ret
            pou.ret_decl = ret
        if pou.kind != "PROGRAM" and "ENO" not in names:
            # matiec adds EN and ENO to every function and FB; the body may read and write ENO
            # (a BOOL output, TRUE when the call starts). It is in `symbols`, not in `blocks`.
            eno = A.VarDecl(line=pou.line, col=pou.col, file=pou.file, name="ENO",
                            type_ref=A.NamedType(line=pou.line, col=pou.col, file=pou.file, name="BOOL"),
                            section="VAR_OUTPUT")
            eno.ty, eno.init_value = T.BOOL, True
            names["ENO"] = eno
            pou.eno_decl = eno
        pou.symbols = names


def _not_a_literal(init: A.Expr) -> str:
    """Why an initial value is refused, with the literal to write where there is one."""
    why = "an initial value must be a literal: OpenPLC's compiler takes no expression, parenthesis or name here"
    if isinstance(init, A.Unary) and init.op == "-" and isinstance(init.operand, A.Literal) \
            and init.operand.type_name and "#" in init.operand.text:
        prefix, digits = init.operand.text.split("#", 1)
        return f"{why} (write {prefix}#-{digits})"
    return why


def _field_matiec_checks(struct: T.StructType, key: str) -> str:
    """The field whose type matiec checks a structure initialiser's `key := value` against: the
    first one declared whose (upper-case) name is `key` or sorts after it. Found with an iec2c
    built from OpenPLC's fork: with `z : INT; a : REAL;`, `(a := 1.5)` is refused ("is set to
    value of incompatible datatype") and `(a := 1)` accepted, both checked against z."""
    return next((k for k in struct.fields if k >= key), key)


def _literal_fits(e: Any, ty: T.Type) -> bool:
    """Whether matiec would take the initial value `e` (a literal, an enumerated value or a
    nested initialiser) for a field of type `ty`."""
    b = T.base_of(ty)
    if isinstance(e, A.ArrayInit):
        return isinstance(b, T.ArrayType)
    if isinstance(e, A.StructInit):
        return isinstance(b, T.StructType)
    if isinstance(e, A.Name) or (isinstance(e, A.Literal) and e.kind == "enum"):
        value = e.key if isinstance(e, A.Name) else str(e.value).upper()
        return isinstance(b, T.EnumType) and value in b.values
    if not isinstance(e, A.Literal):
        return True                       # not an initial value matiec takes: refused elsewhere
    if not isinstance(b, T.ElementaryType):
        return False
    if e.type_name is not None:
        return e.type_name == b.name
    if e.kind == "int":
        return ((b.is_integer or b.kind == "bits") and b.min <= e.value <= b.max) or \
            (b is T.BOOL and e.value in (0, 1))
    if e.kind == "real":
        return b.is_real
    if e.kind == "bool":
        return b is T.BOOL
    if e.kind in ("time", "date", "tod", "dt"):
        return b.kind == e.kind
    return True                           # a string: not probed
