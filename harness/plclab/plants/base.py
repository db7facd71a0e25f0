"""What every plant model has: the I/O it touches, stepping, injectable faults, events.

Contract (plclab.runtime.plantio uses it in-process, plclab.modbus.psm over PSM):
  outputs  PLC outputs the plant reads, OpenPLC location names ("QX0.1", "QW0")
  inputs   PLC inputs the plant drives ("IX0.0", "IW0")
  period   seconds between steps when it runs on its own in real time (PSM)
  step(outputs, dt) -> inputs   values are raw: bits 0/1, words unsigned 16-bit; dt seconds
  step_values(outputs, dt) -> values   optional, the same step on values in order: `outputs`
           the values of `outputs` (None where not given), the result the values of `inputs`,
           raw (0/1, 0..65535); the closed loop then builds and reads no dict
  idle(outputs, dt) -> bool     optional: True where a step of dt under these outputs (their
           values, `outputs` order) would change nothing but the time, which it then moves on;
           once True, True again for the same outputs until the plant is stepped in full or
           its console or faults change (the closed loop runs such stretches in one go)
  FACE     the console face (ConsoleFace): which switches an operator sets, which PLC
           outputs are lamps, which plant readouts are shown; set_switch(name, value) and
           readouts() serve it (plclab.modbus.console puts it on Modbus TCP)
Standard library only (see the package docstring).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class PlantEvent:
    """Something notable the plant saw (a fault it detected, an injected fault), with its time."""

    time: float          # plant seconds since power-up
    kind: str            # e.g. 'valve_conflict', 'collision', 'overvoltage', 'fault_injected'
    detail: str


class PlantError(ValueError):
    """A bad request to a plant (unknown fault, bad parameter): one line for the user."""


@dataclass(frozen=True)
class ConsoleFace:
    """What an operator reaches of a stand without the PLC: the one table of its console face.

    Why a table: OpenPLC's PSM layer overwrites every %IX each scan, so the console inputs of
    a stand running inside OpenPLC can only be set through the plant; this table says, once,
    which coil is which switch (coil n = switches[n]), which discrete input is which lamp
    (discrete input n = lamps[n], a PLC output location), and which input register is which
    plant readout (input register n = readouts[n], in the unit named).
    """

    switches: tuple[str, ...]                  # console input names, in coil order
    lamps: tuple[tuple[str, str], ...]         # (lamp label, PLC output location)
    readouts: tuple[tuple[str, str], ...]      # (readout name, unit)
    tape: int = 0                              # holding registers of a tape reader (0: none), load_tape()
    tape_fields: int = 0                       # values per frame on the tape


class PlantModel:
    """Base class: keeps plant time, the event log and the injected faults."""

    outputs: list[str] = []
    inputs: list[str] = []
    period: float = 0.01
    FAULTS: dict[str, str] = {}          # fault name -> what it does (for help texts)
    FACE = ConsoleFace((), (), ())       # the console face (switches, lamps, readouts)
    CONSOLE: dict[str, str] = {}         # console input name -> PLC input location ("IX0.0")
    NORMALLY_CLOSED: frozenset[str] = frozenset()   # buttons whose contact opens when pressed

    def __init__(self) -> None:
        self.time = 0.0
        self.events: list[PlantEvent] = []
        self.faults: dict[str, dict[str, Any]] = {}
        self.fault_changes = 0       # counts injections and clears: a step may compare it
        self.console_changes = 0     # counts changes of console_bits (written by set_switch only)
        # console inputs at rest: released buttons, switches off (normally closed ones conduct)
        self.console_bits: dict[str, int] = {name: int(name in self.NORMALLY_CLOSED) for name in self.CONSOLE}

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, int]:
        raise NotImplementedError

    def set_switch(self, name: str, value: bool | int) -> None:
        """Set one console input (a name of CONSOLE) to 0/1: the contact's level."""
        if name not in self.CONSOLE:
            if not self.CONSOLE:
                raise PlantError(f"this plant has no console switch {name!r}")
            raise PlantError(f"unknown console input {name!r}; one of {', '.join(self.CONSOLE)}")
        bit = 1 if value else 0
        if self.console_bits[name] != bit:
            self.console_bits[name] = bit
            self.console_changes += 1

    def press(self, name: str = "SB1") -> None:
        """Press a push button: its contact closes, or opens for a normally closed one (an
        emergency stop)."""
        self.set_switch(name, name not in self.NORMALLY_CLOSED)

    def release(self, name: str = "SB1") -> None:
        """Release a push button."""
        self.set_switch(name, name in self.NORMALLY_CLOSED)

    def readouts(self) -> list[int]:
        """The FACE.readouts values now, as raw 16-bit register contents."""
        return []

    def event(self, kind: str, detail: str) -> None:
        self.events.append(PlantEvent(self.time, kind, detail))

    def inject(self, fault: str, **params: Any) -> None:
        """Inject a fault by name (see FAULTS); parameters say where and how much."""
        if fault not in self.FAULTS:
            raise PlantError(f"unknown fault {fault!r}; this plant has: {', '.join(sorted(self.FAULTS))}")
        self.faults[fault] = dict(params)
        self.fault_changes += 1
        self.event("fault_injected", fault_words(fault, params))

    def clear(self, fault: str | None = None) -> None:
        """Remove one injected fault, or all of them."""
        self.fault_changes += 1
        if fault is None:
            self.faults.clear()
        else:
            self.faults.pop(fault, None)


def signed16(raw: int) -> int:
    """A raw register value as the signed INT the PLC wrote."""
    raw &= 0xFFFF
    return raw - 0x10000 if raw & 0x8000 else raw


def unsigned16(value: int) -> int:
    """A signed value as the raw register content."""
    return int(value) & 0xFFFF


def fault_words(fault: str, params: dict[str, Any]) -> str:
    """An injected fault as a student reads it: 'jammed (mechanism lift)', not a Python dict."""
    return f"{fault} ({', '.join(f'{k} {v}' for k, v in params.items())})" if params else fault
