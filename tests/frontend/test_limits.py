"""The checker's limits (issue #25 items 1 and 2; docs/reliability.md "Limits of a program"):
declared memory, POUs that refer to themselves, POU nesting, statement and expression nesting.

Each hostile program here passed `check` before and then exhausted the machine's memory or
crashed `grade`/`sim` with a RecursionError. Now `check` refuses it with one line at the
declaration or statement that crosses the limit, naming the sizes, the loop or the depth; and
a program just inside each limit is accepted (and runs: tests/runtime/test_limits_run.py).
"""
from __future__ import annotations

import re
import resource
import time

import pytest

from plclab.errors import CompileError
from plclab.frontend import check_sources
from plclab.frontend.check_limits import (MAX_BRANCH_DEPTH, MAX_DATA_BYTES, MAX_EXPRESSION_DEPTH, MAX_LOOP_NESTING,
                                          MAX_POU_NESTING, MAX_STATEMENT_NESTING)

LINE = re.compile(r"^t\.st:\d+:\d+: error: \S.*$")
CONFIG = ("CONFIGURATION Config0 RESOURCE Res0 ON PLC TASK t(INTERVAL := T#10ms, PRIORITY := 0); "
          "PROGRAM i WITH t : Prog; END_RESOURCE END_CONFIGURATION\n")


def errors(text: str) -> list[str]:
    """The diagnostics of checking `text` as t.st (each one well-formed line); [] if it checks."""
    try:
        check_sources([("t.st", text)])
    except CompileError as e:
        lines = [str(d) for d in e.diagnostics]
        assert lines and all(LINE.match(line) for line in lines), lines
        return lines
    return []


def program(decls: str, body: str = "x := x;", types: str = "", pous: str = "") -> str:
    return (f"{types}{pous}PROGRAM Prog\nVAR\n  x : DINT;\n{decls}END_VAR\n{body}\nEND_PROGRAM\n{CONFIG}")


def fb_chain(n: int, width: int = 1) -> str:
    """F0 holds an LREAL; F(i) holds `width` instances of F(i-1) and calls the first."""
    out = ["FUNCTION_BLOCK F0\nVAR\n  v : LREAL;\nEND_VAR\nv := v + 1.0;\nEND_FUNCTION_BLOCK\n"]
    for i in range(1, n + 1):
        inner = "".join(f"  a{k} : F{i - 1};\n" for k in range(width))
        out.append(f"FUNCTION_BLOCK F{i}\nVAR\n{inner}END_VAR\na0();\nEND_FUNCTION_BLOCK\n")
    return "".join(out)


# --------------------------------------------------------------------------- declared memory

def test_nested_named_arrays_are_refused_at_the_type_that_crosses_the_limit_before_any_value_is_made():
    # arrays of structures of arrays (an array of arrays does not build in OpenPLC at all)
    types = ("TYPE\n  T0 : ARRAY[1..1000] OF LREAL;\n"
             + "".join(f"  ST_{i} : STRUCT f : T{i - 1}; END_STRUCT;\n  T{i} : ARRAY[1..1000] OF ST_{i};\n"
                       for i in range(1, 6)) + "END_TYPE\n")
    start = time.process_time()
    found = errors(program("  big : T5;\n", types=types))
    assert time.process_time() - start < 5          # nothing of 8 * 10^18 bytes was built
    assert found[0] == ("t.st:4:8: error: T1 (1000 elements of 7.875 KiB) takes 7.69 MiB (8064000 bytes), "
                        "more than the 4 MiB a program may declare in all")


def test_many_large_variables_are_refused_at_the_one_that_crosses_the_total():
    decls = "".join(f"  a{i} : ARRAY[1..400000] OF LREAL;\n" for i in range(40))   # 3.05 MiB each
    found = errors(program(decls))
    assert found[0] == ("t.st:5:3: error: 'a1' (ARRAY[1..400000] OF LREAL) takes 3.052 MiB; with the variables "
                        "declared before it the program declares 6.104 MiB, more than the 4 MiB a program may "
                        "declare")
    assert len(found) == 39                         # every later one too, none of them made


def test_the_python_memory_of_checking_a_hostile_program_stays_small():
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    decls = "".join(f"  a{i} : ARRAY[1..1000000] OF LREAL;\n" for i in range(40))
    assert errors(program(decls))
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 200_000   # KiB: not the 2.6 GB it took


