"""The lab page's panels are derived from each stand's StandSpec (console order, lamps,
injectable faults and their parameters); the panel's Look adds only how things are shown.
A look that names something the stand does not have fails when the panel is built."""
from __future__ import annotations

import dataclasses

import pytest

from plclab.errors import PlcLabError
from plclab.lab.panels import PANELS, Look, derive_panel
from plclab.stands.base import Fault, FaultParam, stand_spec


@pytest.mark.parametrize("stand", sorted(PANELS))
def test_panel_shows_the_stands_console_lamps_and_faults(stand):
    spec, panel = stand_spec(stand), PANELS[stand]
    knobs = {k.label for k in panel.knobs}          # the CNC's RP1: a slider, not a contact
    assert tuple(c.input for c in panel.controls) == tuple(i for i in spec.console if i not in knobs)
    assert knobs & set(spec.console) == ({"RP1"} if stand == "cnc" else set())
    assert set(spec.lamps) <= {lamp.label for lamp in panel.lamps}
    assert [(f.name, [p.name for p in f.params]) for f in panel.faults] == \
        [(f.name, [p.name for p in f.params]) for f in spec.faults]


def test_what_a_stand_adds_appears_on_its_page_with_its_gvl_label():
    spec = stand_spec("mp9c")
    grown = dataclasses.replace(
        spec, console=spec.console + ("SPARE",), lamps=spec.lamps + ("HL2",),
        faults=spec.faults + (Fault("leak", "air leaks", (FaultParam("rate", "l/min", 2),)),))
    panel = derive_panel(grown, Look(labels={"I07": "I0.7"}, buttons=frozenset({"SB1"})))
    assert [(c.label, c.kind) for c in panel.controls][-3:] == [("SB1", "button"), ("I0.7", "switch"), ("SPARE", "switch")]
    assert [lamp.label for lamp in panel.lamps] == ["HL1", "HL2"]
    leak = panel.faults[-1]
    assert (leak.name, leak.text, [(p.name, p.choices, p.default) for p in leak.params]) == \
        ("leak", "air leaks", [("rate", (), "2")])


@pytest.mark.parametrize("look, stale", [
    (Look(labels={"SA9": "SA9"}), "SA9"),
    (Look(hints={"L9": "a coil the stand lacks"}), "L9"),
    (Look(buttons=frozenset({"SB2"})), "SB2"),
    (Look(fault_texts={"flood": "water"}), "flood"),
    (Look(fault_params={("jammed", "where"): ((), "")}), "jammed.where"),
])
def test_a_look_naming_what_the_stand_lacks_is_refused(look, stale):
    with pytest.raises(PlcLabError, match=f"lab panel of mp9c: {stale} not in the stand's StandSpec"):
        derive_panel(stand_spec("mp9c"), look)
