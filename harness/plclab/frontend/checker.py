"""Semantic checks of an ST compilation unit, as strict as OpenPLC's matiec.

The checker resolves every name, types every expression (annotating the AST in place, see
plclab.frontend.ast), evaluates constant expressions (array bounds, CASE labels, initial
values, task intervals) and collects every error it can find in one pass, each with its
source position. Types follow matiec: no implicit conversion between differently typed
variables; an untyped literal takes the type its context needs if its value fits.
"""
from __future__ import annotations

import math
from typing import Any, Optional

from plclab.errors import Diagnostic
from plclab.frontend import ast as A
from plclab.frontend.checked import BIT_LIT, INT_LIT, REAL_LIT, CheckedUnit, EnumValue, LiteralType
from plclab.frontend.stdsigs import FUNCTION_BLOCKS, FUNCTIONS, LIBRARY_VARIABLES, NO_BOOL_OVERLOAD, RESERVED_NAMES, \
    FBSig, FuncSig
from plclab.iec import types as T

LOCATED_AREAS = {"IX": "IX", "QX": "QX", "IW": "IW", "QW": "QW", "MW": "MW", "MD": "MD", "ML": "ML"}
LOCATED_TYPES = {
    "X": {"BOOL"},
    "W": {"INT", "UINT", "WORD"},
    "D": {"DINT", "UDINT", "DWORD", "REAL"},
    "L": {"LINT", "ULINT", "LWORD", "LREAL"},
}
AREA_LIMIT = {"X": 99, "W": 1023, "D": 1023, "L": 1023}
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


