"""Standard functions called from ST: conversions, bit shifts, selection, strings, EXPT.

Reference: OpenPLC v3's C library `webserver/core/lib/iec_std_lib.h` and
`iec_std_functions.h` (the same files as `utils/matiec_src/lib/C/`).
The facts are collected in docs/openplc-stdlib-notes.md.
"""
from __future__ import annotations

import math

import pytest

from st_helpers import MS, S, once, val

pytestmark = pytest.mark.usefixtures("compile_mode")


# --------------------------------------------------------------------------- conversions

@pytest.mark.parametrize("x, expected", [
    # iec_std_lib.h __preal_to_sint / __real_round: IN +- 0.5, then an exact integer is made
    # even ((LINT)IN / 2 * 2): halves round to even, everything else to nearest
    ("2.5", 2), ("3.5", 4), ("-2.5", -2), ("1.4", 1), ("-1.6", -2), ("2.6", 3), ("0.5", 0),
])
def test_real_to_int_rounding(x, expected):
    sim = once(f"VAR r : REAL := {x}; i : INT; END_VAR", "i := REAL_TO_INT(r);")
    assert val(sim, "i") == expected


def test_real_to_uint_negative_gives_zero_and_trunc_truncates():
    # iec_std_lib.h __preal_to_uint: IN < 0 -> 0 (no wrap); TRUNC goes toward zero
    sim = once("VAR r : REAL := -3.7; u : UINT; t : INT; d : DINT; END_VAR",
               "u := REAL_TO_UINT(r); t := TRUNC(r); d := TRUNC(LREAL#2.99);")
    assert val(sim, "u") == 0
    assert val(sim, "t") == -3
    assert val(sim, "d") == 2


def test_integer_narrowing_conversions_wrap():
    sim = once("VAR a : INT := 300; b : SINT; c : DINT := 70000; d : INT; e : INT := -1;"
               " f : UINT; w : WORD := 16#FFFF; g : INT; h : BYTE; END_VAR",
               "b := INT_TO_SINT(a); d := DINT_TO_INT(c); f := INT_TO_UINT(e);"
               " g := WORD_TO_INT(w); h := INT_TO_BYTE(a);")
    assert val(sim, "b") == 44          # 300 - 256
    assert val(sim, "d") == 4464        # 70000 - 65536
    assert val(sim, "f") == 65535
    assert val(sim, "g") == -1
    assert val(sim, "h") == 44


def test_bool_and_real_conversions():
    sim = once("VAR b : BOOL := TRUE; i : INT; x : INT := 7; r : REAL; z : BOOL; k : INT := 0;"
               " y : BOOL; END_VAR",
               "i := BOOL_TO_INT(b); r := INT_TO_REAL(x) / 2.0; z := INT_TO_BOOL(x);"
               " y := INT_TO_BOOL(k);")
    assert val(sim, "i") == 1
    assert val(sim, "r") == 3.5
    assert val(sim, "z") is True and val(sim, "y") is False


def test_time_conversions_count_seconds():
    # iec_std_lib.h: __time_to_int returns IN.tv_sec (whole seconds, not ms);
    # __int_to_time builds (TIME){IN, 0}, i.e. IN seconds; __time_to_real is seconds too
    sim = once("VAR t : TIME := T#1s500ms; d : DINT; r : REAL; u : TIME; END_VAR",
               "d := TIME_TO_DINT(t); r := TIME_TO_REAL(t); u := DINT_TO_TIME(5);")
    assert val(sim, "d") == 1
    assert val(sim, "r") == 1.5
    assert val(sim, "u") == 5 * S


def test_string_number_conversions():
    sim = once("VAR s : STRING := '123'; i : INT; n : INT := -42; t : STRING; END_VAR",
               "i := STRING_TO_INT(s) + 1; t := INT_TO_STRING(n);")
    assert val(sim, "i") == 124
    assert val(sim, "t") == "-42"


# --------------------------------------------------------------------------- shifts and rotates

def test_shifts_on_byte_and_word():
    sim = once("VAR b : BYTE := 16#81; w : WORD := 16#8001; r1, r2, r3 : BYTE; r4, r5 : WORD; END_VAR",
               "r1 := SHL(b, 1); r2 := SHR(b, 1); r3 := SHL(b, 8); r4 := SHL(w, 4); r5 := SHR(w, 15);")
    assert val(sim, "r1") == 0x02       # the bit shifted out of a BYTE is lost
    assert val(sim, "r2") == 0x40
    assert val(sim, "r3") == 0x00       # shift by the full width clears it
    assert val(sim, "r4") == 0x0010
    assert val(sim, "r5") == 0x0001


