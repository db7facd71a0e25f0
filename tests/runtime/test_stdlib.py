"""Standard functions with OpenPLC's semantics (plclab.runtime.stdlib).

"lib.h" below is webserver/core/lib/iec_std_lib.h, "functions.h" is iec_std_functions.h and
"generate_c_st.cc" is utils/matiec_src/stage4/generate_c/generate_c_st.cc, all in
thiagoralves/OpenPLC_v3.
"""
from __future__ import annotations

import math

import pytest

from plclab.iec import types as T
from plclab.iec.types import (BOOL, BYTE, DATE, DINT, DT, DWORD, INT, LINT, LREAL, LWORD, REAL,
                              SINT, STRING, TIME, TOD, UDINT, UINT, USINT, WORD, to_f32)
from plclab.runtime.stdlib import NoSuchFunction, PlcRuntimeFault, lookup, lookup_operator

S_ = 1_000_000_000
MS = 1_000_000


def call(name, types, result, *args):
    return lookup(name, types, result)(*args)


# --------------------------------------------------------------------------- arithmetic


def test_add_int_wraps_like_a_16_bit_c_short():
    assert call("ADD", [INT, INT], INT, 32767, 1) == -32768


def test_add_is_extensible_and_wraps_uint():
    assert call("ADD", [UINT] * 4, UINT, 65000, 500, 30, 10) == 4


def test_mul_sint_wraps():
    assert call("MUL", [SINT, SINT], SINT, 16, 8) == -128


def test_sub_usint_below_zero_wraps_to_255():
    assert call("SUB", [USINT, USINT], USINT, 0, 1) == 255


def test_add_real_rounds_every_step_to_single_precision():
    a, b = to_f32(0.1), to_f32(0.2)
    got = call("ADD", [REAL, REAL], REAL, a, b)
    assert got == to_f32(a + b) and got != a + b


def test_div_int_truncates_toward_zero():
    assert call("DIV", [INT, INT], INT, -7, 2) == -3


def test_div_function_by_zero_returns_zero():
    # functions.h DIV_*: TEST_EN_COND(op2 == 0) returns the type's initial value, ENO FALSE
    assert call("DIV", [DINT, DINT], DINT, 42, 0) == 0
    assert call("DIV", [REAL, REAL], REAL, 1.5, 0.0) == 0.0


def test_div_operator_by_zero_is_a_fault():
    # generate_c_st.cc emits a plain C `/`: an integer division by zero traps
    with pytest.raises(PlcRuntimeFault) as e:
        lookup_operator("/", [INT, INT], INT)(5, 0)
    assert e.value.kind == "division_by_zero"


def test_real_division_operator_by_zero_gives_infinity():
    assert lookup_operator("/", [REAL, REAL], REAL)(-1.0, 0.0) == -math.inf


def test_dint_min_divided_by_minus_one_traps_but_int_wraps():
    with pytest.raises(PlcRuntimeFault) as e:
        lookup_operator("/", [DINT, DINT], DINT)(-2**31, -1)
    assert e.value.kind == "division_overflow"
    assert lookup_operator("/", [INT, INT], INT)(-32768, -1) == -32768  # promoted to int


@pytest.mark.parametrize("a, b, expected", [(-7, 3, -1), (7, -3, 1), (-7, -3, -1), (7, 3, 1)])
def test_mod_takes_the_sign_of_the_dividend(a, b, expected):
    assert call("MOD", [INT, INT], INT, a, b) == expected


def test_mod_by_zero_is_zero_for_function_and_operator():
    # functions.h MOD_*: `if (op2 == 0) return 0`; generate_c_st.cc: `((b == 0)?0:a % b)`
    assert call("MOD", [DINT, DINT], DINT, 7, 0) == 0
    assert lookup_operator("MOD", [INT, INT], INT)(7, 0) == 0


def test_abs_of_int_minimum_wraps_to_itself():
    assert call("ABS", [INT], INT, -32768) == -32768
    assert call("ABS", [INT], INT, -5) == 5


def test_expt_is_c_pow_in_the_base_type():
    assert call("EXPT", [REAL, INT], REAL, 2.0, 10) == 1024.0
    assert math.isnan(call("EXPT", [LREAL, LREAL], LREAL, -8.0, 1 / 3))
    assert call("EXPT", [LREAL, INT], LREAL, 0.0, -1) == math.inf


