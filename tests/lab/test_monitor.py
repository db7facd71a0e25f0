"""Online monitoring without a browser: an indexed use (`Valves[i]`, `Frames[n].Pause`) gets
the value of the element its indexes name now, and nothing (never another element's value)
when an index is out of range or cannot be computed."""
from __future__ import annotations

from plclab.lab.engine import Lab

PROGRAM = """TYPE ST_Frame : STRUCT Data : ARRAY[1..2] OF INT; Pause : TIME; END_STRUCT; END_TYPE
PROGRAM Idx
VAR
    Valves : ARRAY[1..4] OF INT := [10, 20, 30, 40];
    Frames : ARRAY[1..3] OF ST_Frame;
    i : INT := 2;
    n : INT := 1;
    x : INT;
    y : INT;
    z : INT;
    w : INT;
    M : ARRAY[1..2, 1..3] OF INT := [1, 2, 3, 4, 5, 6];
    m2 : INT;
END_VAR
Frames[1].Data[2] := 7;
Frames[2].Pause := T#1500ms;
x := Valves[i];             (* a variable index *)
y := Valves[ 3 ] + Valves[i + 1];   (* a constant; an expression: not computed *)
z := Frames[n].Data[2];
w := Valves[i];
m2 := M[n, i];              (* two dimensions *)
END_PROGRAM
CONFIGURATION Config0
    RESOURCE Res0 ON PLC
        TASK t (INTERVAL := T#10ms, PRIORITY := 0);
        PROGRAM Main WITH t : Idx;
    END_RESOURCE
END_CONFIGURATION
"""


def _values(lab: Lab) -> dict:
    return lab.monitor.values(lab.session.plc, True)


def test_indexed_uses_show_the_element_their_live_indexes_name_and_nothing_out_of_range():
    lab = Lab("mp9c", sources=[("idx.st", PROGRAM)], speed=1.0)
    lab.advance(0.05)
    pou = next(p for p in lab.listing() if p["name"] == "Idx")
    line = pou["lines"]
    shown = {(r[0], line[r[0] - pou["line"]][r[1]:r[2]]) for r in pou["refs"]}
    body = pou["line"] + next(k for k, text in enumerate(line) if text.startswith("y :="))
    assert (body, "Valves[ 3 ]") in shown                  # the use as written, its value after it
    assert (body, "Valves") in shown                       # `Valves[i + 1]`: the array alone (no value)
    assert (body, "i") in shown                            # an index is a use of its own
    lab.select_monitor("Idx", "Main")
    v = _values(lab)
    assert (v["Valves[i]"], v["Valves[3]"], v["Frames[n].Data[2]"], v["M[n,i]"]) == (20, 30, 7, 2)
    assert "Valves" not in v                               # an array has no value to show
    plc = lab.session.plc
    plc.write("Main.i", 4)
    plc.write("Main.n", 2)
    v = _values(lab)
    assert (v["Valves[i]"], v["Frames[n].Data[2]"], v["M[n,i]"]) == (40, 0, "")   # M[2, 4]: out of range
    plc.write("Main.i", 5)                                 # out of range: nothing, not a stale value
    plc.write("Main.n", 0)
    v = _values(lab)
    assert (v["Valves[i]"], v["Frames[n].Data[2]"], v["M[n,i]"]) == ("", "", "")
    plc.write("Main.i", 1)
    plc.write("Main.n", 2)
    assert lab.monitor.values(plc, False) == {"i": 1, "n": 2, "Valves[i]": 10, "Frames[n].Data[2]": 0,
                                              "M[n,i]": 4}   # changes only, as for plain names


def test_every_instance_at_once_reads_as_the_live_view_of_each_ladder_power_included(tmp_path):
    """A graded run's moment (monitor.every_value) shows what the live view would, instance by
    instance: the same values, an LD POU's same power flow."""
    from test_ladder import ladder_program

    from plclab.frontend import read_sources
    from plclab.lab.monitor import every_value
    lab = Lab("mp9c", sources=read_sources([str(p) for p in ladder_program(tmp_path)]), speed=1.0)
    lab.press("SB1", True)
    lab.advance(0.5)
    every = every_value(lab.session.plc, lab.session.sources)
    for pou in lab.listing():
        for instance in pou["instances"] or [None]:
            lab.select_monitor(pou["name"], instance)
            shown = every[pou["name"]][instance or ""]
            assert shown["values"] == _values(lab), (pou["name"], instance)
            assert shown.get("power") == lab._power_flow(), (pou["name"], instance)
    button = every["FB_Sb1Button"]
    assert any(e["power"] and any(v is True for v in e["power"].values()) for e in button.values())   # SB1 held: power flows
    lab.stop()
