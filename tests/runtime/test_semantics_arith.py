"""Arithmetic as the C code matiec generates for OpenPLC computes it.

matiec (`utils/matiec_src/stage4/generate_c/generate_c_st.cc`) prints ST operators as plain C
operators without casts: SINT/INT/USINT/UINT/BYTE/WORD operands are promoted to `int` and
only narrowed when stored; `MOD` is `((b == 0)?0:(a % b))`; `**` is
`__expt((LREAL)a, (LREAL)b)`; an untyped real literal is printed as a C double constant
(`generate_c_base.cc`, `visit(real_c)`), so REAL arithmetic with a literal is done in double.
TIME operators call `__time_add`, `__time_sub`, `__time_mul`, `__time_div` and comparisons
call `EQ_TIME`... (`iec_std_lib.h`).
"""
from __future__ import annotations

import pytest

from plclab.iec.types import to_f32
from st_helpers import MS, S, once, program, val

pytestmark = pytest.mark.usefixtures("compile_mode")


# --------------------------------------------------------------------------- integer wrap

def test_int_overflow_wraps_like_c():
    sim = once("VAR a : INT := 32767; b : INT; c : INT := -32768; d : INT; s : SINT := 127; s2 : SINT;"
               " u : USINT := 255; u2 : USINT; w : UINT := 0; w2 : UINT; END_VAR",
               "b := a + 1; d := c - 1; s2 := s + 1; u2 := u + 1; w2 := w - 1;")
    assert val(sim, "b") == -32768
    assert val(sim, "d") == 32767
    assert val(sim, "s2") == -128
    assert val(sim, "u2") == 0
    assert val(sim, "w2") == 65535


def test_dint_and_udint_wrap_at_32_bits():
    sim = once("VAR a : DINT := 2147483647; b : DINT; u : UDINT := 0; v : UDINT; m : DINT; END_VAR",
               "b := a + 1; v := u - 1; m := a * 2;")
    assert val(sim, "b") == -2147483648
    assert val(sim, "v") == 4294967295
    assert val(sim, "m") == -2


def test_int_intermediates_are_promoted_to_c_int():
    # (a + b) / 2 with INT a = b = 30000: a + b = 60000 in C int, not -5536
    sim = once("VAR a : INT := 30000; b : INT := 30000; avg : INT; big : BOOL; m : INT;"
               " p : INT := 300; q : INT := 200; r : INT; big2 : BOOL; s2 : INT; END_VAR",
               "avg := (a + b) / 2; big := a + b > 32767; m := (a + b) MOD 7; r := (p * q) / 100;"
               " big2 := (a + b) / 1 > 32767; s2 := (a + b) * 2 / 4;")
    assert val(sim, "avg") == 30000
    assert val(sim, "big") is True
    assert val(sim, "big2") is True            # the quotient is an int too
    assert val(sim, "s2") == 30000
    assert val(sim, "m") == 60000 % 7          # 1; wrapped first it would be -5536 MOD 7 = -6
    assert val(sim, "r") == 600


def test_unsigned_small_types_promote_to_signed_int():
    # UINT 1 - 2 is the C int -1 inside an expression (so it is < 0), 65535 once stored
    sim = once("VAR a : UINT := 1; b : UINT := 2; neg : BOOL; d : UINT; x : UDINT := 1; y : UDINT := 2;"
               " neg32 : BOOL; END_VAR",
               "neg := a - b < 0; d := a - b; neg32 := x - y < 0;")
    assert val(sim, "neg") is True
    assert val(sim, "d") == 65535
    assert val(sim, "neg32") is False          # UDINT is unsigned int: no promotion, no sign


def test_not_of_byte_is_a_promoted_int_in_comparisons():
    # NOT is C's `~` on a promoted uint8: NOT 16#FF is the int -256, so the comparison is
    # FALSE, though the value stored in a BYTE is 0
    sim = once("VAR b : BYTE := 16#FF; nb : BYTE; cmp : BOOL; w : WORD := 16#00FF; m : WORD; END_VAR",
               "nb := NOT b; cmp := NOT b = 0; m := NOT w AND 16#0F0F;")
    assert val(sim, "nb") == 0
    assert val(sim, "cmp") is False
    assert val(sim, "m") == 0x0F00


