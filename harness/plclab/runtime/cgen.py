"""Checked AST -> C: the native scan path's code (plclab.runtime.native builds and loads it).

The C is the C that matiec generates for the same ST, as the Python path (runtime/compiler.py)
emulates it: plain C operators on C types, so the C compiler gives C's semantics directly.
Compiled with -fwrapv (signed overflow wraps, as the Python path wraps) and -ffp-contract=off
(no fused multiply-add: every REAL / LREAL operation rounds once, as in Python):
  * SINT/INT/USINT/UINT/BYTE/WORD operands are promoted to int by C itself;
  * REAL is `float`, LREAL and untyped real literals `double` (so `r * 0.1` is double maths
    rounded to REAL where it is stored, as the Python path does);
  * TIME (and DATE, TOD, DT) are int64 nanoseconds, as the Python path holds them;
  * what the Python path checks (integer division by zero, INT_MIN / -1, array indexes, the
    loop watchdog) ends the scan with the same fault kind and message, at the same ST line.

State lives in C structs: one per PROGRAM, FUNCTION_BLOCK, STRUCT and standard block type,
with the same variable names as the Python classes (`f_` prefixed in C); the globals are one
struct. The layout (`Layout`) tells plclab.runtime.native how to mirror each struct as Python
objects that read and write the C memory, so every view of the runtime works unchanged.

What the backend does not cover raises `Unsupported` (naming the construct); the runtime then
runs the Python path: STRING and enumerated types, the standard blocks other than timers,
counters, edges and bistables, and standard functions outside `_STD_FUNCS` and conversions.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

from plclab.frontend import ast as A
from plclab.frontend.checked import CheckedUnit, EnumValue, LiteralType
from plclab.frontend.stdsigs import FBSig
from plclab.iec import types as T
from plclab.iec.address import SIZE_BITS, Address
from plclab.runtime.compiler import LineInfo, _is_double, _param_rank, _params, located_attr
from plclab.runtime.ranges import concrete as _concrete


class Unsupported(Exception):
    """A construct the C backend does not cover: the program runs on the Python path."""


# fault kinds the C code reports (index -> PlcFault kind)
FAULT_KINDS = ("", "division_by_zero", "division_overflow", "index_out_of_range", "watchdog")

_CTYPE = {
    "BOOL": "_Bool", "SINT": "int8_t", "INT": "int16_t", "DINT": "int32_t", "LINT": "int64_t",
    "USINT": "uint8_t", "UINT": "uint16_t", "UDINT": "uint32_t", "ULINT": "uint64_t",
    "BYTE": "uint8_t", "WORD": "uint16_t", "DWORD": "uint32_t", "LWORD": "uint64_t",
    "REAL": "float", "LREAL": "double", "TIME": "int64_t", "DATE": "int64_t",
    "TIME_OF_DAY": "int64_t", "DATE_AND_TIME": "int64_t",
}

STD_FBS = ("TON", "TOF", "TP", "R_TRIG", "F_TRIG", "SR", "RS", "CTU", "CTD", "CTUD")

# Field lists of the standard blocks (name, type name), as plclab.runtime.stdfb declares them.
_STD_FIELDS = {
    "SR": ("S1 BOOL", "R BOOL", "Q1 BOOL"),
    "RS": ("S BOOL", "R1 BOOL", "Q1 BOOL"),
    "R_TRIG": ("CLK BOOL", "Q BOOL", "M BOOL"),
    "F_TRIG": ("CLK BOOL", "Q BOOL", "M BOOL"),
    "CTU": ("CU BOOL", "R BOOL", "PV INT", "Q BOOL", "CV INT"),
    "CTD": ("CD BOOL", "LD BOOL", "PV INT", "Q BOOL", "CV INT"),
    "CTUD": ("CU BOOL", "CD BOOL", "R BOOL", "LD BOOL", "PV INT", "QU BOOL", "QD BOOL", "CV INT"),
    "TON": ("IN BOOL", "PT TIME", "Q BOOL", "ET TIME", "STATE SINT", "PREV_IN BOOL",
            "CURRENT_TIME TIME", "START_TIME TIME"),
}
_STD_FIELDS["TOF"] = _STD_FIELDS["TP"] = _STD_FIELDS["TON"]
_STD_NESTED = {"CTU": ("CU_T",), "CTD": ("CD_T",), "CTUD": ("CD_T", "CU_T")}

_STD_BODIES = {
    "SR": "s->f_Q1 = s->f_S1 || (!s->f_R && s->f_Q1);",
    "RS": "s->f_Q1 = !s->f_R1 && (s->f_S || s->f_Q1);",
    "R_TRIG": "_Bool clk = s->f_CLK; s->f_Q = clk && !s->f_M; s->f_M = clk;",
    "F_TRIG": "_Bool clk = s->f_CLK; s->f_Q = !clk && s->f_M; s->f_M = clk;",
    "CTU": """s->f_CU_T.f_CLK = s->f_CU; std_R_TRIG(&s->f_CU_T);
    if (s->f_R) s->f_CV = 0;
    else if (s->f_CU_T.f_Q && s->f_CV < s->f_PV) s->f_CV += 1;
    s->f_Q = s->f_CV >= s->f_PV;""",
    "CTD": """s->f_CD_T.f_CLK = s->f_CD; std_R_TRIG(&s->f_CD_T);
    if (s->f_LD) s->f_CV = s->f_PV;
    else if (s->f_CD_T.f_Q && s->f_CV > 0) s->f_CV -= 1;
    s->f_Q = s->f_CV <= 0;""",
    "CTUD": """s->f_CD_T.f_CLK = s->f_CD; std_R_TRIG(&s->f_CD_T);
    s->f_CU_T.f_CLK = s->f_CU; std_R_TRIG(&s->f_CU_T);
    if (s->f_R) s->f_CV = 0;
    else if (s->f_LD) s->f_CV = s->f_PV;
    else if (!(s->f_CU_T.f_Q && s->f_CD_T.f_Q)) {
        if (s->f_CU_T.f_Q && s->f_CV < s->f_PV) s->f_CV += 1;
        else if (s->f_CD_T.f_Q && s->f_CV > 0) s->f_CV -= 1;
    }
    s->f_QU = s->f_CV >= s->f_PV; s->f_QD = s->f_CV <= 0;""",
    "TON": """int64_t now = s->f_CURRENT_TIME = c->now;
    if (!s->f_IN) { s->f_ET = 0; s->f_Q = 0; s->f_STATE = 0; s->f_PREV_IN = 0; return; }
    if (s->f_STATE == 0 && !s->f_PREV_IN) { s->f_STATE = 1; s->f_Q = 0; s->f_START_TIME = now; }
    else if (s->f_STATE == 1) {
        if (s->f_START_TIME + s->f_PT <= now) { s->f_STATE = 2; s->f_Q = 1; s->f_ET = s->f_PT; }
        else s->f_ET = now - s->f_START_TIME;
    }
    s->f_PREV_IN = 1;""",
    "TOF": """int64_t now = s->f_CURRENT_TIME = c->now;
    if (s->f_IN) { s->f_ET = 0; s->f_STATE = 0; s->f_Q = 1; s->f_PREV_IN = 1; return; }
    if (s->f_STATE == 0 && s->f_PREV_IN) { s->f_STATE = 1; s->f_START_TIME = now; }
    else if (s->f_STATE == 1) {
        if (s->f_START_TIME + s->f_PT <= now) { s->f_STATE = 2; s->f_ET = s->f_PT; }
        else s->f_ET = now - s->f_START_TIME;
    }
    s->f_Q = s->f_STATE == 1; s->f_PREV_IN = 0;""",
    "TP": """int64_t now = s->f_CURRENT_TIME = c->now;
    if (s->f_STATE == 0 && !s->f_PREV_IN && s->f_IN) { s->f_STATE = 1; s->f_Q = 1; s->f_START_TIME = now; }
    else if (s->f_STATE == 1) {
        if (s->f_START_TIME + s->f_PT <= now) { s->f_STATE = 2; s->f_Q = 0; s->f_ET = s->f_PT; }
        else s->f_ET = now - s->f_START_TIME;
    }
    if (s->f_STATE == 2 && !s->f_IN) { s->f_ET = 0; s->f_STATE = 0; }
    s->f_PREV_IN = s->f_IN;""",
}

_MAX_LOCAL_ELEMENTS = 8192
"""A FUNCTION's local arrays live on the C stack: a bigger one runs on the Python path."""

