"""Checked AST -> Python source -> code objects: the soft PLC executes compiled POUs.

Every POU becomes Python code once, at load time, so a scan is plain Python calls with no
tree walking:
  PROGRAM / FUNCTION_BLOCK -> a class with __slots__ (one attribute per variable, named by
                              the variable's upper-case key) and _run = the body (also its
                              __call__); while the body runs, the variables it names often
                              live in Python locals (`v_KEY`), stored back when it ends
  FUNCTION                 -> a Python function with positional parameters and Python
                              locals; VAR_OUTPUT / VAR_IN_OUT arrive as Ref cells
  globals                  -> attributes of one `G` object
A variable passed by reference (plclab.runtime.varuse) stays in its object, so the callee
writes where the caller reads.
Expressions compute what the C that matiec generates (stage4/generate_c/generate_c_st.cc:
plain C operators, no casts) computes:
  * SINT/INT/USINT/UINT/BYTE/WORD operands are promoted to C `int`: intermediates (also of
    `/`, `MOD` and `NOT` on BYTE/WORD) are 32-bit and only narrowed where the value is stored
    or passed (assignment, parameter, CASE selector);
  * REAL is single precision, except that an untyped real literal is a C double constant,
    so an expression mixing them is computed in double and rounded to REAL once, where it is
    stored or passed (`r = 0.1` is FALSE after `r := 0.1`);
  * FOR is matiec's while(1) loop: END and BY re-evaluated on every pass, BY 0 tests `>=`.
A line map from generated Python lines to ST lines lets a runtime fault name the POU, file
and line without any cost on the hot path.
"""
from __future__ import annotations

import itertools
import linecache
import math
import weakref
from array import array
from dataclasses import dataclass, field
from typing import Any, Optional

from plclab.errors import CompileError, Diagnostic
from plclab.frontend import ast as A
from plclab.frontend.checked import CheckedUnit, EnumValue, LiteralType
from plclab.frontend.stdsigs import FBSig
from plclab.iec import types as T
from plclab.limits import at_memory_limit
from plclab.runtime import stdfb, stdlib
from plclab.runtime.faults import PlcFault
from plclab.runtime.ranges import Range, RangeOf, concrete as _concrete, ring_type, type_range, \
    within, wrap_bounds
from plclab.runtime.varuse import body_use


class Ref:
    """A reference to a scalar variable (VAR_IN_OUT and function outputs)."""

    __slots__ = ("obj", "attr")

    def __init__(self, obj: Any, attr: Any):
        self.obj, self.attr = obj, attr

    def get(self) -> Any:
        o = self.obj
        return o[self.attr] if isinstance(o, list) else getattr(o, self.attr)

    def set(self, value: Any) -> None:
        o = self.obj
        if isinstance(o, list):
            o[self.attr] = value
        else:
            setattr(o, self.attr, value)


def _bound(i: int, lo: int, hi: int) -> int:
    """Array index check: out of range is a runtime fault (C would overrun memory)."""
    if lo <= i <= hi:
        return i - lo
    raise PlcFault("index_out_of_range", f"array index {i} outside {lo}..{hi}")


@dataclass
class LineInfo:
    file: str
    line: int
    pou: str


@dataclass
class CompiledProgram:
    """What the runtime loads: the namespace with the generated classes and tables."""

    checked: CheckedUnit
    namespace: dict[str, Any]
    source: str
    line_map: dict[int, LineInfo]
    filename: str
    program_classes: dict[str, str] = field(default_factory=dict)   # PROGRAM key -> class name
    retained_globals: list[str] = field(default_factory=list)

    def where(self, py_line: int) -> Optional[LineInfo]:
        return self.line_map.get(py_line)

    def annotated_source(self) -> str:
        """The generated Python, each line that comes from ST ending in `# FILE:LINE POU`:
        what `plclab check --emit-python` prints, and what a traceback through the compiled
        code shows (it is registered with linecache under `filename`)."""
        lines = self.source.splitlines()
        width = max((len(line) for line in lines), default=0)
        out = []
        for n, line in enumerate(lines, start=1):
            info = self.line_map.get(n)
            out.append(f"{line:<{width}}  # {info.file}:{info.line} {info.pou}" if info else line)
        return "\n".join(out) + "\n"


_counter = itertools.count()


def _pyname(kind: str, name: str) -> str:
    return f"{kind}_{name.upper()}"


