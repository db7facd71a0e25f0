"""The lab page's panels show each stand as the stand declares itself (plclab.stands.base
StandSpec: console order, lamps, injectable faults): the panel adds only how things are
shown (labels as the console prints them, hints, parameter choices)."""
from __future__ import annotations

import pytest

from plclab.lab.panels import PANELS
from plclab.stands.base import stand_spec


@pytest.mark.parametrize("stand", sorted(PANELS))
def test_panel_console_is_the_stands_console_in_its_order(stand):
    spec, panel = stand_spec(stand), PANELS[stand]
    assert tuple(c.input for c in panel.controls) == spec.console


@pytest.mark.parametrize("stand", sorted(PANELS))
def test_panel_lamps_and_faults_are_the_stands(stand):
    spec, panel = stand_spec(stand), PANELS[stand]
    shown = {lamp.label for lamp in panel.lamps}
    assert set(spec.lamps) <= shown
    assert {f.name for f in panel.faults} == {f.name for f in spec.faults}
    for f in panel.faults:
        declared = {p.name for p in spec.fault(f.name).params}
        assert {p.name for p in f.params} <= declared, f.name