_MATH1 = {"SQRT": "sqrt", "SIN": "sin", "COS": "cos", "TAN": "tan", "ASIN": "asin", "ACOS": "acos",
          "ATAN": "atan", "LN": "log", "LOG": "log10", "EXP": "exp"}

_PRELUDE = r"""
#include <stdint.h>
#include <string.h>
#include <math.h>
#include <setjmp.h>
#include <time.h>

typedef struct Ctx {
    jmp_buf jb;
    int64_t now;
    double watchdog, started;
    int64_t loops;
    State *st;
} Ctx;

static double wall(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + t.tv_nsec * 1e-9; }

static void fault(Ctx *c, int kind, int site, int64_t a, int64_t b, int64_t d) {
    c->st->fault_kind = kind; c->st->fault_site = site;
    c->st->fault_a = a; c->st->fault_b = b; c->st->fault_c = d;
    longjmp(c->jb, 1);
}
static inline void loop_check(Ctx *c, int site) {
    if (++c->loops % 4096 == 0 && wall() - c->started > c->watchdog) fault(c, 4, site, 0, 0, 0);
}
static inline int64_t bound(Ctx *c, int64_t i, int64_t lo, int64_t hi, int site) {
    if (lo <= i && i <= hi) return i - lo;
    fault(c, 3, site, i, lo, hi); return 0;
}
static inline int32_t div_i32(Ctx *c, int32_t a, int32_t b, int site) {
    if (b == 0) fault(c, 1, site, 0, 0, 0);
    if (b == -1 && a == INT32_MIN) fault(c, 2, site, a, 32, 0);
    return a / b;
}
static inline int64_t div_i64(Ctx *c, int64_t a, int64_t b, int site) {
    if (b == 0) fault(c, 1, site, 0, 0, 0);
    if (b == -1 && a == INT64_MIN) fault(c, 2, site, a, 64, 0);
    return a / b;
}
static inline uint32_t div_u32(Ctx *c, uint32_t a, uint32_t b, int site) {
    if (b == 0) fault(c, 1, site, 0, 0, 0);
    return a / b;
}
static inline uint64_t div_u64(Ctx *c, uint64_t a, uint64_t b, int site) {
    if (b == 0) fault(c, 1, site, 0, 0, 0);
    return a / b;
}
static inline int32_t mod_i32(Ctx *c, int32_t a, int32_t b, int site) {
    if (b == 0) return 0;
    if (b == -1 && a == INT32_MIN) fault(c, 2, site, a, 32, 1);
    return a % b;
}
static inline int64_t mod_i64(Ctx *c, int64_t a, int64_t b, int site) {
    if (b == 0) return 0;
    if (b == -1 && a == INT64_MIN) fault(c, 2, site, a, 64, 1);
    return a % b;
}
static inline uint32_t mod_u32(uint32_t a, uint32_t b) { return b == 0 ? 0 : a % b; }
static inline uint64_t mod_u64(uint64_t a, uint64_t b) { return b == 0 ? 0 : a % b; }
static inline int64_t cvtt64(double x) {
    if (x != x || !(x >= -9223372036854775808.0 && x < 9223372036854775808.0)) return INT64_MIN;
    return (int64_t)x;
}
static inline int64_t real_round(double x) {
    if (isfinite(x) && fmod(x, 1.0) == 0.0) return cvtt64(x) / 2 * 2;
    return cvtt64(x);
}
static inline int64_t real_to_sint(double x) { return x >= 0 ? real_round(x + 0.5) : real_round(x - 0.5); }
static inline uint64_t real_to_uint(double x) { return x >= 0 ? (uint64_t)real_round(x + 0.5) : 0; }
static inline int64_t real_to_time(double x) {
    int64_t sec = cvtt64(x);
    return (int64_t)((uint64_t)sec * 1000000000u + (uint64_t)cvtt64((x - (double)sec) * 1e9));
}
static inline double time_to_real(int64_t t) {
    int64_t sec = t / 1000000000; int64_t nsec = t - sec * 1000000000;
    return (double)sec + (double)nsec / 1e9;
}
static inline double c_pow(double x, double y) { return pow(x, y); }
"""


@dataclass
class Field:
    """One variable of a C struct, for the Python mirror: `kind` is 'scalar', 'array',
    'struct' (a STRUCT value), 'fb' (a block instance) or 'ref' (a VAR_IN_OUT pointer)."""

    name: str                       # the Python attribute (upper-case key)
    cname: str                      # the C member
    kind: str
    ty: Any = None                  # elementary type (scalar), element type (array)
    sub: Optional[str] = None       # struct / fb: the C struct name; array: the element's
    sub_kind: str = "scalar"        # array: the element's kind
    size: int = 0                   # array: element count


@dataclass
class Layout:
    """A C struct as the Python mirror sees it."""

    cname: str
    fields: list[Field]
    st_name: str = ""               # PROGRAM / FB: its ST name (the Python class's _ST_NAME)
    kind: str = "struct"            # 'program', 'fb', 'std', 'struct', 'globals'


@dataclass
class CProgram:
    """The generated C and what the runtime needs to load and mirror it."""

    source: str
    cdef: str
    layouts: dict[str, Layout]
    run_functions: dict[str, str]              # PROGRAM key -> the C function of its body
    program_structs: dict[str, str]            # PROGRAM key -> C struct name
    sites: list[Optional[LineInfo]] = field(default_factory=list)
    instances: list[str] = field(default_factory=list)      # State.inst0.. : their PROGRAM keys
    io_bindings: Any = None         # ([(area, index)] of io_in's raw, the same of io_out's)


def _b(ty: Any) -> Any:
    return T.base_of(_concrete(ty)) if ty is not None else None


