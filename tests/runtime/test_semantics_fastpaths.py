"""The compiled body keeps variables in Python locals while it runs (for speed): these cases
check that nothing a program can observe changes. References (VAR_IN_OUT, function outputs),
a fault in the middle of a body, EN/ENO, inputs passed by value, and the inline forms of
shifts and REAL rounding."""
from __future__ import annotations

import random

import pytest

from hypothesis import assume, example, given, settings, strategies as st

from plclab.errors import CompileError
from plclab.iec import types as T
from plclab.runtime import stdlib
from st_helpers import MS, once, program, val

pytestmark = pytest.mark.usefixtures("compile_mode")

BUMP_FB = """
FUNCTION_BLOCK FB_Bump
VAR_IN_OUT v : INT; END_VAR
VAR_OUTPUT seen : INT; END_VAR
seen := v;
v := v + 10;
END_FUNCTION_BLOCK
"""


def test_variable_passed_by_reference_is_seen_by_callee_and_caller():
    # x is named many times (a local candidate) and handed to a VAR_IN_OUT: the block must
    # read the caller's latest value and the caller must see what the block wrote
    sim = once("VAR x : INT; b : FB_Bump; before, seen, after : INT; END_VAR",
               "x := 1; x := x + 1; before := x; b(v := x); seen := b.seen; x := x + 1; after := x;",
               BUMP_FB)
    assert (val(sim, "before"), val(sim, "seen"), val(sim, "after")) == (2, 2, 13)


def test_function_output_into_a_busy_variable():
    extra = """
FUNCTION FC_Split : INT
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT hi : INT; END_VAR
hi := x / 100;
FC_Split := x MOD 100;
END_FUNCTION
"""
    sim = once("VAR h, lo, sum : INT; END_VAR",
               "h := 1; sum := h; lo := FC_Split(x := 1234, hi => h); sum := sum + h + lo; h := h + 1;",
               extra)
    assert (val(sim, "h"), val(sim, "lo"), val(sim, "sum")) == (13, 34, 1 + 12 + 34)


def test_fb_keeps_state_in_its_instance_between_calls():
    extra = """
FUNCTION_BLOCK FB_Count
VAR_OUTPUT n : INT; END_VAR
VAR inc : INT := 2; END_VAR
n := n + inc; n := n + inc; inc := inc + 1;
END_FUNCTION_BLOCK
"""
    sim = program("VAR c : FB_Count; END_VAR", "c();", extra)
    sim.step(3)
    assert val(sim, "c.n") == (2 + 2) + (3 + 3) + (4 + 4)
    assert val(sim, "c.inc") == 5


def test_values_written_before_a_fault_are_kept():
    sim = program("VAR a, z, q : INT; END_VAR",
                  "a := a + 1; a := a + 1; IF a > 2 THEN q := 10 / z; END_IF; a := 100;")
    sim.step(3)
    assert sim.plc.state == "FAULT" and sim.plc.fault.kind == "division_by_zero"
    assert sim.plc.fault.time_ns == 20 * MS
    assert val(sim, "a") == 102       # scan 1 ends at 100; scan 2 adds 2, then faults before `a := 100`


ENO_FB = """
FUNCTION_BLOCK FB_Check
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT ok : BOOL; END_VAR
ok := x >= 0;
IF x < 0 THEN ENO := FALSE; END_IF;
END_FUNCTION_BLOCK
"""


def test_fb_body_sets_eno_and_en_false_skips_the_body():
    sim = once("VAR f : FB_Check; e1, e2, e3, e4, e5 : BOOL; ok3 : BOOL; x4 : INT; END_VAR",
               "f(x := 5, ENO => e1); f(x := -5, ENO => e2); "
               "f(EN := FALSE, x := 7, ENO => e3); ok3 := f.ok; "
               "f(x := 1, ENO => e4); x4 := f.x; f(EN := TRUE, x := 1, ENO => e5);",
               ENO_FB)
    assert (val(sim, "e1"), val(sim, "e2"), val(sim, "e3")) == (True, False, False)
    assert val(sim, "ok3") is False       # the skipped call left the output of x := -5
    # matiec assigns only the parameters a call names: EN stays FALSE until a call sets it,
    # while the inputs named are assigned even when the body does not run
    assert (val(sim, "e4"), val(sim, "x4"), val(sim, "e5")) == (False, 1, True)
    assert val(sim, "f.ok") is True


