"""The declared stand specs (plclab.stands.base): what runner, grader and views rely on.

Each stand names its console, lamps, sensors, actuators, faults and observables once; these
tests hold those names to the other sources of the same facts: the GVL (the I/O map), the
plant models (standard library only, so they carry their own copy of the map: it must agree
with the GVL) and the shipped programs (every observable exists in every variant).
"""
from __future__ import annotations

import pytest

from plclab.errors import PlcLabError
from plclab.plants import mp9c as mp9c_plant
from plclab.plants import thermo as thermo_plant
from plclab.plants import tur10 as tur10_plant
from plclab.stands import STANDS, gvl_labels
from plclab.stands.base import StandSpec, stand_spec

SPECS = [stand_spec(name) for name in STANDS]


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: s.name)
def test_every_io_name_of_a_spec_is_a_gvl_label(spec: StandSpec) -> None:
    labels = spec.labels()
    for group in (spec.console, spec.lamps, spec.sensors, spec.actuators):
        assert set(group) <= set(labels), set(group) - set(labels)
    assert len(set(spec.console)) == len(spec.console)


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: s.name)
def test_declared_faults_are_the_plants_faults(spec: StandSpec) -> None:
    plant = spec.stand.make_plant()
    assert {f.name for f in spec.faults} == set(plant.FAULTS)


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: s.name)
def test_every_observable_exists_in_every_shipped_variant(spec: StandSpec, tmp_path) -> None:
    for variant in [v for v in spec.stand.variants if spec.stand.available(v)]:
        s = spec.session(variant, retain_path=tmp_path / f"{variant}.json")
        s.run(s.tick)
        for name in spec.observables_for(variant):
            assert name in s.trace, f"{spec.name} {variant}: observable {name} not recorded"
            assert s.value(name) == s.trace.value_at(name, s.now - s.tick)
        assert not any(path in s.trace for path in spec.observables_for(variant).values()
                       if path not in spec.observables), "traced under the ST path, not the name"


def test_a_student_program_without_an_observable_runs_and_names_what_is_missing(tmp_path) -> None:
    spec = stand_spec("mp9c")
    program = [("student.st", """
PROGRAM Main
VAR n : INT; END_VAR
VAR_EXTERNAL HL1 : BOOL; END_VAR
n := n + 1;
HL1 := TRUE;
END_PROGRAM
CONFIGURATION Config0
  VAR_GLOBAL HL1 AT %QX1.0 : BOOL; END_VAR
  RESOURCE Res0 ON PLC
    TASK MainTask (INTERVAL := T#10ms, PRIORITY := 1);
    PROGRAM Main WITH MainTask : Main;
  END_RESOURCE
END_CONFIGURATION
""")]
    s = spec.session(program=program)
    s.run(0.05)
    assert s.value("HL1") is True
    # shown as absent, never invented; a scenario does not read it (it would be told so)
    assert s.trace.changes("FramePtr") == [(0, "absent")] and "FramePtr" in s.absent
    assert not s.has("FramePtr") and s.observed("FramePtr") is None
    with pytest.raises(AssertionError, match="reads FramePtr .*Main.Robot.Sequencer.Ptr.*does not have"):
        s.value("FramePtr")


def test_unknown_scenario_and_fault_are_one_line_errors() -> None:
    spec = stand_spec("tur10")
    with pytest.raises(PlcLabError, match="unknown scenario 'nope' \\(one of demo, "):
        spec.scenario("nope")
    with pytest.raises(PlcLabError, match="unknown fault 'nope' \\(one of dead_sensor, "):
        spec.fault("nope")
    with pytest.raises(PlcLabError, match="unknown stand 'cnc9'"):
        stand_spec("cnc9")


# ------------------------------------------------------------------- plants agree with the GVL

def _gvl(stand: str) -> dict[str, str]:
    """GVL label -> address without the '%' (the plants' spelling)."""
    return {k: v[1:] for k, v in gvl_labels(stand_spec(stand).stand).items()}


def test_mp9c_plant_map_is_the_gvl() -> None:
    gvl = _gvl("mp9c")
    plant = {**mp9c_plant.SENSORS, **mp9c_plant.CONSOLE, **mp9c_plant.COILS}
    assert {k: gvl[k] for k in plant} == plant
    lamp = [k for k, v in gvl.items() if v == "QX1.0"]
    assert lamp == ["HL1"] and set(gvl) == set(plant) | {"HL1"}
    assert set(mp9c_plant.MP9C.inputs) == {v for k, v in gvl.items() if v.startswith("I")}
    assert set(mp9c_plant.MP9C.outputs) == {v for k, v in gvl.items() if v.startswith("Q")}


def test_tur10_plant_map_is_the_gvl() -> None:
    gvl = _gvl("tur10")
    assert {k: gvl[k] for k in tur10_plant.CONSOLE} == tur10_plant.CONSOLE
    assert tuple(gvl[f"BUS{n}"] for n in range(1, 16)) == tur10_plant.BUS_BITS
    assert {k: gvl[f"RE{k}"] for k in tur10_plant.AXES} == tur10_plant.ENABLE
    assert {k: gvl[f"DRIVE{k}"] for k in tur10_plant.AXES} == tur10_plant.DAC
    assert gvl["HL1"] == tur10_plant.RESET_LAMP
    assert set(tur10_plant.Tur10.inputs) == {v for v in gvl.values() if v.startswith("I")}
    assert set(tur10_plant.Tur10.outputs) == {v for v in gvl.values() if v.startswith("Q")}


def test_thermo_plant_map_is_the_gvl() -> None:
    gvl = _gvl("thermo")
    plant = thermo_plant.ThermoPlant
    # the raw tacho bit %IX0.1 is wired (the plant drives it) but the program reads the counter
    assert set(plant.inputs) == {v for v in gvl.values() if v.startswith("I")} | {"IX0.1"}
    assert set(plant.outputs) == {v for v in gvl.values() if v.startswith("Q")}
    assert (gvl["DISTURBANCE"], gvl["TEMP_ADC"], gvl["FAN_COUNT"]) == ("IX0.0", "IW0", "IW1")
    assert (gvl["FAN"], gvl["HEATER"]) == ("QW0", "QW1")
