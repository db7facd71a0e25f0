"""The variable lists of an OpenPLC Editor project, read as the Editor's generator writes them.

Each test is one rule of the Editor's interface generation (docs/ladder.md, "How the Editor's
generator reads your project"): a project drawn as the Editor saves it (drawing.py), and the ST
the Editor writes for it, written here by hand from the rule. Both run in the soft PLC from the
same inputs and must agree scan for scan on every output and watched variable; where a rule is
about the declarations' text, that text is checked too. What the Editor would write as another
program (or as ST that does not compile) is refused in one line naming the variable.
"""
from __future__ import annotations

import pytest

from drawing import Diagram, Pou, project
from plclab.errors import CompileError, PlcLabError
from plclab.frontend import check_sources, load_files, read_sources
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.runtime.sim import Simulation

CONFIG = """
CONFIGURATION Config0
    RESOURCE Res0 ON PLC
        TASK task0 (INTERVAL := T#10ms, PRIORITY := 0);
        PROGRAM instance0 WITH task0 : {program};
    END_RESOURCE
END_CONFIGURATION
"""


def save(tmp_path, pous: list[Pou], program: str = "main", **kw):
    path = tmp_path / "plc.xml"
    path.write_bytes(project(pous, program=program, **kw))
    return path


def emitted(path) -> str:
    return str(read_sources([path])[0][1])


def run(sim: Simulation, inputs: list[dict], watch: list[str]) -> list:
    """Per scan: the output areas and the watched variables, after that scan's inputs."""
    rows = []
    for step in inputs:
        for name, value in step.items():
            sim.set(name, value)
        sim.step(1)
        rows.append(({a: list(v) for a, v in sim.plc.image.areas.items() if a.startswith("Q")},
                     [sim.plc.read(w) for w in watch]))
    return rows


def same_run(path, editor_st: str, inputs: list[dict], watch: list[str]) -> list:
    """Run the project and the ST the Editor writes for it; they agree scan for scan. Returns
    the trace (for the test to check the inputs exercised the program)."""
    drawn = run(Simulation(PLC(compile_unit(load_files([path])))), inputs, watch)
    written = run(Simulation(PLC(compile_unit(check_sources([("editor.st", editor_st)])))), inputs, watch)
    for n, (a, b) in enumerate(zip(drawn, written)):
        assert a == b, f"scan {n}: project {a} vs the Editor's ST {b}"
    return drawn


def refused(path) -> str:
    with pytest.raises((CompileError, PlcLabError)) as e:
        load_files([path])
    text = str(e.value)
    assert "\n" not in text.strip() and "Traceback" not in text
    return text


# --------------------------------------------------------------------------- the two refused shapes

def latch_ton() -> Pou:
    """START latches RUN until STOP; LAMP lights 30 ms after RUN: I/O located in the same
    table as the timer, in the order a student adds them."""
    d = Diagram()
    start = d.contact("START", 0, 0)
    held = d.contact("RUN", 1, 0)
    stop = d.contact("STOP", 0, 1, after=[start, held], negated=True)
    d.coil("RUN", 0, 3, after=stop)
    run_ = d.contact("RUN", 2, 0)
    pt = d.invar("T#30ms", 3, 1)
    t = d.block("TON", 2, 2, [("IN", run_), ("PT", pt)], ["Q", "ET"], instance="TON0")
    d.coil("LAMP", 2, 4, after=(t, "Q"))
    return Pou("LatchTon", "program", d, {"localVars": [
        ("START", "BOOL", None, "%IX0.0"), ("RUN", "BOOL", None), ("STOP", "BOOL", None, "%IX0.1"),
        ("TON0", "TON", None), ("LAMP", "BOOL", None, "%QX0.0")]})


LATCH_TON_ST = """
PROGRAM LatchTon
  VAR
    RUN : BOOL;
    TON0 : TON;
  END_VAR
  VAR
    START AT %IX0.0 : BOOL;
    STOP AT %IX0.1 : BOOL;
    LAMP AT %QX0.0 : BOOL;
  END_VAR
  RUN := NOT(STOP) AND (RUN OR START);
  TON0(IN := RUN, PT := T#30ms);
  LAMP := TON0.Q;
END_PROGRAM
""" + CONFIG.format(program="LatchTon")

LATCH_INPUTS = ([{"%IX0.0": False, "%IX0.1": False}] * 3 + [{"%IX0.0": True}] * 2 + [{"%IX0.0": False}] * 8
                + [{"%IX0.1": True}] * 2 + [{"%IX0.1": False}] * 3 + [{"%IX0.0": True}] + [{"%IX0.0": False}] * 2
                + [{"%IX0.1": True}] + [{"%IX0.1": False}] * 4)