def test_mod_and_division_with_negative_operands_truncate_like_c():
    sim = once("VAR a : INT := -7; b : INT := 3; m1, m2, m3, d1, d2 : INT; z : INT; mz : INT; END_VAR",
               "m1 := a MOD b; m2 := 7 MOD -3; m3 := -7 MOD -3; d1 := a / b; d2 := 7 / -2;"
               " mz := a MOD z;")
    assert val(sim, "m1") == -1                # sign of the dividend (C %), not Python's 2
    assert val(sim, "m2") == 1
    assert val(sim, "m3") == -1
    assert val(sim, "d1") == -2                # truncation toward zero, not floor (-3)
    assert val(sim, "d2") == -3
    assert val(sim, "mz") == 0                 # ((b == 0)?0:(a % b))
    assert sim.plc.state == "RUN"


def test_mod_of_the_most_negative_value_by_minus_one_faults_like_the_library_mod():
    # C's `INT_MIN % -1` traps (SIGFPE on x86: OpenPLC's runtime dies), as MOD(a, b) does
    for ty, lo in (("DINT", -2**31), ("LINT", -2**63)):
        for body in ("r := a MOD b;", "r := MOD(a, b);"):
            sim = once(f"VAR a : {ty} := {lo}; b : {ty} := -1; r : {ty} := 5; END_VAR", body)
            assert sim.plc.state == "FAULT", (ty, body)
            assert sim.plc.fault.kind == "division_overflow"
            assert val(sim, "r") == 5
    # one above the most negative value is an ordinary remainder
    sim = once("VAR a : DINT := -2147483647; b : DINT := -1; r : DINT := 5; END_VAR", "r := a MOD b;")
    assert (sim.plc.state, val(sim, "r")) == ("RUN", 0)


def test_mod_by_a_positive_constant_keeps_the_sign_of_the_dividend():
    # the compiler inlines MOD by a positive constant: same C semantics as the general case
    sim = once("VAR a : INT := -7; m1, m2, m3, m4 : INT; d : DINT := -2147483648; m5 : DINT; END_VAR",
               "m1 := a MOD 3; m2 := (a - 3) MOD 4; m3 := (a * a) MOD 5; m4 := (a + 7) MOD 6; m5 := d MOD 10;")
    assert (val(sim, "m1"), val(sim, "m2"), val(sim, "m3"), val(sim, "m4")) == (-1, -2, 4, 0)
    assert val(sim, "m5") == -8


# --------------------------------------------------------------------------- REAL

def test_real_is_single_precision():
    sim = once("VAR r : REAL := 16777216.0; r1 : REAL; x : REAL := 0.1; l : LREAL := 0.1; d : LREAL;"
               " third : REAL; END_VAR",
               "r1 := r + 1.0; d := REAL_TO_LREAL(x); third := 1.0 / 3.0;")
    assert val(sim, "r1") == 16777216.0        # 2**24 + 1 is not a float
    assert val(sim, "d") == to_f32(0.1) != 0.1
    assert val(sim, "l") == 0.1
    assert val(sim, "third") == to_f32(1.0 / 3.0)


def test_real_compared_with_untyped_literal_is_compared_in_double():
    # `r = 0.1` is `(r == 0.1)` in C: the float 0.1f widened to double is not the double 0.1
    sim = once("VAR r : REAL; same, above, same_t : BOOL; big : REAL := 16777216.0; grows : BOOL; END_VAR",
               "r := 0.1; same := r = 0.1; above := r > 0.1; same_t := r = REAL#0.1;"
               " grows := big + 1.0 > big;")
    assert val(sim, "same") is False
    assert val(sim, "above") is True
    assert val(sim, "same_t") is True            # a typed literal is a float
    assert val(sim, "grows") is True           # computed in double, not rounded to REAL


def test_real_filter_with_literals_rounds_once_per_assignment():
    # y := y * 0.9 + x * 0.1 is evaluated in double (literals are doubles) and rounded to
    # REAL once per scan; rounding every operation to REAL drifts to a different value
    sim = program("VAR x : REAL := 100.0; y : REAL; END_VAR", "y := y * 0.9 + x * 0.1;")
    sim.step(200)
    c_model = f32_each = 0.0
    for _ in range(200):
        c_model = to_f32(c_model * 0.9 + 100.0 * 0.1)
        f32_each = to_f32(to_f32(f32_each * to_f32(0.9)) + to_f32(100.0 * to_f32(0.1)))
    assert c_model != f32_each                 # the two models really differ here
    assert val(sim, "y") == c_model


