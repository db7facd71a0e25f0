"""POUs: FB instances, VAR_IN_OUT, VAR_TEMP, FUNCTION results and outputs, initial values,
R_EDGE / F_EDGE inputs."""
from __future__ import annotations

import pytest

from plclab.errors import CompileError
from plclab.iec.types import to_f32
from st_helpers import MS, S, once, program, val

pytestmark = pytest.mark.usefixtures("compile_mode")

COUNTER_FB = """
FUNCTION_BLOCK Acc
VAR_INPUT inc : INT; END_VAR
VAR_OUTPUT total : INT; calls : INT; END_VAR
VAR hidden : INT := 100; END_VAR
total := total + inc;
calls := calls + 1;
hidden := hidden + 1;
END_FUNCTION_BLOCK
"""


# --------------------------------------------------------------------------- FB instances

def test_two_instances_keep_separate_state():
    sim = program("VAR a : Acc; b : Acc; ta, tb : INT; END_VAR",
                  "a(inc := 1); b(inc := 10); b(inc := 10); ta := a.total; tb := b.total;",
                  COUNTER_FB)
    sim.step(3)
    assert val(sim, "ta") == 3
    assert val(sim, "tb") == 60
    assert val(sim, "a.calls") == 3 and val(sim, "b.calls") == 6
    assert val(sim, "a.hidden") == 103 and val(sim, "b.hidden") == 106


def test_fb_state_persists_across_scans_and_uncalled_instance_is_frozen():
    sim = program("VAR a : Acc; b : Acc; n : INT; END_VAR",
                  "n := n + 1; a(inc := 2); IF n <= 2 THEN b(inc := 5); END_IF;", COUNTER_FB)
    sim.step(6)
    assert val(sim, "a.total") == 12
    assert val(sim, "b.total") == 10


def test_fb_input_keeps_last_value_when_omitted():
    # an input not passed in a call keeps the value of the previous call (FB memory)
    sim = program("VAR a : Acc; n : INT; END_VAR",
                  "n := n + 1; IF n = 1 THEN a(inc := 7); ELSE a(); END_IF;", COUNTER_FB)
    sim.step(3)
    assert val(sim, "a.total") == 21


def test_fb_inside_fb_and_output_binding():
    extra = COUNTER_FB + """
FUNCTION_BLOCK Pair
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT s : INT; END_VAR
VAR lo : Acc; hi : Acc; END_VAR
lo(inc := x); hi(inc := x * 100);
s := lo.total + hi.total;
END_FUNCTION_BLOCK
"""
    sim = program("VAR p1, p2 : Pair; r1, r2 : INT; END_VAR",
                  "p1(x := 1, s => r1); p2(x := 2, s => r2);", extra)
    sim.step(2)
    assert val(sim, "r1") == 202
    assert val(sim, "r2") == 404


# --------------------------------------------------------------------------- VAR_IN_OUT

INOUT_FB = """
FUNCTION_BLOCK Bump
VAR_IN_OUT v : INT; END_VAR
VAR_INPUT amount : INT; END_VAR
v := v + amount;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Swap
VAR_IN_OUT a : INT; b : INT; END_VAR
VAR t : INT; END_VAR
t := a; a := b; b := t;
END_FUNCTION_BLOCK

FUNCTION_BLOCK FillArr
VAR_IN_OUT arr : ARRAY[0..3] OF INT; END_VAR
VAR_INPUT v : INT; END_VAR
VAR i : INT; END_VAR
FOR i := 0 TO 3 DO arr[i] := arr[i] + v * i; END_FOR;
END_FUNCTION_BLOCK
"""


def test_in_out_scalar_is_passed_by_reference():
    sim = once("VAR x : INT := 5; y : INT := 1; b : Bump; END_VAR",
               "b(v := x, amount := 3); b(v := y, amount := 4); b(v := x, amount := 10);", INOUT_FB)
    assert val(sim, "x") == 18
    assert val(sim, "y") == 5


def test_in_out_array_elements_swap():
    sim = once("VAR a : ARRAY[1..3] OF INT := [1, 2, 3]; s : Swap; k : INT := 3; END_VAR",
               "s(a := a[1], b := a[k]);", INOUT_FB)
    assert val(sim, "main.a") == [3, 2, 1]


def test_in_out_whole_array_is_modified_in_place():
    sim = once("VAR data : ARRAY[0..3] OF INT := [4(1)]; f : FillArr; END_VAR",
               "f(arr := data, v := 10); f(arr := data, v := 1);", INOUT_FB)
    assert val(sim, "main.data") == [1, 12, 23, 34]


def test_in_out_struct_field_and_function_in_out():
    extra = INOUT_FB + """
TYPE Point : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
FUNCTION Twice : BOOL
VAR_IN_OUT n : INT; END_VAR
n := n * 2;
Twice := n > 10;
END_FUNCTION
"""
    sim = once("VAR p : Point := (x := 3, y := 7); b : Bump; big : BOOL; END_VAR",
               "b(v := p.y, amount := 1); big := Twice(p.x); big := Twice(p.x);", extra)
    assert val(sim, "p.y") == 8
    assert val(sim, "p.x") == 12
    assert val(sim, "big") is True


# --------------------------------------------------------------------------- VAR_TEMP, FUNCTION