def test_located_io_beside_a_timer_in_one_table_loads_and_runs_as_the_editor_writes_it(tmp_path):
    """The commonest Editor project: one local table with I/O at addresses and a TON. The
    Editor writes its unlocated variables as one VAR block and its located ones as another."""
    path = save(tmp_path, [latch_ton()], program="LatchTon")
    text = emitted(path)
    assert ("VAR\n    RUN : BOOL;\n    TON0 : TON;\nEND_VAR\n"
            "VAR\n    START AT %IX0.0 : BOOL;\n    STOP AT %IX0.1 : BOOL;\n    LAMP AT %QX0.0 : BOOL;\nEND_VAR\n") in text
    trace = same_run(path, LATCH_TON_ST, LATCH_INPUTS, ["instance0.RUN", "instance0.TON0.ET"])
    lamp = [row[0]["QX"][0] for row in trace]                       # %QX0.0
    assert 0 in lamp and 1 in lamp                      # the latch and the timer did their work


def counter_ctu() -> Pou:
    """PULSE counts up to 3 (DONE), RESET clears: a CTU and located I/O in one table."""
    d = Diagram("FBD")
    pulse = d.invar("PULSE", 0, 0)
    reset = d.invar("RESET", 1, 0)
    pv = d.invar("3", 2, 0)
    c = d.block("CTU", 0, 1, [("CU", pulse), ("R", reset), ("PV", pv)], ["Q", "CV"], instance="CTU0")
    d.outvar("DONE", 0, 3, (c, "Q"))
    d.outvar("COUNT", 1, 3, (c, "CV"))
    return Pou("Counter", "program", d, {"localVars": [
        ("CTU0", "CTU", None), ("PULSE", "BOOL", None, "%IX0.2"), ("COUNT", "INT", None),
        ("RESET", "BOOL", None, "%IX0.3"), ("DONE", "BOOL", None, "%QX0.1")]})


COUNTER_ST = """
PROGRAM Counter
  VAR
    CTU0 : CTU;
    COUNT : INT;
  END_VAR
  VAR
    PULSE AT %IX0.2 : BOOL;
    RESET AT %IX0.3 : BOOL;
    DONE AT %QX0.1 : BOOL;
  END_VAR
  CTU0(CU := PULSE, R := RESET, PV := 3);
  DONE := CTU0.Q;
  COUNT := CTU0.CV;
END_PROGRAM
""" + CONFIG.format(program="Counter")


def test_located_io_beside_a_counter_in_one_table_loads_and_runs_as_the_editor_writes_it(tmp_path):
    path = save(tmp_path, [counter_ctu()], program="Counter")
    inputs = [{"%IX0.2": n % 2 == 1, "%IX0.3": n == 14} for n in range(20)]
    trace = same_run(path, COUNTER_ST, inputs, ["instance0.COUNT"])
    assert [row[1][0] for row in trace][:16] == [0, 1, 1, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3, 3, 0, 1]   # up to PV, then reset
    assert [row[0]["QX"][1] for row in trace][4:7] == [0, 1, 1]                           # DONE (%QX0.1) at PV


# --------------------------------------------------------------------------- lists, qualifiers, values

def test_a_list_with_no_variable_writes_no_block_and_located_keep_their_order(tmp_path):
    d = Diagram()
    d.coil("B_OUT", 0, 2, after=d.contact("A_IN", 0, 0))
    pou = Pou("main", "program", d, {"localVars": [], "localVars#2": [
        ("B_OUT", "BOOL", None, "%QX0.3"), ("A_IN", "BOOL", None, "%IX0.5")]})
    path = save(tmp_path, [pou])
    text = emitted(path)
    assert text.count("VAR") - text.count("END_VAR") == 1          # one block: the empty list writes none
    assert text.index("B_OUT AT %QX0.3") < text.index("A_IN AT %IX0.5")
    st = "PROGRAM main\nVAR\n  B_OUT AT %QX0.3 : BOOL;\n  A_IN AT %IX0.5 : BOOL;\nEND_VAR\nB_OUT := A_IN;\nEND_PROGRAM\n"
    trace = same_run(path, st + CONFIG.format(program="main"), [{"%IX0.5": n % 3 == 0} for n in range(6)], [])
    assert [row[0]["QX"][3] for row in trace] == [1, 0, 0, 1, 0, 0]       # %QX0.3 follows %IX0.5