def test_numeric_functions_return_c_special_values():
    assert math.isnan(call("SQRT", [REAL], REAL, -1.0))
    assert call("LN", [LREAL], LREAL, 0.0) == -math.inf
    assert call("EXP", [REAL], REAL, 1000.0) == math.inf
    assert call("LOG", [REAL], REAL, 1000.0) == pytest.approx(3.0)
    assert call("SIN", [REAL], REAL, 1.0) == to_f32(math.sin(1.0))


# --------------------------------------------------------------------------- conversions


@pytest.mark.parametrize("x, expected", [
    (2.5, 2), (3.5, 4), (-2.5, -2), (0.5, 0), (1.5, 2), (2.4999, 2), (2.6, 3), (-2.6, -3),
])
def test_real_to_int_rounds_half_to_even(x, expected):
    # lib.h __real_round: an exact .5 becomes ((LINT)x / 2) * 2
    assert call("REAL_TO_INT", [REAL], INT, to_f32(x)) == expected


def test_real_to_int_out_of_range_wraps_modulo_16_bits():
    assert call("REAL_TO_INT", [REAL], INT, 40000.0) == -25536


def test_real_to_unsigned_of_a_negative_value_is_zero():
    # lib.h __preal_to_uint: IN >= 0 ? ... : 0
    assert call("REAL_TO_UINT", [REAL], UINT, -3.7) == 0
    assert call("REAL_TO_BYTE", [REAL], BYTE, 300.4) == 44


def test_trunc_cuts_toward_zero():
    assert call("TRUNC", [REAL], INT, to_f32(-2.7)) == -2
    assert call("TRUNC", [LREAL], DINT, 2.9) == 2


def test_trunc_out_of_range_gives_x86_integer_indefinite():
    assert call("TRUNC", [LREAL], DINT, 3e9) == -2**31


def test_int_to_real_rounds_once_to_single_precision():
    assert call("DINT_TO_REAL", [DINT], REAL, 16777217) == 16777216.0
    assert call("LINT_TO_REAL", [LINT], REAL, 2**60 + 2**36 + 1) == float(2**60 + 2**37)


def test_conversions_to_bool_test_for_nonzero():
    assert call("INT_TO_BOOL", [INT], BOOL, -3) is True
    assert call("REAL_TO_BOOL", [REAL], BOOL, 0.0) is False
    assert call("TIME_TO_BOOL", [TIME], BOOL, 1) is True


def test_int_to_time_counts_seconds_not_milliseconds():
    # lib.h __int_to_time: (TIME){IN, 0}
    assert call("INT_TO_TIME", [INT], TIME, 5) == 5 * S_
    assert call("DINT_TO_DATE", [DINT], DATE, 86400) == 86400 * S_


def test_time_to_int_is_whole_seconds_truncated():
    # lib.h __time_to_int returns tv_sec
    assert call("TIME_TO_DINT", [TIME], DINT, 1500 * MS) == 1
    assert call("TIME_TO_DINT", [TIME], DINT, -1500 * MS) == -1


def test_time_to_real_and_back_are_in_seconds():
    assert call("TIME_TO_REAL", [TIME], REAL, 1500 * MS) == 1.5
    assert call("REAL_TO_TIME", [REAL], TIME, 1.5) == 1500 * MS


def test_dt_splits_into_date_and_tod_and_concat_joins_them():
    dt = (3 * 86400 + 3661) * S_ + 5
    date = call("DT_TO_DATE", [DT], DATE, dt)
    tod = call("DT_TO_TOD", [DT], TOD, dt)
    assert (date, tod) == (3 * 86400 * S_, 3661 * S_ + 5)
    assert call("CONCAT_DATE_TOD", [DATE, TOD], DT, date, tod) == dt


def test_unsupported_time_conversions_do_not_exist():
    # functions.h: "Not supported: TOD_TO_TIME", DATE_TO_DT, TIME_TO_TOD...
    for name, src in (("TOD_TO_TIME", TOD), ("DATE_TO_DT", DATE), ("TIME_TO_TOD", TIME)):
        with pytest.raises(NoSuchFunction):
            lookup(name, [src], TIME)


@pytest.mark.parametrize("name, src, value, text", [
    ("INT_TO_STRING", INT, -42, "-42"),
    ("UDINT_TO_STRING", UDINT, 4000000000, "4000000000"),
    ("BYTE_TO_STRING", BYTE, 255, "16#ff"),          # lib.h __bit_to_string: "16#%llx"
    ("BOOL_TO_STRING", BOOL, True, "TRUE"),
    ("REAL_TO_STRING", REAL, to_f32(0.1), "0.1000000015"),   # "%.10g" of the widened float
    ("LREAL_TO_STRING", LREAL, 1e20, "1e+20"),
])
def test_to_string_formats(name, src, value, text):
    assert call(name, [src], STRING, value) == text