def test_standard_fb_with_en():
    sim = program("VAR t : TON; q1, q2, e1, e2 : BOOL; n : INT; END_VAR",
                  "n := n + 1; t(EN := n <> 3, IN := TRUE, PT := T#20ms, Q => q1, ENO => e1); "
                  "IF n = 3 THEN q2 := t.Q; e2 := e1; END_IF;", tick_ms=10)
    sim.step(2)                           # t = 0, 10 ms: started, 10 ms elapsed
    assert val(sim, "q1") is False and val(sim, "e1") is True
    sim.step(1)                           # t = 20 ms: EN FALSE, the timer is not called
    assert (val(sim, "q2"), val(sim, "e2"), val(sim, "q1")) == (False, False, False)
    sim.step(1)                           # t = 30 ms: called again, 30 ms since the start
    assert val(sim, "q1") is True and val(sim, "e1") is True


def test_function_body_sets_eno():
    extra = """
FUNCTION FC_SafeDiv : INT
VAR_INPUT a, b : INT; END_VAR
IF b = 0 THEN ENO := FALSE; ELSE FC_SafeDiv := a / b; END_IF;
END_FUNCTION
"""
    sim = once("VAR r1, r2, r3 : INT; e1, e2, e3 : BOOL; END_VAR",
               "r1 := FC_SafeDiv(a := 9, b := 3, ENO => e1); r2 := FC_SafeDiv(a := 9, b := 0, ENO => e2); "
               "r3 := FC_SafeDiv(EN := FALSE, a := 9, b := 3, ENO => e3);", extra)
    assert (val(sim, "r1"), val(sim, "e1")) == (3, True)
    assert (val(sim, "r2"), val(sim, "e2")) == (0, False)
    assert (val(sim, "r3"), val(sim, "e3")) == (0, False)


def test_array_input_of_fb_is_passed_by_value():
    extra = """
TYPE T_Three : ARRAY[1..3] OF INT; END_TYPE
FUNCTION_BLOCK FB_Scratch
VAR_INPUT a : T_Three; END_VAR
VAR_OUTPUT r : INT; END_VAR
a[2] := 77;
r := a[1] + a[2];
END_FUNCTION_BLOCK
"""
    sim = once("VAR x : T_Three; f : FB_Scratch; x2, r : INT; END_VAR",
               "x[1] := 1; f(a := x); r := f.r; x2 := x[2];", extra)
    assert (val(sim, "r"), val(sim, "x2")) == (78, 0)


def test_real_overflow_in_an_assignment_is_infinite():
    sim = program("VAR r : REAL := 1.0; big : REAL := 1.0E30; END_VAR", "r := r * big;")
    sim.step(2)
    assert val(sim, "r") == float("inf") and sim.plc.state == "RUN"


# every constant count from 0 to 70 (past each type's width), each direction, in one program
# per type (one build on the native path); the value is the variable's, written from outside
SHIFT_COUNTS = range(71)


@pytest.mark.parametrize("type_name", ["BYTE", "WORD", "DWORD", "LWORD"])
def test_constant_shift_inline_matches_the_library(type_name):
    ty = T.ELEMENTARY[type_name]
    mask = (1 << ty.bits) - 1
    body = " ".join(f"l[{k}] := SHL(x, {k}); r[{k}] := SHR(x, {k});" for k in SHIFT_COUNTS)
    sim = program(f"VAR x : {type_name}; l, r : ARRAY[0..70] OF {type_name}; END_VAR", body)
    shl, shr = stdlib.lookup("SHL", [ty, T.INT], ty), stdlib.lookup("SHR", [ty, T.INT], ty)
    rng = random.Random(type_name)
    edges = [0, 1, 2, 0x80, 0x8000, 0x8000_0000, 1 << 63, mask, mask >> 1, 0x5A5A_5A5A_5A5A_5A5A]
    for value in edges + [rng.getrandbits(64) for _ in range(20)]:
        value &= mask
        sim.plc.write("main.x", value)
        sim.step(1)
        for k in SHIFT_COUNTS:
            assert (val(sim, f"l[{k}]"), val(sim, f"r[{k}]")) == (shl(value, k), shr(value, k)), (value, k)