def test_each_half_of_a_list_keeps_its_one_qualifier_constant_first(tmp_path):
    """The Editor writes one qualifier: CONSTANT, else RETAIN, else NON_RETAIN; both halves of
    a split list carry it."""
    d = Diagram("FBD")
    add = d.block("ADD", 0, 1, [("IN1", d.invar("N", 0, 0)), ("IN2", d.invar("INC", 1, 0))], ["OUT"])
    d.outvar("N", 0, 3, (add, "OUT"))
    d.outvar("MIRROR", 1, 3, d.invar("N", 2, 2))
    pou = Pou("main", "program", d, {
        "localVars constant retain": [("INC", "INT", "2")],
        "localVars retain nonretain": [("N", "INT", "5"), ("MIRROR", "INT", None, "%QW0")]})
    path = save(tmp_path, [pou])
    text = emitted(path)
    assert "VAR CONSTANT\n    INC : INT := 2;\nEND_VAR\n" in text
    assert "VAR RETAIN\n    N : INT := 5;\nEND_VAR\nVAR RETAIN\n    MIRROR AT %QW0 : INT;\nEND_VAR\n" in text
    st = """PROGRAM main
VAR CONSTANT
  INC : INT := 2;
END_VAR
VAR RETAIN
  N : INT := 5;
END_VAR
VAR RETAIN
  MIRROR AT %QW0 : INT;
END_VAR
VAR
  _TMP_ADD1_OUT : INT;
END_VAR
_TMP_ADD1_OUT := ADD(N, INC);
N := _TMP_ADD1_OUT;
MIRROR := N;
END_PROGRAM
""" + CONFIG.format(program="main")
    trace = same_run(path, st, [{}] * 4, ["instance0.N"])
    assert [row[1][0] for row in trace] == [7, 9, 11, 13]


def test_initial_values_as_the_editor_writes_them(tmp_path):
    """Values are pasted as written; a STRING value without quotes gets them; an array value
    writes `n(v)` for a repetition above 1 and the value alone for 1; a located output may have one."""
    pou = Pou("main", "program", "LIT := TABLE[IDX] + LEN(NAME); NAME2 := CONCAT(NAME, '!');", {"localVars": [
        ("NAME", "STRING", "abc"), ("NAME2", "STRING", "'q'"), ("IDX", "INT", "2"),
        ("TABLE", "ARRAY [1..5] OF INT", [(None, "10"), ("1", "20"), ("3", "7")]),
        ("LIT", "INT", "99", "%QW1"), ("WAIT", "TIME", "T#1s500ms")]})
    path = save(tmp_path, [pou])
    text = emitted(path)
    assert "NAME : STRING := 'abc';" in text and "NAME2 : STRING := 'q';" in text
    assert "TABLE : ARRAY [1..5] OF INT := [10, 20, 3(7)];" in text and "LIT AT %QW1 : INT := 99;" in text
    st = """PROGRAM main
VAR
  NAME : STRING := 'abc';
  NAME2 : STRING := 'q';
  IDX : INT := 2;
  TABLE : ARRAY [1..5] OF INT := [10, 20, 3(7)];
  WAIT : TIME := T#1s500ms;
END_VAR
VAR
  LIT AT %QW1 : INT := 99;
END_VAR
LIT := TABLE[IDX] + LEN(NAME); NAME2 := CONCAT(NAME, '!');
END_PROGRAM
""" + CONFIG.format(program="main")
    trace = same_run(path, st, [{}] * 2, ["instance0.NAME2", "instance0.TABLE", "instance0.WAIT"])
    assert trace[0][0]["QW"][1] == 23 and trace[0][1][0] == "abc!"


def test_documentation_is_a_comment_only(tmp_path):
    d = Diagram()
    d.coil("Q", 0, 2, after=d.contact("A", 0, 0))
    pou = Pou("main", "program", d, {"localVars": [("A", "BOOL", None, "%IX0.0", "the (*start*) button"),
                                                   ("Q", "BOOL", None, "%QX0.0", "lamp")]})
    path = save(tmp_path, [pou])
    assert "A AT %IX0.0 : BOOL;    (* the (*start* ) button *)" in emitted(path)
    st = "PROGRAM main\nVAR\n  A AT %IX0.0 : BOOL;\n  Q AT %QX0.0 : BOOL;\nEND_VAR\nQ := A;\nEND_PROGRAM\n"
    same_run(path, st + CONFIG.format(program="main"), [{"%IX0.0": n % 2 == 0} for n in range(4)], [])


# --------------------------------------------------------------------------- every kind of list