@pytest.mark.parametrize("ns, text", [
    (90 * S_, "T#0d0h1m30s"),
    (1500 * MS, "T#0d0h0m1s500ms"),
    (2 * 86400 * S_, "T#2d"),
    (3600 * S_, "T#0d1h"),
])
def test_time_to_string_formats(ns, text):
    assert call("TIME_TO_STRING", [TIME], STRING, ns) == text


def test_date_to_string_shows_the_first_of_a_month_as_day_32_of_the_previous():
    # lib.h convert_seconds_to_date_and_time: `while (days > __mon_yday[..][mon])` needs >=
    assert call("DATE_TO_STRING", [DATE], STRING, 0) == "D#1970-01-01"
    assert call("DATE_TO_STRING", [DATE], STRING, 31 * 86400 * S_) == "D#1970-01-32"
    assert call("DATE_TO_STRING", [DATE], STRING, 32 * 86400 * S_) == "D#1970-02-02"


def test_tod_to_string_with_fraction_and_out_of_range():
    tod = (13 * 3600 + 5 * 60 + 7) * S_ + 250 * MS
    assert call("TOD_TO_STRING", [TOD], STRING, tod) == "TOD#13:05:07.250000"
    assert call("TOD_TO_STRING", [TOD], STRING, 86400 * S_) == "TOD#ERROR"


@pytest.mark.parametrize("text, expected", [
    ("123", 123), ("-42", -42), (" 42", 42),
    ("12.7", 12),      # the '.' restarts the number read from the right
    ("1_000", 1),      # so does '_'
    ("16#FF", 255), ("40000", -25536),
])
def test_string_to_int_parses_like_openplc(text, expected):
    # lib.h __pstring_to_sint
    assert call("STRING_TO_INT", [STRING], INT, text) == expected


def test_string_to_bits_accepts_base_prefixes():
    assert call("STRING_TO_BYTE", [STRING], BYTE, "2#1010") == 10
    assert call("STRING_TO_WORD", [STRING], WORD, "8#777") == 511


def test_string_to_real_needs_a_dot_after_the_first_character():
    # lib.h __string_to_real: atof only if a '.' is found at index >= 1
    assert call("STRING_TO_REAL", [STRING], REAL, "2.5") == 2.5
    assert call("STRING_TO_LREAL", [STRING], LREAL, "-1.25e2x") == -125.0
    assert call("STRING_TO_REAL", [STRING], REAL, "1e3") == 1.0
    assert call("STRING_TO_REAL", [STRING], REAL, ".5") == 0.0


def test_string_to_bool_and_time():
    assert call("STRING_TO_BOOL", [STRING], BOOL, "true") is True
    assert call("STRING_TO_BOOL", [STRING], BOOL, "1") is True
    assert call("STRING_TO_BOOL", [STRING], BOOL, "yes") is False
    # lib.h __string_to_time: seconds only, the fraction is dropped; 'T#5s' is not parsed
    assert call("STRING_TO_TIME", [STRING], TIME, "7") == 7 * S_
    assert call("STRING_TO_TIME", [STRING], TIME, "1.5") == 1 * S_
    assert call("STRING_TO_TIME", [STRING], TIME, "T#5s") == 0


def test_bcd_round_trip_and_invalid_digit():
    assert call("UINT_TO_BCD_WORD", [UINT], WORD, 1234) == 0x1234
    assert call("WORD_BCD_TO_UINT", [WORD], UINT, 0x1234) == 1234
    # functions.h BCD_TO: TEST_EN_COND(__test_bcd(op)) -> 0 for a nibble > 9
    assert call("WORD_BCD_TO_UINT", [WORD], UINT, 0x12A4) == 0
    assert call("UDINT_TO_BCD_BYTE", [UDINT], BYTE, 1234) == 0x34


# --------------------------------------------------------------------------- bit strings


@pytest.mark.parametrize("n, expected", [(1, 0x02), (7, 0x80), (8, 0x00), (20, 0x00), (33, 0x02)])
def test_shl_byte_masks_to_8_bits_and_x86_masks_the_count(n, expected):
    # `IN << N` on a BYTE promoted to int: bits past 8 are cut on return; the CPU uses N & 31
    assert call("SHL", [BYTE, INT], BYTE, 0x81, n) == expected