class _Emitter:
    """Collects generated lines with their ST origin."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.origin: dict[int, LineInfo] = {}
        self.pou = ""

    def emit(self, indent: int, text: str, node: Any = None) -> None:
        self.lines.append("    " * indent + text)
        if node is not None and getattr(node, "line", 0):
            self.origin[len(self.lines)] = LineInfo(node.file, node.line, self.pou)


class Compiler:
    """Generates the Python of one checked unit.

    `optimize` switches on every fast path at once; each is guarded by `self.optimize` and
    the plain path beside it computes the same values the straightforward way (the
    semantics tests run both ways, so the two cannot drift apart):
      * ranges: a wrap or narrowing the declared types prove idle is left out
        (plclab.runtime.ranges), and a chain of + - * is computed exactly and wrapped once;
      * cached locals: a PROGRAM's / FB's busy variables live in Python locals while its
        body runs (body_locals);
      * f32 codes: a REAL stored is rounded through a float array, not a call (assign);
      * EN types: a FB type no call gives an EN is entered straight, without the EN test;
      * inline forms: MOD by a positive constant, widening conversions, constant shifts,
        and array indexes known at compile time to be in range.
    """

    def __init__(self, checked: CheckedUnit, optimize: bool = True):
        self.cu = checked
        self.optimize = optimize
        self.out = _Emitter()
        self.const_ids: dict[int, str] = {}
        self.ns: dict[str, Any] = {
            "_bound": _bound, "_store_into": _store_into,
            "_f32": T.to_f32, "_copy": T.copy_value, "Ref": Ref, "PlcFault": PlcFault,
            "_StructValue": T.StructValue,
            "_Locals": _Locals, "_NegRef": _NegRef, "_fa": array("f", [0.0]),
        }
        self.tmp = itertools.count()
        self.pou: Optional[A.PouDecl] = None
        self.in_function = False
        self.loop_stack: list[str] = []
        self.local: dict[int, str] = {}     # id(VarDecl) -> its storage while the body runs
        self.ret_code = "None"              # a FUNCTION's result (a local, or _L.RET_)
        self.ranges = RangeOf() if optimize else _NoRanges()
        self.en_types: set[Any] = set()     # FB types some call gives an EN (see fb_call)

    # ------------------------------------------------------------------ helpers
    def const(self, value: Any) -> str:
        """A name in the generated module bound to a (possibly mutable) constant value."""
        if isinstance(value, (bool, int, float, str)) and not isinstance(value, float) or value is None:
            return repr(value)
        if isinstance(value, float):
            if math.isfinite(value):
                return repr(value)
        key = id(value)
        if key not in self.const_ids:
            name = f"_k{len(self.const_ids)}"
            self.const_ids[key] = name
            self.ns[name] = value
        return self.const_ids[key]

    def init_code(self, value: Any) -> str:
        """Code creating a fresh copy of an initial value."""
        if isinstance(value, (list, T.StructValue)):
            return f"_copy({self.const(value)})"
        return self.const(value)

    def bind(self, obj: Any, prefix: str = "_f") -> str:
        name = f"{prefix}{next(self.tmp)}"
        self.ns[name] = obj
        return name

    def wrap(self, code: str, ty: Optional[T.Type], rng: Optional[Range] = None) -> str:
        """Normalise an arithmetic result to the C type of `ty`; nothing to do when its range
        `rng` (plclab.runtime.ranges) shows it cannot leave the type."""
        b = T.base_of(ty) if ty is not None else None
        if isinstance(b, LiteralType) or b is None:
            return code
        if isinstance(b, T.ElementaryType):
            if b.kind in ("sint", "uint", "bits"):
                lo, hi = wrap_bounds(b)
                if within(rng, (lo, hi)):
                    return code
                if lo == 0:
                    return f"(({code}) & {hi})"
                # C promotes SINT/INT/USINT/UINT operands to int: the intermediate is 32-bit.
                # A test first: the value nearly always fits, and comparing is cheaper.
                return self._signed_wrap(code, lo, hi)
            if b is T.REAL:
                return F32Code(code)
            if b.kind in ("time", "date", "tod", "dt"):
                return self._signed_wrap(code, -(1 << 63), (1 << 63) - 1)
        return code

    def ring(self, e: A.Expr) -> Optional[T.ElementaryType]:
        """The integer type of a ring operation computed exactly and wrapped once (fast
        path); None on the plain path, where every operation wraps its own result."""
        return ring_type(e) if self.optimize else None

    def _signed_wrap(self, code: str, lo: int, hi: int) -> str:
        t = f"_w{next(self.tmp)}"
        return f"({t} if {lo} <= ({t} := {code}) <= {hi} else (({t} + {-lo}) & {hi - lo}) + {lo})"

    # ------------------------------------------------------------------ driver
    def compile(self) -> CompiledProgram:
        cu = self.cu
        out = self.out
        out.emit(0, "# generated by plclab from ST; do not edit")
        out.emit(0, "class _Globals:")
        out.emit(1, "pass")
        out.emit(0, "G = _Globals()")
        # functions first (they are called by FBs and programs), then FBs, then programs
        order = [p for p in cu.unit.pous if p.kind == "FUNCTION"] + \
                [p for p in cu.unit.pous if p.kind == "FUNCTION_BLOCK"] + \
                [p for p in cu.unit.pous if p.kind == "PROGRAM"]
        result = CompiledProgram(cu, self.ns, "", {}, f"<plc-{next(_counter)}>")
        self.en_types = self.fb_types_given_en() if self.optimize else set()
        for pou in order:
            if cu.pous.get(pou.key) is not pou:
                continue
            out.pou = pou.name
            if pou.kind == "FUNCTION":
                self.function(pou)
            else:
                cls = self.pou_class(pou)
                if pou.kind == "PROGRAM":
                    result.program_classes[pou.key] = cls
        out.pou = "CONFIGURATION"
        self.globals_init(result)
        source = "\n".join(out.lines) + "\n"
        try:
            code = compile(source, result.filename, "exec")
        except MemoryError as e:
            if at_memory_limit():            # a failed allocation at the process's memory limit, not the code
                raise
            raise _too_complex(e, out.origin, cu) from None
        except (SyntaxError, RecursionError) as e:
            raise _too_complex(e, out.origin, cu) from None
        exec(code, self.ns)
        result.source = source
        result.line_map = out.origin
        _register_source(result)
        return result

    def fb_types_given_en(self) -> set[Any]:
        """The FB types some call gives an EN (the others are entered without the EN test)."""
        return {_fb_key(c.fb_type) for p in self.cu.unit.pous for c in A.walk_statements(p.body)
                if isinstance(c, A.CallStmt) and c.fb_type is not None
                and any(a.key == "EN" and not a.is_output for a in c.args)}

    def globals_init(self, result: CompiledProgram) -> None:
        out = self.out
        out.emit(0, "def _init_globals():")
        any_ = False
        for key, d in self.cu.globals.items():
            if key.startswith("%"):
                continue
            any_ = True
            out.emit(1, f"G.{key} = {self.var_init(d)}", d)
            if d.retain:
                result.retained_globals.append(key)
        for key, d in self.cu.globals.items():
            if key.startswith("%") and d.ty is not None:
                out.emit(1, f"G.{located_attr(d)} = {self.var_init(d)}", d)
                any_ = True
        if not any_:
            out.emit(1, "pass")

    def var_init(self, d: A.VarDecl) -> str:
        ty = d.ty
        if isinstance(ty, T.FBType):
            return self.fb_new(ty, d)
        return self.init_code(d.init_value if d.init_value is not None else T.default_value(ty))

    def fb_new(self, ty: T.FBType, d: Optional[A.VarDecl]) -> str:
        inits = d.fb_init if d is not None else None
        if isinstance(ty.pou, FBSig):
            cls = self.bind(getattr(stdfb, ty.pou.name), "_std")
            code = f"{cls}(_rt.scan_clock)"
        else:
            code = f"{_pyname('FB', ty.pou.name)}()"
        if inits:
            return f"_rt.init_fb({code}, {self.const(dict(inits))})"
        return code

    # ------------------------------------------------------------------ POU classes
    def pou_class(self, pou: A.PouDecl) -> str:
        out = self.out
        self.pou = pou
        self.in_function = False
        name = _pyname("FB" if pou.kind == "FUNCTION_BLOCK" else "PRG", pou.name)
        decls = [d for d in pou.decls if d.name]
        located = [d for d in pou.decls if d.location is not None]
        eno = pou.eno_decl
        attrs = [d.key for d in decls] + [located_attr(d) for d in located if not d.name] + \
            (["ENO"] if eno is not None else []) + (["EN"] if pou.kind == "FUNCTION_BLOCK" else [])
        out.emit(0, f"class {name}:")
        out.emit(1, f"__slots__ = {tuple(attrs)!r}")
        out.emit(1, f"_ST_NAME = {pou.name!r}")
        in_out = tuple(d.key for d in decls if d.section == "VAR_IN_OUT")
        if in_out:       # bound anew by each call (what the line tracer must not take as fixed)
            out.emit(1, f"_IN_OUT = {in_out!r}")
        out.emit(1, "def __init__(self):", pou)
        for d in decls:
            if d.section == "VAR_EXTERNAL":
                continue
            if d.section == "VAR_IN_OUT":
                out.emit(2, f"self.{d.key} = None", d)
                continue
            out.emit(2, f"self.{d.key} = {self.var_init(d)}", d)
        for d in located:
            if not d.name:
                out.emit(2, f"self.{located_attr(d)} = {self.var_init(d)}", d)
        if eno is not None:
            out.emit(2, "self.ENO = True")
        if pou.kind == "FUNCTION_BLOCK":
            out.emit(2, "self.EN = True")
        out.emit(2, "pass")
        out.emit(1, "def _run(self):", pou)
        stores = self.body_locals(pou, eno)
        self.body_then(pou.body, 2, [f"self.{attr} = {local}" for attr, local in stores])
        out.emit(2, "return")
        out.emit(1, "__call__ = _run")
        self.local = {}
        return name

    def body_locals(self, pou: A.PouDecl, eno: Optional[A.VarDecl]) -> list[tuple[str, str]]:
        """The prologue of a PROGRAM / FB body: the variables worth a Python local are loaded
        (VAR_TEMP ones initialised) and recorded in self.local; returns the (attribute, local)
        pairs to store back when the body ends."""
        out = self.out
        use = body_use(pou.body)
        self.local = {}
        loads, stores = [], []
        for d in [d for d in pou.decls if d.section != "VAR_EXTERNAL"] + ([eno] if eno is not None else []):
            i = id(d)
            attr = d.key if d.name else located_attr(d)
            temp = d.section == "VAR_TEMP"
            if d is eno:
                if use.count[i]:                      # matiec: ENO is TRUE when the body starts
                    if i in use.by_ref or not self.optimize:
                        out.emit(2, "self.ENO = True")
                    else:
                        self.local[i] = "v_ENO"
                        out.emit(2, "v_ENO = True")
                        stores.append(("ENO", "v_ENO"))
            elif i in use.by_ref or not self.optimize or not (temp or use.count[i] >= _LOCAL_MIN_USES):
                if temp:
                    out.emit(2, f"self.{attr} = {self.var_init(d)}", d)
            else:
                local = f"v_{attr}"
                self.local[i] = local
                loads.append(f"{local} = {self.var_init(d)}" if temp else f"{local} = self.{attr}")
                if temp or (i in use.written and self._is_scalar(d.ty)):
                    stores.append((attr, local))
        for line in loads:
            out.emit(2, line)
        return stores

    def function(self, pou: A.PouDecl) -> None:
        """A FUNCTION: positional parameters in declaration order (see user_call), every
        variable a Python local unless something takes its reference (then it lives in `_L`)."""
        out = self.out
        self.pou = pou
        self.in_function = True
        use = body_use(pou.body)
        params = _params(pou)
        ret = pou.ret_decl
        eno = pou.eno_decl
        boxed = lambda d: id(d) in use.by_ref   # noqa: E731
        self.local = {}
        for d in pou.decls:
            if d.name:
                self.local[id(d)] = f"_L.{d.key}" if boxed(d) else f"v_{d.key}"
        if ret is not None:
            self.local[id(ret)] = "_L.RET_" if boxed(ret) else "_ret"
        if eno is not None:
            self.local[id(eno)] = "_L.ENO" if boxed(eno) else "v_ENO"
        self.ret_code = self.local[id(ret)] if ret is not None else "None"
        # an input or in-out parameter kept in a local is the Python parameter itself
        direct = {id(d) for d in params if d.section != "VAR_OUTPUT" and not boxed(d)}
        sig = [self.local[id(d)] if id(d) in direct else f"p_{d.key}" for d in params] + ["_eno=None"]
        out.emit(0, f"def {_pyname('FC', pou.name)}({', '.join(sig)}):", pou)
        if any(boxed(d) for d in pou.decls) or (ret is not None and boxed(ret)) or \
                (eno is not None and boxed(eno)):
            out.emit(1, "_L = _Locals()")
        outs = []
        for d in params:
            store = self.local[id(d)]
            if d.section == "VAR_OUTPUT":
                outs.append((f"p_{d.key}", store))
                out.emit(1, f"{store} = {self.var_init(d)}", d)
            elif id(d) not in direct:
                out.emit(1, f"{store} = p_{d.key}", d)
        for d in pou.decls:
            if d.section in ("VAR", "VAR_TEMP") and d.name:
                out.emit(1, f"{self.local[id(d)]} = {self.var_init(d)}", d)
        if ret is not None:
            out.emit(1, f"{self.ret_code} = {self.init_code(ret.init_value)}", pou)
        if eno is not None and (use.count[id(eno)] or id(eno) in use.by_ref):
            out.emit(1, f"{self.local[id(eno)]} = True")        # the body may clear it
            outs.append(("_eno", self.local[id(eno)]))
        elif eno is not None:
            out.emit(1, "if _eno is not None: _eno.set(True)")
        self.body_then(pou.body, 1, [f"if {ref} is not None: {ref}.set({store})" for ref, store in outs])
        out.emit(1, f"return {self.ret_code}")
        self.local = {}
        self.ret_code = "None"

    def body_then(self, body: list[A.Stmt], ind: int, epilogue: list[str]) -> None:
        """A POU body followed by `epilogue`, which runs also when the body returns early or
        faults (so the variables hold what the body wrote before the fault)."""
        if not epilogue:
            self.block(body, ind)
            return
        self.out.emit(ind, "try:")
        self.block(body, ind + 1)
        self.out.emit(ind, "finally:")
        for line in epilogue:
            self.out.emit(ind + 1, line)

    # ------------------------------------------------------------------ statements
    def block(self, body: list[A.Stmt], ind: int) -> None:
        if not body:
            self.out.emit(ind, "pass")
        for s in body:
            self.stmt(s, ind)

    def stmt(self, s: A.Stmt, ind: int) -> None:
        out = self.out
        if isinstance(s, A.Assign):
            self.assign(s.target, self.expr_as(s.value, s.target.ty), ind, s, s.value)
        elif isinstance(s, A.CallStmt):
            self.fb_call(s, ind)
        elif isinstance(s, A.If):
            for i, (cond, body) in enumerate(s.branches):
                out.emit(ind, f"{'if' if i == 0 else 'elif'} {self.expr(cond)}:", cond)
                self.block(body, ind + 1)
            if s.else_body is not None:
                out.emit(ind, "else:")
                self.block(s.else_body, ind + 1)
        elif isinstance(s, A.Case):
            sel = f"_c{next(self.tmp)}"
            # matiec: `<type> __case_expression = <selector>;` narrows a promoted value
            out.emit(ind, f"{sel} = {self.expr_as(s.selector, s.selector.ty)}", s)
            first = True
            for br in s.branches:
                conds = []
                for lab in br.labels:
                    if lab.hi is not None and lab.hi_value != lab.lo_value:
                        conds.append(f"{self.const(lab.lo_value)} <= {sel} <= {self.const(lab.hi_value)}")
                    else:
                        conds.append(f"{sel} == {self.const(lab.lo_value)}")
                out.emit(ind, f"{'if' if first else 'elif'} {' or '.join(conds) or 'False'}:", br)
                first = False
                self.block(br.body, ind + 1)
            if s.else_body is not None:
                if first:
                    out.emit(ind, "if True:")
                else:
                    out.emit(ind, "else:")
                self.block(s.else_body, ind + 1)
        elif isinstance(s, A.For):
            self.for_(s, ind)
        elif isinstance(s, A.While):
            out.emit(ind, f"while {self.expr(s.cond)}:", s)
            out.emit(ind + 1, "_rt.loop_check()", s)
            self.loop_stack.append("")
            self.block(s.body, ind + 1)
            self.loop_stack.pop()
        elif isinstance(s, A.Repeat):
            flag = f"_x{next(self.tmp)}"
            out.emit(ind, "while True:", s)
            out.emit(ind + 1, "_rt.loop_check()", s)
            self.one_shot_body(s.body, flag, ind + 1)
            out.emit(ind + 1, f"if {self.expr(s.cond)}: break", s.cond)
        elif isinstance(s, A.Exit):
            flag = self.loop_stack[-1] if self.loop_stack else ""
            out.emit(ind, f"{flag} = True; break" if flag else "break", s)
        elif isinstance(s, A.Continue):
            flag = self.loop_stack[-1] if self.loop_stack else ""
            out.emit(ind, "break" if flag else "continue", s)
        elif isinstance(s, A.Return):
            out.emit(ind, "return" if not self.in_function else f"return {self.ret_code}", s)
        elif isinstance(s, A.Empty):
            out.emit(ind, "pass", s)
        else:  # pragma: no cover - the checker admits nothing else
            raise TypeError(f"cannot compile {type(s).__name__}")

    def one_shot_body(self, body: list[A.Stmt], flag: str, ind: int) -> None:
        """A loop body inside `for _once in (0,)`, so that CONTINUE (a `break` out of the
        one-shot) still reaches the loop's step / UNTIL, and EXIT sets `flag` first."""
        out = self.out
        out.emit(ind, f"{flag} = False")
        out.emit(ind, "for _once in (0,):")
        self.loop_stack.append(flag)
        self.block(body, ind + 1)
        self.loop_stack.pop()
        out.emit(ind, f"if {flag}: break")

    def for_(self, s: A.For, ind: int) -> None:
        """FOR as matiec's generate_c_st.cc emits it: `v := start`, then a loop that tests
        `v <= end` (with BY: `(step) > 0 ? v <= end : v >= end`, so BY 0 tests `>=`),
        runs the body and does `v := v + step` (narrowed to v's type, so it can wrap). END
        and BY are re-evaluated on every test, as C int expressions (not narrowed)."""
        out = self.out
        var_code = self.lvalue_get(s.var)
        vt = s.var.ty
        self.assign(s.var, self.expr_as(s.start, vt), ind, s)
        out.emit(ind, "while True:", s)
        end = self.expr(s.end)
        if s.step is None:
            test = f"{var_code} <= {end}"
            step = "1"
        else:
            step = self.expr(s.step)
            test = f"({var_code} <= {end}) if ({step}) > 0 else ({var_code} >= {end})"
        out.emit(ind + 1, f"if not ({test}): break", s)
        out.emit(ind + 1, "_rt.loop_check()", s)
        self.one_shot_body(s.body, f"_x{next(self.tmp)}", ind + 1)
        self.assign(s.var, self.narrow(self.wrap(f"{var_code} + ({step})", vt), vt), ind + 1, s)

    # ------------------------------------------------------------------ assignment
    def assign(self, target: A.Expr, value_code: str, ind: int, node: Any, value: Optional[A.Expr] = None) -> None:
        ty = target.ty
        b = T.base_of(ty) if ty is not None else None
        if isinstance(b, T.StringType) and b.length < 126:
            value_code = f"({value_code})[:{b.length}]"
        if isinstance(b, (T.ArrayType, T.StructType)):
            # IEC variables have fixed storage: copy the value into it (this also keeps
            # VAR_IN_OUT references and watched elements pointing at the variable)
            self.out.emit(ind, f"_store_into({self.lvalue_get(target)}, {value_code})", node)
            return
        if isinstance(value_code, F32Code) and self.optimize:
            # rounding to single precision through a float array is the cheapest way Python has
            self.out.emit(ind, f"_fa[0] = {value_code.inner}", node)
            value_code = "_fa[0]"
        self.out.emit(ind, self.store(target, value_code), node)

    def store(self, target: A.Expr, value_code: str) -> str:
        if isinstance(target, A.Name):
            sym = target.sym
            if isinstance(sym, A.VarDecl) and sym.section == "VAR_IN_OUT" and self._is_scalar(sym.ty):
                return f"{self.name_code(target)}.set({value_code})"
            return f"{self.name_code(target)} = {value_code}"
        return f"{self.lvalue_get(target)} = {value_code}"

    @staticmethod
    def _is_scalar(ty: Optional[T.Type]) -> bool:
        return not isinstance(T.base_of(ty) if ty is not None else None, (T.ArrayType, T.StructType, T.FBType))

    def name_code(self, e: A.Name) -> str:
        """The storage of a name (without the .get() of scalar VAR_IN_OUT refs)."""
        sym = e.sym
        if isinstance(sym, A.VarDecl):
            local = self.local.get(id(sym))
            if local is not None:
                return local
            if not sym.name:                       # `%QW1` of an anonymous AT declaration
                return f"G.{located_attr(sym)}" if sym.section == "VAR_GLOBAL" else f"self.{located_attr(sym)}"
            if sym.section == "VAR_EXTERNAL":
                return f"G.{sym.key}"
            if sym.section == "VAR_GLOBAL":
                return f"G.{sym.key}"
            return f"self.{sym.key}"
        raise TypeError(f"not a variable: {e.name}")

    def lvalue_get(self, e: A.Expr) -> str:
        """Code reading a variable/element/field (also the target form for stores)."""
        if isinstance(e, A.Name):
            sym = e.sym
            if isinstance(sym, EnumValue):
                return repr(sym.name)
            code = self.name_code(e)
            if isinstance(sym, A.VarDecl) and sym.section == "VAR_IN_OUT" and self._is_scalar(sym.ty):
                return code + ".get()"
            return code
        if isinstance(e, A.Member):
            return f"{self.lvalue_get(e.base)}.{e.key}"
        if isinstance(e, A.Index):
            arr = T.base_of(e.base.ty)
            return f"{self.lvalue_get(e.base)}[{self.flat_index(e, arr)}]"
        raise TypeError(f"not an lvalue: {type(e).__name__}")

    def flat_index(self, e: A.Index, arr: T.ArrayType) -> str:
        parts = []
        stride = 1
        strides = []
        for lo, hi in reversed(arr.dims):
            strides.append(stride)
            stride *= hi - lo + 1
        strides.reverse()
        for ix, (lo, hi), st in zip(e.indexes, arr.dims, strides):
            v = self.cu_const(ix)
            if self.optimize and isinstance(v, int) and not isinstance(v, bool) and lo <= v <= hi:
                off = str(v - lo)
            else:
                off = f"_bound({self.expr(ix)}, {lo}, {hi})"
            parts.append(off if st == 1 else f"{off} * {st}")
        return " + ".join(parts)

    def cu_const(self, e: A.Expr) -> Any:
        if isinstance(e, A.Literal):
            return e.value
        return None

    # ------------------------------------------------------------------ FB calls
    def fb_call(self, s: A.CallStmt, ind: int) -> None:
        """A FB call as matiec's fb_invocation compiles it: the inputs the call names
        (EN included) are assigned, the body runs (and checks EN itself), the outputs the
        call names (ENO included) are copied out. So EN keeps its value between calls."""
        out = self.out
        inst = self.lvalue_get(s.target)
        fb: T.FBType = s.fb_type
        if inst.isidentifier():
            iv = inst            # the instance is in a local already
        else:
            iv = f"_i{next(self.tmp)}"
            out.emit(ind, f"{iv} = {inst}", s)
        outputs = []
        eno = next((a for a in s.args if a.key == "ENO" and a.is_output), None)
        for a in s.args:
            key = a.key
            if a.is_output:
                if key != "ENO":
                    outputs.append(a)
                continue
            if key == "ENO":
                continue
            decl = a.param if isinstance(a.param, A.VarDecl) else None
            if key == "EN":
                out.emit(ind, f"{iv}.EN = {self.expr_as(a.value, T.BOOL)}", a)
            elif decl is not None and decl.section == "VAR_IN_OUT":
                out.emit(ind, f"{iv}.{key} = {self.ref_to(a.value, decl.ty)}", a)
            else:
                ptype = decl.ty if decl is not None else a.value.ty
                if isinstance(T.base_of(ptype) if ptype is not None else None, (T.ArrayType, T.StructType)):
                    # passed by value: copied into the block's own input (as C copies it)
                    out.emit(ind, f"_store_into({iv}.{key}, {self.expr(a.value)})", a)
                    continue
                out.emit(ind, f"{iv}.{key} = {self.expr_as(a.value, ptype)}", a)
        std = isinstance(fb.pou, FBSig)
        if not self.optimize or _fb_key(fb) in self.en_types:
            # some call in the program sets this block type's EN: the body checks it
            if std:
                out.emit(ind, f"{iv}()", s)          # the library block's EN/ENO handling
            else:
                out.emit(ind, f"if {iv}.EN: {iv}.ENO = True; {iv}._run()", s)
                out.emit(ind, f"else: {iv}.ENO = False")
        else:
            # EN is TRUE throughout: straight into the body
            if eno is not None:
                out.emit(ind, f"{iv}.ENO = True")
            out.emit(ind, f"{iv}._body()" if std else f"{iv}._run()", s)
        for a in outputs:
            code = f"{iv}.{a.key}"
            if a.negated:
                code = f"not {code}"
            self.assign(a.value, code, ind, a)
        if eno is not None:
            self.assign(eno.value, f"{iv}.ENO", ind, eno)

    def ref_to(self, e: A.Expr, ty: Optional[T.Type]) -> str:
        """A reference to variable `e` for a VAR_IN_OUT parameter."""
        if not self._is_scalar(ty):
            return self.lvalue_get(e)
        if isinstance(e, A.Name):
            sym = e.sym
            if isinstance(sym, A.VarDecl) and sym.section == "VAR_IN_OUT":
                return self.name_code(e)   # pass the caller's reference on
            code = self.name_code(e)
            obj, _, attr = code.rpartition(".")
            if not obj:   # pragma: no cover - varuse keeps variables passed by reference in objects
                raise AssertionError(f"{e.name} is passed by reference but was compiled as a local")
            return f"Ref({obj}, {attr!r})"
        if isinstance(e, A.Member):
            return f"Ref({self.lvalue_get(e.base)}, {e.key!r})"
        if isinstance(e, A.Index):
            arr = T.base_of(e.base.ty)
            return f"Ref({self.lvalue_get(e.base)}, {self.flat_index(e, arr)})"
        raise TypeError("not a reference")

    # ------------------------------------------------------------------ expressions
    def expr_as(self, e: A.Expr, ty: Optional[T.Type]) -> str:
        """`e` as stored into a variable of type `ty`: a promoted small-integer arithmetic
        result is narrowed here, as the C assignment matiec generates narrows it."""
        b = T.base_of(ty) if ty is not None else None
        if self.ring(e) is not None and isinstance(b, T.ElementaryType) and b.bits < 32 \
                and b.kind in ("sint", "uint", "bits"):
            return self.narrow(self.raw(e), ty, self.ranges.raw(e))     # the low bits of the exact result
        code = self.expr(e)
        if isinstance(e, (A.Binary, A.Unary)):
            code = self.narrow(code, ty, self.ranges.value(e))
        if _is_double(e) and ty is not None and T.base_of(ty) is T.REAL:
            code = F32Code(code)
        return code

    def narrow(self, code: str, ty: Optional[T.Type], rng: Optional[Range] = None) -> str:
        """Store a C int into a smaller integer variable: keep the low bits (unless `rng`
        shows the value fits)."""
        b = T.base_of(ty) if ty is not None else None
        if isinstance(b, T.ElementaryType) and b.kind in ("sint", "uint", "bits") and b.bits < 32:
            if within(rng, type_range(b)):
                return code
            if b.kind == "sint":
                return self._signed_wrap(code, b.min, b.max)
            return f"(({code}) & {b.max})"
        return code

    def expr(self, e: A.Expr) -> str:
        if isinstance(e, A.Literal):
            v = e.value
            tb = T.base_of(e.ty) if e.ty is not None else None
            if tb is T.REAL and isinstance(v, (int, float)) and not _is_double(e):
                v = T.to_f32(float(v))
            elif tb is not None and isinstance(tb, T.ElementaryType) and tb.is_real:
                v = float(v)
            elif tb is T.BOOL:
                v = bool(v)
            return self.const(v) if not isinstance(v, float) or math.isfinite(v) else self.bind(v, "_x")
        if isinstance(e, (A.Name, A.Member, A.Index)):
            if isinstance(e, A.Name) and isinstance(e.sym, EnumValue):
                return repr(e.sym.name)
            return self.lvalue_get(e)
        if isinstance(e, A.Unary):
            inner = self.expr(e.operand)
            b = T.base_of(e.ty)
            if e.op == "NOT":
                if b is T.BOOL:
                    return f"(not {inner})"
                if b.bits < 32:
                    # C's `~` on a promoted BYTE/WORD: an int (NOT 16#FF is -256 until stored)
                    return f"(~({inner}))"
                return f"(~({inner}) & {(1 << b.bits) - 1})"
            if b is T.REAL and _is_double(e):
                return f"(-({inner}))"
            if self.ring(e) is not None:
                return self.wrap(self.raw(e), _concrete(e.ty), self.ranges.raw(e))
            return self.wrap(f"-({inner})", _concrete(e.ty))
        if isinstance(e, A.Binary):
            return self.binary(e)
        if isinstance(e, A.Call):
            return self.call(e)
        raise TypeError(f"cannot compile {type(e).__name__}")

    _PYOP = {"=": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}

    def operator(self, op: str, arg_types: list, result: T.Type) -> str:
        """A module-level name bound to the standard library's implementation of `op`."""
        fn = stdlib.lookup_operator(op, [_lib_type(t) for t in arg_types], _lib_type(result))
        return self.bind(fn, "_op")

    def raw(self, e: A.Expr) -> str:
        """Code of `e` without the final wrap when it is an integer ring operation."""
        b = self.ring(e)
        if b is None:
            return self.expr(e)
        if isinstance(e, A.Unary):
            return f"(-{self._ring_child(e.operand, b)})"
        return f"({self._ring_child(e.left, b)} {e.op} {self._ring_child(e.right, b)})"

    def _ring_child(self, e: A.Expr, b: T.ElementaryType) -> str:
        return self.raw(e) if self.ring(e) is b else self.expr(e)

    def binary(self, e: A.Binary) -> str:
        if self.ring(e) is not None:
            return self.wrap(self.raw(e), _concrete(e.ty), self.ranges.raw(e))
        l, r = self.expr(e.left), self.expr(e.right)
        op = e.op
        lt = _concrete(e.left.ty)
        rt_ = _concrete(e.right.ty)
        ot = T.base_of(_concrete(e.operand_ty)) if e.operand_ty is not None else T.base_of(lt)
        rt = _concrete(e.ty)
        rb = T.base_of(rt)
        if op in self._PYOP:
            if isinstance(ot, T.StringType):
                return f"{self.operator(op, [lt, rt_], T.BOOL)}({l}, {r})"
            return f"({l} {self._PYOP[op]} {r})"
        if op in ("AND", "OR", "XOR"):
            if ot is T.BOOL or rb is T.BOOL:
                if op == "XOR":
                    return f"({l} != {r})"
                return f"({l} {'and' if op == 'AND' else 'or'} {r})"
            return f"({l} {'&' if op == 'AND' else '|' if op == 'OR' else '^'} {r})"
        if isinstance(rb, T.ElementaryType) and rb.kind in ("sint", "uint") and rb.bits < 32 \
                and op in ("/", "MOD"):
            # C computes SINT/INT/USINT/UINT operands as int: (a + b) / 2 does not overflow
            lt = rt_ = rt = T.DINT
        elif rb is T.REAL and _is_double(e):
            # a REAL operand mixed with a double (an untyped real literal): C double maths,
            # rounded to REAL only where it is stored or passed
            lt = rt_ = rt = T.LREAL
        if op == "MOD" and isinstance(rb, T.ElementaryType) and rb.kind in ("sint", "uint"):
            divisor = e.right.value if isinstance(e.right, A.Literal) else None
            if self.optimize and isinstance(divisor, int) and divisor > 0:
                # C's `%` by a positive constant, inline (a MOD in every scan is common):
                # the result takes the dividend's sign
                dividend = self.ranges.value(e.left)
                if dividend is not None and dividend[0] >= 0:
                    return f"({l} % {divisor})"
                t = f"_m{next(self.tmp)}"
                return f"(-(-{t} % {divisor}) if ({t} := {l}) < 0 else {t} % {divisor})"
        if op in ("/", "MOD") or (op == "*" and isinstance(rb, T.ElementaryType) and rb.kind == "time"):
            return f"{self.operator(op, [lt, rt_], rt)}({l}, {r})"
        return self.wrap(f"({l} {op} {r})", rt)

    def call(self, c: A.Call) -> str:
        en = next((a for a in c.args if a.key == "EN" and not a.is_output), None)
        eno = next((a for a in c.args if a.key == "ENO" and a.is_output), None)
        eno_ref = self.ref_to(eno.value, T.BOOL) if eno is not None else None
        if c.pou is not None:
            code = self.user_call(c, eno_ref)       # the function sets ENO itself
        else:
            code = self.std_call(c)
            if eno_ref is not None and en is None:
                code = f"({eno_ref}.set(True), {code})[1]"
        if en is None:
            return code
        default = self.const(T.default_value(c.ty)) if c.ty is not None else "None"
        if eno_ref is not None:
            if c.pou is None:
                code = f"({eno_ref}.set(True), {code})[1]"
            default = f"({eno_ref}.set(False), {default})[1]"
        return f"({code} if {self.expr(en.value)} else {default})"

    def user_call(self, c: A.Call, eno_ref: Optional[str] = None) -> str:
        """Every parameter positionally, in declaration order: a missing input gets its
        initial value, a missing output None (see `function`)."""
        pou: A.PouDecl = c.pou
        given = {id(a.param): a for a in c.args if a.key not in ("EN", "ENO") and a.param is not None}
        args = []
        for d in _params(pou):
            a = given.get(id(d))
            if a is None:
                args.append(self.init_code(d.init_value) if d.section == "VAR_INPUT" else "None")
            elif d.section == "VAR_INPUT":
                args.append(self.expr_as(a.value, d.ty))
            elif d.section == "VAR_OUTPUT" and a.negated:
                args.append(f"_NegRef({self.ref_to(a.value, d.ty)})")
            else:
                args.append(self.ref_to(a.value, d.ty))
        if eno_ref is not None:
            args.append(eno_ref)
        return f"{_pyname('FC', pou.name)}({', '.join(args)})"

    def std_call(self, c: A.Call) -> str:
        args = [a for a in c.args if a.key not in ("EN", "ENO")]
        names = c.bound_params if c.bound_params is not None else [a.key for a in args]
        arg_types = list(c.arg_types or [a.value.ty for a in args])
        arg_types = [_concrete(t) for t in arg_types]
        fn = stdlib.lookup(c.std, [_lib_type(t) for t in arg_types], _lib_type(c.ty))
        fname = self.bind(fn, f"_{c.std.lower()}")
        # arguments in the signature's order (formal calls may list them in any order)
        ordered = sorted(zip(names, args), key=lambda na: _param_rank(na[0]))
        types = dict(zip(names, arg_types))
        codes = [self.expr_as(a.value, types.get(n)) for n, a in ordered]
        if self.optimize:
            inline = _inline_conversion(c.std, arg_types, _concrete(c.ty), codes)
            if inline is None and c.std in ("SHL", "SHR") and len(ordered) == 2:
                inline = _inline_shift(c.std, arg_types[0], self.cu_const(ordered[1][1].value), codes[0])
            if inline is not None:
                return inline
        return f"{fname}({', '.join(codes)})"


