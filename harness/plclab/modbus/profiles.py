"""Register tables of the Twido-style Modbus face, as data.

A SCADA exercise relies on a register contract (which %MW exist, which are read-only, which
values are accepted and when); keeping that contract in a table rather than in code lets the
server, the thermo stand, the HMI and the docs share one source. THERMO is `docs/thermo.md`'s table.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass

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


_MANUAL = WhenEquals(address=0, value=0)

THERMO = TwidoProfile(
    name="thermo",
    registers=(
        Register(0, "mode", Access.RW, ValueSet(frozenset({0, 1, 2})),
                 description="0 manual, 1 automatic-1 (heater regulates), 2 automatic-2 (fan regulates)"),
        Register(1, "fan", Access.RW, ValueRange(0, 1000), writable_when=_MANUAL,
                 description="fan control; in automatic modes the current fan command"),
        Register(2, "heater", Access.RW, ValueRange(0, 2000), writable_when=_MANUAL,
                 description="heater control; in automatic modes the current heater command"),
        Register(3, "temperature", Access.RO, description="heat-sink temperature, whole C"),
        Register(4, "fan_speed", Access.RO, description="fan speed, pulses per second"),
        Register(5, "reserved", Access.RO, description="reserved, reads 0"),
        Register(6, "setpoint", Access.RW, ValueRange(25, 70),
                 description="temperature setpoint, whole C"),
    ),
)

# Profile name used in openplc.conf (`profile = twido`) -> the stand's table.
TWIDO_PROFILES: dict[str, TwidoProfile] = {"thermo": THERMO}