def test_shr_word_and_dword_beyond_width():
    assert call("SHR", [WORD, INT], WORD, 0x8001, 15) == 1
    assert call("SHR", [WORD, INT], WORD, 0x8001, 16) == 0
    assert call("SHR", [DWORD, INT], DWORD, 0x80000001, 32) == 0x80000001  # count & 31 == 0


def test_rotates_wrap_the_count_modulo_the_width():
    assert call("ROL", [BYTE, INT], BYTE, 0x81, 1) == 0x03
    assert call("ROR", [BYTE, INT], BYTE, 0x81, 9) == 0xC0
    assert call("ROL", [BYTE, SINT], BYTE, 0x81, -1) == 0xC0   # N %= 8 in size_t arithmetic
    assert call("ROR", [LWORD, INT], LWORD, 1, 1) == 2**63


def test_shift_and_rotate_of_a_bool():
    assert call("SHL", [BOOL, INT], BOOL, True, 0) is True
    assert call("SHL", [BOOL, INT], BOOL, True, 1) is False
    assert call("ROR", [BOOL, INT], BOOL, True, 5) is True


def test_bitwise_functions_are_masked_and_extensible():
    assert call("NOT", [WORD], WORD, 0x00FF) == 0xFF00
    assert call("AND", [BYTE] * 3, BYTE, 0xF0, 0x3C, 0xFF) == 0x30
    assert call("XOR", [BOOL] * 3, BOOL, True, True, True) is True


# --------------------------------------------------------------------------- selection


@pytest.mark.parametrize("mn, x, mx, expected", [(0, 50, 100, 50), (0, -5, 100, 0), (0, 150, 100, 100)])
def test_limit_clamps(mn, x, mx, expected):
    assert call("LIMIT", [INT] * 3, INT, mn, x, mx) == expected


def test_limit_with_mn_above_mx_returns_mx_for_high_inputs_else_mn():
    # functions.h: IN > MN ? IN < MX ? IN : MX : MN
    assert call("LIMIT", [INT] * 3, INT, 10, 5, 0) == 10
    assert call("LIMIT", [INT] * 3, INT, 10, 20, 0) == 0


def test_mux_is_zero_based_and_out_of_range_gives_the_initial_value():
    mux = lookup("MUX", [INT, INT, INT, INT], INT)
    assert [mux(k, 10, 20, 30) for k in range(3)] == [10, 20, 30]
    assert mux(3, 10, 20, 30) == 0 and mux(-1, 10, 20, 30) == 0
    assert call("MUX", [INT, STRING, STRING], STRING, 5, "a", "b") == ""


def test_sel_picks_in1_when_g_is_true():
    assert call("SEL", [BOOL, INT, INT], INT, True, 1, 2) == 2
    assert call("SEL", [BOOL, INT, INT], INT, False, 1, 2) == 1


def test_max_min_are_extensible():
    assert call("MAX", [INT] * 4, INT, 3, 9, -2, 7) == 9
    assert call("MIN", [REAL] * 3, REAL, 3.0, -1.5, 2.0) == -1.5
    assert call("MAX", [TIME, TIME], TIME, 2 * S_, 1 * S_) == 2 * S_


def test_comparisons_chain_over_all_inputs():
    assert call("GT", [INT] * 3, BOOL, 3, 2, 1) is True
    assert call("GT", [INT] * 3, BOOL, 3, 1, 2) is False
    assert call("EQ", [INT] * 3, BOOL, 4, 4, 4) is True


def test_string_comparison_only_looks_at_the_shorter_length():
    # functions.h __STR_CMP: memcmp(..., min(len1, len2))
    assert call("EQ", [STRING, STRING], BOOL, "AB", "ABC") is True
    assert lookup_operator("<", [STRING, STRING], BOOL)("AB", "ABC") is False
    assert call("MAX", [STRING, STRING], STRING, "AB", "ABC") == "AB"
    assert call("LT", [STRING, STRING], BOOL, "ABC", "ABD") is True


def test_nan_compares_unequal_to_everything():
    nan = float("nan")
    assert call("NE", [REAL, REAL], BOOL, nan, nan) is True
    assert call("EQ", [REAL, REAL], BOOL, nan, nan) is False


# --------------------------------------------------------------------------- strings


def test_len_left_right():
    assert call("LEN", [STRING], INT, "hello") == 5
    assert call("LEFT", [STRING, INT], STRING, "ABC", 5) == "ABC"
    assert call("RIGHT", [STRING, INT], STRING, "ABCDE", 2) == "DE"
    assert call("LEFT", [STRING, INT], STRING, "ABC", -1) == ""


