"""Random programs compute the same on the native path as on the Python path, scan for scan.

The stands' programs and the semantics suite cover what students write; random programs
cover the corners nobody writes on purpose: typed 32- and 64-bit literals in comparisons,
ABS of a type's least value, conversions of huge, tiny, negative-zero and not-a-number REALs,
shifts by more than the width, CASE ranges, FOR bounds re-evaluated, functions and blocks
with narrowed arguments. Each program declares three variables of every elementary type,
runs random statements over them for 15 scans on both paths, and every variable (and every
fault's kind, message and line) must be the same after every scan. The seeds are fixed: a
failure names its seed, and `program(random.Random(seed))` prints the program.
"""
from __future__ import annotations

import math
import random
from typing import Any

import pytest

from plclab.frontend import check_sources
from plclab.runtime import native
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import FAULT, PLC

SIGNED = ["SINT", "INT", "DINT", "LINT"]
UNSIGNED = ["USINT", "UINT", "UDINT", "ULINT"]
BITS = ["BYTE", "WORD", "DWORD", "LWORD"]
REALS = ["REAL", "LREAL"]
INTEGERS = SIGNED + UNSIGNED
TYPES = INTEGERS + REALS + BITS + ["BOOL", "TIME"]
WIDTH = {t: 8 << (i % 4) for i, t in enumerate(SIGNED + UNSIGNED + BITS)}
ARRAYS = ["INT", "DINT", "UDINT", "REAL", "BOOL", "WORD"]
REAL_LITERALS = ["0.0", "1.5", "-2.25", "0.1", "2.5", "-3.5", "0.5", "1.0E10", "3.0E-5", "3.4E38", "-0.0",
                 "1.0E-40", "4294967296.0", "9.3E18", "-2147483648.5"]
LREAL_LITERALS = [x for x in REAL_LITERALS if x != "1.0E-40"]   # OpenPLC reads it in single precision

LIBRARY = """
FUNCTION FC_Mix : DINT
VAR_INPUT x : INT; y : REAL; z : UDINT; END_VAR
VAR t : LINT; END_VAR
t := INT_TO_LINT(x) * 3 - UDINT_TO_LINT(z);
IF y > 0.0 THEN t := t + REAL_TO_LINT(y); END_IF;
FC_Mix := LINT_TO_DINT(t) + INT_TO_DINT(x);
END_FUNCTION

FUNCTION_BLOCK FB_Acc
VAR_INPUT x : INT; w : WORD; END_VAR
VAR_IN_OUT io : DINT; END_VAR
VAR_OUTPUT y : REAL; q : BOOL; END_VAR
VAR acc : DINT; END_VAR
acc := acc + INT_TO_DINT(x);
io := io + acc MOD 17;
y := DINT_TO_REAL(acc) / 3.0;
q := (w AND WORD#16#8) <> WORD#0 XOR q;
END_FUNCTION_BLOCK
"""