def test_inputs_outputs_in_outs_externals_temps_and_globals_as_the_editor_writes_them(tmp_path):
    """An LD function block with every kind of list, called from an ST program; globals in a
    configuration list (located and not in one VAR_GLOBAL block, as IEC allows there) and a
    resource list, one CONSTANT."""
    d = Diagram()
    en = d.contact("EN_IN", 0, 0)
    lim = d.contact("BLOCKED", 0, 1, after=en, negated=True)
    d.coil("Q", 0, 3, after=lim)
    d.coil("TMP", 1, 3, after=d.contact("EN_IN", 1, 0))
    d.coil("SHARED_Q", 2, 3, after=d.contact("TMP", 2, 0))
    d.coil("TOGGLE", 3, 3, after=d.contact("TOGGLE", 3, 0, negated=True))
    fb = Pou("FB_Every", "functionBlock", d, {
        "inputVars": [("EN_IN", "BOOL", None)], "outputVars": [("Q", "BOOL", None)],
        "inOutVars": [("TOGGLE", "BOOL", None)], "externalVars constant": [("BLOCKED", "BOOL", None)], "externalVars": [("SHARED_Q", "BOOL", None)],
        "tempVars": [("TMP", "BOOL", None)]})
    prg = Pou("main", "program", "F(EN_IN := GO, TOGGLE := T); OUT := F.Q;", {
        "localVars": [("F", "FB_Every", None), ("T", "BOOL", None), ("OUT", "BOOL", None, "%QX0.2")],
        "externalVars": [("GO", "BOOL", None)]})
    path = save(tmp_path, [fb, prg], global_lists=[("globalVars", [("GO", "BOOL", None, "%IX0.0"),
                                                                   ("SHARED_Q", "BOOL", None)])],
                resource_lists=[("globalVars constant", [("BLOCKED", "BOOL", "FALSE")])])
    text = emitted(path)
    assert "    VAR_GLOBAL\n        GO AT %IX0.0 : BOOL;\n        SHARED_Q : BOOL;\n    END_VAR\n" in text
    assert "        VAR_GLOBAL CONSTANT\n            BLOCKED : BOOL := FALSE;\n        END_VAR\n" in text
    st = """FUNCTION_BLOCK FB_Every
VAR_INPUT
  EN_IN : BOOL;
END_VAR
VAR_OUTPUT
  Q : BOOL;
END_VAR
VAR_IN_OUT
  TOGGLE : BOOL;
END_VAR
VAR_EXTERNAL CONSTANT
  BLOCKED : BOOL;
END_VAR
VAR_EXTERNAL
  SHARED_Q : BOOL;
END_VAR
VAR_TEMP
  TMP : BOOL;
END_VAR
Q := NOT(BLOCKED) AND EN_IN;
TMP := EN_IN;
SHARED_Q := TMP;
TOGGLE := NOT(TOGGLE);
END_FUNCTION_BLOCK

PROGRAM main
VAR
  F : FB_Every;
  T : BOOL;
END_VAR
VAR
  OUT AT %QX0.2 : BOOL;
END_VAR
VAR_EXTERNAL
  GO : BOOL;
END_VAR
F(EN_IN := GO, TOGGLE := T); OUT := F.Q;
END_PROGRAM

CONFIGURATION Config0
  VAR_GLOBAL
    GO AT %IX0.0 : BOOL;
    SHARED_Q : BOOL;
  END_VAR
  RESOURCE Res0 ON PLC
    VAR_GLOBAL CONSTANT
      BLOCKED : BOOL := FALSE;
    END_VAR
    TASK task0 (INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM instance0 WITH task0 : main;
  END_RESOURCE
END_CONFIGURATION
"""
    trace = same_run(path, st, [{"%IX0.0": n in (1, 2, 5)} for n in range(7)], ["instance0.T", "SHARED_Q"])
    assert [row[0]["QX"][2] for row in trace] == [0, 1, 1, 0, 0, 1, 0]          # OUT (%QX0.2) follows GO
    assert [row[1][0] for row in trace] == [True, False, True, False, True, False, True]   # in-out toggled
    assert [row[1][1] for row in trace] == [row[0]["QX"][2] == 1 for row in trace]        # the external written


def test_a_located_input_of_a_function_block_is_refused_as_matiec_refuses_it(tmp_path):
    """The Editor writes a located VAR_INPUT as its own block; matiec refuses AT there."""
    fb = Pou("FB_X", "functionBlock", "Y := X;", {"inputVars": [("X", "BOOL", None, "%IX0.0")],
                                                  "outputVars": [("Y", "BOOL", None)]})
    prg = Pou("main", "program", "F();", {"localVars": [("F", "FB_X", None)]})
    assert "located variables" in refused(save(tmp_path, [fb, prg]))