class Checker:
    def __init__(self, unit: A.Unit):
        self.unit = unit
        self.diags: list[Diagnostic] = []
        self.types: dict[str, T.Type] = {}
        self.type_decls: dict[str, A.TypeDecl] = {}
        self.enum_values: dict[str, list[EnumValue]] = {}
        self.pous: dict[str, A.PouDecl] = {}
        self.fb_types: dict[str, T.FBType] = {}
        self.globals: dict[str, A.VarDecl] = {}
        self._resolving: set[str] = set()
        self._unresolvable: set[str] = set()

    # ------------------------------------------------------------------ reporting
    def error(self, node: Any, message: str) -> None:
        self.diags.append(Diagnostic(node.file, node.line, node.col, message))

    # ------------------------------------------------------------------ driver
    def check(self) -> CheckedUnit:
        u = self.unit
        for td in u.types:
            if self._declare_name(td, td.name, "type"):
                self.type_decls[td.key] = td
        for pou in u.pous:
            if self._declare_name(pou, pou.name, pou.kind.lower().replace("_", " ")):
                self.pous[pou.key] = pou
                if pou.kind == "FUNCTION_BLOCK":
                    self.fb_types[pou.key] = T.FBType(pou.name, pou)
        for td in u.types:
            self._resolve_type_decl(td)
        # configuration-level globals (GVL files count as the configuration's own)
        config = u.configs[0] if u.configs else None
        if len(u.configs) > 1:
            for c in u.configs[1:]:
                self.error(c, "only one CONFIGURATION is allowed in a program")
        # Global scopes. Inside a CONFIGURATION there is one. Without one, each GVL file is a
        # scope of its own: the files of several stands can be checked together (`plclab
        # check harness/plclab/plc/GVL/*.st ...`), each POU against the GVL that declares its
        # VAR_EXTERNALs, although two stands' consoles both have an SB1.
        config_blocks = []
        if config:
            config_blocks += config.globals
            for res in config.resources:
                config_blocks += res.globals
        scopes: dict[str, list[A.VarBlock]] = {}
        for block in u.gvls:
            scopes.setdefault("" if config else block.file, []).append(block)
        if config or not scopes:
            scopes = {"": list(u.gvls) + config_blocks}
        self.global_scopes: list[dict[str, A.VarDecl]] = []
        for blocks in scopes.values():
            self.globals = {}
            for block in blocks:
                self._check_block_rules(block, None)
                for d in block.decls:
                    self._declare_var(d, self.globals, None)
            self.global_scopes.append(self.globals)
        for pou in u.pous:
            if pou.key in self.pous and self.pous[pou.key] is pou:
                self.globals = self._scope_for(pou)
                self._check_pou_decls(pou)
        self.globals = self.global_scopes[0]
        for pou in u.pous:
            if pou.key in self.pous and self.pous[pou.key] is pou:
                self._check_pou_body(pou)
        if config:
            self._check_config(config)
        return CheckedUnit(u, self.types, self.pous, self.globals, config, sorted(set(self.diags)),
                           len(self.global_scopes))

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
            length = 126
            if ref.length is not None:
                length = self.const_int(ref.length, "a string length", scope)
                if length is None:
                    return None
                if not 1 <= length <= 126:
                    self.error(ref.length, f"string length {length} out of range (1..126 in OpenPLC)")
                    return None
            st = T.StringType(name or (f"STRING[{length}]" if ref.length is not None else "STRING"), length)
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
            size = 1
            for lo, hi in dims:
                size *= hi - lo + 1
            if size > 1_000_000:
                self.error(ref, f"array of {size} elements is too large")
                return None
            arr = T.ArrayType(name or f"ARRAY[{','.join(f'{a}..{b}' for a, b in dims)}] OF {elem.name}",
                              elem, tuple(dims))
            if init is not None:
                arr = T.ArrayType(arr.name, elem, tuple(dims), self._init_value(init, arr))
            return arr
        if isinstance(ref, A.EnumTypeRef):
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
                fv = self._init_value(f.init, ft) if f.init is not None else None
                f.ty = ft
                fields[f.key] = (ft, fv)
                names[f.key] = f.name
            return T.StructType(name or "STRUCT", fields, names)
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
        self.error(ref, f"unknown type '{ref.name}'")
        return None

    _std_fb_cache: dict[str, T.FBType] = {}

    def std_fb_type(self, key: str) -> T.FBType:
        if key not in Checker._std_fb_cache:
            Checker._std_fb_cache[key] = T.FBType(key, FUNCTION_BLOCKS[key])
        return Checker._std_fb_cache[key]

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
            try:
                if e.op == "+":
                    return a + b
                if e.op == "-":
                    return a - b
                if e.op == "*":
                    return a * b
                if e.op == "/":
                    if isinstance(a, int) and isinstance(b, int):
                        return int(a / b)
                    return a / b
                if e.op == "MOD":
                    return int(math.fmod(a, b))
                if e.op == "**":
                    return float(a) ** b
            except (ZeroDivisionError, OverflowError, ValueError):
                return None
        return None

    def _init_value(self, init: Any, ty: T.Type, scope: Optional[_Scope] = None) -> Any:
        """Check an initializer against `ty` and return the runtime value (None if invalid)."""
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
                else:
                    v = self._init_value(item, base.elem, scope)
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
                v = self._init_value(fval, base.fields[key][0], scope)
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
        if v is None:
            self.error(init, "an initial value must be a constant expression")
            return None
        return self._normalise(v, ty, init)

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
            if pou is not None:
                # as in matiec, the body may then use the address itself (`%QX0.0 := TRUE;`)
                names.setdefault(d.location.key, d)
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
        if d.section in ("VAR_IN_OUT", "VAR_TEMP") and d.init is not None \
                and not isinstance(d.type_ref, A.StringTypeRef):   # (matiec's grammar allows it for STRING)
            self.error(d.init, f"a {d.section} cannot have an initial value in OpenPLC's compiler")
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
            v = self._init_value(fval, p[1])
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
        if isinstance(d.type_ref, A.StringTypeRef) and d.type_ref.length is not None:
            self.error(d.type_ref, "STRING[n] is not allowed in VAR_EXTERNAL by OpenPLC's compiler")
        ty = self.resolve_type(d.type_ref)
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
            return a.dims == b.dims and Checker._decl_types_match(a.elem, b.elem)
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
        for block in pou.blocks:
            self._check_block_rules(block, pou)
            sec = block.section
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
            ret.init_value = T.default_value(pou.ret_ty)
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

    # ------------------------------------------------------------------ bodies
    def _check_pou_body(self, pou: A.PouDecl) -> None:
        scope = _Scope(pou, pou.symbols or {})
        if not pou.body:
            self.error(pou, f"{pou.kind} '{pou.name}' has no statements: OpenPLC's compiler needs at least one")
        for s in pou.body:
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
        t = self.expr(target, scope, None, allow_fb=True)
        if t is None:
            for a in s.args:
                self.expr(a.value, scope, None)
            return
        if not isinstance(t, T.FBType):
            self.error(target, f"'{self._path_text(target)}' is not a function block instance or a function")
            return
        if isinstance(target, A.Name) and isinstance(target.sym, A.VarDecl) and target.sym.section == "VAR_EXTERNAL" \
                and target.sym.constant:
            self.error(target, f"'{target.name}' is CONSTANT: it cannot be called")
        s.fb_type = t
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
                    if a.negated and T.base_of(pty) is not T.BOOL:
                        self.error(a, "NOT on an output needs a BOOL output")
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
        if a.negated and d.ty is not None and T.base_of(d.ty) is not T.BOOL:
            self.error(a, "NOT on an output needs a BOOL output")
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
        if isinstance(sym, A.VarDecl):
            if sym.constant or (sym.global_decl is not None and sym.global_decl.constant):
                self.error(e, f"'{root.name}' is a CONSTANT: it cannot be assigned")
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
                    self.error(e, f"'{bt.name}' has no field '{e.name}'")
                    return None
                return b.fields[e.key][0]
            if isinstance(b, T.FBType):
                if isinstance(b.pou, FBSig):
                    for n, tn in b.pou.inputs + b.pou.outputs:
                        if n == e.key:
                            e.sym = n
                            return T.ELEMENTARY[tn]
                    self.error(e, f"function block {b.name} has no variable '{e.name}'")
                    return None
                d = (b.pou.symbols or {}).get(e.key)
                if d is None or d.section == "RETURN":
                    self.error(e, f"function block {b.name} has no variable '{e.name}'")
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
            if expected is not None and isinstance(T.base_of(expected), T.EnumType):
                for v in values:
                    if v.ty is T.base_of(expected):
                        e.sym = v
                        return v.ty
            if len(values) == 1:
                e.sym = values[0]
                return values[0].ty
            self.error(e, f"'{e.name}' is a value of several enumerated types; qualify it (e.g. "
                          f"{values[0].ty.name}#{e.name})")
            return None
        if e.key.startswith("%"):
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
        self.error(e, f"undeclared identifier '{e.name}'")
        return None

    _CMP = {"=", "<>", "<", ">", "<=", ">="}

    def _binary(self, e: A.Binary, scope: _Scope, expected: Optional[T.Type]) -> Optional[T.Type]:
        op = e.op
        hint = None if op in self._CMP else expected
        if op == "**":
            lt = self.expr(e.left, scope, hint)
            rt = self.expr(e.right, scope, None)
            if lt is None or rt is None:
                return None
            if isinstance(lt, LiteralType):
                lt = self.settle(e.left, lt, hint if hint is not None and T.in_generic(hint, "ANY_REAL") else DEFAULT_REAL)
            rt = self.settle(e.right, rt)
            if not T.in_generic(lt, "ANY_REAL"):
                self.error(e, f"'**' needs a REAL or LREAL base, not {self._tname(lt)}")
                return None
            if not T.in_generic(rt, "ANY_NUM"):
                self.error(e.right, f"'**' needs a numeric exponent, not {self._tname(rt)}")
                return None
            return lt
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
                return lt
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

    def _set_lit_type(self, e: A.Expr, target: T.Type) -> None:
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
                    if tb is T.REAL and v is not None and abs(v) > 3.4028234663852886e38:
                        shown = e.text if isinstance(e, A.Literal) and e.text else v
                        self.error(e, f"{shown} does not fit in REAL (use LREAL)")
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
            self.error(e, f"type mismatch in {what}: {self._tname(target)} cannot take "
                          f"{'a real' if t.kind == 'real' else 'an integer'} literal")
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

    # ------------------------------------------------------------------ configuration
    def _check_config(self, config: A.Configuration) -> None:
        if config.name.upper() in LIBRARY_VARIABLES:
            self.error(config, _library_variable_message(config.name, "configuration"))
        seen_tasks: dict[str, A.TaskDecl] = {}
        seen_progs: set[str] = set()
        for res in config.resources:
            for task in res.tasks:
                if task.key in seen_tasks:
                    self.error(task, f"task '{task.name}' is already declared")
                    continue
                seen_tasks[task.key] = task
                sc = _Scope(None, dict(self.globals))
                if task.interval is not None:
                    t = self.expr(task.interval, sc, T.TIME)
                    if t is not None and T.base_of(t) is not T.TIME:
                        what = f"an {t.name}" if isinstance(t, LiteralType) else self._tname(t)
                        self.error(task.interval, f"INTERVAL must be a TIME (e.g. T#20ms), not {what}")
                    else:
                        v = self.const_value(task.interval)
                        if isinstance(v, int) and v > 0:
                            task.interval_ns = v
                        elif v is None:
                            self.error(task.interval, "INTERVAL must be a constant TIME (e.g. T#10ms)")
                        else:
                            self.error(task.interval, "INTERVAL must be greater than zero")
                if task.single is not None:
                    t = self.expr(task.single, sc, T.BOOL)
                    if t is not None and T.base_of(t) is not T.BOOL:
                        self.error(task.single, "SINGLE must be a BOOL")
                p = self.const_value(task.priority)
                if not isinstance(p, int) or isinstance(p, bool) or p < 0:
                    self.error(task.priority, "PRIORITY must be a non-negative integer constant")
                else:
                    task.priority.ty = T.UINT
                if task.interval is None and task.single is None:
                    self.error(task, f"task '{task.name}' has neither INTERVAL nor SINGLE: it would never run")
            for prog in res.programs:
                if prog.key in seen_progs:
                    self.error(prog, f"program instance '{prog.name}' is already declared")
                    continue
                seen_progs.add(prog.key)
                pou = self.pous.get(prog.type_name.upper())
                if pou is None:
                    self.error(prog, f"unknown program '{prog.type_name}'")
                    continue
                if pou.kind != "PROGRAM":
                    kind = pou.kind.lower().replace("_", " ")
                    self.error(prog, f"'{prog.type_name}' is a {kind}, not a PROGRAM: only programs run in a task")
                    continue
                prog.pou = pou
                if prog.task is not None:
                    task = seen_tasks.get(prog.task.upper())
                    if task is None:
                        self.error(prog, f"unknown task '{prog.task}'")
                    prog.task_decl = task
                if prog.args:
                    self.error(prog.args[0], "program instance parameters are not supported; "
                                             "connect programs through VAR_GLOBAL / VAR_EXTERNAL")

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


def check_unit(unit: A.Unit) -> CheckedUnit:
    return Checker(unit).check()