def _inline_conversion(name: str, arg_types: list, result: Optional[T.Type], codes: list[str]) -> Optional[str]:
    """Conversions that need no code at run time (on the hot path of every scan): an integer
    widened to a type that holds all its values, BOOL to an integer, a <= 16-bit integer to
    REAL or a <= 32-bit one to LREAL (exact in the float). Everything else calls the library."""
    if len(codes) != 1 or len(arg_types) != 1 or name.count("_TO_") != 1:
        return None
    src_name, dst_name = name.split("_TO_")
    if src_name not in T.ELEMENTARY or dst_name not in T.ELEMENTARY:   # e.g. USINT_TO_BCD: not a cast
        return None
    src, dst = T.base_of(arg_types[0]), T.base_of(result) if result is not None else None
    if not isinstance(src, T.ElementaryType) or not isinstance(dst, T.ElementaryType):
        return None
    ints = ("sint", "uint", "bits")
    if src.kind in ints and dst.kind in ints and dst.min <= src.min and src.max <= dst.max:
        return codes[0]
    if src is T.BOOL and dst.kind in ints:
        return f"(1 if {codes[0]} else 0)"
    if src.kind in ints and dst.is_real and src.bits <= (16 if dst is T.REAL else 32):
        return f"float({codes[0]})"
    return None