def test_function_blocks_that_double_are_refused_at_the_instance_too_large():
    found = errors(program("  f : F40;\n", body="f();", pous=fb_chain(40, width=2)))
    assert len(found) == 1
    assert re.fullmatch(r"t\.st:\d+:3: error: an instance of function block 'F15' takes more than the 4 MiB a "
                        r"program may declare: 'a1' \(F14, 2\.\d+ MiB\) brings it to 4\.\d+ MiB", found[0]), found


def test_struct_arrays_count_their_bookkeeping():
    types = "TYPE\n  Cell : STRUCT b : BOOL; END_STRUCT;\n  A : ARRAY[1..100000] OF Cell;\nEND_TYPE\n"
    found = errors(program("  v : A;\n", types=types))
    assert found == ["t.st:3:7: error: A (100000 elements of 65 bytes) takes 6.199 MiB (6500000 bytes), more than "
                     "the 4 MiB a program may declare in all"]


def test_program_instances_and_globals_count_in_the_total():
    half = "ARRAY[1..300000] OF LREAL"                  # 2.29 MiB
    fb = f"FUNCTION_BLOCK Big\nVAR\n  d : {half};\nEND_VAR\nd[1] := 1.0;\nEND_FUNCTION_BLOCK\n"
    found = errors(program("  b1 : Big;\n  b2 : Big;\n", body="b1(); b2();", pous=fb))
    assert found == ["t.st:11:3: error: an instance of program 'Prog' takes more than the 4 MiB a program may "
                     "declare: 'b2' (Big, 2.289 MiB) brings it to 4.578 MiB"]
    two = program("  b1 : Big;\n", body="b1();", pous=fb).replace(
        "PROGRAM i WITH t : Prog;", "PROGRAM i WITH t : Prog; PROGRAM j WITH t : Prog;")
    found = errors(two)
    assert len(found) == 1 and found[0].startswith("t.st:14:120: error: ") and \
        "the program declares 4.578 MiB with program instance 'j' of 'Prog' (2.289 MiB; VAR_GLOBALs 0 bytes)" in found[0]


def test_a_program_within_the_limit_is_accepted():
    decls = f"  a : ARRAY[1..{MAX_DATA_BYTES // 8 - 1000}] OF LREAL;\n"
    assert errors(program(decls)) == []
    assert errors(program("  f : F12;\n", body="f();", pous=fb_chain(12, width=2))) == []   # 64 KiB of LREALs


# --------------------------------------------------------------------------- POUs that refer to themselves

def test_two_function_blocks_containing_each_other_are_a_named_loop():
    pous = ("FUNCTION_BLOCK FB_A\nVAR\n  b : FB_B;\nEND_VAR\nb();\nEND_FUNCTION_BLOCK\n"
            "FUNCTION_BLOCK FB_B\nVAR\n  a : FB_A;\nEND_VAR\na();\nEND_FUNCTION_BLOCK\n")
    assert errors(program("  f : FB_A;\n", body="f();", pous=pous)) == [
        "t.st:9:3: error: function blocks contain each other in a loop: FB_A -> FB_B -> FB_A (recursion is not "
        "allowed: OpenPLC's compiler refuses a POU that refers to itself)"]


def test_a_longer_loop_of_function_blocks_is_named_once():
    pous = "".join(f"FUNCTION_BLOCK L{i}\nVAR\n  n : L{(i + 1) % 4};\nEND_VAR\nn();\nEND_FUNCTION_BLOCK\n"
                   for i in range(4))
    found = errors(program("  f : L0;\n", body="f();", pous=pous))
    assert len(found) == 1 and "L0 -> L1 -> L2 -> L3 -> L0" in found[0], found


def test_a_function_block_holding_itself_is_refused():
    pous = "FUNCTION_BLOCK Me\nVAR\n  m : Me;\nEND_VAR\nm();\nEND_FUNCTION_BLOCK\n"
    assert errors(program("  f : Me;\n", body="f();", pous=pous)) == [
        "t.st:3:3: error: function block 'Me' cannot contain an instance of itself"]


def test_arrays_of_function_blocks_and_fb_struct_members_cannot_make_a_loop():
    """OpenPLC refuses both, so no loop can pass through them."""
    pous = "FUNCTION_BLOCK Me\nVAR\n  m : ARRAY[1..2] OF Me;\nEND_VAR\nm[1]();\nEND_FUNCTION_BLOCK\n"
    assert any("arrays of function block instances (Me) are not supported" in e
               for e in errors(program("  f : Me;\n", body="f();", pous=pous)))
    types = "TYPE S : STRUCT m : Me; END_STRUCT; END_TYPE\n"
    pous = "FUNCTION_BLOCK Me\nVAR\n  s : S;\nEND_VAR\ns.m();\nEND_FUNCTION_BLOCK\n"
    assert any("a STRUCT field cannot be a function block instance" in e
               for e in errors(program("  f : Me;\n", body="f();", types=types, pous=pous)))