def test_a_function_drawn_in_ladder_returns_its_result(tmp_path):
    d = Diagram()
    d.coil("FC_Both", 0, 3, after=d.contact("B", 0, 1, after=d.contact("A", 0, 0)))
    fc = Pou("FC_Both", "function", d, {"inputVars": [("A", "BOOL", None), ("B", "BOOL", None)]}, return_type="BOOL")
    prg = Pou("main", "program", "Q := FC_Both(X, Y);", {"localVars": [
        ("X", "BOOL", None, "%IX0.0"), ("Y", "BOOL", None, "%IX0.1"), ("Q", "BOOL", None, "%QX0.0")]})
    path = save(tmp_path, [prg, fc])          # the function after its user: the Editor writes it first
    assert "FUNCTION FC_Both : BOOL\nVAR_INPUT\n" in emitted(path)
    st = """FUNCTION FC_Both : BOOL
VAR_INPUT
  A : BOOL;
  B : BOOL;
END_VAR
FC_Both := B AND A;
END_FUNCTION
PROGRAM main
VAR
  X AT %IX0.0 : BOOL;
  Y AT %IX0.1 : BOOL;
  Q AT %QX0.0 : BOOL;
END_VAR
Q := FC_Both(X, Y);
END_PROGRAM
""" + CONFIG.format(program="main")
    trace = same_run(path, st, [{"%IX0.0": bool(n & 1), "%IX0.1": bool(n & 2)} for n in range(4)], [])
    assert [row[0]["QX"][0] for row in trace] == [0, 0, 0, 1]


# --------------------------------------------------------------------------- refused by name

@pytest.mark.parametrize("variable,words", [
    (("TON0", "TON", "(PT := T#1s)"), "variable TON0: TON instance with an initial value: OpenPLC Editor drops it"),
    (("TON0", "TON", None, "%MW3"), "variable TON0: TON instance located at %MW3: OpenPLC Editor drops the address"),
    (("NAME", "STRING[10]", None), "variable NAME: STRING[10]: OpenPLC Editor drops the length"),
])
def test_what_the_editor_would_drop_is_refused_by_name(tmp_path, variable, words):
    pou = Pou("main", "program", "X := NOT X;", {"localVars": [("X", "BOOL", None), variable]})
    assert words in refused(save(tmp_path, [pou]))


def test_a_type_the_editor_cannot_spell_is_refused_by_name(tmp_path):
    path = save(tmp_path, [Pou("main", "program", "X := 1;", {"localVars": [("X", "INT", None)]})])
    data = path.read_bytes().replace(b"<INT/>", b'<enum><values><value name="A"/></values></enum>', 1)
    path.write_bytes(data)
    assert "POU main, variable X: an inline <enum> type" in refused(path)


def test_a_pou_without_variables_is_refused_in_st_too(tmp_path):
    """The Editor refuses to generate any POU with no variable, whatever its language."""
    pous = [Pou("FB_Empty", "functionBlock", ";", {}),
            Pou("main", "program", "X := NOT X;", {"localVars": [("X", "BOOL", None)]})]
    assert "POU FB_Empty: no variable defined in this POU" in refused(save(tmp_path, pous))


def test_an_il_body_and_an_empty_drawing_are_refused_by_name(tmp_path):
    """The Editor pastes an IL body as text for matiec's IL, which plclab does not read; a
    drawing with nothing that writes code the Editor refuses to generate."""
    data = project([Pou("main", "program", "X := NOT X;", {"localVars": [("X", "BOOL", None)]})], program="main")
    path = tmp_path / "plc.xml"
    path.write_bytes(data.replace(b"<ST>", b"<IL>").replace(b"</ST>", b"</IL>"))
    assert "main (IL): IL bodies are not supported: write this POU in ST, LD or FBD" in refused(path)
    empty = Pou("main", "program", Diagram(), {"localVars": [("X", "BOOL", None)]})
    assert "main (LD): the body is empty (OpenPLC Editor refuses to generate it)" in refused(save(tmp_path, [empty]))


def test_task_settings_as_the_editor_pastes_them(tmp_path):
    """INTERVAL and PRIORITY pasted as written (a PLCopen v1 duration converted, as the Editor
    converts it when it opens such a file); SINGLE names one variable, a list is refused."""
    pou = Pou("main", "program", "N := N + 1;", {"localVars": [("N", "INT", None)]})
    path = save(tmp_path, [pou], interval="PT0.02S")
    assert "TASK task0 (INTERVAL := T#20ms, PRIORITY := 0);" in emitted(path)
    path.write_bytes(path.read_bytes().replace(b'interval="PT0.02S"', b'single="[A, B]"'))
    assert "task task0: SINGLE needs one BOOL variable" in refused(path)