class CGen:
    def __init__(self, checked: CheckedUnit):
        self.cu = checked
        self.layouts: dict[str, Layout] = {}
        self.order: list[str] = []                  # struct definitions in dependency order
        self.struct_names: dict[int, str] = {}      # id(StructType) -> C name
        self.defs: dict[str, str] = {}              # C struct name -> its typedef
        self.lines: list[str] = []
        self.sites: list[Optional[LineInfo]] = [None]
        self.tmp = 0
        self.pou: Optional[A.PouDecl] = None
        self.in_function = False
        self.fn_locals: dict[int, str] = {}
        self.loop_labels: list[Optional[str]] = []
        self.protos: list[str] = []
        self.bodies: list[str] = []

    # ------------------------------------------------------------------ types
    def ctype(self, ty: Any, where: Any = None) -> str:
        b = _b(ty)
        if isinstance(b, T.ElementaryType):
            c = _CTYPE.get(b.name)
            if c is None:
                raise Unsupported(f"type {b.name}")
            return c
        if isinstance(b, T.StructType):
            return self.struct_type(b)
        if isinstance(b, T.FBType):
            return self.fb_type(b)
        raise Unsupported(f"type {getattr(b, 'name', type(b).__name__)}")

    def struct_type(self, st: T.StructType) -> str:
        name = self.struct_names.get(id(st))
        if name is not None:
            return name
        name = f"S{len(self.struct_names)}_{_ident(st.name)}"
        self.struct_names[id(st)] = name
        fields = [self.field(k, t) for k, (t, _i) in st.fields.items()]
        self.add_struct(name, fields, st.name, "struct")
        return name

    def fb_type(self, fb: T.FBType) -> str:
        if isinstance(fb.pou, FBSig):
            return self.std_type(fb.pou.name)
        pou = fb.pou
        name = f"FB_{pou.key}"
        if name not in self.layouts:
            self.pou_struct(pou, name, "fb")
        return name

    def std_type(self, n: str) -> str:
        if n not in STD_FBS:
            raise Unsupported(f"standard block {n}")
        name = f"STD_{n}"
        if name not in self.layouts:
            if n in _STD_NESTED:
                self.std_type("R_TRIG")
            fields = [self.field(*p.split()) for p in _STD_FIELDS[n]]
            fields += [Field(k, f"f_{k}", "fb", sub="STD_R_TRIG") for k in _STD_NESTED.get(n, ())]
            fields += [Field("EN", "f_EN", "scalar", T.BOOL), Field("ENO", "f_ENO", "scalar", T.BOOL)]
            self.add_struct(name, fields, n, "std")
        return name

    def field(self, key: str, ty: Any) -> Field:
        if isinstance(ty, str):
            ty = T.ELEMENTARY[ty]
        b = _b(ty)
        cname = f"f_{key}"
        if isinstance(b, T.ArrayType):
            eb = _b(b.elem)
            if isinstance(eb, T.ArrayType):
                raise Unsupported("arrays of arrays")
            ec = self.ctype(b.elem)
            kind = "struct" if isinstance(eb, T.StructType) else "fb" if isinstance(eb, T.FBType) else "scalar"
            return Field(key, cname, "array", eb, ec if kind != "scalar" else None, kind, b.size)
        c = self.ctype(ty)
        if isinstance(b, T.StructType):
            return Field(key, cname, "struct", b, c)
        if isinstance(b, T.FBType):
            return Field(key, cname, "fb", b, c)
        return Field(key, cname, "scalar", b)

    def decl_of(self, f: Field) -> str:
        if f.kind == "array":
            et = _CTYPE[f.ty.name] if f.sub_kind == "scalar" else f.sub
            return f"{et} {f.cname}[{f.size}];"
        if f.kind == "ref":
            return f"{f.sub} *{f.cname};"
        if f.kind in ("struct", "fb"):
            return f"{f.sub} {f.cname};"
        return f"{_CTYPE[f.ty.name]} {f.cname};"

    def add_struct(self, name: str, fields: list[Field], st_name: str, kind: str) -> None:
        self.layouts[name] = Layout(name, fields, st_name, kind)
        body = "".join(f"    {self.decl_of(f)}\n" for f in fields) or "    char f__empty;\n"
        self.defs[name] = f"typedef struct {name} {{\n{body}}} {name};\n"
        self.order.append(name)

    def pou_struct(self, pou: A.PouDecl, name: str, kind: str) -> None:
        fields = []
        self.layouts[name] = Layout(name, [], pou.name, kind)      # placeholder against cycles
        for d in pou.decls:
            if d.section == "VAR_EXTERNAL":
                continue
            if d.edge is not None:
                raise Unsupported("R_EDGE / F_EDGE inputs")
            attr = d.key if d.name else located_attr(d)
            if d.section == "VAR_IN_OUT":
                b = _b(d.ty)
                if isinstance(b, T.ArrayType):
                    sub = self.ctype(b.elem)
                else:
                    sub = self.ctype(d.ty)
                fields.append(Field(attr, f"f_{attr}", "ref", b, sub))
                continue
            fields.append(self.field(attr, d.ty))
        fields.append(Field("ENO", "f_ENO", "scalar", T.BOOL))
        fields.append(Field("EN", "f_EN", "scalar", T.BOOL))
        del self.layouts[name]
        self.add_struct(name, fields, pou.name, kind)

    # ------------------------------------------------------------------ driver
    def generate(self) -> CProgram:
        cu = self.cu
        self.check_types()
        gfields = []
        for key, d in cu.globals.items():
            if d.ty is None:
                continue
            attr = key if not key.startswith("%") else located_attr(d)
            gfields.append(self.field(attr, d.ty))
        pous = [p for p in cu.unit.pous if cu.pous.get(p.key) is p]
        for p in pous:
            if p.kind == "FUNCTION_BLOCK":
                self.fb_type(T.FBType(p.name, p))
        program_structs = {}
        for p in pous:
            if p.kind == "PROGRAM":
                name = f"PRG_{p.key}"
                self.pou_struct(p, name, "program")
                program_structs[p.key] = name
        self.add_struct("GLOBALS", gfields, "", "globals")
        # code
        for n in self.order:
            lay = self.layouts[n]
            if lay.kind == "std":
                self.protos.append(f"static void std_{lay.st_name}({n} *s);" if lay.st_name in ("SR", "RS", "R_TRIG", "F_TRIG", "CTU", "CTD", "CTUD")
                                   else f"static void std_{lay.st_name}(Ctx *c, {n} *s);")
                self.bodies.append(self.std_body(lay))
        for p in pous:
            if p.kind == "FUNCTION":
                self.function(p)
        for p in pous:
            if p.kind == "FUNCTION_BLOCK":
                self.pou_body(p, f"FB_{p.key}")
        run_functions = {}
        for p in pous:
            if p.kind == "PROGRAM":
                self.pou_body(p, f"PRG_{p.key}")
                run_functions[p.key] = f"body_PRG_{p.key}"
        instances = self._instance_keys()
        types = "".join(self.defs[n] for n in self.order)
        inst_fields = "".join(f"    PRG_{k} inst{i};\n" for i, k in enumerate(instances))
        state = (f"typedef struct State {{\n    GLOBALS g;\n{inst_fields}    int32_t fault_kind, fault_site;\n"
                 f"    int64_t fault_a, fault_b, fault_c;\n}} State;\n")
        io_src, io_bindings = self.io_functions(instances)
        self.bodies.append(io_src)
        runs = "".join(f"    if (periods[{i}] == 1 || tick % periods[{i}] == 0) body_PRG_{k}(&c, &st->inst{i});\n"
                       for i, k in enumerate(instances))
        nin = len(io_bindings[0])
        params = "".join(f", int64_t in{i}" for i in range(nin))
        gather = ", ".join(f"in{i}" for i in range(nin)) or "0"
        self.bodies.append(
            f"void io_in(State *st{params}) {{\n"
            f"    const int64_t raw[{max(1, nin)}] = {{{gather}}};\n"
            "    copy_in(st, raw);\n}\n")
        sig = "int scan(State *st, int64_t now, double watchdog, int64_t tick, const int64_t *periods)"
        self.bodies.append(
            sig + " {\n"
            "    Ctx c; c.now = now; c.watchdog = watchdog; c.started = wall(); c.loops = 0; c.st = st;\n"
            "    st->fault_kind = 0;\n"
            "    if (setjmp(c.jb)) return st->fault_kind;\n" + runs +
            "    return 0;\n}\n")
        nout = max(1, len(io_bindings[1]))
        quiet_sig = ("int64_t scan_quiet(State *st, int64_t tick, int64_t dt, double watchdog, const int64_t *periods, "
                     "int64_t n, const int64_t *raw_in, uint64_t *raw_out, char **watch, const int64_t *sizes, "
                     "int64_t nwatch, char *snap, int32_t *rc)")
        self.bodies.append(
            "/* up to n scans (ticks tick.., at tick * dt ns) with the same raw inputs, while the\n"
            "   outputs (raw_out: the last scan's) and the watched memory (copied into snap first)\n"
            "   stay as they were; returns the scans run, the last one the first that changed them\n"
            "   or faulted (*rc: its fault kind) */\n"
            + quiet_sig + " {\n"
            f"    uint64_t out[{nout}] = {{0}};\n"
            "    *rc = 0;\n"
            "    char *at = snap;\n"
            "    for (int64_t w = 0; w < nwatch; w++) { memcpy(at, watch[w], (size_t)sizes[w]); at += sizes[w]; }\n"
            "    for (int64_t i = 0; i < n; i++) {\n"
            "        copy_in(st, raw_in);\n"
            "        *rc = scan(st, (tick + i) * dt, watchdog, tick + i, periods);\n"
            "        if (*rc) return i + 1;\n"
            "        io_out(st, out);\n"
            "        int changed = memcmp(out, raw_out, sizeof out) != 0;\n"
            "        if (changed) memcpy(raw_out, out, sizeof out);\n"
            "        char *s = snap;\n"
            "        for (int64_t w = 0; w < nwatch; w++) {\n"
            "            if (memcmp(watch[w], s, (size_t)sizes[w]) != 0) { memcpy(s, watch[w], (size_t)sizes[w]); changed = 1; }\n"
            "            s += sizes[w];\n"
            "        }\n"
            "        if (changed) return i + 1;\n"
            "    }\n"
            "    return n;\n}\n")
        exports = (sig + ";\n" + f"void io_in(State *st{params});\n"
                   "void io_out(State *st, uint64_t *raw);\n" + quiet_sig + ";\n")
        cdef = types + state + exports
        source = ("/* generated by plclab from ST (plclab check --emit-c); do not edit */\n"
                  + "#include <stdint.h>\n" + types + state + _PRELUDE
                  + "\n".join(self.protos) + "\n\n" + "\n".join(self.bodies))
        return CProgram(source, cdef, self.layouts, run_functions, program_structs, self.sites,
                        instances, io_bindings)

    def _instance_keys(self) -> list[str]:
        """The PROGRAM key of each instance, in the order the PLC makes them
        (PLC._setup_instances): the RESOURCE's, or every PROGRAM without a CONFIGURATION."""
        config = self.cu.config
        if config is not None:
            return [p.pou.key for res in config.resources for p in res.programs if p.pou is not None]
        return [p.key for p in self.cu.unit.pous if p.kind == "PROGRAM" and self.cu.pous.get(p.key) is p]

    def io_functions(self, instances: list[str]) -> tuple[str, list[tuple[str, int]]]:
        """copy_in (io_in) / io_out: the located variables from / to raw image values, in the
        order of PLC._bind_located, converted as PLC._compile_io converts them."""
        located = []
        for key, d in self.cu.globals.items():
            if d.location is not None and d.ty is not None:
                attr = key if not key.startswith("%") else located_attr(d)
                located.append((d, f"st->g.f_{attr}"))
        for i, k in enumerate(instances):
            for d in self.cu.pous[k].decls:
                if d.location is not None and d.ty is not None:
                    attr = d.key if d.name else located_attr(d)
                    located.append((d, f"st->inst{i}.f_{attr}"))
        ins, outs, bindings_in, bindings_out = [], [], [], []
        for d, lv in located:
            loc = d.location
            a = Address(loc.area, loc.size, loc.parts[0], loc.parts[1] if loc.size == "X" else None)
            b = _b(d.ty)
            if not isinstance(b, T.ElementaryType):
                raise Unsupported("located variables of derived types")
            bits = a.bits
            mask = "UINT64_MAX" if bits == 64 else f"UINT64_C({(1 << bits) - 1})"
            if a.area[0] == "I":
                raw = f"raw[{len(bindings_in)}]"
                bindings_in.append((a.area, a.index))
                ins.append(f"    {lv} = {_from_raw(b, raw, mask)};")
            else:
                raw = f"raw[{len(bindings_out)}]"
                bindings_out.append((a.area, a.index))
                outs.append(f"    {raw} = {_to_raw(b, lv, mask, SIZE_BITS[a.area[1]])};")
        src = ("static void copy_in(State *st, const int64_t *raw) {\n" + "\n".join(ins) + "\n}\n"
               "void io_out(State *st, uint64_t *raw) {\n" + "\n".join(outs) + "\n}\n")
        return src, (bindings_in, bindings_out)

    def check_types(self) -> None:
        """Refuse early what the backend does not cover anywhere in the program."""
        for p in self.cu.unit.pous:
            for d in p.decls:
                self._check_type(d.ty)
            if p.kind == "FUNCTION" and p.ret_decl is not None:
                self._check_type(p.ret_decl.ty)
        for d in self.cu.globals.values():
            self._check_type(d.ty)

    def _check_type(self, ty: Any) -> None:
        b = _b(ty)
        if isinstance(b, (T.StringType, T.EnumType)):
            raise Unsupported(f"{'STRING' if isinstance(b, T.StringType) else 'enumerated'} variables")
        if isinstance(b, T.ArrayType):
            self._check_type(b.elem)
        if isinstance(b, T.StructType):
            for t, _i in b.fields.values():
                self._check_type(t)

    def site(self, node: Any) -> int:
        if node is None or not getattr(node, "line", 0):
            return 0
        self.sites.append(LineInfo(node.file, node.line, self.pou.name if self.pou else "CONFIGURATION"))
        return len(self.sites) - 1

    def fresh(self, stem: str = "t") -> str:
        self.tmp += 1
        return f"_{stem}{self.tmp}"

    # ------------------------------------------------------------------ bodies
    def std_body(self, lay: Layout) -> str:
        n = lay.st_name
        sig = f"static void std_{n}({lay.cname} *s)" if n in ("SR", "RS", "R_TRIG", "F_TRIG", "CTU", "CTD", "CTUD") \
            else f"static void std_{n}(Ctx *c, {lay.cname} *s)"
        return f"{sig} {{\n    {_STD_BODIES[n]}\n}}\n"

    def emit(self, ind: int, text: str) -> None:
        self.lines.append("    " * ind + text)

    def pou_body(self, pou: A.PouDecl, sname: str) -> None:
        self.pou, self.in_function, self.fn_locals = pou, False, {}
        self.lines = []
        for d in pou.decls:
            if d.section == "VAR_TEMP":
                attr = d.key if d.name else located_attr(d)
                self.init_value(1, f"self->f_{attr}", d.ty, d.init_value if d.init_value is not None
                                else T.default_value(d.ty), d)
        if pou.eno_decl is not None:
            self.emit(1, "self->f_ENO = 1;")
        self.block(pou.body, 1)
        self.protos.append(f"static void body_{sname}(Ctx *c, {sname} *self);")
        self.bodies.append(f"static void body_{sname}(Ctx *c, {sname} *self) {{\n" + "\n".join(self.lines) + "\n}\n")

    def function(self, pou: A.PouDecl) -> None:
        self.pou, self.in_function = pou, True
        self.lines = []
        self.fn_locals = {}
        params = _params(pou)
        sig = ["Ctx *c"]
        for d in params:
            b = _b(d.ty)
            if isinstance(b, T.FBType):
                raise Unsupported("function block parameters of functions")
            if isinstance(b, T.ArrayType):
                sig.append(f"{self.ctype(b.elem)} *p_{d.key}")
                self.fn_locals[id(d)] = f"p_{d.key}"
            elif isinstance(b, T.StructType):
                sig.append(f"{self.ctype(d.ty)} *p_{d.key}")
                self.fn_locals[id(d)] = f"(*p_{d.key})"
            elif d.section == "VAR_INPUT":
                sig.append(f"{self.ctype(d.ty)} v_{d.key}")
                self.fn_locals[id(d)] = f"v_{d.key}"
            elif d.section == "VAR_IN_OUT":
                sig.append(f"{self.ctype(d.ty)} *p_{d.key}")
                self.fn_locals[id(d)] = f"(*p_{d.key})"
            else:   # VAR_OUTPUT: a local, copied out at the end (NULL: the call did not take it)
                sig.append(f"{self.ctype(d.ty)} *p_{d.key}")
                self.fn_locals[id(d)] = f"v_{d.key}"
        for d in pou.decls:
            if d.section in ("VAR", "VAR_TEMP") and d.name:
                b = _b(d.ty)
                if isinstance(b, T.FBType):
                    raise Unsupported("function block instances inside functions")
                if isinstance(b, T.ArrayType):
                    if b.size > _MAX_LOCAL_ELEMENTS:      # the C stack is small; Python's lists are not
                        raise Unsupported("ARRAY variables of more than 8192 elements in functions")
                    self.emit(1, f"{self.ctype(b.elem)} v_{d.key}[{b.size}];")
                else:
                    self.emit(1, f"{self.ctype(d.ty)} v_{d.key};")
                self.fn_locals[id(d)] = f"v_{d.key}"
        for d in params:
            if d.section == "VAR_OUTPUT":
                b = _b(d.ty)
                if isinstance(b, (T.ArrayType, T.StructType)):
                    raise Unsupported("ARRAY / STRUCT outputs of functions")
                self.emit(1, f"{self.ctype(d.ty)} v_{d.key};")
                self.init_value(1, f"v_{d.key}", d.ty, d.init_value if d.init_value is not None
                                else T.default_value(d.ty), d)
        for d in pou.decls:
            if d.section in ("VAR", "VAR_TEMP") and d.name:
                self.init_value(1, f"v_{d.key}", d.ty, d.init_value if d.init_value is not None
                                else T.default_value(d.ty), d)
        ret = pou.ret_decl
        rtype = self.ctype(ret.ty) if ret is not None and ret.ty is not None else "void"
        if ret is not None and ret.ty is not None:
            if isinstance(_b(ret.ty), (T.ArrayType, T.StructType)):
                raise Unsupported("functions returning ARRAY / STRUCT")
            self.emit(1, f"{rtype} _ret;")
            self.init_value(1, "_ret", ret.ty, ret.init_value if ret.init_value is not None
                            else T.default_value(ret.ty), pou)
            self.fn_locals[id(ret)] = "_ret"
        if pou.eno_decl is not None:
            self.emit(1, "_Bool v_ENO = 1;")
            self.fn_locals[id(pou.eno_decl)] = "v_ENO"
        self.block(pou.body, 1)
        self.emit(0, "fc_exit:")
        for d in params:
            if d.section == "VAR_OUTPUT":
                self.emit(1, f"if (p_{d.key}) *p_{d.key} = v_{d.key};")
        self.emit(1, "return _ret;" if rtype != "void" else "return;")
        proto = f"static {rtype} FC_{pou.key}({', '.join(sig)})"
        self.protos.append(proto + ";")
        self.bodies.append(proto + " {\n" + "\n".join(self.lines) + "\n}\n")

    def init_value(self, ind: int, lv: str, ty: Any, value: Any, node: Any) -> None:
        """C statements giving storage `lv` of type `ty` the runtime value `value`."""
        b = _b(ty)
        if isinstance(b, T.ArrayType):
            for i, v in enumerate(value):
                self.init_value(ind, f"{lv}[{i}]", b.elem, v, node)
            return
        if isinstance(b, T.StructType):
            for k, (t, _i) in b.fields.items():
                self.init_value(ind, f"{lv}.f_{k}", t, getattr(value, k), node)
            return
        if isinstance(b, T.FBType):
            raise Unsupported("function block instances as temporaries")
        self.emit(ind, f"{lv} = {self.const(value, b)};")

    # ------------------------------------------------------------------ statements
    def block(self, body: list, ind: int) -> None:
        for s in body:
            self.stmt(s, ind)

    def stmt(self, s: Any, ind: int) -> None:
        if isinstance(s, A.Assign):
            self.assign(s.target, s.value, ind)
        elif isinstance(s, A.CallStmt):
            self.fb_call(s, ind)
        elif isinstance(s, A.If):
            for i, (cond, body) in enumerate(s.branches):
                self.emit(ind, f"{'if' if i == 0 else '} else if'} ({self.expr(cond)}) {{")
                self.block(body, ind + 1)
            if s.else_body is not None:
                self.emit(ind, "} else {")
                self.block(s.else_body, ind + 1)
            self.emit(ind, "}")
        elif isinstance(s, A.Case):
            sel = self.fresh("c")
            self.emit(ind, "{")
            self.emit(ind + 1, f"{self.ctype(s.selector.ty)} {sel} = {self.expr(s.selector)};")
            first = True
            for br in s.branches:
                conds = []
                for lab in br.labels:
                    if lab.hi is not None and lab.hi_value != lab.lo_value:
                        conds.append(f"({self.const(lab.lo_value, None)} <= {sel} && {sel} <= {self.const(lab.hi_value, None)})")
                    else:
                        conds.append(f"{sel} == {self.const(lab.lo_value, None)}")
                self.emit(ind + 1, f"{'if' if first else '} else if'} ({' || '.join(conds) or '0'}) {{")
                first = False
                self.block(br.body, ind + 2)
            if s.else_body is not None:
                self.emit(ind + 1, "if (1) {" if first else "} else {")
                first = False
                self.block(s.else_body, ind + 2)
            if not first:
                self.emit(ind + 1, "}")
            self.emit(ind, "}")
        elif isinstance(s, A.For):
            self.for_(s, ind)
        elif isinstance(s, A.While):
            self.emit(ind, f"while ({self.expr(s.cond)}) {{")
            self.emit(ind + 1, f"loop_check(c, {self.site(s)});")
            self.loop_labels.append(None)
            self.block(s.body, ind + 1)
            self.loop_labels.pop()
            self.emit(ind, "}")
        elif isinstance(s, A.Repeat):
            self.emit(ind, "do {")
            self.emit(ind + 1, f"loop_check(c, {self.site(s)});")
            self.loop_labels.append(None)
            self.block(s.body, ind + 1)
            self.loop_labels.pop()
            self.emit(ind, f"}} while (!({self.expr(s.cond)}));")
        elif isinstance(s, A.Exit):
            self.emit(ind, "break;")
        elif isinstance(s, A.Continue):
            label = self.loop_labels[-1] if self.loop_labels else None
            self.emit(ind, f"goto {label};" if label else "continue;")
        elif isinstance(s, A.Return):
            self.emit(ind, "goto fc_exit;" if self.in_function else "return;")
        elif isinstance(s, A.Empty):
            pass
        else:
            raise Unsupported(type(s).__name__)

    def for_(self, s: A.For, ind: int) -> None:
        var = self.lvalue(s.var)
        vt = self.ctype(s.var.ty)
        self.emit(ind, f"{var} = ({vt})({self.expr(s.start)});")
        label = self.fresh("next")
        self.emit(ind, "for (;;) {")
        end = self.expr(s.end)
        if s.step is None:
            test, step = f"{var} <= {end}", "1"
        else:
            step = self.expr(s.step)
            test = f"(({step}) > 0 ? {var} <= {end} : {var} >= {end})"
        self.emit(ind + 1, f"if (!({test})) break;")
        self.emit(ind + 1, f"loop_check(c, {self.site(s)});")
        self.loop_labels.append(label)
        self.block(s.body, ind + 1)
        self.loop_labels.pop()
        self.emit(ind, f"{label}:")
        self.emit(ind + 1, f"{var} = ({vt})({var} + ({step}));")
        self.emit(ind, "}")

    def assign(self, target: A.Expr, value: A.Expr, ind: int) -> None:
        b = _b(target.ty)
        if isinstance(b, (T.ArrayType, T.StructType)):
            dst, src = self.lvalue(target), self.lvalue(value) if isinstance(value, (A.Name, A.Member, A.Index)) else None
            if src is None:
                raise Unsupported("ARRAY / STRUCT values other than variables")
            self.emit(ind, f"memmove(&{dst}, &{src}, sizeof({dst}));" if isinstance(b, T.StructType)
                      else f"memmove({dst}, {src}, sizeof({self.ctype(b.elem)}) * {b.size});")
            return
        self.emit(ind, f"{self.lvalue(target)} = {self.expr(value)};")

    def fb_call(self, s: A.CallStmt, ind: int) -> None:
        fb: T.FBType = s.fb_type
        if fb is None:
            raise Unsupported("a call statement that is no block call")
        sname = self.fb_type(fb)
        iv = self.fresh("i")
        self.emit(ind, "{")
        self.emit(ind + 1, f"{sname} *{iv} = &{self.lvalue(s.target)};")
        outputs, eno = [], None
        for a in s.args:
            if a.is_output:
                if a.key == "ENO":
                    eno = a
                else:
                    outputs.append(a)
                continue
            if a.key == "ENO":
                continue
            decl = a.param if isinstance(a.param, A.VarDecl) else None
            if a.key == "EN":
                self.emit(ind + 1, f"{iv}->f_EN = {self.expr(a.value)};")
            elif decl is not None and decl.section == "VAR_IN_OUT":
                pb = _b(decl.ty)
                lv = self.lvalue(a.value)
                self.emit(ind + 1, f"{iv}->f_{a.key} = {lv};" if isinstance(pb, T.ArrayType)
                          else f"{iv}->f_{a.key} = &{lv};")
            else:
                ptype = decl.ty if decl is not None else a.value.ty
                pb = _b(ptype)
                if isinstance(pb, (T.ArrayType, T.StructType)):
                    src = self.lvalue(a.value)
                    dst = f"{iv}->f_{a.key}"
                    self.emit(ind + 1, f"memmove(&{dst}, &{src}, sizeof({dst}));" if isinstance(pb, T.StructType)
                              else f"memmove({dst}, {src}, sizeof({dst}));")
                    continue
                self.emit(ind + 1, f"{iv}->f_{a.key} = {self.expr(a.value)};")
        if isinstance(fb.pou, FBSig):
            n = fb.pou.name
            call = f"std_{n}({iv});" if n in ("SR", "RS", "R_TRIG", "F_TRIG", "CTU", "CTD", "CTUD") else f"std_{n}(c, {iv});"
        else:
            call = f"body_{sname}(c, {iv});"
        self.emit(ind + 1, f"if ({iv}->f_EN) {{ {iv}->f_ENO = 1; {call} }} else {iv}->f_ENO = 0;")
        for a in outputs:
            code = f"{iv}->f_{a.key}"
            if a.negated:
                code = f"!{code}"
            tb = _b(a.value.ty)
            if isinstance(tb, (T.ArrayType, T.StructType)):
                raise Unsupported("ARRAY / STRUCT outputs of blocks")
            self.emit(ind + 1, f"{self.lvalue(a.value)} = {code};")
        if eno is not None:
            self.emit(ind + 1, f"{self.lvalue(eno.value)} = {iv}->f_ENO;")
        self.emit(ind, "}")

    # ------------------------------------------------------------------ lvalues
    def lvalue(self, e: A.Expr) -> str:
        if isinstance(e, A.Name):
            sym = e.sym
            if isinstance(sym, EnumValue) or not isinstance(sym, A.VarDecl):
                raise Unsupported(f"name {e.name}")
            local = self.fn_locals.get(id(sym))
            if local is not None:
                return local
            if sym.section in ("VAR_EXTERNAL", "VAR_GLOBAL"):
                attr = sym.key if sym.name else located_attr(sym)
                return f"c->st->g.f_{attr}"
            attr = sym.key if sym.name else located_attr(sym)
            if sym.section == "VAR_IN_OUT":
                if isinstance(_b(sym.ty), T.ArrayType):
                    return f"self->f_{attr}"
                return f"(*self->f_{attr})"
            if self.in_function:
                raise Unsupported(f"variable {e.name} in a function")
            return f"self->f_{attr}"
        if isinstance(e, A.Member):
            return f"{self.lvalue(e.base)}.f_{e.key}"
        if isinstance(e, A.Index):
            arr = _b(e.base.ty)
            return f"{self.lvalue(e.base)}[{self.flat_index(e, arr)}]"
        raise Unsupported(f"not a variable: {type(e).__name__}")

    def flat_index(self, e: A.Index, arr: T.ArrayType) -> str:
        stride, strides = 1, []
        for lo, hi in reversed(arr.dims):
            strides.append(stride)
            stride *= hi - lo + 1
        strides.reverse()
        parts = []
        for ix, (lo, hi), st in zip(e.indexes, arr.dims, strides):
            off = f"bound(c, (int64_t)({self.expr(ix)}), {lo}, {hi}, {self.site(e)})"
            parts.append(off if st == 1 else f"{off} * {st}")
        return " + ".join(parts)

    # ------------------------------------------------------------------ expressions
    def const(self, v: Any, b: Any) -> str:
        if isinstance(v, bool):
            return "1" if v else "0"
        if isinstance(v, EnumValue) or isinstance(v, str):
            raise Unsupported("enumerated or string constants")
        if isinstance(v, float) or (b is not None and isinstance(b, T.ElementaryType) and b.is_real):
            v = float(v)
            if b is T.REAL:
                return f"((float){_cdouble(T.to_f32(v))})"
            return _cdouble(v)
        if isinstance(v, int):
            if -(1 << 31) <= v < (1 << 31):
                return str(v)
            if -(1 << 63) <= v < (1 << 63):
                return f"INT64_C({v})" if v != -(1 << 63) else "INT64_MIN"
            return f"UINT64_C({v})"
        raise Unsupported(f"constant {v!r}")

    def expr(self, e: A.Expr) -> str:
        if isinstance(e, A.Literal):
            v = e.value
            tb = _b(e.ty)
            if isinstance(tb, T.ElementaryType) and tb.is_real:
                if tb is T.REAL and not _is_double(e):
                    return self.const(float(v), T.REAL)
                return self.const(float(v), T.LREAL)
            if tb is T.BOOL:
                return "1" if v else "0"
            if isinstance(v, float):
                return self.const(v, T.LREAL)
            if isinstance(tb, T.ElementaryType) and tb.kind in ("sint", "uint", "bits") and tb.bits >= 32:
                # matiec writes a typed literal as `(DWORD)5`: `NOT DWORD#5 > DWORD#0` is TRUE
                return f"(({_CTYPE[tb.name]}){self.const(v, tb)})"
            return self.const(v, tb)
        if isinstance(e, (A.Name, A.Member, A.Index)):
            if isinstance(e, A.Name) and isinstance(e.sym, EnumValue):
                raise Unsupported("enumerated values")
            b = _b(e.ty)
            if isinstance(b, (T.ArrayType, T.StructType, T.FBType)):
                raise Unsupported("ARRAY / STRUCT values in expressions")
            return self.lvalue(e)
        if isinstance(e, A.Unary):
            inner = self.expr(e.operand)
            b = _b(e.ty)
            if e.op == "NOT":
                return f"(!{inner})" if b is T.BOOL else f"(~{inner})"
            return f"(- {inner})" if inner.startswith("-") else f"(-{inner})"    # `-INT#-5`: not C's `--`
        if isinstance(e, A.Binary):
            return self.binary(e)
        if isinstance(e, A.Call):
            return self.call(e)
        raise Unsupported(type(e).__name__)

    _COP = {"=": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}

    def binary(self, e: A.Binary) -> str:
        l, r = self.expr(e.left), self.expr(e.right)
        op = e.op
        ot = _b(e.operand_ty) if e.operand_ty is not None else _b(e.left.ty)
        rb = _b(e.ty)
        if isinstance(ot, (T.StringType, T.EnumType)) or isinstance(rb, (T.StringType, T.EnumType)):
            raise Unsupported("STRING / enumerated operations")
        if op in self._COP:
            return f"({l} {self._COP[op]} {r})"
        if op in ("AND", "OR", "XOR"):
            if ot is T.BOOL or rb is T.BOOL:
                return f"({l} {'&&' if op == 'AND' else '||' if op == 'OR' else '!='} {r})"
            return f"({l} {'&' if op == 'AND' else '|' if op == 'OR' else '^'} {r})"
        if not isinstance(rb, T.ElementaryType):
            raise Unsupported(f"operator {op}")
        if rb.kind in ("time", "date", "tod", "dt"):
            kinds = ("time", "date", "tod", "dt")
            if op in ("+", "-") and _b(e.left.ty).kind in kinds and _b(e.right.ty).kind in kinds:
                return f"((int64_t)((uint64_t)({l}) {op} (uint64_t)({r})))"
            raise Unsupported(f"TIME {op}")
        if op in ("/", "MOD"):
            if rb.is_real:
                if op == "MOD":
                    raise Unsupported("MOD of REAL")
                return f"({l} / {r})"
            if rb.kind == "bits":
                raise Unsupported(f"{op} on bit strings")
            site = self.site(e)
            if rb.bits < 32 or (rb.kind == "sint" and rb.bits == 32):
                fn, ct = "32", "int32_t"
                kind = "i"
            elif rb.kind == "sint":
                fn, ct, kind = "64", "int64_t", "i"
            else:
                fn, ct, kind = ("32", "uint32_t", "u") if rb.bits == 32 else ("64", "uint64_t", "u")
            if op == "/":
                return f"div_{kind}{fn}(c, ({ct})({l}), ({ct})({r}), {site})"
            if kind == "u":
                return f"mod_u{fn}(({ct})({l}), ({ct})({r}))"
            return f"mod_i{fn}(c, ({ct})({l}), ({ct})({r}), {site})"
        if op in ("+", "-", "*"):
            if rb.kind == "bits":
                raise Unsupported(f"{op} on bit strings")
            return f"({l} {op} {r})"
        raise Unsupported(f"operator {op}")

    def call(self, c: A.Call) -> str:
        if any(a.key in ("EN", "ENO") for a in c.args):
            raise Unsupported("EN / ENO of function calls")
        if c.pou is not None:
            return self.user_call(c)
        return self.std_call(c)

    def user_call(self, c: A.Call) -> str:
        pou: A.PouDecl = c.pou
        given = {id(a.param): a for a in c.args if a.param is not None}
        args = ["c"]
        for d in _params(pou):
            a = given.get(id(d))
            b = _b(d.ty)
            if a is None:
                if d.section == "VAR_INPUT":
                    if isinstance(b, (T.ArrayType, T.StructType)):
                        raise Unsupported("a missing ARRAY / STRUCT input")
                    v = d.init_value if d.init_value is not None else T.default_value(d.ty)
                    args.append(self.const(v, b))
                else:
                    if d.section == "VAR_IN_OUT":
                        raise Unsupported("a missing VAR_IN_OUT")
                    args.append("0")
            elif isinstance(b, T.ArrayType):
                args.append(self.lvalue(a.value))
            elif isinstance(b, T.StructType):
                args.append(f"&{self.lvalue(a.value)}")
            elif d.section == "VAR_INPUT":
                args.append(self.expr(a.value))
            elif a.negated:
                raise Unsupported("negated function outputs")
            else:
                args.append(f"&{self.lvalue(a.value)}")
        if len(args) > 1:
            # C leaves the order of argument evaluation open; the Python path goes left to right
            temps, decls = [], []
            for i, code in enumerate(args[1:]):
                if _pure(code):
                    temps.append(code)
                    continue
                t = self.fresh("a")
                decls.append(f"__auto_type {t} = {code};")
                temps.append(t)
            if decls:
                return "({ " + " ".join(decls) + f" FC_{pou.key}(c, {', '.join(temps)}); }})"
        return f"FC_{pou.key}({', '.join(args)})"

    def std_call(self, c: A.Call) -> str:
        name = c.std
        args = [a for a in c.args if a.key not in ("EN", "ENO")]
        names = c.bound_params if c.bound_params is not None else [a.key for a in args]
        arg_types = [_concrete(t) for t in (c.arg_types or [a.value.ty for a in args])]
        ordered = sorted(zip(names, args, arg_types), key=lambda nat: _param_rank(nat[0]))
        codes = [self.expr(a.value) for _n, a, _t in ordered]
        types = [_b(t) for _n, _a, t in ordered]
        rb = _b(c.ty)
        for t in types + [rb]:
            if not isinstance(t, T.ElementaryType):
                raise Unsupported(f"{name} on {getattr(t, 'name', t)}")
        rc = _CTYPE[rb.name]
        # each argument as its parameter's type, as the C call converts it (a double
        # expression passed as a REAL is rounded to float first: Python's expr_as)
        codes = [f"(({_CTYPE[t.name]})({code}))" for code, t in zip(codes, types)]
        if name.count("_TO_") == 1 and len(codes) == 1:
            if any(n not in T.ELEMENTARY for n in name.split("_TO_")):
                raise Unsupported(f"standard function {name}")
            return self.conversion(name, types[0], rb, codes[0])
        if name in _MATH1 and len(codes) == 1 and types[0].is_real:
            if types[0] is T.REAL and name != "SQRT":      # OpenPLC's C++ calls sinf & co for a REAL
                return f"({_MATH1[name]}f((float)({codes[0]})))"
            return f"(({_CTYPE[types[0].name]}){_MATH1[name]}((double)({codes[0]})))"
        if name == "EXPT" and len(codes) == 2 and types[0] is T.REAL and types[1] is T.REAL:
            return f"(powf((float)({codes[0]}), (float)({codes[1]})))"
        if name == "EXPT" and len(codes) == 2 and types[0].is_real and types[1].kind in ("sint", "uint", "real"):
            return f"(({_CTYPE[types[0].name]})c_pow((double)({codes[0]}), (double)({codes[1]})))"
        if name == "ABS" and len(codes) == 1:
            k = types[0].kind
            if k == "uint":
                return codes[0]
            t = _CTYPE[types[0].name]
            x = self.fresh("x")
            if k == "sint":
                # negated as unsigned: gcc turns `x < 0 ? -x : x` into its abs, which it takes
                # as never negative even under -fwrapv (ABS(b) > ABS(LINT's least) came out
                # FALSE); the Python path wraps the least value to itself
                u = "uint64_t" if types[0].bits == 64 else "uint32_t"
                return f"({{ {t} {x} = {codes[0]}; ({t})({x} < 0 ? ({u})0 - ({u}){x} : ({u}){x}); }})"
            if k == "real":
                return f"({{ {t} {x} = {codes[0]}; ({t})({x} < 0 ? -{x} : {x}); }})"
            raise Unsupported(f"ABS of {types[0].name}")
        if name in ("MIN", "MAX", "LIMIT", "SEL"):
            if any(t.kind not in ("bool", "sint", "uint", "bits", "real", "time") for t in types):
                raise Unsupported(f"{name} on these types")
            if name != "SEL" and types[0] is T.BOOL and name != "MAX":
                raise Unsupported(f"{name} of BOOL")
            ts = [self.fresh("x") for _ in codes]
            decl = " ".join(f"{_CTYPE[t.name]} {v} = {code};" for v, t, code in zip(ts, types, codes))
            if name == "SEL":
                return f"({{ {decl} ({rc})({ts[0]} ? {ts[2]} : {ts[1]}); }})"
            if name == "LIMIT":
                mn, x, mx = ts
                return f"({{ {decl} ({rc})(({mn} < {x}) ? (({x} < {mx}) ? {x} : {mx}) : {mn}); }})"
            acc = ts[0]
            steps = " ".join(f"if ({acc} < {v}) {acc} = {v};" if name == "MAX" else f"if ({v} < {acc}) {acc} = {v};"
                             for v in ts[1:])
            return f"({{ {decl} {steps} ({rc}){acc}; }})"
        if name in ("SHL", "SHR") and len(codes) == 2 and types[0].kind == "bits" and types[0] is not T.BOOL \
                and types[1].kind in ("sint", "uint", "bits"):
            bits = types[0].bits
            mask = 63 if bits == 64 else 31
            wide = "uint64_t" if bits == 64 else "uint32_t"
            op = "<<" if name == "SHL" else ">>"
            return f"(({rc})(({wide})({codes[0]}) {op} (({codes[1]}) & {mask})))"
        raise Unsupported(f"standard function {name}")

    def conversion(self, name: str, src: T.ElementaryType, dst: T.ElementaryType, code: str) -> str:
        s, d = src.kind, dst.kind
        timelike = ("time", "date", "tod", "dt")
        intlike = ("bool", "sint", "uint", "bits")
        dc = _CTYPE[dst.name]
        if s in ("date", "tod", "dt") or d in ("date", "tod", "dt"):
            raise Unsupported(name)
        if src is dst:
            if s == "bool":
                raise Unsupported(name)
            return code
        if d == "bool":
            return f"(({code}) != 0)"
        if s in intlike:
            if d in ("sint", "uint", "bits", "real"):
                return f"(({dc})({code}))"
            if d == "time":
                return f"((int64_t)((uint64_t)(int64_t)({code}) * 1000000000u))" if src.kind != "uint" or src.bits < 64 \
                    else f"((int64_t)((uint64_t)({code}) * 1000000000u))"
        if s == "real":
            if d == "sint":
                return f"(({dc})real_to_sint((double)({code})))"
            if d in ("uint", "bits"):
                return f"(({dc})real_to_uint((double)({code})))"
            if d == "real":
                return f"(({dc})({code}))"
            if d == "time":
                return f"real_to_time((double)({code}))"
        if s == "time":
            if d in ("sint", "uint", "bits"):
                return f"(({dc})(({code}) / 1000000000))"
            if d == "real":
                return f"(({dc})time_to_real({code}))"
        raise Unsupported(name)