def test_functions_calling_each_other_are_a_named_loop():
    pous = ("FUNCTION Ping : DINT\nVAR_INPUT n : DINT; END_VAR\nPing := Pong(n - 1);\nEND_FUNCTION\n"
            "FUNCTION Pong : DINT\nVAR_INPUT n : DINT; END_VAR\nPong := Ping(n);\nEND_FUNCTION\n")
    assert errors(program("", body="x := Ping(3);", pous=pous)) == [
        "t.st:7:9: error: functions call each other in a loop: Ping -> Pong -> Ping (recursion is not allowed: "
        "OpenPLC's compiler refuses a POU that refers to itself)"]


def test_a_function_calling_itself_is_refused():
    pous = "FUNCTION Fact : DINT\nVAR_INPUT n : DINT; END_VAR\nFact := n * Fact(n - 1);\nEND_FUNCTION\n"
    assert errors(program("", body="x := Fact(3);", pous=pous)) == [
        "t.st:3:13: error: recursive call of 'Fact' (IEC 61131-3 forbids recursion)"]


# --------------------------------------------------------------------------- nesting depths

def test_function_blocks_nested_too_deeply_are_refused_with_the_depth():
    found = errors(program("  f : F500;\n", body="f();", pous=fb_chain(500)))
    assert len(found) == 1 and re.fullmatch(
        rf"t\.st:\d+:3: error: function blocks and function calls nested more than {MAX_POU_NESTING} levels deep "
        rf"\('F{MAX_POU_NESTING + 1}' reaches {MAX_POU_NESTING + 1} levels of POUs below it\)", found[0]), found
    # the program holds F99 ... F0: 100 levels below it
    assert errors(program(f"  f : F{MAX_POU_NESTING - 1};\n", body="f();", pous=fb_chain(MAX_POU_NESTING - 1))) == []
    assert len(errors(program(f"  f : F{MAX_POU_NESTING};\n", body="f();", pous=fb_chain(MAX_POU_NESTING)))) == 1


def test_function_calls_nested_too_deeply_are_refused():
    pous = "FUNCTION G0 : DINT\nVAR_INPUT n : DINT; END_VAR\nG0 := n;\nEND_FUNCTION\n" + "".join(
        f"FUNCTION G{i} : DINT\nVAR_INPUT n : DINT; END_VAR\nG{i} := G{i - 1}(n + 1);\nEND_FUNCTION\n"
        for i in range(1, 300))
    found = errors(program("", body="x := G299(0);", pous=pous))
    assert len(found) == 1 and f"nested more than {MAX_POU_NESTING} levels deep" in found[0]


def nested(kind: str, n: int) -> str:
    opening = {"IF": "IF x > 0 THEN\n", "FOR": "FOR x := 1 TO 2 DO\n", "WHILE": "WHILE x > 5 DO\n",
               "REPEAT": "REPEAT\n", "CASE": "CASE x OF 1:\n"}[kind]
    closing = {"IF": "END_IF;\n", "FOR": "END_FOR;\n", "WHILE": "END_WHILE;\n", "REPEAT": "UNTIL x > 0 END_REPEAT;\n",
               "CASE": "END_CASE;\n"}[kind]
    return opening * n + "y := y + 1;\n" + closing * n


@pytest.mark.parametrize("kind", ["IF", "CASE"])
def test_statements_nested_beyond_the_limit_are_refused_at_the_one_that_crosses_it(kind):
    assert errors(program("  y : DINT;\n", body=nested(kind, MAX_STATEMENT_NESTING))) == []
    found = errors(program("  y : DINT;\n", body=nested(kind, 10_000)))
    assert found == [f"t.st:{6 + MAX_STATEMENT_NESTING}:1: error: statements nested more than {MAX_STATEMENT_NESTING} "
                     f"levels deep (IF, CASE, FOR, WHILE, REPEAT inside each other); move the inner part into a "
                     f"function or function block"]


@pytest.mark.parametrize("kind", ["FOR", "WHILE", "REPEAT"])
def test_loops_nested_beyond_the_limit_are_refused_at_the_one_that_crosses_it(kind):
    assert errors(program("  y : DINT;\n", body=nested(kind, MAX_LOOP_NESTING))) == []
    found = errors(program("  y : DINT;\n", body=nested(kind, 10_000)))
    assert found == [f"t.st:{6 + MAX_LOOP_NESTING}:1: error: loops nested more than {MAX_LOOP_NESTING} levels deep "
                     f"(FOR, WHILE, REPEAT inside each other); move the inner loops into a function or function block"]


