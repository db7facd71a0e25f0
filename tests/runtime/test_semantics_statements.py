"""Every ST statement, run as OpenPLC runs it.

Loops follow the C that matiec emits (`utils/matiec_src/stage4/generate_c/generate_c_st.cc`):
FOR is `v := start; while(1) { if (do_inc) v := v + step; if (step > 0 ? v <= end : v >= end)
{ body } else break; }` with END and BY re-evaluated on every test; WHILE is a C `while`,
REPEAT a `do { } while (!(cond))`; EXIT is `break`, CONTINUE is `continue`; RETURN jumps to the
end of the POU.
"""
from __future__ import annotations

import pytest

from st_helpers import once, program, val

pytestmark = pytest.mark.usefixtures("compile_mode")


# --------------------------------------------------------------------------- IF

@pytest.mark.parametrize("x, expected", [(-5, 1), (0, 2), (7, 3), (100, 4)])
def test_if_elsif_else_takes_first_true_branch(x, expected):
    sim = once(f"VAR x : INT := {x}; r : INT; END_VAR",
               "IF x < 0 THEN r := 1; ELSIF x = 0 THEN r := 2; ELSIF x < 10 THEN r := 3;"
               " ELSIF x < 50 THEN r := 99; ELSE r := 4; END_IF;")
    assert val(sim, "r") == expected


def test_if_without_else_leaves_value():
    sim = once("VAR x : BOOL; r : INT := 5; END_VAR", "IF x THEN r := 1; END_IF;")
    assert val(sim, "r") == 5


# --------------------------------------------------------------------------- CASE

CASE_BODY = """
CASE x OF
  1: r := 10;
  2, 4, 6: r := 20;
  10..19: r := 30;
  -5..-1, 100: r := 40;
ELSE
  r := 99;
END_CASE;
"""


@pytest.mark.parametrize("x, expected", [
    (1, 10), (4, 20), (6, 20), (10, 30), (15, 30), (19, 30), (20, 99), (-3, 40), (100, 40), (3, 99),
])
def test_case_labels_lists_ranges_else(x, expected):
    sim = once(f"VAR x : INT := {x}; r : INT; END_VAR", CASE_BODY)
    assert val(sim, "r") == expected


def test_case_first_matching_branch_wins_and_no_else_does_nothing():
    # overlapping labels are only a warning in matiec; the C is an if / else if chain
    sim = once("VAR x : INT := 5; r : INT := -1; s : INT := -1; END_VAR",
               "CASE x OF 1..9: r := 1; 5: r := 2; END_CASE; CASE x OF 1: s := 1; END_CASE;")
    assert val(sim, "r") == 1
    assert val(sim, "s") == -1


def test_case_on_enum_state_machine():
    extra = "TYPE Mode : (Idle, Run, Stop); END_TYPE"
    sim = program("VAR m : Mode := Idle; n : INT; trace : INT; END_VAR",
                  """
n := n + 1;
CASE m OF
  Idle: trace := trace * 10 + 1; m := Run;
  Run:  trace := trace * 10 + 2; IF n >= 3 THEN m := Stop; END_IF;
ELSE
  trace := trace * 10 + 9;
END_CASE;""", extra)
    sim.step(5)
    assert val(sim, "trace") == 12299
    assert val(sim, "m") == "STOP"


def test_case_selector_is_narrowed_to_its_type():
    # matiec declares `INT __case_expression = a + b;`: 60000 becomes -5536
    sim = once("VAR a : INT := 30000; r : INT; END_VAR",
               "CASE a + a OF -5536: r := 1; ELSE r := 3; END_CASE;")
    assert val(sim, "r") == 1


# --------------------------------------------------------------------------- FOR

def test_for_sum_and_final_value_of_control_variable():
    sim = once("VAR i : INT; s : INT; END_VAR", "FOR i := 1 TO 10 DO s := s + i; END_FOR;")
    assert val(sim, "s") == 55
    assert val(sim, "i") == 11                 # the increment that failed the test stays