def _from_raw(b: T.ElementaryType, raw: str, mask: str) -> str:
    """A raw image value as the variable (plc._converters / PLC._compile_io)."""
    if b is T.BOOL:
        return f"({raw} != 0)"
    if b is T.REAL:
        return f"({{ uint32_t _u = (uint32_t)((uint64_t){raw} & {mask}); float _f; memcpy(&_f, &_u, 4); _f; }})"
    if b is T.LREAL:
        return f"({{ uint64_t _u = (uint64_t){raw} & {mask}; double _f; memcpy(&_f, &_u, 8); _f; }})"
    return f"(({_CTYPE[b.name]})((uint64_t){raw} & {mask}))"


def _to_raw(b: T.ElementaryType, lv: str, mask: str, area_bits: int) -> str:
    if b is T.BOOL:
        return f"({lv} ? 1 : 0)"
    if b is T.REAL:
        return f"({{ uint32_t _u; float _f = {lv}; memcpy(&_u, &_f, 4); (uint64_t)_u; }})"
    if b is T.LREAL:
        return f"({{ uint64_t _u; double _f = {lv}; memcpy(&_u, &_f, 8); _u; }})"
    amask = "UINT64_MAX" if area_bits == 64 else f"UINT64_C({(1 << area_bits) - 1})"
    return f"((uint64_t)(int64_t){lv} & {amask})" if b.kind in ("sint", "time", "date", "tod", "dt") \
        else f"((uint64_t){lv} & {amask})"


def _pure(code: str) -> bool:
    return "(" not in code or code.replace("c->st->g.", "").replace("self->", "").isidentifier()


def _ident(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch == "_" else "_" for ch in name)


def _cdouble(v: float) -> str:
    if math.isnan(v):
        return "(double)NAN" if math.copysign(1.0, v) > 0 else "(-(double)NAN)"
    if math.isinf(v):
        return "(double)INFINITY" if v > 0 else "(-(double)INFINITY)"
    r = repr(v)
    if "e" not in r and "." not in r:
        r += ".0"
    return f"({r})" if v < 0 else r


def emit_c(checked: CheckedUnit) -> CProgram:
    """The C of a checked program; Unsupported when the backend does not cover it."""
    return CGen(checked).generate()


__all__ = ["CProgram", "FAULT_KINDS", "Field", "Layout", "Unsupported", "emit_c"]
