"""The thermo register contract has one source per fact: the GVL (which %MW exist, names,
types, initial values, meanings) and the Twido rules declared once in plclab.modbus.profiles
(access, valid values, manual-only writes). What ST also says -- PRG_Thermo's modes and
command ranges, the GVL comments' ranges -- is held to those rules here."""
from __future__ import annotations

import pytest

from plclab.frontend.parser import parse_source
from plclab.modbus.profiles import (THERMO_MODES, THERMO_RULES, Access, GvlRegister, RegisterRule,
                                    ValueRange, ValueSet, profile_from_gvl, valid_range)
from plclab.stands import PLC_DIR, twido_profile, get_stand, gvl_variables


def _program_constants(pou: str) -> dict[str, int]:
    """The integer VAR CONSTANTs of a shipped POU, as the project's parser reads them."""
    path = PLC_DIR / "POUs" / f"{pou}.st"
    unit, diagnostics = parse_source(path.read_text(encoding="utf-8"), str(path))
    assert unit is not None and not diagnostics, diagnostics
    (decl,) = [p for p in unit.pous if p.name == pou]
    return {d.name: d.init.value for b in decl.blocks if b.constant for d in b.decls
            if getattr(d.init, "kind", None) == "int"}


def test_the_profile_is_the_gvl_under_the_rules() -> None:
    thermo = twido_profile("thermo")
    gvl = {v.name: v for v in gvl_variables(get_stand("thermo")) if v.address.startswith("%MW")}
    assert [r.address for r in thermo.registers] == [int(gvl[rule.label].address[3:]) for rule in THERMO_RULES]
    assert [r.description for r in thermo.registers] == [gvl[rule.label].comment for rule in THERMO_RULES]
    assert {rule.label for rule in THERMO_RULES} == set(gvl)
    mode = thermo.register(int(gvl["MODE"].address[3:]))
    assert mode is not None and mode.name == "mode"
    for reg in thermo.registers:
        if reg.writable_when is not None:
            assert reg.writable_when.address == mode.address


def test_prg_thermo_agrees_with_the_twido_rules() -> None:
    constants = _program_constants("PRG_Thermo")
    assert {constants["MODE_MANUAL"], constants["MODE_AUTO1"], constants["MODE_AUTO2"]} == set(THERMO_MODES)
    (mode,) = [r for r in THERMO_RULES if r.label == "MODE"]
    assert mode.valid == ValueSet(frozenset(THERMO_MODES))
    assert valid_range(THERMO_RULES, "FAN_CTRL") == ValueRange(0, constants["FAN_MAX"])
    assert valid_range(THERMO_RULES, "HEATER_CTRL") == ValueRange(0, constants["HEATER_MAX"])
    assert valid_range(THERMO_RULES, "SETPOINT") == ValueRange(constants["SETPOINT_MIN"], constants["SETPOINT_MAX"])


def test_gvl_comments_state_the_ranges_and_initial_values_are_valid() -> None:
    thermo = twido_profile("thermo")
    initial = {v.name: v.initial for v in gvl_variables(get_stand("thermo"))}
    for rule in THERMO_RULES:
        reg = thermo.register(_address(rule.label))
        assert reg is not None
        if isinstance(rule.valid, ValueRange):
            assert str(rule.valid) in reg.description, (rule.label, reg.description)
        if rule.valid is not None and initial[rule.label] is not None:
            assert int(initial[rule.label]) in rule.valid
    mode = thermo.register(_address("MODE"))
    assert mode is not None and all(f"{value} {name}" in mode.description for value, name in THERMO_MODES.items())


def _address(label: str) -> int:
    return next(int(v.address[3:]) for v in gvl_variables(get_stand("thermo")) if v.name == label)


def test_a_gvl_register_without_a_rule_or_a_rule_without_a_register_is_refused() -> None:
    gvl = {"MODE": GvlRegister(0, "INT", ""), "EXTRA": GvlRegister(1, "WORD", "")}
    with pytest.raises(ValueError, match="no Twido rule for EXTRA"):
        profile_from_gvl("t", gvl, (RegisterRule("MODE", "mode"),))
    with pytest.raises(ValueError, match="GONE is not a %MW variable"):
        profile_from_gvl("t", gvl, (RegisterRule("MODE", "mode"), RegisterRule("EXTRA", "x"),
                                    RegisterRule("GONE", "g", Access.RO)))
    words = profile_from_gvl("t", gvl, (RegisterRule("MODE", "mode"), RegisterRule("EXTRA", "x")))
    assert [r.signed for r in words.registers] == [True, False]     # INT signed, WORD not: the GVL type
