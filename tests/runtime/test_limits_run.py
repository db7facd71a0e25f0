"""A program just inside each of the checker's limits (plclab.frontend.check_limits) compiles and
runs, on both compiler paths: the limits are where the compiled Python is still safe (Python's
100 indentation levels, 200 nested parentheses, its stack), so `check` saying ok means `sim`,
`grade` and the lab run it (before, 300 nested IFs passed `check` and stopped `sim` with exit 70).
"""
from __future__ import annotations

import pytest

from plclab.frontend.check_limits import (MAX_EXPRESSION_DEPTH, MAX_LOOP_NESTING, MAX_POU_NESTING,
                                          MAX_STATEMENT_NESTING)
from st_helpers import once, val

pytestmark = pytest.mark.usefixtures("compile_mode")


@pytest.mark.parametrize("kind", ["FOR", "REPEAT", "IF", "CASE", "WHILE"])
def test_statements_nested_to_the_limit_run(kind):
    # IF/CASE: inside loops as deep as allowed, the innermost IF (with the EXIT) at the limit
    n = MAX_STATEMENT_NESTING - MAX_LOOP_NESTING - 1 if kind in ("IF", "CASE") else MAX_LOOP_NESTING
    opening = {"IF": "IF x >= 0 THEN\n", "FOR": "FOR i{k} := 1 TO 1 DO\n", "WHILE": "WHILE y < 1 DO\n",
               "REPEAT": "REPEAT\n", "CASE": "CASE x OF 0:\n"}[kind]
    closing = {"IF": "END_IF;\n", "FOR": "END_FOR;\n", "WHILE": "END_WHILE;\n", "REPEAT": "UNTIL TRUE END_REPEAT;\n",
               "CASE": "END_CASE;\n"}[kind]
    decls = "VAR x : DINT; y : DINT; " + "".join(f"i{k} : DINT; " for k in range(n)) + "END_VAR"
    body = "".join(opening.format(k=k) for k in range(n)) + "y := y + 1;\nIF y > 9 THEN EXIT; END_IF;\n" + closing * n
    if kind in ("IF", "CASE"):
        body = "FOR i0 := 1 TO 1 DO\n" * MAX_LOOP_NESTING + body + "END_FOR;\n" * MAX_LOOP_NESTING
    assert val(once(decls, body), "y") == 1


def test_loops_nested_to_the_limit_run_in_function_blocks_and_functions():
    loops = "FOR i := 1 TO 1 DO\n" * MAX_LOOP_NESTING + "q := q + 1;\nIF q > 9 THEN EXIT; END_IF;\n" + \
        "END_FOR;\n" * MAX_LOOP_NESTING
    extra = (f"FUNCTION_BLOCK Fb\nVAR_OUTPUT q : DINT; END_VAR\nVAR i : DINT; END_VAR\n{loops}END_FUNCTION_BLOCK\n"
             f"FUNCTION Fn : DINT\nVAR_INPUT q : DINT; END_VAR\nVAR i : DINT; END_VAR\n{loops}Fn := q;\nEND_FUNCTION\n")
    sim = once("VAR f : Fb; y : DINT; END_VAR", "f();\ny := Fn(q := f.q);", extra=extra)
    assert val(sim, "y") == 2


@pytest.mark.parametrize("make, expected", [
    (lambda n: "(t + " * n + "T#1ms" + ")" * n, None),
    (lambda n: "ABS(" * n + "i" + ")" * n, None),
    (lambda n: "(i * " * n + "1" + ")" * n, None),
    (lambda n: "(r / " * n + "1.0" + ")" * n, None),
    (lambda n: "LIMIT(0, " * n + "i" + ", 9)" * n, None),
])
def test_expressions_nested_to_the_limit_run(make, expected):
    expr = make(MAX_EXPRESSION_DEPTH - 1)
    target = "t" if expr.startswith("(t") else "r" if "(r /" in expr else "i"
    sim = once("VAR t : TIME; i : INT := 3; r : REAL := 2.0; END_VAR", f"{target} := {expr};")
    assert val(sim, target) is not None


def test_function_blocks_nested_to_the_limit_run():
    n = MAX_POU_NESTING
    fbs = "FUNCTION_BLOCK F0\nVAR_OUTPUT q : DINT; END_VAR\nq := q + 1;\nEND_FUNCTION_BLOCK\n" + "".join(
        f"FUNCTION_BLOCK F{i}\nVAR_OUTPUT q : DINT; END_VAR\nVAR a : F{i - 1}; END_VAR\na();\nq := a.q;\n"
        f"END_FUNCTION_BLOCK\n" for i in range(1, n))
    sim = once(f"VAR f : F{n - 1}; y : DINT; END_VAR", "f();\ny := f.q;", extra=fbs)   # n levels below main
    assert val(sim, "y") == 1


def test_function_calls_nested_to_the_limit_run():
    n = MAX_POU_NESTING
    fns = "FUNCTION G0 : DINT\nVAR_INPUT n : DINT; END_VAR\nG0 := n;\nEND_FUNCTION\n" + "".join(
        f"FUNCTION G{i} : DINT\nVAR_INPUT n : DINT; END_VAR\nG{i} := G{i - 1}(n + 1);\nEND_FUNCTION\n"
        for i in range(1, n))
    assert val(once("VAR y : DINT; END_VAR", f"y := G{n - 1}(0);", extra=fns), "y") == n - 1