def test_for_by_negative_step():
    sim = once("VAR i : INT; n : INT; last : INT; a : ARRAY[0..9] OF INT; END_VAR",
               "FOR i := 9 TO 0 BY -3 DO n := n + 1; last := i; a[i] := 1; END_FOR;")
    assert val(sim, "n") == 4                  # 9, 6, 3, 0
    assert val(sim, "last") == 0
    assert val(sim, "i") == -3
    assert val(sim, "main.a") == [1, 0, 0, 1, 0, 0, 1, 0, 0, 1]


def test_for_with_start_past_end_runs_zero_times():
    sim = once("VAR i : INT; n : INT; END_VAR", "FOR i := 5 TO 1 DO n := n + 1; END_FOR;")
    assert val(sim, "n") == 0
    assert val(sim, "i") == 5


def test_for_exit_and_continue():
    # CONTINUE goes on with the increment (C `continue` in matiec's while(1) loop)
    sim = once("VAR i : INT; odd : INT; stop : INT; END_VAR",
               "FOR i := 1 TO 100 DO IF i MOD 2 = 0 THEN CONTINUE; END_IF;"
               " IF i > 9 THEN stop := i; EXIT; END_IF; odd := odd + i; END_FOR;")
    assert val(sim, "odd") == 1 + 3 + 5 + 7 + 9
    assert val(sim, "stop") == 11
    assert val(sim, "i") == 11                 # EXIT leaves the control variable as it is


def test_exit_leaves_only_the_innermost_loop():
    sim = once("VAR i, j : INT; n : INT; END_VAR",
               "FOR i := 1 TO 3 DO FOR j := 1 TO 10 DO IF j > 2 THEN EXIT; END_IF; n := n + 1;"
               " END_FOR; END_FOR;")
    assert val(sim, "n") == 6
    assert val(sim, "i") == 4


def test_for_end_is_reevaluated_every_iteration():
    # the C test is `i <= (n)` on every pass: shrinking n ends the loop early
    sim = once("VAR i : INT; n : INT := 10; k : INT; END_VAR",
               "FOR i := 1 TO n DO n := n - 1; k := k + 1; END_FOR;")
    assert val(sim, "k") == 5
    assert val(sim, "n") == 5


def test_for_by_is_reevaluated_at_every_increment():
    # matiec re-evaluates the BY expression at each increment (and in the test)
    sim = once("VAR i : INT; s : INT := 1; n : INT; END_VAR",
               "FOR i := 0 TO 100 BY s DO s := s * 2; n := n + 1; END_FOR;")
    assert val(sim, "n") == 6                  # i = 0, 2, 6, 14, 30, 62
    assert val(sim, "i") == 126


def test_for_by_zero_tests_greater_or_equal():
    # `(step) > 0 ? i <= end : i >= end`: BY 0 with start above end loops (until EXIT)
    sim = once("VAR i : INT; n : INT; m : INT; END_VAR",
               "FOR i := 5 TO 1 BY 0 DO n := n + 1; IF n >= 10 THEN EXIT; END_IF; END_FOR;"
               " FOR i := 1 TO 5 BY 0 DO m := m + 1; END_FOR;")
    assert val(sim, "n") == 10
    assert val(sim, "m") == 0                  # 1 >= 5 is false: no iteration


def test_for_end_is_a_c_int_expression_not_narrowed():
    # TO k * 2 with INT k = -20000 is the C int -40000: no iteration (narrowed to INT it
    # would be 25536 and the loop would run 25537 times)
    sim = once("VAR i : INT; k : INT := -20000; n : INT; END_VAR",
               "FOR i := 0 TO k * 2 DO n := n + 1; END_FOR;")
    assert val(sim, "n") == 0


def test_for_loop_in_dint_over_array():
    sim = once("VAR i : DINT; a : ARRAY[1..5] OF DINT := [10, 20, 30, 40, 50]; mx : DINT; END_VAR",
               "FOR i := 1 TO 5 DO IF a[i] > mx THEN mx := a[i]; END_IF; END_FOR;")
    assert val(sim, "mx") == 50