def test_mid_uses_one_based_positions():
    mid = lookup("MID", [STRING, INT, INT], STRING)
    assert mid("ABCDEF", 3, 2) == "BCD"
    assert mid("ABCDEF", 3, 5) == "EF"
    assert mid("ABC", 1, 4) == ""


def test_mid_at_position_zero_reads_the_length_byte():
    # functions.h MID: P -= 1 then memcpy from &IN.body[-1], the int8 length field
    assert call("MID", [STRING, INT, INT], STRING, "ABC", 2, 0) == "\x03A"


def test_concat_is_extensible_and_truncates_at_126():
    assert call("CONCAT", [STRING] * 3, STRING, "a", "b", "c") == "abc"
    assert len(call("CONCAT", [STRING] * 2, STRING, "x" * 100, "y" * 100)) == 126


def test_insert_after_p_characters():
    ins = lookup("INSERT", [STRING, STRING, INT], STRING)
    assert ins("ABC", "XY", 2) == "ABXYC"
    assert ins("ABC", "XY", 0) == "XYABC"
    assert ins("ABC", "XY", 9) == "ABCXY"


def test_delete_and_replace():
    assert call("DELETE", [STRING, INT, INT], STRING, "ABXYC", 2, 3) == "ABC"
    rep = lookup("REPLACE", [STRING, STRING, INT, INT], STRING)
    assert rep("ABCDE", "X", 2, 3) == "ABXE"
    assert rep("ABCDE", "XYZ", 1, 2) == "AXCDE"   # IN2 is cut to L characters


def test_delete_at_position_zero_is_a_memory_fault():
    # functions.h __delete: to_copy = P-1 = -1, memcpy of (size_t)-1 bytes
    with pytest.raises(PlcRuntimeFault) as e:
        call("DELETE", [STRING, INT, INT], STRING, "ABC", 1, 0)
    assert e.value.kind == "memory_fault"


def test_find_returns_one_based_position():
    assert call("FIND", [STRING, STRING], INT, "ABCDE", "CD") == 3
    assert call("FIND", [STRING, STRING], INT, "ABC", "X") == 0


def test_find_bug_a_miss_of_a_two_character_pattern_returns_len_plus_one():
    # functions.h __pfind: `return count2 == IN2->len - 1 ? 0 : count1 + 1;`
    assert call("FIND", [STRING, STRING], INT, "ABC", "XY") == 4
    assert call("FIND", [STRING, STRING], INT, "AAB", "AB") == 4   # no backtracking


# --------------------------------------------------------------------------- time


def test_time_arithmetic_functions():
    assert call("ADD_TIME", [TIME, TIME], TIME, 1 * S_, 500 * MS) == 1500 * MS
    assert call("SUB_DATE_DATE", [DATE, DATE], TIME, 86400 * S_, 0) == 86400 * S_
    assert call("MUL", [TIME, INT], TIME, 1500 * MS, 2) == 3 * S_
    assert call("DIV", [TIME, INT], TIME, 1 * S_, 4) == 250 * MS
    assert call("MULTIME", [TIME, REAL], TIME, 1 * S_, 2.5) == 2500 * MS


def test_time_multiplication_overflows_when_the_nanosecond_product_passes_2_31():
    # lib.h __time_mul: div((int)(tv_nsec * IN2), 1e9) overflows an int: T#900ms * 3 < 0
    assert call("MUL", [TIME, INT], TIME, 900 * MS, 3) == -2147483648
    assert lookup_operator("*", [TIME, INT], TIME)(900 * MS, 2) == 1800 * MS


# --------------------------------------------------------------------------- lookup


def test_unknown_or_untyped_calls_raise_no_such_function():
    with pytest.raises(NoSuchFunction):
        lookup("FOO", [INT], INT)
    with pytest.raises(NoSuchFunction):
        lookup("MOD", [REAL, REAL], REAL)
    with pytest.raises(NoSuchFunction):
        lookup_operator("*", [INT, TIME], TIME)  # __time_mul(number, TIME) does not compile


def test_sized_strings_are_strings_for_every_lookup():
    s20 = T.StringType("STRING", 20)          # STRING[20] is its own type object
    assert call("STRING_TO_INT", [s20], INT, "42") == 42
    assert call("MAX_STRING", [s20, STRING], STRING, "A", "B") == "B"
    assert call("LEN", [s20], INT, "abc") == 3
