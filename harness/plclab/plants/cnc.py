"""The CNC stand (docs/cnc.md): an X-Y-Z table driven by stepper motors through
step/direction drives, with limit switches, an emergency stop and the operator's console.

Drives. Each axis has a STEP and a DIR line. The drives step on both edges of STEP (the
"double-edge" mode of stepper drivers): every change of the STEP output is one step, so a
PLC that sets its outputs once per fine cycle can issue one step per cycle. DIR = 1 steps in
the negative direction. A drive follows at most `max_rate` steps per second: a step beyond
that rate is missed (counted per axis, the table does not move); a step against a closed
limit switch is blocked by the stop (counted too). With the emergency stop pressed (or the
drives not enabled) the drives take no steps at all.

Pulse counts (the paper's position-control module). Instead of step edges the PLC may send,
once per interpolation cycle, a signed pulse count per axis on %QW (PULSES_X/Y/Z) with the
cycle's number on %QW3: each new number hands the counts to a pulse generator that spreads
them evenly over the next `pulse_cycle` seconds (pulse k of n at (k + 1/2) T / n), with the
count's sign as the direction. The drives count what they receive either way; counts of a
cycle not yet spread when the next arrives are still issued, never dropped.

Backlash. A transmission may have `backlash` steps of play: the table follows the motor
only after the motor has crossed the dead band, so on each reversal the table lags the motor
by the play (textbook 4.2.2.3). At power-up the play is taken up on the positive side (the
table was last approached moving positive, as after referencing).

Touch probe. For the blank-installation measuring cycle (textbook 4.2.2.2, Fig. 18) the
blank carries base holes (`set_blank`: their centres on the machine, their radius). A probe
in the spindle, lowered into the hole the tool is over, makes contact (B1, %IX1.2) when it
reaches the hole's wall: inside a collar of three hole radii around a centre, contact means
at or beyond the wall; elsewhere the probe is above the blank and open.

Position counters. The table reports each axis's position in steps as a 16-bit counter on
%IW (it wraps), what a linear scale's counter card would give; the plant's own positions in
mm (`position_mm`) are what the harness plots and checks.

Tape reader. Inside OpenPLC nothing but located I/O reaches the PLC, so the part program's
frames come in the way a punched-tape reader gave them to a CNC: `load_tape` (the console
face's holding registers, `plclab console cnc --part`) puts a prepared frame table on the
reader; once the PLC's acknowledgement TAPE_ACK (%QW4) is 0, the reader presents frame 1 on
%IW4 (its number), %IW5 (the frame count), %IW6 (the method) and %IW7..%IW15 (kind, X, Y, Z,
I, J, feed, comp, radius: the frame table's values, steps, 16-bit signed); each time the PLC
acknowledges the frame shown (TAPE_ACK = its number) the next one follows; after the last,
the reader shows 0. The PLC stores the frames while idle (PRG_CncStand).

Standard library only (see the package docstring).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

from plclab.plants.base import ConsoleFace, PlantError, PlantModel, signed16, unsigned16

AXES = ("X", "Y", "Z")
STEP = {"X": "QX0.0", "Y": "QX0.2", "Z": "QX0.4"}
DIR = {"X": "QX0.1", "Y": "QX0.3", "Z": "QX0.5"}
PULSES = {"X": "QW0", "Y": "QW1", "Z": "QW2"}   # pulse counts of one cycle, signed
PULSE_CYCLE = "QW3"       # the cycle's number: a new value hands the counts to the generator
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
PROBE = "IX1.2"           # B1: the touch probe made contact
OVERRIDE = "IW0"          # RP1 feed override potentiometer, percent 0..150
COUNTER = {"X": "IW1", "Y": "IW2", "Z": "IW3"}
TAPE_FRAME, TAPE_COUNT, TAPE_METHOD = "IW4", "IW5", "IW6"   # tape reader: frame shown, count, method
TAPE_WORDS = tuple(f"IW{7 + k}" for k in range(9))          # kind, X, Y, Z, I, J, feed, comp, radius
TAPE_ACK = "QW4"          # the PLC: the number of the frame it stored (0: ready for a tape)
TAPE_FIELDS = len(TAPE_WORDS)
TAPE_FRAMES = 200         # the frame table's size (GVL_CNC)
_LAMP_ITEMS = tuple(LAMPS.items())
# The console face (docs/openplc.md): coils SB1, SB2, SA1, SB3 (1 = released); lamps HL1, HL2;
# the table's positions and the missed steps.
FACE = ConsoleFace(switches=tuple(CONSOLE), lamps=tuple(LAMPS.items()),
                   readouts=tuple((f"{a}", "table position, steps (16-bit, signed)") for a in AXES)
                   + (("missed", "steps missed by all drives (16-bit)"),
                      ("tape", "frames of the last tape the PLC has stored")),
                   tape=2 + TAPE_FIELDS * TAPE_FRAMES, tape_fields=TAPE_FIELDS)


@dataclass
class Axis:
    """One axis: where the table is and what its drive did."""

    steps: int = 0             # table position, steps from the machine zero
    motor: int = 0             # where the motor has turned to, steps (differs by the play)
    step_line: int = 0         # the STEP level the drive saw last
    budget: float = 1.0        # steps the drive can still take at its maximum rate
    received: int = 0          # steps commanded (edges of STEP)
    missed: int = 0            # steps lost: rate exceeded
    blocked: int = 0           # steps against a closed limit switch
    clock: float = 0.0         # time of the drive's last pulse (its rate budget)
    pending: list[tuple[float, int, int]] = field(default_factory=list)   # generator: (time, direction, cycle)


class CncTable(PlantModel):
    """The X-Y-Z table, its drives, limit switches and console."""

    outputs = ([STEP[a] for a in AXES] + [DIR[a] for a in AXES] + [ENABLE] + list(LAMPS.values())
               + [PULSES[a] for a in AXES] + [PULSE_CYCLE, TAPE_ACK])
    inputs = (list(CONSOLE.values()) + list(LIMITS.values()) + [PROBE, OVERRIDE] + list(COUNTER.values())
              + [TAPE_FRAME, TAPE_COUNT, TAPE_METHOD] + list(TAPE_WORDS))
    FACE = FACE
    CONSOLE = CONSOLE             # set_switch / press / release: plants.base.PlantModel
    NORMALLY_CLOSED = frozenset({"SB3"})
    FAULTS = {
        "slow_drive": "axis=X|Y|Z rate=steps_per_s: that drive's maximum step rate drops (missed steps)",
    }

    def __init__(self, step_mm: float = 0.01, max_rate: float = 20_000.0,
                 travel_mm: tuple[float, float] = (-150.0, 150.0), period: float = 0.001,
                 backlash: int = 0, pulse_cycle: float = 0.004) -> None:
        super().__init__()
        if step_mm <= 0 or max_rate <= 0 or period <= 0:
            raise PlantError("step_mm, max_rate and period must be positive")
        if int(backlash) < 0:
            raise PlantError("backlash must be >= 0 steps")
        self.backlash = int(backlash)
        if pulse_cycle <= 0:
            raise PlantError("pulse_cycle must be positive")
        self.pulse_cycle = float(pulse_cycle)
        self.cycle_seen = 0                             # the last pulse-cycle number taken
        self.last_cycle = 0                             # the cycle of the last generator pulse a drive got
        self.pulse_log: Optional[dict[str, list[float]]] = None   # log_pulses(): each pulse's time
        self.holes: list[tuple[float, float]] = []      # base holes' centres on the machine, mm
        self.hole_radius = 0.0
        if not travel_mm[0] < 0 < travel_mm[1]:
            raise PlantError("travel_mm must contain the machine zero: (min < 0 < max)")
        self.step_mm, self.max_rate, self.period = float(step_mm), float(max_rate), float(period)
        self.travel = (round(travel_mm[0] / step_mm), round(travel_mm[1] / step_mm))
        self.axes = {a: Axis() for a in AXES}
        self._sensed = tuple((a, self.axes[a], LIMITS[(a, -1)], LIMITS[(a, 1)], COUNTER[a]) for a in AXES)
        self._lines = tuple((a, self.axes[a], STEP[a], DIR[a]) for a in AXES)   # step(): per axis
        self.override = 100
        self.lamps = {name: 0 for name in LAMPS}
        self.enabled = False
        self.tape: Optional[list[tuple[int, ...]]] = None   # frames on the reader
        self.tape_method = 0
        self.tape_at = 0            # the frame shown (1..), 0: waiting for TAPE_ACK = 0
        self.tape_stored = 0        # frames of the last tape the PLC acknowledged
        self._tape_shown = False    # the reader's inputs need reporting (a tape, or just finished)

    # --- the plant contract -------------------------------------------------------------

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, int]:
        """Take the steps the outputs' edges command over dt seconds; report the inputs.
        (The hot path of a CNC run, once per fine cycle: kept lean, `plclab bench`.)"""
        if dt < 0:
            raise PlantError(f"dt must not be negative (got {dt})")
        get = outputs.get
        self.lamps = {name: 1 if get(loc, 0) else 0 for name, loc in _LAMP_ITEMS}
        self.enabled = bool(get(ENABLE, 0)) and bool(self.console_bits["SB3"])
        if self.tape is not None:
            self._read_tape(signed16(get(TAPE_ACK, 0)))
        cycle = get(PULSE_CYCLE, 0)
        if cycle != self.cycle_seen:
            self.cycle_seen = cycle
            self._generate(outputs)
        self.time += dt
        for a, axis, step_loc, dir_loc in self._lines:
            if axis.pending:
                self._spread(a, axis)
            line = 1 if get(step_loc, 0) else 0
            if line != axis.step_line:
                axis.step_line = line
                self._pulse(a, axis, -1 if get(dir_loc, 0) else 1, self.time)
        return self._inputs()

    def _generate(self, outputs: dict[str, int]) -> None:
        """A new cycle's counts: pulse k of n at (k + 1/2) T / n from now, after any left over."""
        t0, period = self.time, self.pulse_cycle
        for a in AXES:
            count = signed16(outputs.get(PULSES[a], 0))
            if count:
                n, direction = abs(count), 1 if count > 0 else -1
                pending = self.axes[a].pending
                interleave = bool(pending)          # a burst alone is in time order already
                seen = self.cycle_seen
                pending.extend([(t0 + (k + 0.5) * period / n, direction, seen) for k in range(n)])
                if interleave:
                    pending.sort()

    def _spread(self, a: str, axis: Axis) -> None:
        """The generator's pulses due by now go to the drive, each at its own time."""
        del axis.pending[:self._drive(a, axis, axis.pending, self.time + 1e-12)]

    def _pulse(self, a: str, axis: Axis, direction: int, t: float) -> None:
        """One step edge reaches the drive at time t."""
        self._drive(a, axis, ((t, direction, None),), t)

    def _drive(self, a: str, axis: Axis, pulses, until: float) -> int:
        """Pulses (time, direction, generator cycle or None for a step edge) reach the drive in
        time order up to `until`: each is taken, missed (rate exceeded) or blocked (limit
        switch); the table follows the motor once it crosses the play. The one model of the
        drive for both interfaces, one loop for the tens of pulses of a cycle (the hot path
        of a CNC run: `plclab bench`). Returns how many pulses were due."""
        rate = self._rate(a)
        enabled = self.enabled
        log = self.pulse_log[a] if self.pulse_log is not None else None
        lo, hi = self.travel
        play = self.backlash
        budget, clock, steps, motor = axis.budget, axis.clock, axis.steps, axis.motor
        due = 0
        for t, direction, cycle in pulses:
            if t > until:
                break
            due += 1
            if cycle is not None:
                self.last_cycle = cycle
            budget += rate * (t - clock)
            if budget > 1.0:                 # min(1.0, ...): the drive's rate budget is full
                budget = 1.0
            clock = t
            if not enabled:
                continue
            axis.received += 1
            if log is not None:
                log.append(t)
            if budget < 1.0:
                axis.missed += 1
                continue
            budget -= 1.0
            turned = motor + direction
            target = min(max(steps, turned), turned + play) if play else turned
            if not lo <= target <= hi:
                axis.blocked += 1
                continue
            motor, steps = turned, target
        axis.budget, axis.clock, axis.steps, axis.motor = budget, clock, steps, motor
        return due

    def pulses_pending(self) -> bool:
        """The pulse generator still has pulses to spread."""
        return any(axis.pending for axis in self.axes.values())

    def log_pulses(self) -> None:
        """Record the time of every pulse each drive receives (for the tests' timing checks)."""
        self.pulse_log = {a: [] for a in AXES}

    # --- the tape reader -----------------------------------------------------------------

    def load_tape(self, method: int, frames: list[tuple[int, ...]]) -> None:
        """Put a part program on the tape reader: the method (0 evaluation function, 1 DDA,
        2 digital integration) and per frame the frame table's nine values (see the module
        docstring), 16-bit signed. Replaces a tape still being read."""
        if not 1 <= len(frames) <= TAPE_FRAMES:
            raise PlantError(f"a tape holds 1..{TAPE_FRAMES} frames (got {len(frames)})")
        if method not in (0, 1, 2):
            raise PlantError(f"tape method {method}: 0 evaluation function, 1 DDA, 2 digital integration")
        for k, frame in enumerate(frames, start=1):
            if len(frame) != TAPE_FIELDS or not all(-0x8000 <= int(v) <= 0x7FFF for v in frame):
                raise PlantError(f"tape frame {k}: {TAPE_FIELDS} values of -32768..32767 expected")
            if frame[0] not in (0, 1, 2, 3) or frame[7] not in (0, 1, 2):
                raise PlantError(f"tape frame {k}: kind {frame[0]} (0..3) or correction {frame[7]} (0..2)")
        self.tape = [tuple(int(v) for v in frame) for frame in frames]
        self.tape_method = int(method)
        self.tape_at = 0
        self.tape_stored = 0
        self._tape_shown = True

    def _read_tape(self, ack: int) -> None:
        """The PLC's acknowledgement of the last scan moves the tape on."""
        assert self.tape is not None
        if self.tape_at == 0:
            if ack == 0:                 # the PLC is ready: show frame 1
                self.tape_at = 1
        elif ack == self.tape_at:
            self.tape_stored = ack
            self.tape_at += 1
            if self.tape_at > len(self.tape):
                self.tape = None         # read to its end: the reader shows 0 once more
                self.tape_at = 0

    def _tape_inputs(self, out: dict[str, int]) -> None:
        tape, at = self.tape, self.tape_at
        if tape is None or at == 0:
            out[TAPE_FRAME] = 0
            self._tape_shown = tape is not None
            return
        out[TAPE_FRAME] = at
        out[TAPE_COUNT] = len(tape)
        out[TAPE_METHOD] = self.tape_method
        for loc, value in zip(TAPE_WORDS, tape[at - 1]):
            out[loc] = value & 0xFFFF

    # --- console and set-up ----------------------------------------------------------------

    def set_backlash(self, steps: int) -> None:
        """The play of every axis's transmission, in steps (textbook 4.2.2.3)."""
        if int(steps) < 0:
            raise PlantError("backlash must be >= 0 steps")
        self.backlash = int(steps)

    def set_blank(self, holes: list[tuple[float, float]], radius: float) -> None:
        """Put a blank on the table whose base holes have these centres on the machine (mm)."""
        if radius <= 0 or not holes:
            raise PlantError("a blank needs base holes and a positive hole radius")
        self.holes = [(float(x), float(y)) for x, y in holes]
        self.hole_radius = float(radius)

    def probe_contact(self) -> bool:
        """The probe touches a base hole's wall (see the module docstring)."""
        x, y = self.position_mm("X"), self.position_mm("Y")
        r = self.hole_radius
        for cx, cy in self.holes:
            d = ((x - cx) ** 2 + (y - cy) ** 2) ** 0.5
            if d < 3.0 * r:
                return d >= r
        return False

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
        return ([unsigned16(self.axes[a].steps) for a in AXES] + [unsigned16(sum(self.missed().values()))]
                + [self.tape_stored])

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
        lo, hi = self.travel
        for a, axis, low_loc, high_loc, counter_loc in self._sensed:
            steps = axis.steps
            out[low_loc] = 1 if steps == lo else 0
            out[high_loc] = 1 if steps == hi else 0
            out[counter_loc] = steps & 0xFFFF             # unsigned16
        out[PROBE] = 1 if self.holes and self.probe_contact() else 0
        out[OVERRIDE] = self.override
        if self._tape_shown:                   # reported while a tape is read, and once after it
            self._tape_inputs(out)
        return out


def create(**params: Any) -> CncTable:
    return CncTable(**params)