# --------------------------------------------------------------------------- WHILE / REPEAT

def test_while_loop():
    sim = once("VAR n : DINT := 27; steps : INT; END_VAR",
               "WHILE n <> 1 DO IF n MOD 2 = 0 THEN n := n / 2; ELSE n := 3 * n + 1; END_IF;"
               " steps := steps + 1; END_WHILE;")
    assert val(sim, "steps") == 111            # Collatz 27
    assert val(sim, "n") == 1


def test_while_false_never_runs_and_exit():
    sim = once("VAR i : INT; n : INT; END_VAR",
               "WHILE FALSE DO n := 100; END_WHILE;"
               " WHILE TRUE DO i := i + 1; IF i >= 4 THEN EXIT; END_IF; END_WHILE;")
    assert val(sim, "n") == 0
    assert val(sim, "i") == 4


def test_while_continue_retests_condition():
    sim = once("VAR i : INT; s : INT; END_VAR",
               "WHILE i < 6 DO i := i + 1; IF i = 3 THEN CONTINUE; END_IF; s := s + i; END_WHILE;")
    assert val(sim, "s") == 1 + 2 + 4 + 5 + 6


def test_repeat_runs_at_least_once():
    sim = once("VAR n : INT; END_VAR", "REPEAT n := n + 1; UNTIL TRUE END_REPEAT;")
    assert val(sim, "n") == 1


def test_repeat_continue_evaluates_until_and_exit_leaves():
    # CONTINUE in C's do { } while (!cond) jumps to the condition test
    sim = once("VAR i : INT; s : INT; k : INT; END_VAR",
               "REPEAT i := i + 1; IF i = 2 THEN CONTINUE; END_IF; s := s + i; UNTIL i >= 5 END_REPEAT;"
               " REPEAT k := k + 1; IF k = 3 THEN EXIT; END_IF; UNTIL FALSE END_REPEAT;")
    assert val(sim, "s") == 1 + 3 + 4 + 5
    assert val(sim, "i") == 5
    assert val(sim, "k") == 3


# --------------------------------------------------------------------------- RETURN

def test_return_in_function_keeps_result_assigned_so_far():
    extra = """
FUNCTION Clamp : INT
VAR_INPUT x : INT; END_VAR
Clamp := 0;
IF x < 0 THEN RETURN; END_IF;
Clamp := x;
IF x > 100 THEN Clamp := 100; RETURN; END_IF;
Clamp := Clamp * 2;
END_FUNCTION
"""
    sim = once("VAR a, b, c : INT; END_VAR", "a := Clamp(-5); b := Clamp(500); c := Clamp(7);", extra)
    assert (val(sim, "a"), val(sim, "b"), val(sim, "c")) == (0, 100, 14)


def test_return_in_function_block_skips_rest_of_body_only():
    extra = """
FUNCTION_BLOCK Stepper
VAR_INPUT hold : BOOL; END_VAR
VAR_OUTPUT count : INT; tail : INT; END_VAR
count := count + 1;
IF hold THEN RETURN; END_IF;
tail := tail + 1;
END_FUNCTION_BLOCK
"""
    sim = program("VAR s : Stepper; h : BOOL; after : INT; END_VAR",
                  "s(hold := h); after := after + 1;", extra)
    sim.step(2)
    sim.set("main.h", True)
    sim.step(3)
    assert val(sim, "s.count") == 5
    assert val(sim, "s.tail") == 2
    assert val(sim, "after") == 5              # the caller goes on after the call


def test_return_in_program_ends_that_scan():
    sim = program("VAR n : INT; m : INT; END_VAR",
                  "n := n + 1; IF n > 2 THEN RETURN; END_IF; m := m + 1;")
    sim.step(5)
    assert val(sim, "n") == 5
    assert val(sim, "m") == 2