class Generator:
    """Random well-typed ST over the variables `v_<TYPE>_<k>` (k < 3) and the arrays `a_<TYPE>`."""

    def __init__(self, r: random.Random) -> None:
        self.r = r

    def literal(self, t: str) -> str:
        r = self.r
        if t == "BOOL":
            return r.choice(["TRUE", "FALSE"])
        if t == "TIME":
            return f"T#{r.randint(0, 5000)}ms"
        if t in REALS:
            return f"{t}#{r.choice(REAL_LITERALS if t == 'REAL' else LREAL_LITERALS)}"
        bits = WIDTH[t]
        if t in SIGNED:
            v = r.choice([0, 1, -1, 7, -(1 << (bits - 1)), (1 << (bits - 1)) - 1, r.randint(-100, 100)])
            return f"{t}#{v}"
        v = r.choice([0, 1, 2, (1 << bits) - 1, r.randrange(1 << bits)])
        return f"{t}#16#{v:X}" if t in BITS and r.random() < 0.5 else f"{t}#{v}"

    def var(self, t: str) -> str:
        return f"v_{t}_{self.r.randrange(3)}"

    def index(self) -> str:
        return self.r.choice(["LIMIT(0, k, 5)", "LIMIT(0, v_INT_0, 5)", "(v_USINT_1 MOD 6)", "ABS(v_SINT_2 MOD 6)", "2"])

    def expr(self, t: str, depth: int) -> str:
        r = self.r
        if depth <= 0 or r.random() < 0.25:
            if t in ARRAYS and r.random() < 0.15:
                return f"a_{t}[{self.index()}]"
            return self.var(t) if r.random() < 0.7 else self.literal(t)
        sub = lambda tt=t: self.expr(tt, depth - 1)         # noqa: E731
        c = r.random()
        if t == "BOOL":
            if c < 0.4:
                s = r.choice(TYPES[:-2] + ["TIME"])
                return f"({self.expr(s, depth - 1)} {r.choice(['=', '<>', '<', '>', '<=', '>='])} {self.expr(s, depth - 1)})"
            if c < 0.7:
                return f"({sub()} {r.choice(['AND', 'OR', 'XOR'])} {sub()})"
            return f"(NOT {sub()})" if c < 0.85 else f"SEL({sub()}, {sub()}, {sub()})"
        if t == "TIME":
            if c < 0.5:
                return f"({sub()} {r.choice(['+', '-'])} {sub()})"
            if c < 0.8:
                s = r.choice(["DINT", "UDINT", "LINT", "REAL", "LREAL"])
                return f"{s}_TO_TIME({self.expr(s, depth - 1)})"
            return f"MAX({sub()}, {sub()})"
        if c < 0.15:
            s = r.choice([x for x in INTEGERS + REALS + BITS if x != t and not (t in BITS and x in REALS)])
            return f"{s}_TO_{t}({self.expr(s, depth - 1)})"
        if t in BITS:
            if c < 0.45:
                return f"({sub()} {r.choice(['AND', 'OR', 'XOR'])} {sub()})"
            if c < 0.55:
                return f"(NOT {sub()})"
            if c < 0.8:
                return f"{r.choice(['SHL', 'SHR'])}({sub()}, {r.choice([0, 1, 7, 8, 15, 16, 31, 32, 63, 64, 70])})"
            return f"SEL({self.expr('BOOL', depth - 1)}, {sub()}, {sub()})"
        if c < 0.55:
            # a variable on one side: OpenPLC's compiler folds an operation on two literals
            # and refuses it where the value leaves the type (INT#32767 + 1)
            op = r.choice(["+", "-", "*", "/", "MOD"] if t in INTEGERS else ["+", "-", "*", "/"])
            if op in ("/", "MOD") and r.random() < 0.97:    # mostly a divisor that cannot be 0
                low = f"{t}#0.5" if t in REALS else f"{t}#1"
                return f"({self.var(t)} {op} MAX({sub()}, {low}))" if t not in SIGNED \
                    else f"({sub()} {op} LIMIT({low}, {self.var(t)}, {t}#100))"
            return f"({self.var(t)} {op} {sub()})" if r.random() < 0.5 else f"({sub()} {op} {self.var(t)})"
        if c < 0.7 and t not in UNSIGNED:
            return f"(-{sub()})" if c < 0.62 else f"ABS({sub()})"
        if c < 0.78:
            return f"{r.choice(['MIN', 'MAX'])}({sub()}, {sub()})"
        if c < 0.84:
            return f"LIMIT({sub()}, {sub()}, {sub()})"
        if c < 0.92 and t in REALS:
            return f"{r.choice(['SQRT', 'LN', 'EXP', 'SIN', 'ATAN'])}({sub()})"
        if c < 0.95 and t in REALS:
            return f"EXPT({sub()}, {sub()})"
        return f"SEL({self.expr('BOOL', depth - 1)}, {sub()}, {sub()})"

    def statement(self, depth: int = 0) -> str:
        r = self.r
        c = r.random()
        t = r.choice(TYPES)
        if c < 0.45 or depth > 2:
            target = f"a_{t}[{self.index()}]" if t in ARRAYS and r.random() < 0.3 else self.var(t)
            return f"{target} := {self.expr(t, r.randint(1, 3))};"
        inner = lambda: self.statement(depth + 1)           # noqa: E731
        if c < 0.55:
            other = f" ELSE {inner()}" if r.random() < 0.5 else ""
            return f"IF {self.expr('BOOL', 2)} THEN {inner()} {inner()}{other} END_IF;"
        if c < 0.65:
            selector = r.choice(["v_INT_0", "v_SINT_1", "v_USINT_2", "(v_DINT_0 MOD 7)", "k"])
            labels = r.sample(["0", "1", "2..4", "5, 6", "100..120", "3"] + ([] if "U" in selector else ["-1"]), 2)
            return f"CASE {selector} OF {labels[0]}: {inner()} {labels[1]}: {inner()} ELSE {inner()} END_CASE;"
        if c < 0.8 and depth == 0:          # loops at the top only: a loop's body never loops
            body = self.statement(3)
            if c < 0.7:
                by = r.choice(["", " BY 2", " BY -1", " BY ABS(v_INT_1 MOD 3) + 1"])
                return (f"FOR k := {r.randint(-2, 2)} TO {r.choice(['4', 'v_INT_0 MOD 6', '0', '7'])}{by} DO "
                        f"a_DINT[LIMIT(0, k, 5)] := a_DINT[LIMIT(0, k, 5)] + INT_TO_DINT(k); {body} END_FOR;")
            if c < 0.75:
                return (f"n := 0; WHILE n < {r.randint(0, 5)} DO n := n + 1; {body} "
                        f"IF {self.expr('BOOL', 1)} THEN EXIT; END_IF; END_WHILE;")
            return f"n := 0; REPEAT n := n + 1; {body} UNTIL n >= {r.randint(1, 4)} OR {self.expr('BOOL', 1)} END_REPEAT;"
        if c < 0.9:
            return (f"tn(IN := {self.expr('BOOL', 2)}, PT := T#{r.choice([0, 10, 30, 100])}ms); "
                    f"ct(CU := {self.expr('BOOL', 1)}, R := {self.expr('BOOL', 1)}, PV := {r.randint(0, 5)}); "
                    f"rt(CLK := {self.expr('BOOL', 1)}); v_BOOL_0 := tn.Q OR ct.Q OR rt.Q;")
        if c < 0.95:
            return (f"fb(x := {self.expr('INT', 2)}, w := {self.expr('WORD', 2)}, io := {self.var('DINT')}); "
                    f"{self.var('REAL')} := fb.y;")
        return f"{self.var('DINT')} := FC_Mix({self.expr('INT', 2)}, {self.expr('REAL', 2)}, {self.expr('UDINT', 2)});"


