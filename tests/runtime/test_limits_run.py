"""A program just inside each of the checker's limits (plclab.frontend.check_limits) compiles and
runs, on both compiler paths: the limits are where the compiled Python is still safe (Python's
100 indentation levels, 200 nested parentheses, its stack), so `check` saying ok means `sim`,
`grade` and the lab run it (before, 300 nested IFs passed `check` and stopped `sim` with exit 70).
"""
from __future__ import annotations

import pytest

from plclab.frontend.check_limits import (MAX_BRANCH_DEPTH, MAX_EXPRESSION_DEPTH, MAX_LOOP_NESTING, MAX_POU_NESTING,
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


def test_every_limit_at_once_runs():
    """Loops, an IF of as many ELSIFs as the branch depth leaves, IFs nested to the statement
    limit in its last branch, the deepest expression inside: what Python's compiler sees is
    deepest here, and it still compiles (an IF of 3000 ELSIFs alone used to stop it)."""
    loops, nested = MAX_LOOP_NESTING, MAX_STATEMENT_NESTING - MAX_LOOP_NESTING - 1
    elsifs = MAX_BRANCH_DEPTH - loops - nested - 1
    inner = "IF x >= 0 THEN\n" * nested + "y := " + "(y + " * (MAX_EXPRESSION_DEPTH - 1) + "1" + \
        ")" * (MAX_EXPRESSION_DEPTH - 1) + ";\n" + "END_IF;\n" * nested
    chain = "IF x < 0 THEN y := -1;\n" + "ELSIF x < -1 THEN y := -2;\n" * (elsifs - 1) + "ELSE\n" + inner + "END_IF;\n"
    body = "FOR i := 1 TO 1 DO\n" * loops + chain + "END_FOR;\n" * loops
    assert val(once("VAR x : DINT; y : DINT; i : DINT; END_VAR", body), "y") == 1


def test_a_case_of_as_many_branches_as_allowed_runs():
    body = "CASE x OF\n" + "".join(f"{k}: y := {k};\n" for k in range(MAX_BRANCH_DEPTH)) + "END_CASE;\n"
    assert val(once("VAR x : DINT := 999; y : DINT; END_VAR", body), "y") == 999


def test_behind_the_limits_python_refusing_the_code_is_a_diagnostic_not_an_internal_error(monkeypatch):
    """Were a limit too generous, Python's parser or compiler refusing the generated code
    (RecursionError, MemoryError, SyntaxError) is one `file:line:col: error:` at the ST line."""
    from plclab.errors import CompileError
    from plclab.frontend import check_limits

    monkeypatch.setattr(check_limits, "MAX_BRANCH_DEPTH", 10**6)
    body = "IF x = 0 THEN x := 1;\n" + "ELSIF x = 1 THEN x := 2;\n" * 5000 + "END_IF;\n"
    with pytest.raises(CompileError) as info:
        once("VAR x : DINT; END_VAR", body)
    [line] = [str(d) for d in info.value.diagnostics]
    assert line.startswith("t.st:") and ": error: this code nests too deeply for PLC Lab's compiler (Python refused " \
        "it: " in line, line
