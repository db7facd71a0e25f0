"""Register tables of the Twido-style Modbus face, as data.

A SCADA exercise relies on a register contract (which %MW exist, which are read-only, which
values are accepted and when); keeping that contract in a table rather than in code lets the
server, the thermo stand, the HMI and the docs share one source. The thermo stand's table
(`docs/thermo.md`) is `plclab.stands.twido_profile("thermo")`.

Each fact has one home. The stand's GVL (plc/GVL/GVL_THERMO.st) says which %MW exist, their
names, types, initial values and meanings; what ST cannot say -- the Twido's refusal rules
(read only, valid values, writable only in manual mode) and the HMI's point names -- is
declared here once, per GVL label (THERMO_RULES), and tests/modbus/test_profiles.py holds the
ranges to PRG_Thermo's constants. The stands build a profile from both
(plclab.stands.twido_profile): the ST sources are theirs, and the PSM script embeds this module
(for TwidoMap's types) without them.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Mapping, Sequence

from .protocol import (READ_HOLDING_REGISTERS, READ_WRITE_MULTIPLE_REGISTERS,
                       WRITE_MULTIPLE_REGISTERS, WRITE_SINGLE_REGISTER)


class Access(enum.Enum):
    RW = "read/write"
    RO = "read only"


@dataclass(frozen=True)
class ValueRange:
    """Inclusive range of valid values (compared after the register's signedness is applied)."""

    low: int
    high: int

    def __contains__(self, value: object) -> bool:
        return isinstance(value, int) and self.low <= value <= self.high

    def __str__(self) -> str:
        return f"{self.low}..{self.high}"


@dataclass(frozen=True)
class ValueSet:
    """An explicit set of valid values (e.g. the mode register's 0, 1, 2)."""

    values: frozenset[int]

    def __contains__(self, value: object) -> bool:
        return value in self.values

    def __str__(self) -> str:
        return ", ".join(str(v) for v in sorted(self.values))


@dataclass(frozen=True)
class WhenEquals:
    """A write rule: the register is writable only while register `address` holds `value`.

    Evaluated on the registers as they would be after the whole request, so one FC 16 that
    sets manual mode and a heater value together is accepted.
    """

    address: int
    value: int

    def __str__(self) -> str:
        return f"%MW{self.address} = {self.value}"


@dataclass(frozen=True)
class Register:
    """One holding register n = %MWn of a Twido profile."""

    address: int
    name: str
    access: Access = Access.RW
    valid: ValueRange | ValueSet | None = None      # None: any 16-bit value
    writable_when: WhenEquals | None = None
    signed: bool = True                             # Twido %MW are INT
    description: str = ""

    def as_value(self, raw: int) -> int:
        """The register's number as the program sees it (raw 16-bit word -> INT or WORD)."""
        return raw - 0x10000 if self.signed and raw >= 0x8000 else raw


@dataclass(frozen=True)
class TwidoProfile:
    """A Twido-style map: only the declared %MW exist (anything else is exception 02)."""

    name: str
    registers: tuple[Register, ...]
    functions: frozenset[int] = frozenset({READ_HOLDING_REGISTERS, WRITE_SINGLE_REGISTER,
                                           WRITE_MULTIPLE_REGISTERS,
                                           READ_WRITE_MULTIPLE_REGISTERS})

    def __post_init__(self) -> None:
        addresses = [r.address for r in self.registers]
        if len(set(addresses)) != len(addresses):
            raise ValueError(f"profile {self.name}: duplicate register address")

    def register(self, address: int) -> Register | None:
        for reg in self.registers:
            if reg.address == address:
                return reg
        return None


@dataclass(frozen=True)
class RegisterRule:
    """What a Twido enforces on one %MW of a stand's GVL (`label`), which ST cannot say."""

    label: str                                      # the GVL variable: 'HEATER_CTRL'
    name: str                                       # the point name SCADA and the HMI use: 'heater'
    access: Access = Access.RW
    valid: ValueRange | ValueSet | None = None
    writable_when: tuple[str, int] | None = None    # (GVL label, value): writable only while it holds it


@dataclass(frozen=True)
class GvlRegister:
    """What a profile takes of one %MW global of the GVL (plclab.stands.gvl_variables reads them)."""

    address: int
    type: str
    comment: str


_SIGNED_TYPES = frozenset({"SINT", "INT", "DINT", "LINT"})


def profile_from_gvl(name: str, gvl: Mapping[str, GvlRegister], rules: Sequence[RegisterRule]) -> TwidoProfile:
    """A profile with one register per rule, at its GVL label's address, signed as its GVL type,
    described by its GVL comment."""
    def address(label: str) -> int:
        if label not in gvl:
            raise ValueError(f"profile {name}: {label} is not a %MW variable of the stand's GVL")
        return gvl[label].address

    unruled = set(gvl) - {rule.label for rule in rules}
    if unruled:
        raise ValueError(f"profile {name}: no Twido rule for {', '.join(sorted(unruled))} of the stand's GVL")
    registers = []
    for rule in rules:
        when = None if rule.writable_when is None else WhenEquals(address(rule.writable_when[0]),
                                                                 rule.writable_when[1])
        var = gvl[rule.label] if rule.label in gvl else None
        registers.append(Register(address(rule.label), rule.name, rule.access, rule.valid, when,
                                  signed=var is not None and var.type in _SIGNED_TYPES,
                                  description=var.comment if var is not None else ""))
    return TwidoProfile(name, tuple(registers))


# The thermo stand's modes (%MW0), as PRG_Thermo's MODE_MANUAL / MODE_AUTO1 / MODE_AUTO2.
MANUAL, AUTO1, AUTO2 = 0, 1, 2
THERMO_MODES = {MANUAL: "manual", AUTO1: "automatic-1", AUTO2: "automatic-2"}

THERMO_RULES = (
    RegisterRule("MODE", "mode", Access.RW, ValueSet(frozenset(THERMO_MODES))),
    RegisterRule("FAN_CTRL", "fan", Access.RW, ValueRange(0, 1000), writable_when=("MODE", MANUAL)),
    RegisterRule("HEATER_CTRL", "heater", Access.RW, ValueRange(0, 2000), writable_when=("MODE", MANUAL)),
    RegisterRule("TEMPERATURE", "temperature", Access.RO),
    RegisterRule("FAN_SPEED", "fan_speed", Access.RO),
    RegisterRule("RESERVED", "reserved", Access.RO),
    RegisterRule("SETPOINT", "setpoint", Access.RW, ValueRange(25, 70)),
)

def valid_range(rules: Sequence[RegisterRule], label: str) -> ValueRange:
    """The range of values the rule of `label` accepts (its bounds are the command's scale)."""
    valid = next((r.valid for r in rules if r.label == label), None)
    if not isinstance(valid, ValueRange):
        raise ValueError(f"{label}: no range of valid values")
    return valid


# Stand name (and openplc.conf `profile = twido`) -> the rules of its Twido map.
TWIDO_RULES: dict[str, tuple[RegisterRule, ...]] = {"thermo": THERMO_RULES}