def test_var_temp_is_reinitialised_on_every_call():
    extra = """
FUNCTION_BLOCK FB_Temp
VAR_OUTPUT t_out : INT; v_out : INT; END_VAR
VAR_TEMP t : INT; END_VAR
VAR v : INT := 5; END_VAR
t := t + 1; v := v + 1;
t_out := t; v_out := v;
END_FUNCTION_BLOCK
"""
    sim = program("VAR f : FB_Temp; END_VAR", "f(); f();", extra)
    sim.step(2)
    assert val(sim, "f.t_out") == 1            # VAR_TEMP starts from 0 on each call (matiec: no initial value)
    assert val(sim, "f.v_out") == 9            # VAR keeps its value


def test_function_locals_do_not_persist_between_calls():
    extra = """
FUNCTION Cnt : INT
VAR_INPUT d : INT; END_VAR
VAR n : INT := 10; END_VAR
n := n + d;
Cnt := n;
END_FUNCTION
"""
    sim = program("VAR a, b : INT; END_VAR", "a := Cnt(1); b := Cnt(1);", extra)
    sim.step(3)
    assert (val(sim, "a"), val(sim, "b")) == (11, 11)


def test_function_result_and_var_output():
    extra = """
FUNCTION DivMod : BOOL
VAR_INPUT a : INT; b : INT; END_VAR
VAR_OUTPUT q : INT; r : INT; END_VAR
IF b = 0 THEN DivMod := FALSE; RETURN; END_IF;
q := a / b;
r := a MOD b;
DivMod := TRUE;
END_FUNCTION
"""
    sim = once("VAR ok1, ok2 : BOOL; q1, r1 : INT; q2 : INT := -1; r2 : INT := -1; END_VAR",
               "ok1 := DivMod(a := 17, b := 5, q => q1, r => r1);"
               " ok2 := DivMod(a := 1, b := 0, q => q2, r => r2);", extra)
    assert val(sim, "ok1") is True and (val(sim, "q1"), val(sim, "r1")) == (3, 2)
    assert val(sim, "ok2") is False
    # outputs not assigned before RETURN are copied out with their initial value (0)
    assert (val(sim, "q2"), val(sim, "r2")) == (0, 0)


def test_function_result_defaults_and_nested_calls():
    extra = """
FUNCTION Sq : DINT
VAR_INPUT x : DINT; END_VAR
Sq := x * x;
END_FUNCTION
FUNCTION Nothing : REAL
VAR_INPUT x : REAL; END_VAR
IF x > 0.0 THEN Nothing := x; END_IF;
END_FUNCTION
"""
    sim = once("VAR a : DINT; z : REAL := 1.5; b : REAL; END_VAR",
               "a := Sq(Sq(3) + 1); b := Nothing(-1.0) + Nothing(z);", extra)
    assert val(sim, "a") == 100
    assert val(sim, "b") == 1.5                # an unassigned result is 0.0


# --------------------------------------------------------------------------- initial values

def test_array_initial_values_with_repetition_and_2d():
    sim = once("VAR a : ARRAY[1..8] OF INT := [1, 2, 3(7), 2(-1), 5]; m : ARRAY[0..1, 0..2] OF INT :="
               " [1, 2, 3, 4, 5, 6]; x : INT; part : ARRAY[0..4] OF INT := [9, 9]; END_VAR",
               "x := m[1, 0];")
    assert val(sim, "main.a") == [1, 2, 7, 7, 7, -1, -1, 5]
    assert val(sim, "x") == 4                  # row-major
    assert val(sim, "main.part") == [9, 9, 0, 0, 0]


def test_struct_enum_and_nested_initial_values():
    extra = """
TYPE
  Color : (Red, Green, Blue);
  Cfg : STRUCT speed : INT := 50; gain : REAL := 1.5; mode : Color := Green; END_STRUCT;
END_TYPE
"""
    sim = once("VAR c1 : Cfg; c2 : Cfg := (speed := 7); col : Color; col2 : Color := Blue;"
               " s : INT; isg : BOOL; END_VAR",
               "s := c1.speed + c2.speed; isg := c2.mode = Green AND col = Red;", extra)
    assert val(sim, "s") == 57
    assert val(sim, "c2.gain") == 1.5
    assert val(sim, "isg") is True             # an enum starts at its first value
    assert val(sim, "col2") == "BLUE"


def test_fb_instance_initialisation_and_string_time_defaults():
    sim = once("VAR t : TON := (PT := T#2s500ms); c : CTU := (PV := 4); s : STRING; tm : TIME;"
               " r : REAL := 0.1; w : WORD := 16#BEEF; b : BOOL := 1; END_VAR",
               "tm := t.PT;")
    assert val(sim, "tm") == 2 * S + 500 * MS
    assert val(sim, "c.PV") == 4
    assert val(sim, "s") == ""
    assert val(sim, "r") == to_f32(0.1)
    assert val(sim, "w") == 0xBEEF
    assert val(sim, "b") is True


def test_variables_are_initialised_once_not_every_scan():
    sim = program("VAR n : INT := 40; END_VAR", "n := n + 1;")
    sim.step(3)
    assert val(sim, "n") == 43


# --------------------------------------------------------------------------- R_EDGE / F_EDGE

def test_edge_inputs_are_refused_because_openplc_ignores_them():
    """matiec declares an R_EDGE / F_EDGE input as a plain BOOL (generate_c_vardecl.cc): the
    front end refuses it rather than run edges here and levels on OpenPLC."""
    extra = """
FUNCTION_BLOCK Edge
VAR_INPUT clk : BOOL R_EDGE; END_VAR
VAR_OUTPUT ups : INT; END_VAR
IF clk THEN ups := ups + 1; END_IF;
END_FUNCTION_BLOCK
"""
    with pytest.raises(CompileError, match="R_EDGE compiles in OpenPLC but has no effect there"):
        program("VAR e : Edge; x : BOOL; END_VAR", "e(clk := x);", extra)
