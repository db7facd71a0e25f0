"""The stands' programs compiled without fast paths (`optimize=False`) play each stand's demo
exactly as its reviewed golden trace says: the plain path and the fast paths agree on whole
programs, not only on the semantics cases."""
from __future__ import annotations

import functools

import pytest
from golden import check_golden

import plclab.scenario
from plclab.runtime.compiler import compile_unit
from plclab.stands import mp9c, thermo, tur10


@pytest.mark.parametrize("stand", [mp9c, tur10, thermo], ids=lambda m: m.__name__.rsplit(".", 1)[1])
def test_demo_compiled_plain_matches_the_golden_trace(stand, tmp_path, monkeypatch):
    monkeypatch.setattr(plclab.scenario, "compile_unit", functools.partial(compile_unit, optimize=False))
    s = stand.session("full", retain_path=tmp_path / "retain.json")
    stand.SCENARIOS["demo"](s)
    name = stand.__name__.rsplit(".", 1)[1]
    check_golden(s.trace, f"{name}-full-demo", s.tick)