def _inline_shift(name: str, ty: Optional[T.Type], count: Any, code: str) -> Optional[str]:
    """SHL / SHR of a bit string by a constant count, as the library computes it."""
    b = T.base_of(ty) if ty is not None else None
    if not isinstance(b, T.ElementaryType) or b.kind != "bits" or b is T.BOOL or \
            not isinstance(count, int) or isinstance(count, bool) or count < 0:
        return None
    count &= 63 if b.bits == 64 else 31        # x86 masks the count (stdlib._count_mask)
    if name == "SHR":
        return f"({code} >> {count})"
    return f"(({code} << {count}) & {(1 << b.bits) - 1})"


def located_attr(d: A.VarDecl) -> str:
    """The attribute holding an anonymous located variable (`AT %QW1 : WORD;`)."""
    loc = d.location
    return f"_AT_{loc.area}{loc.size}{'_'.join(map(str, loc.parts))}"


def _store_into(dst: Any, src: Any) -> None:
    """Assign an ARRAY or STRUCT value into existing storage, element by element."""
    if isinstance(dst, list):
        if dst and isinstance(dst[0], (list, T.StructValue)):
            for d, v in zip(dst, src):
                _store_into(d, v)
        else:
            dst[:] = src
        return
    fields = dst.__dict__
    for k, v in src.__dict__.items():
        cur = fields.get(k)
        if isinstance(cur, (list, T.StructValue)):
            _store_into(cur, v)
        else:
            fields[k] = v


