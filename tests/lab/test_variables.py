"""The watch and force table's engine side: forced values are what the program and the
plant see every scan until released, kept through a PLC restart, dropped with one line when
a new program lacks the variable; values are checked against the variable's type."""
from __future__ import annotations

import pytest

from plclab.lab.engine import Lab, LabError
from plclab.lab.variables import VariableError

BLINKER = """PROGRAM Blinker
VAR n : INT; END_VAR
n := n + 1;
END_PROGRAM
CONFIGURATION Config0
    RESOURCE Res0 ON PLC
        TASK t (INTERVAL := T#10ms, PRIORITY := 0);
        PROGRAM Main WITH t : Blinker;
    END_RESOURCE
END_CONFIGURATION
"""


@pytest.fixture
def lab():
    lab = Lab("mp9c")
    lab.session.run(lab.session.tick)
    yield lab
    lab.stop()


def test_a_forced_input_and_output_hold_every_scan_until_released(lab):
    s = lab.session
    lab.force("SA5", "TRUE")                 # manual mode: the arm is told down
    lab.force("L2", "1")                      # ... and the up coil held on as well: a valve conflict
    s.run(1.0)
    assert s.trace.changes("SA5")[-1][1] is True and s.value("L3") is True and s.value("L2") is True
    assert lab.session.plant.console_bits.get("SA5", 0) in (0, False)      # the console never moved
    assert lab.panel.mimic(s)["conflict"] == ["lift"]                     # the plant saw both coils
    lab.restart_plc()                         # forces stay through a power cycle
    s.run(0.1)
    assert s.value("L2") is True and s.plc.read("SA5") is True
    lab.unforce("L2")
    s.run(0.1)
    assert s.value("L2") is False and s.value("L3") is True
    lab.unforce(None)
    s.run(0.1)
    assert s.value("L3") is False and lab.forces.values == {}
    assert [a.text for a in s.actions if "FORCE" in a.text or "released" in a.text] == [
        "FORCE SA5 := TRUE", "FORCE L2 := TRUE", "force released: L2", "force released: SA5"]


def test_a_forced_internal_variable_and_values_its_type_refuses(lab):
    s = lab.session
    lab.force("Main.Cp.Count", "3")
    s.run(0.1)
    assert s.plc.read("Main.Cp.Count") == 3
    for path, value, message in (
            ("Main.Cp.Count", "70000", "70000 is outside INT (-32768..32767)"),
            ("Main.Cp.Count", "1.5", "a INT is forced with a whole number, not '1.5'"),
            ("SA5", "maybe", "a BOOL is forced TRUE or FALSE (1 or 0), not 'maybe'"),
            ("Main.Cp", "1", "'Main.Cp' is not an elementary variable: pick one of its elements or fields"),
            ("Main.Nothing", "1", "'Main.Nothing': unknown variable 'Main.Nothing'")):
        with pytest.raises(VariableError) as e:
            lab.force(path, value)
        assert str(e.value) == message
    assert lab.forces.values == {"Main.Cp.Count": 3}


def test_a_new_program_drops_the_forces_it_cannot_hold(lab):
    from plclab.lab.engine import check_program

    lab.force("SA5", "TRUE")
    lab.set_watch(["SA5", "Main.Cp.Count"])
    checked, errors = check_program([("blink.st", BLINKER)], trial=True)
    assert not errors
    lab.load_program([("blink.st", BLINKER)], checked, "blink.st", upload=True)
    lab.session.run(0.05)
    assert lab.forces.values == {}
    assert lab.watched == []
    assert lab.session.actions[-1].text == "force released: SA5 (not in the program loaded)"
    with pytest.raises(LabError):
        lab.set_watch([f"Main.N{i}" for i in range(40)])