@pytest.mark.parametrize("expr", [
    lambda n: "(x + " * n + "1" + ")" * n,
    lambda n: " + ".join(["x"] * (n + 1)),
    lambda n: "ABS(" * n + "x" + ")" * n,
    lambda n: "-(" * n + "x" + ")" * n,
])
def test_expressions_nested_beyond_the_limit_are_refused(expr):
    assert errors(program("", body=f"x := {expr(MAX_EXPRESSION_DEPTH - 1)};")) == []
    found = errors(program("", body=f"x := {expr(MAX_EXPRESSION_DEPTH + 1)};"))
    assert len(found) == 1 and f"expression nested more than {MAX_EXPRESSION_DEPTH} levels deep" in found[0], found
    assert len(errors(program("", body=f"x := {expr(5000)};"))) == 1      # one clean line, no RecursionError


def test_an_if_of_thousands_of_elsifs_is_refused_at_the_branch_that_crosses_the_limit():
    """Python compiles an ELSIF chain as nested IFs: 3000 of them passed `check` and stopped
    `sim` with exit 70 (RecursionError during compilation)."""
    body = "IF x = 0 THEN x := 1;\n" + "ELSIF x = 1 THEN x := 2;\n" * 10_000 + "END_IF;"
    found = errors(program("", body=body))
    assert found == [f"t.st:{5 + MAX_BRANCH_DEPTH}:18: error: too many ELSIF or CASE branches before this statement: "
                     f"counting each branch of each IF and CASE around it, it is {MAX_BRANCH_DEPTH + 1} branches deep "
                     f"(at most {MAX_BRANCH_DEPTH}); split the IF or CASE (e.g. a CASE per range of values) or move "
                     f"its branches into functions"]
    case = "CASE x OF\n" + "".join(f"{k}: x := {k};\n" for k in range(MAX_BRANCH_DEPTH)) + "END_CASE;"
    assert errors(program("", body=case)) == []
    case = "CASE x OF\n" + "".join(f"{k}: x := {k};\n" for k in range(MAX_BRANCH_DEPTH + 1)) + "END_CASE;"
    assert len(errors(program("", body=case))) == 1


def test_initial_values_of_types_count_too():
    """A TYPE's initial value is made when it is declared: many large ones are refused."""
    types = "TYPE\n" + "".join(f"  A{i} : ARRAY[1..300000] OF LREAL := [300000(1.0)];\n" for i in range(10)) + "END_TYPE\n"
    found = errors(program("", types=types))
    assert found[0] == ("t.st:3:8: error: the initial value of A1 takes 2.289 MiB; with what is declared before it the "
                        "program declares 4.578 MiB, more than the 4 MiB a program may declare")


def test_function_blocks_referring_to_each_other_through_in_out_are_a_loop_too():
    """matiec orders POUs so that each comes after those it names: a VAR_IN_OUT of the other's
    type closes a loop as well."""
    pous = ("FUNCTION_BLOCK FB_A\nVAR_IN_OUT b : FB_B; END_VAR\nVAR n : INT; END_VAR\nn := n + 1;\nEND_FUNCTION_BLOCK\n"
            "FUNCTION_BLOCK FB_B\nVAR a : FB_A; n : INT; END_VAR\nn := n + 1;\nEND_FUNCTION_BLOCK\n")
    assert errors(program("  f : FB_B;\n", body="f();", pous=pous)) == [
        "t.st:7:5: error: function blocks refer to each other in a loop: FB_A -> FB_B -> FB_A (recursion is not "
        "allowed: OpenPLC's compiler refuses a POU that refers to itself)"]


def test_a_function_block_naming_its_own_type_as_external_is_refused():
    pous = "FUNCTION_BLOCK Me\nVAR_EXTERNAL g : Me; END_VAR\nVAR n : INT; END_VAR\nn := n + 1;\nEND_FUNCTION_BLOCK\n"
    text = pous + "PROGRAM Prog\nVAR x : DINT; END_VAR\nx := x;\nEND_PROGRAM\n" + CONFIG.replace(
        "RESOURCE R", "VAR_GLOBAL g : Me; END_VAR RESOURCE R")
    assert "t.st:2:14: error: function block 'Me' names its own type in a VAR_EXTERNAL (OpenPLC's compiler refuses a " \
        "POU that refers to itself)" in errors(text)