def _register_source(program: CompiledProgram) -> None:
    """Put the annotated source in linecache (with no mtime, so checkcache keeps it) while the
    program lives: a Python traceback through compiled code shows the generated line and the
    ST file:line it comes from."""
    lines = program.annotated_source().splitlines(keepends=True)
    linecache.cache[program.filename] = (sum(map(len, lines)), None, lines, program.filename)
    weakref.finalize(program, linecache.cache.pop, program.filename, None)


def _is_double(e: A.Expr) -> bool:
    """Whether the C that matiec generates computes REAL expression `e` as a double: an
    untyped real literal is a C double constant (`0.1`, not `0.1f`), and C promotes the
    other float operand of + - * / to double. (So `r = 0.1` is FALSE for a REAL r even right after `r := 0.1`.)"""
    if isinstance(e, A.Literal):
        return e.kind == "real" and e.type_name is None
    if isinstance(e, A.Binary):
        if e.op in ("+", "-", "*", "/"):
            return _is_double(e.left) or _is_double(e.right)
        return False
    if isinstance(e, A.Unary):
        return e.op != "NOT" and _is_double(e.operand)
    return False


def _lib_type(t: Optional[T.Type]) -> Optional[T.Type]:
    """The type the standard library knows `t` by: literal types made concrete, and every
    STRING / STRING[n] (the checker makes one StringType per declaration) as T.STRING,
    since the library's functions do not depend on the declared length."""
    t = _concrete(t)
    if t is not None and isinstance(T.base_of(t), T.StringType):
        return T.STRING
    return t