# --------------------------------------------------------------------------- left-out wraps
# The compiler leaves out a wrap where the declared types prove the value cannot leave its
# type (plclab.runtime.ranges). Checked against a reference that wraps after every operation,
# as the C that matiec generates does.

_TYPES = {"SINT": (8, True), "INT": (16, True), "DINT": (32, True), "LINT": (64, True),
          "USINT": (8, False), "UINT": (16, False), "UDINT": (32, False)}


def _wrap(v: int, bits: int, signed: bool) -> int:
    v &= (1 << bits) - 1
    return v - (1 << bits) if signed and v >> (bits - 1) else v


class _Trap(Exception):
    """The C expression traps (the PLC goes to FAULT with division_overflow)."""


def _c_eval(node, env, bits, signed):
    """C semantics: operands promoted to int (32-bit) below 32 bits, each result wrapped."""
    cbits, csigned = (32, True) if bits < 32 else (bits, signed)
    if isinstance(node, str):
        return env[node] if node in env else int(node)
    op, left, right = node
    a, b = _c_eval(left, env, bits, signed), _c_eval(right, env, bits, signed)
    if op == "MOD":
        if b == 0:
            return 0
        if csigned and b == -1 and a == -(1 << (cbits - 1)):
            raise _Trap()                  # C's INT_MIN % -1: SIGFPE, the PLC faults
        r = abs(a) % abs(b)
        return _wrap(-r if a < 0 else r, cbits, csigned)
    return _wrap({"+": a + b, "-": a - b, "*": a * b}[op], cbits, csigned)


def _st(node) -> str:
    if isinstance(node, str):
        return node
    op, left, right = node
    return f"({_st(left)} {op} {_st(right)})"


_leaf = st.sampled_from(["a", "b", "c", "0", "1", "7", "100", "127"])
_expr = st.recursive(_leaf, lambda inner: st.tuples(st.sampled_from(["+", "-", "*", "MOD"]), inner, inner),
                     max_leaves=6)


@settings(max_examples=120, deadline=None)
@example(type_name="DINT", tree=("MOD", "a", "b"), values=[-2**31, -1, 0])
@example(type_name="INT", tree=("MOD", ("*", ("*", "a", "b"), "c"), "b"), values=[-32768, -1, 65536 // 2])
@given(type_name=st.sampled_from(sorted(_TYPES)), tree=_expr, values=st.lists(st.integers(), min_size=3, max_size=3))
def test_integer_expressions_wrap_like_c(type_name, tree, values):
    bits, signed = _TYPES[type_name]
    env = {k: _wrap(v, bits, signed) for k, v in zip("abc", values)}
    try:
        sim = program(f"VAR a, b, c, r : {type_name}; END_VAR", f"r := {_st(tree)};")
    except CompileError as e:      # a constant part that overflows or divides by 0 is refused
        assume("does not fit" not in str(e) and "zero" not in str(e))
        raise
    for k, v in env.items():
        sim.plc.write(f"main.{k}", v)
    sim.step(1)
    try:
        expected = _wrap(_c_eval(tree, env, bits, signed), bits, signed)
    except _Trap:
        assert sim.plc.state == "FAULT" and sim.plc.fault.kind == "division_overflow", _st(tree)
        return
    assert sim.plc.state == "RUN", _st(tree)
    assert val(sim, "r") == expected, _st(tree)


def test_a_value_written_from_outside_is_stored_as_its_type():
    sim = once("VAR x, y : INT; END_VAR", "y := x + 1;")
    sim.plc.write("main.x", 40000)          # INT: stored as C stores it
    sim.step(1)
    assert (val(sim, "x"), val(sim, "y")) == (40000 - 65536, 40000 - 65536 + 1)