def test_rotates_by_width_and_beyond():
    # iec_std_functions.h ROL/ROR: N %= 8*sizeof(IN), so rotating by the width is identity
    sim = once("VAR b : BYTE := 16#81; w : WORD := 1; d : DWORD := 16#80000000;"
               " r1, r2, r3, r4 : BYTE; r5 : WORD; r6 : DWORD; END_VAR",
               "r1 := ROL(b, 1); r2 := ROR(b, 1); r3 := ROL(b, 8); r4 := ROL(b, 9);"
               " r5 := ROR(w, 1); r6 := ROL(d, 1);")
    assert val(sim, "r1") == 0x03
    assert val(sim, "r2") == 0xC0
    assert val(sim, "r3") == 0x81
    assert val(sim, "r4") == 0x03
    assert val(sim, "r5") == 0x8000
    assert val(sim, "r6") == 0x00000001


# --------------------------------------------------------------------------- selection

def test_sel_mux():
    sim = once("VAR g : BOOL := TRUE; a : INT; b : INT; k : INT := 2; m : INT; m2 : INT := 99;"
               " k2 : INT := 5; END_VAR",
               "a := SEL(g, 10, 20); b := SEL(NOT g, 10, 20); m := MUX(k, 100, 200, 300, 400);"
               " m2 := MUX(k2, 1, 2, 3);")
    assert val(sim, "a") == 20          # G TRUE selects IN1
    assert val(sim, "b") == 10
    assert val(sim, "m") == 300         # K is 0-based
    # K out of range: OpenPLC's MUX returns the type's initial value (ENO FALSE)
    assert val(sim, "m2") == 0


def test_limit_max_min():
    sim = once("VAR x : INT := 150; y : INT := -5; a, b, c, d, e : INT; r : REAL; t : TIME; END_VAR",
               "a := LIMIT(0, x, 100); b := LIMIT(0, y, 100); c := LIMIT(0, 50, 100);"
               " d := MAX(3, x, 7); e := MIN(3, y, 7); r := MAX(1.5, 2.25);"
               " t := MIN(T#2s, T#500ms);")
    assert (val(sim, "a"), val(sim, "b"), val(sim, "c")) == (100, 0, 50)
    assert val(sim, "d") == 150
    assert val(sim, "e") == -5
    assert val(sim, "r") == 2.25
    assert val(sim, "t") == 500 * MS


def test_limit_with_mn_above_mx_returns_mn():
    # iec_std_functions.h LIMIT: IN > MN ? (IN < MX ? IN : MX) : MN
    sim = once("VAR a : INT; b : INT; END_VAR", "a := LIMIT(10, 5, 0); b := LIMIT(10, 20, 0);")
    assert val(sim, "a") == 10
    assert val(sim, "b") == 0


# --------------------------------------------------------------------------- strings

def test_string_functions():
    sim = once("VAR s : STRING := 'HELLO WORLD'; n : INT; l, r, m, c, i, d, p : STRING; f : INT;"
               " END_VAR",
               "n := LEN(s); l := LEFT(s, 5); r := RIGHT(s, 5); m := MID(s, 3, 2);"
               " c := CONCAT(l, '-', r); i := INSERT('ABEF', 'CD', 2); d := DELETE(s, 6, 6);"
               " p := REPLACE(s, 'THERE', 5, 7); f := FIND(s, 'WOR');")
    assert val(sim, "n") == 11
    assert val(sim, "l") == "HELLO"
    assert val(sim, "r") == "WORLD"
    assert val(sim, "m") == "ELL"       # MID(IN, L, P): L characters from position P (1-based)
    assert val(sim, "c") == "HELLO-WORLD"
    assert val(sim, "i") == "ABCDEF"    # INSERT after the first P characters
    assert val(sim, "d") == "HELLO"
    assert val(sim, "p") == "HELLO THERE"
    assert val(sim, "f") == 7


def test_string_comparison():
    # (STRING[n] does not build in OpenPLC: tests/frontend/cases/invalid/type_string_n_variable.st)
    sim = once("VAR t : STRING := 'ABC'; less, same, gt2 : BOOL; END_VAR",
               "less := t < 'ABD'; same := t = 'ABC'; gt2 := 'B' > t;")
    assert val(sim, "less") is True
    assert val(sim, "same") is True
    assert val(sim, "gt2") is True