def _param_rank(name: str) -> tuple:
    order = {"G": 0, "K": 0, "MN": 1, "IN": 2, "MX": 3, "N": 3, "L": 4, "P": 5}
    stem = name.rstrip("0123456789")
    num = name[len(stem):]
    return (order.get(stem, 2), int(num) if num else 0)


_LOCAL_MIN_USES = 2
"""A PROGRAM's or FB's variable named this often in its body is kept in a Python local
while the body runs (loaded on entry, stored back on exit)."""


class F32Code(str):
    """Code of a REAL result still to be rounded to single precision: it reads as
    `_f32(inner)`, and an assignment rounds it through the `_fa` float array instead."""

    inner: str

    def __new__(cls, inner: str) -> "F32Code":
        obj = super().__new__(cls, f"_f32({inner})")
        obj.inner = inner
        return obj


def _fb_key(fb: T.FBType) -> Any:
    """What identifies a FB type for fb_call: the standard block's name or the user POU."""
    return fb.pou.name if isinstance(fb.pou, FBSig) else id(fb.pou)


def _params(pou: A.PouDecl) -> list[A.VarDecl]:
    """A FUNCTION's parameters in declaration order: its positional signature."""
    return [d for d in pou.decls if d.section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT")]


class _Locals:
    """The local variables of one FUNCTION call (an object, so they can be passed by reference)."""


class _NegRef:
    """`NOT out => v`: stores the negation of an output."""

    __slots__ = ("ref",)

    def __init__(self, ref: Ref):
        self.ref = ref

    def set(self, value: Any) -> None:
        self.ref.set(not value)


class _NoRanges:
    """The plain path's ranges: nothing is known, so every wrap and narrowing is kept."""

    def value(self, e: A.Expr) -> Optional[Range]:
        return None

    def raw(self, e: A.Expr) -> Optional[Range]:
        return None


def _too_complex(exc: BaseException, origin: dict[int, LineInfo], cu: CheckedUnit) -> CompileError:
    """Python's own compiler refused the generated code (nesting past its parser's or
    compiler's limits): a diagnostic at the ST line, never an internal error. The checker's
    limits (plclab.frontend.check_limits) are set so that this does not happen; this is the
    wall behind them."""
    line = getattr(exc, "lineno", None)
    info = origin.get(line) if line else None
    if info is None:
        pou = next((p for p in cu.unit.pous), None)
        where = (pou.file, pou.line, 1) if pou is not None else ("", 1, 1)
    else:
        where = (info.file, info.line, 1)
    return CompileError([Diagnostic(*where, "this code nests too deeply for PLC Lab's compiler (Python refused it: "
                                            f"{getattr(exc, 'msg', None) or type(exc).__name__}); split the statement "
                                            "or move parts of it into functions")])


def compile_unit(checked: CheckedUnit, optimize: bool = True) -> CompiledProgram:
    """Compile a checked unit. `optimize=False` compiles every construct the plain way (no
    fast path, see Compiler): slower, and meant to compute exactly the same values."""
    return Compiler(checked, optimize).compile()