def test_real_division_by_zero_is_infinite_not_a_fault():
    sim = once("VAR a : REAL := 1.0; z : REAL; q : REAL; n : REAL; END_VAR",
               "q := a / z; n := -a / z;")
    assert val(sim, "q") == float("inf")
    assert val(sim, "n") == float("-inf")
    assert sim.plc.state == "RUN"


def test_expt_of_negative_bases_and_nested():
    # `**` does not build in OpenPLC (tests/frontend: sem_power_operator); EXPT is its form
    sim = once("VAR a, b, c : LREAL; x : LREAL := 2.0; END_VAR",
               "a := EXPT(-2.0, 2.0); b := EXPT(-x, 3.0); c := EXPT(EXPT(2.0, 3.0), 2.0);")
    assert val(sim, "a") == 4.0
    assert val(sim, "b") == -8.0
    assert val(sim, "c") == 64.0


def test_real_to_int_of_expression():
    sim = once("VAR x : REAL := 10.0; i : INT; END_VAR", "i := REAL_TO_INT(x / 4.0);")
    assert val(sim, "i") == 2                  # 2.5 rounds to even (__real_round)


# --------------------------------------------------------------------------- precedence

def test_not_binds_tighter_than_and():
    sim = once("VAR a : BOOL := FALSE; b : BOOL := FALSE; r1, r2 : BOOL; END_VAR",
               "r1 := NOT a AND b; r2 := NOT (a AND b);")
    assert val(sim, "r1") is False             # (NOT a) AND b
    assert val(sim, "r2") is True


def test_arithmetic_and_logic_precedence():
    sim = once("VAR a, b, c : INT; t, f : BOOL := TRUE; o : BOOL; x : BOOL; END_VAR",
               "a := 2 + 3 * 4; b := (2 + 3) * 4; c := 10 - 4 - 3; f := FALSE;"
               " o := t OR f AND f; x := t XOR t OR t;")
    assert (val(sim, "a"), val(sim, "b"), val(sim, "c")) == (14, 20, 3)
    assert val(sim, "o") is True               # AND before OR
    assert val(sim, "x") is True               # XOR before OR: (t XOR t) OR t


def test_comparison_chain_with_booleans():
    # comparisons bind tighter than AND; `=` on BOOL results compares the booleans
    sim = once("VAR a : INT := 1; b : INT := 2; c : INT := 3; r1, r2, r3 : BOOL; END_VAR",
               "r1 := a < b AND b < c; r2 := (a < b) = (b < c); r3 := a < b = FALSE;")
    assert val(sim, "r1") is True
    assert val(sim, "r2") is True
    assert val(sim, "r3") is False             # (a < b) = FALSE


def test_bitwise_ops_on_words():
    sim = once("VAR w : WORD := 16#F0F0; a, o, x : WORD; b : BYTE := 16#0F; nb : BYTE; END_VAR",
               "a := w AND 16#FF00; o := w OR 16#000F; x := w XOR 16#FFFF; nb := NOT b;")
    assert val(sim, "a") == 0xF000
    assert val(sim, "o") == 0xF0FF
    assert val(sim, "x") == 0x0F0F
    assert val(sim, "nb") == 0xF0


# --------------------------------------------------------------------------- TIME

def test_time_arithmetic():
    sim = once("VAR a : TIME := T#1s; b : TIME := T#250ms; s, d, m, q : TIME; n : TIME; END_VAR",
               "s := a + b; d := b - a; m := b * 4; q := a / 4; n := T#1m30s;")
    assert val(sim, "s") == 1250 * MS
    assert val(sim, "d") == -750 * MS
    assert val(sim, "m") == S
    assert val(sim, "q") == 250 * MS
    assert val(sim, "n") == 90 * S


def test_time_comparisons_and_literal_forms():
    sim = once("VAR a : TIME := T#1500ms; less, same, atleast : BOOL; neg : BOOL; END_VAR",
               "less := a < T#1s500ms; same := a = TIME#1.5s; atleast := a >= t#1s; neg := T#-2s < T#0s;")
    assert val(sim, "less") is False
    assert val(sim, "same") is True
    assert val(sim, "atleast") is True
    assert val(sim, "neg") is True


def test_elapsed_time_measured_with_ton_et():
    sim = program("VAR t : TON; el : TIME; late : BOOL; END_VAR",
                  "t(IN := TRUE, PT := T#1h); el := t.ET; late := el >= T#70ms;", tick_ms=10)
    sim.step(8)                                # scans at 0..70 ms
    assert val(sim, "el") == 70 * MS
    assert val(sim, "late") is True
