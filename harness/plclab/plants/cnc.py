"""The CNC stand (docs/cnc.md): an X-Y-Z table driven by stepper motors through
step/direction drives, with limit switches, an emergency stop and the operator's console.

Drives. Each axis has a STEP and a DIR line. The drives step on both edges of STEP (the
"double-edge" mode of stepper drivers): every change of the STEP output is one step, so a
PLC that sets its outputs once per fine cycle can issue one step per cycle. DIR = 1 steps in
the negative direction. A drive follows at most `max_rate` steps per second: a step beyond
that rate is missed (counted per axis, the table does not move); a step against a closed
limit switch is blocked by the stop (counted too). With the emergency stop pressed (or the
drives not enabled) the drives take no steps at all.

Position counters. The table reports each axis's position in steps as a 16-bit counter on
%IW (it wraps), what a linear scale's counter card would give; the plant's own positions in
mm (`position_mm`) are what the harness plots and checks.

Standard library only (see the package docstring).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from plclab.plants.base import ConsoleFace, PlantError, PlantModel, unsigned16

AXES = ("X", "Y", "Z")
STEP = {"X": "QX0.0", "Y": "QX0.2", "Z": "QX0.4"}
DIR = {"X": "QX0.1", "Y": "QX0.3", "Z": "QX0.5"}
ENABLE = "QX0.6"          # KM1: drive power (the program switches it on when running)
LAMPS = {"HL1": "QX0.7", "HL2": "QX1.0"}      # HL1 program running, HL2 fault / emergency stop
CONSOLE = {
    "SB1": "IX0.0",       # start (push button)
    "SB2": "IX0.1",       # stop / feed hold (push button)
    "SA1": "IX0.2",       # single block (toggle switch)
    "SB3": "IX0.3",       # emergency stop, normally closed: 1 = released, 0 = pressed
}
LIMITS = {                # normally open limit switches at the ends of travel: 1 = reached
    ("X", -1): "IX0.4", ("X", 1): "IX0.5",
    ("Y", -1): "IX0.6", ("Y", 1): "IX0.7",
    ("Z", -1): "IX1.0", ("Z", 1): "IX1.1",
}
LIMIT_LABELS = {("X", -1): "SQ1", ("X", 1): "SQ2", ("Y", -1): "SQ3", ("Y", 1): "SQ4",
                ("Z", -1): "SQ5", ("Z", 1): "SQ6"}
OVERRIDE = "IW0"          # RP1 feed override potentiometer, percent 0..150
COUNTER = {"X": "IW1", "Y": "IW2", "Z": "IW3"}
# The console face (docs/openplc.md): coils SB1, SB2, SA1, SB3 (1 = released); lamps HL1, HL2;
# the table's positions and the missed steps.
FACE = ConsoleFace(switches=tuple(CONSOLE), lamps=tuple(LAMPS.items()),
                   readouts=tuple((f"{a}", "table position, steps (16-bit, signed)") for a in AXES)
                   + (("missed", "steps missed by all drives (16-bit)"),))


@dataclass
class Axis:
    """One axis: where the table is and what its drive did."""

    steps: int = 0             # table position, steps from the machine zero
    step_line: int = 0         # the STEP level the drive saw last
    budget: float = 1.0        # steps the drive can still take at its maximum rate
    received: int = 0          # steps commanded (edges of STEP)
    missed: int = 0            # steps lost: rate exceeded
    blocked: int = 0           # steps against a closed limit switch


class CncTable(PlantModel):
    """The X-Y-Z table, its drives, limit switches and console."""

    outputs = [STEP[a] for a in AXES] + [DIR[a] for a in AXES] + [ENABLE] + list(LAMPS.values())
    inputs = list(CONSOLE.values()) + list(LIMITS.values()) + [OVERRIDE] + list(COUNTER.values())
    FACE = FACE
    FAULTS = {
        "slow_drive": "axis=X|Y|Z rate=steps_per_s: that drive's maximum step rate drops (missed steps)",
    }

    def __init__(self, step_mm: float = 0.01, max_rate: float = 2000.0,
                 travel_mm: tuple[float, float] = (-150.0, 150.0), period: float = 0.001) -> None:
        super().__init__()
        if step_mm <= 0 or max_rate <= 0 or period <= 0:
            raise PlantError("step_mm, max_rate and period must be positive")
        if not travel_mm[0] < 0 < travel_mm[1]:
            raise PlantError("travel_mm must contain the machine zero: (min < 0 < max)")
        self.step_mm, self.max_rate, self.period = float(step_mm), float(max_rate), float(period)
        self.travel = (round(travel_mm[0] / step_mm), round(travel_mm[1] / step_mm))
        self.axes = {a: Axis() for a in AXES}
        self.console_bits = {"SB1": 0, "SB2": 0, "SA1": 0, "SB3": 1}
        self.override = 100
        self.lamps = {name: 0 for name in LAMPS}
        self.enabled = False

    # --- the plant contract -------------------------------------------------------------

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, int]:
        """Take the steps the outputs' edges command over dt seconds; report the inputs."""
        if dt < 0:
            raise PlantError(f"dt must not be negative (got {dt})")
        self.lamps = {name: 1 if outputs.get(loc, 0) else 0 for name, loc in LAMPS.items()}
        self.enabled = bool(outputs.get(ENABLE, 0)) and bool(self.console_bits["SB3"])
        self.time += dt
        for a, axis in self.axes.items():
            rate = self._rate(a)
            axis.budget = min(1.0, axis.budget + rate * dt)
            line = 1 if outputs.get(STEP[a], 0) else 0
            if line == axis.step_line:
                continue
            axis.step_line = line
            if not self.enabled:
                continue
            axis.received += 1
            direction = -1 if outputs.get(DIR[a], 0) else 1
            if axis.budget < 1.0:
                axis.missed += 1
                continue
            axis.budget -= 1.0
            target = axis.steps + direction
            if not self.travel[0] <= target <= self.travel[1]:
                axis.blocked += 1
                continue
            axis.steps = target
        return self._inputs()

    # --- console --------------------------------------------------------------------------

    def set_switch(self, name: str, on: bool | int) -> None:
        """Set a console input: SB1, SB2, SA1, or SB3 (1 = released, 0 = emergency stop pressed)."""
        if name not in CONSOLE:
            raise PlantError(f"unknown console input {name!r}; one of {', '.join(CONSOLE)}")
        self.console_bits[name] = 1 if on else 0

    def press(self, name: str = "SB1") -> None:
        """Press a button; SB3 is normally closed, pressing it opens the contact."""
        self.set_switch(name, 0 if name == "SB3" else 1)

    def release(self, name: str = "SB1") -> None:
        self.set_switch(name, 1 if name == "SB3" else 0)

    def set_override(self, percent: int) -> None:
        """Turn RP1, the feed override potentiometer (0..150 %)."""
        if not 0 <= int(percent) <= 150:
            raise PlantError("feed override must be 0..150 %")
        self.override = int(percent)

    def inject(self, fault: str, **params: Any) -> None:
        if fault == "slow_drive":
            if params.get("axis") not in AXES or float(params.get("rate", 0)) <= 0:
                raise PlantError("slow_drive needs axis=X|Y|Z and a positive rate (steps/s)")
        super().inject(fault, **params)

    # --- what the harness reads -------------------------------------------------------------

    def readouts(self) -> list[int]:
        """The console face's readouts: the positions (steps) and the missed steps."""
        return [unsigned16(self.axes[a].steps) for a in AXES] + [unsigned16(sum(self.missed().values()))]

    def position_mm(self, axis: str) -> float:
        return self.axes[axis].steps * self.step_mm

    def missed(self) -> dict[str, int]:
        return {a: ax.missed for a, ax in self.axes.items()}

    def _rate(self, a: str) -> float:
        slow = self.faults.get("slow_drive")
        if slow and slow.get("axis") == a:
            return float(slow["rate"])
        return self.max_rate

    def _inputs(self) -> dict[str, int]:
        out = {CONSOLE[name]: bit for name, bit in self.console_bits.items()}
        for (a, side), loc in LIMITS.items():
            edge = self.travel[1] if side > 0 else self.travel[0]
            out[loc] = 1 if self.axes[a].steps == edge else 0
        out[OVERRIDE] = self.override
        for a, loc in COUNTER.items():
            out[loc] = unsigned16(self.axes[a].steps)
        return out


def create(**params: Any) -> CncTable:
    return CncTable(**params)