def test_string_equality_compares_only_the_common_prefix():
    # iec_std_lib.h: __STR_CMP is memcmp over the *shorter* length, so in OpenPLC
    # 'AB' = 'ABC' is TRUE and '' equals every string
    sim = once("VAR a : STRING := 'AB'; b : STRING := 'ABC'; e : STRING; r1, r2, r3, r4 : BOOL; END_VAR",
               "r1 := a = b; r2 := e = 'XYZ'; r3 := a < b; r4 := 'ABD' = b;")
    assert val(sim, "r1") is True
    assert val(sim, "r2") is True
    assert val(sim, "r3") is False
    assert val(sim, "r4") is False


# --------------------------------------------------------------------------- numeric

# OpenPLC's library is C++: SIN(op) of a REAL calls the float overload, glibc's sinf, whose
# result can be one unit in the last place away from sin() rounded to REAL. Each value below
# is what OpenPLC computed (iec2c + g++ with webserver/core/lib, run), for an argument where
# the two differ; LREAL and SQRT are the double functions.
@pytest.mark.parametrize("call, openplc", [
    ("SIN(REAL#40.395835876464844)", 0.4303392767906189),
    ("COS(REAL#153.0837860107422)", -0.6567812561988831),
    ("TAN(REAL#98.38943481445312)", 1.557621955871582),
    ("ATAN(REAL#21.36781883239746)", 1.524031162261963),
    ("EXP(REAL#5.874266624450684)", 355.763671875),
    ("LN(REAL#217.871337890625)", 5.383904933929443),
    ("LOG(REAL#40.16196060180664)", 1.6038148403167725),
    ("ASIN(REAL#0.21408352255821228)", 0.2157534956932068),
    ("ACOS(REAL#0.48075562715530396)", 1.0692801475524902),
    ("EXPT(REAL#1.0574874877929688, REAL#-2.447187900543213)", 0.8721555471420288),   # powf
    ("EXPT(REAL#1.0574874877929688, n)", 1.1825668811798096),       # pow(float, int): in double
])
def test_real_math_functions_compute_in_single_precision_as_openplc_does(call, openplc):
    sim = once("VAR r : REAL; n : INT := 3; END_VAR", f"r := {call};")
    assert val(sim, "r") == openplc


def test_expt_and_numeric_functions():
    sim = once("VAR e1, e2, a, q, l : REAL; i : INT := -7; ai : INT; x : REAL := 2.0; END_VAR",
               "e1 := EXPT(x, 10); e2 := EXPT(x, -1.0); a := ABS(-2.5); ai := ABS(i);"
               " q := SQRT(16.0); l := EXPT(x, 0.5);")
    assert val(sim, "e1") == 1024.0
    assert val(sim, "e2") == 0.5
    assert val(sim, "a") == 2.5
    assert val(sim, "ai") == 7
    assert val(sim, "q") == 4.0
    assert val(sim, "l") == pytest.approx(math.sqrt(2.0), rel=1e-7)
    assert val(sim, "l") != math.sqrt(2.0)      # but single precision, not a double


def test_arithmetic_functions_and_move():
    sim = once("VAR a, b, c, d, f : INT; x : INT := 7; z : INT; END_VAR",
               "a := ADD(1, 2, 3, 4); b := MUL(x, 3); c := SUB(x, 10); d := DIV(x, 2);"
               " f := MOVE(x); z := DIV(x, z);")
    assert (val(sim, "a"), val(sim, "b"), val(sim, "c")) == (10, 21, -3)
    assert (val(sim, "d"), val(sim, "f")) == (3, 7)
    # the DIV *function* by zero returns 0 (iec_std_functions.h DIV: TEST_EN_COND on IN2 = 0);
    # only the `/` operator faults (see test_semantics_faults.py)
    assert val(sim, "z") == 0
    assert sim.plc.state == "RUN"


def test_comparison_functions_are_chains():
    # GT(a, b, c) is a > b AND b > c (extensible comparison in iec_std_functions.h)
    sim = once("VAR g1, g2, e1 : BOOL; END_VAR",
               "g1 := GT(5, 3, 1); g2 := GT(5, 3, 4); e1 := EQ(2, 2, 2);")
    assert val(sim, "g1") is True
    assert val(sim, "g2") is False
    assert val(sim, "e1") is True