def program(r: random.Random) -> str:
    g = Generator(r)
    decl = [f"v_{t}_{k} : {t} := {g.literal(t)};" for t in TYPES for k in range(3)]
    decl += [f"a_{t} : ARRAY[0..5] OF {t};" for t in ARRAYS]
    decl += ["k : INT; n : INT; tn : TON; ct : CTU; rt : R_TRIG; fb : FB_Acc;"]
    body = [g.statement() for _ in range(40)]
    return LIBRARY + "PROGRAM main\nVAR\n" + "\n".join(decl) + "\nEND_VAR\n" + "\n".join(body) + "\nEND_PROGRAM\n"


NAMES = [f"main.v_{t}_{k}" for t in TYPES for k in range(3)] + [f"main.a_{t}" for t in ARRAYS] + \
    ["main.k", "main.n", "main.tn.ET", "main.ct.CV", "main.fb.acc", "main.fb.y"]


def _same(a: Any, b: Any) -> bool:
    """Equal, NaN equal to NaN, and 0.0 not equal to -0.0."""
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(map(_same, a, b))
    if isinstance(a, float) and isinstance(b, float):
        return (math.isnan(a) and math.isnan(b)) or (a == b and math.copysign(1, a) == math.copysign(1, b))
    return type(a) is type(b) and a == b


@pytest.mark.parametrize("seed", range(10))
def test_a_random_program_computes_the_same_on_both_paths(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(native, "PREFER_API", False)     # the same C, a third of the build time
    cu = check_sources([("random.st", program(random.Random(seed)))])
    py, na = PLC(compile_unit(cu), native=False), PLC(compile_unit(cu), native=True)
    assert na.native is not None, "the native path should cover every construct generated here"
    for scan in range(15):
        for plc in (py, na):
            plc.scan()
            plc.advance()
        assert py.state == na.state, f"seed {seed} scan {scan}: {py.fault} / {na.fault}"
        if py.state == FAULT:
            assert str(py.fault) == str(na.fault), f"seed {seed}"
            return
        for name in NAMES:
            assert _same(py.read(name), na.read(name)), \
                f"seed {seed} scan {scan}: {name} Python {py.read(name)!r}, native {na.read(name)!r}"
