"""TUR-10 five-axis electromechanical robot, positional control: the plant model.

The contract is docs/tur10.md (plant, sensor bus, I/O map, Fig. 6-7 of the textbook).
Each link is a DC motor-reducer under an analog speed loop (ARS with tacho feedback): the PLC
writes a speed reference to a DAC word and the link follows it as a first-order lag. Link
positions come back as absolute 15-bit codes on ONE shared sensor bus; the PLC selects a sensor
by driving its read-enable output OFF (active low, textbook Table 1 codes written to QB0).

Timing of the bus: the plant returns the code for the enables it is given in the same step.
The harness steps the plant between scans (outputs of scan n -> plant step -> inputs of scan
n+1), so a sensor selected in one scan is read by the next one: the one scan of latency that
docs/tur10.md describes, exactly as on the S7-200 (outputs written at the end of a scan, inputs sampled
at the start of the next). Adding a delay inside the plant would make it two scans.

The console (SA1..SA7, SB1, the spare I1.5) is part of this plant too, so that one object is
the single writer of every %IX of the stand; scenarios operate it with set_switch / press /
release / jog. The reset indicator (Q1.0) is read back for the snapshot.

Events (base.PlantEvent kinds): 'overvoltage' (DAC code beyond the ARS limit: the drive trips
and ignores its reference until reset_trip), 'bus_contention' (two or more sensors enabled),
'collision' (a link driven into a mechanical stop), 'out_of_range' (a link left the working
range: a warning, the hardware does not care), 'fault_injected'.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Iterable

from plclab.plants.base import ConsoleFace, PlantError, PlantModel, signed16

AXES = (1, 2, 3, 4, 5)
LINKS = {1: "shoulder", 2: "raceme rotation", 3: "raceme inclination",
         4: "platform rotation", 5: "hand"}
SELECT_CODES = {1: 15, 2: 23, 3: 27, 4: 29, 5: 30}     # textbook Table 1, written to QB0
ENABLE = {k: f"QX0.{5 - k}" for k in AXES}             # sensor 1 <- Q0.4 ... sensor 5 <- Q0.0
DAC = {k: f"QW{k - 1}" for k in AXES}                  # AQW0, AQW2 ... AQW8 -> %QW0..%QW4
RESET_LAMP = "QX1.0"
FULL_SCALE = 0x7FFF                                    # 15-bit code; also the idle bus
# Sensor bit n (n = 1 is the LSB) -> input: bits 1..8 on I3.0..I3.7, bits 9..15 on I2.0..I2.6.
BUS_BITS = tuple(f"IX3.{i}" for i in range(8)) + tuple(f"IX2.{i}" for i in range(7))
CONSOLE = {
    "SA1_FWD": "IX0.0", "SA1_BWD": "IX0.1", "SA2_FWD": "IX0.2", "SA2_BWD": "IX0.3",
    "SA3_FWD": "IX0.4", "SA3_BWD": "IX0.5", "SA4_FWD": "IX0.6", "SA4_BWD": "IX0.7",
    "SA5_FWD": "IX1.0", "SA5_BWD": "IX1.1",
    "SA6": "IX1.2",      # low speed (1 = low)
    "SB1": "IX1.3",      # start / stop / save / reset
    "SA7": "IX1.4",      # mode: 0 manual, 1 automatic
    "I15": "IX1.5",      # spare input of Tasks 2 and 3
}
# The console face (docs/openplc.md): coils in CONSOLE's order; lamp HL1 (the reset
# indicator Q1.0); the true link positions in sensor codes.
FACE = ConsoleFace(switches=tuple(CONSOLE), lamps=(("HL1", RESET_LAMP),),
                   readouts=tuple((f"link{k}", f"{LINKS[k]} position, codes 0..{FULL_SCALE}")
                                  for k in AXES))

# Stepping runs every scan of every grading: its tables are made once here, so that a step
# builds nothing but the inputs it returns.
_OUTPUT_LOCS = tuple([ENABLE[k] for k in AXES] + [RESET_LAMP] + [DAC[k] for k in AXES])   # Tur10.outputs
_INPUT_LOCS = tuple(CONSOLE.values()) + BUS_BITS                                          # Tur10.inputs
_SELECTED: dict[tuple[Any, ...], tuple[int, ...]] = {}     # enable outputs -> the sensors they select
# Below this speed (codes/s) a link told to stop is at rest: what is left of its coasting
# (speed x tau, 5e-5 codes) is added to its position at once. The exact lag only tends to zero
# (a float takes some 35 s to get there), and a link that keeps "moving" by 1e-300 codes costs
# its step every scan of every grading.
REST_SPEED = 1e-3
_CONSOLE_NAMES = tuple(CONSOLE)
# The bus bits of a code, low byte (I3.0..I3.7) and high seven bits (I2.0..I2.6) looked up
_LOW_BITS = tuple(tuple((v >> b) & 1 for b in range(8)) for v in range(256))
_HIGH_BITS = tuple(tuple((v >> b) & 1 for b in range(7)) for v in range(128))


@dataclass(slots=True)
class Drive:
    """One link with its drive: the state the ARS and the mechanics carry between steps."""

    position: float            # codes
    speed: float = 0.0         # codes/s
    reference: int = 0         # DAC code as the PLC wrote it (signed)
    tripped: bool = False      # overvoltage protection: ignores the reference until reset
    at_stop: bool = False      # resting against a mechanical stop
    in_range: bool = True      # inside the working range


class Tur10(PlantModel):
    """The TUR-10 stand: five drives, the multiplexed sensor bus and the control console."""

    outputs = list(_OUTPUT_LOCS)
    inputs = list(_INPUT_LOCS)
    FACE = FACE
    CONSOLE = CONSOLE             # set_switch / press / release: plants.base.PlantModel
    FAULTS = {
        "dead_sensor": "axis=k [value=code]: sensor k reads a constant (default: its code now)",
        "stuck_drive": "axis=k: link k does not move whatever its reference",
        "slow_drive": "axis=k factor=f: link k runs at f times the normal speed",
    }

    def __init__(self, gain: float = 4.0, tau: float = 0.05,
                 start: float | Iterable[float] = 16000,
                 working: tuple[float, float] = (2000, 30000),
                 stops: tuple[float, float] = (1000, 31000),
                 dac_limit: int = 1500, period: float = 0.01) -> None:
        super().__init__()
        starts = [start] * 5 if isinstance(start, (int, float)) else list(start)
        if tau <= 0 or period <= 0:
            raise PlantError("tau and period must be positive")
        if not 0 <= stops[0] < working[0] < working[1] < stops[1] <= FULL_SCALE:
            raise PlantError(f"need 0 <= stops[0] < working range < stops[1] <= {FULL_SCALE}")
        if len(starts) != 5 or not all(stops[0] <= s <= stops[1] for s in starts):
            raise PlantError("start: one position (or five) between the stops")
        self.gain, self.tau, self.period = float(gain), float(tau), float(period)
        self.working, self.stops, self.dac_limit = tuple(working), tuple(stops), int(dac_limit)
        self.drives = {k: Drive(float(s), in_range=working[0] <= s <= working[1])
                       for k, s in zip(AXES, starts)}
        self.reset_indicator = 0
        self.selected: tuple[int, ...] = ()
        self.bus = FULL_SCALE
        self._contention: tuple[int, ...] = ()
        self._lag: tuple[float, float, float] = (-1.0, -1.0, 0.0)   # (dt, tau, exp(-dt / tau)) last used
        self._console_seen = -1                        # console_changes when _console_values was made
        self._console_values: tuple[int, ...] = ()
        # counts the steps that changed a link (reference, trip, position, speed) or the reset
        # lamp: what the stand shows stays as it was while this and the console stay the same
        # (the sensor selection and the bus may change: a grader's probe need not look again)
        self.state_changes = 0
        self._last_outputs: tuple[Any, ...] | None = None   # of the last step of time
        self._faults_seen = 0                          # fault_changes at that step
        self._dacs: tuple[Any, ...] | None = None      # the DAC outputs the references were read from

    # --- the plant contract -------------------------------------------------------------

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, int]:
        """Advance dt seconds under the PLC's outputs; return every input of the stand.

        dt = 0 changes nothing (no time, motion or events): it reports the current state.
        Conditions of the outputs (overvoltage, contention) are stamped at the start of the
        step, when the PLC published them; collisions at its end, when they are seen.
        """
        return dict(zip(_INPUT_LOCS, self.step_values(tuple(map(outputs.get, _OUTPUT_LOCS)), dt)))

    def step_values(self, outputs: tuple[Any, ...], dt: float) -> tuple[int, ...]:
        """`step` on values in order (the plant contract's optional form, which the closed loop
        uses): `outputs` the values of self.outputs (None: not given), the inputs returned as
        the values of self.inputs, raw."""
        if dt < 0:
            raise PlantError(f"dt must not be negative (got {dt})")
        moved = False                                     # anything but the time, bus and selection
        reset = 1 if outputs[5] else 0
        if reset != self.reset_indicator:
            self.reset_indicator = reset
            moved = True
        enables = outputs[:5]
        selected = _SELECTED.get(enables)
        if selected is None:                               # each pattern worked out once
            selected = _SELECTED[enables] = tuple([k for k, on in zip(AXES, enables) if not on])
        self.selected = selected
        if dt > 0:
            limit = self.dac_limit
            faults = self.faults
            dacs = outputs[6:]
            if dacs != self._dacs:                         # the references as last step: as they are
                self._dacs = dacs
                moved = True
                for d, raw in zip(self.drives.values(), dacs):
                    raw = (raw or 0) & 0xFFFF               # the signed INT the PLC wrote
                    d.reference = raw - 0x10000 if raw & 0x8000 else raw
            for k, d in self.drives.items():
                reference = d.reference
                if (reference > limit or reference < -limit) and not d.tripped:
                    self._check_overvoltage(k, d)
                    moved = True
            if len(selected) > 1 or self._contention:
                self._check_contention()
            self.time += dt
            for k, d in self.drives.items():
                # a link at rest and told to stay, without a fault, does not move (most
                # links, most ticks): _move would return at once
                if faults or d.speed != 0.0 or not (d.tripped or d.reference == 0):
                    x, v = d.position, d.speed
                    self._move(k, d, dt)
                    moved = moved or d.position != x or d.speed != v
        if moved:
            self.state_changes += 1
        bus = self.bus = self._bus_value(selected)
        self._last_outputs = outputs if dt > 0 else None
        self._faults_seen = self.fault_changes
        if self.console_changes != self._console_seen:     # the console's part again where a contact changed
            self._console_seen = self.console_changes
            self._console_values = tuple(map(self.console_bits.__getitem__, _CONSOLE_NAMES))
        return self._console_values + _LOW_BITS[bus & 0xFF] + _HIGH_BITS[(bus >> 8) & 0x7F]

    def idle(self, outputs: tuple[int, ...], dt: float) -> bool:
        """The plant contract's optional shortcut (plclab.runtime.plantio): would a step of dt
        under `outputs` (the values of self.outputs, in order) change nothing but the time?
        So it is where the outputs are those of the last step (the same sensors on the bus,
        the same references: no new trip or contention), the faults are those of that step
        (each acts the same at every step), the console is as that step saw it and every link
        stands still and is told to (a link with a tripped or stuck drive stays). Then the time
        has moved on by dt and the answer is True."""
        if (self._last_outputs != outputs or dt <= 0 or self.fault_changes != self._faults_seen
                or self.console_changes != self._console_seen):
            return False
        stuck = self.faults["stuck_drive"]["axis"] if "stuck_drive" in self.faults else None
        for k, d in self.drives.items():
            if d.speed != 0.0 or not (d.tripped or d.reference == 0 or k == stuck):
                return False
        self.time += dt
        return True

    # --- console: the operator's side of the inputs -----------------------------------------

    def jog(self, axis: int, direction: int) -> None:
        """Hold SAk forward (+1) or backward (-1), or release both (0)."""
        k = _axis(axis)
        self.set_switch(f"SA{k}_FWD", direction > 0)
        self.set_switch(f"SA{k}_BWD", direction < 0)

    def readouts(self) -> list[int]:
        """The five true link positions in codes (what a sensor would read, fault or not)."""
        return [min(max(math.floor(self.drives[k].position), 0), FULL_SCALE) for k in AXES]

    @property
    def console(self) -> dict[str, int]:
        """Console inputs by label (a copy)."""
        return dict(self.console_bits)

    # --- faults and maintenance -----------------------------------------------------------

    def inject(self, fault: str, **params: Any) -> None:
        """Inject 'dead_sensor' (axis, value), 'stuck_drive' (axis), 'slow_drive' (axis, factor)."""
        if fault in self.FAULTS:
            params["axis"] = _axis(params.get("axis"))
            if fault == "dead_sensor":
                params.setdefault("value", self._code(params["axis"]))
                if not 0 <= int(params["value"]) <= FULL_SCALE:
                    raise PlantError(f"dead_sensor value must be 0..{FULL_SCALE}")
            if fault == "slow_drive":
                factor = params.get("factor")
                if not isinstance(factor, (int, float)) or factor < 0:
                    raise PlantError("slow_drive needs factor >= 0 (e.g. factor=0.5)")
        super().inject(fault, **params)

    def reset_trip(self, axis: int | None = None) -> None:
        """Reset the overvoltage trip of one drive (or all): it follows its reference again."""
        for k in AXES if axis is None else (_axis(axis),):
            self.drives[k].tripped = False
        self.state_changes += 1

    def snapshot(self) -> dict[str, Any]:
        """Flat state for timelines and plots: posK, codeK, speedK, refK, trippedK, bus..."""
        snap: dict[str, Any] = {"time": self.time}
        for k, d in self.drives.items():
            snap.update({f"pos{k}": d.position, f"code{k}": self._code(k), f"speed{k}": d.speed,
                         f"ref{k}": d.reference, f"tripped{k}": d.tripped,
                         f"at_stop{k}": d.at_stop})
        snap.update(bus=self.bus, selected=self.selected, reset_indicator=self.reset_indicator)
        snap.update(self.console_bits)
        return snap

    # --- internals ------------------------------------------------------------------------

    def _check_overvoltage(self, k: int, d: Drive) -> None:
        """The DAC's full scale exceeds what the ARS takes: beyond the limit the drive trips."""
        if abs(d.reference) > self.dac_limit and not d.tripped:
            d.tripped = True
            self.event("overvoltage", f"drive {k} ({LINKS[k]}): DAC code {d.reference} "
                                      f"beyond +/-{self.dac_limit}; drive tripped")

    def _check_contention(self) -> None:
        """Two sensors driving the bus at once: one event each time a new such set appears."""
        sel = self.selected
        if len(sel) > 1 and sel != self._contention:
            self.event("bus_contention", f"sensors {', '.join(map(str, sel))} enabled together "
                                         f"({', '.join('Q' + ENABLE[k][2:] for k in sel)} OFF); "
                                         f"bus reads {self._bus_value(sel)}")
        self._contention = sel if len(sel) > 1 else ()

    def _move(self, k: int, d: Drive, dt: float) -> None:
        """Exact solution of the first-order speed lag over dt (stable for any dt), then stops."""
        faults = self.faults
        if faults:
            if "stuck_drive" in faults and faults["stuck_drive"]["axis"] == k:
                d.speed = 0.0
                return
            factor = faults["slow_drive"]["factor"] \
                if "slow_drive" in faults and faults["slow_drive"]["axis"] == k else 1.0
        else:
            factor = 1.0
        target = 0.0 if d.tripped else d.reference * self.gain * factor
        if target == 0.0 and d.speed == 0.0:
            return                      # at rest and told to stay: nothing moves (most links, most ticks)
        x0, v0, tau = d.position, d.speed, self.tau
        if self._lag[0] == dt and self._lag[1] == tau:
            decay = self._lag[2]        # the same tick as last time (every tick but the first)
        else:
            decay = math.exp(-dt / tau)
            self._lag = (dt, tau, decay)
        x1 = x0 + target * dt + (v0 - target) * tau * (1.0 - decay)
        v1 = target + (v0 - target) * decay
        low, high = self.stops
        above = x0 > high or x1 > high  # where the link was over the step: both ends, and
        below = x0 < low or x1 < low
        if v0 * target < 0:             # where the speed reverses: the link turns where it reaches zero
            t_turn = tau * math.log((target - v0) / target)
            if t_turn < dt:
                turn = x0 + v0 * tau + target * t_turn
                above = above or turn > high
                below = below or turn < low
        if above or below:
            d.position = high if above else low
            d.speed = 0.0
            if not d.at_stop:
                self.event("collision", f"link {k} ({LINKS[k]}) hit the mechanical stop "
                                        f"at {d.position:g}")
            d.at_stop = True
        else:
            if target == 0.0 and -REST_SPEED < v1 < REST_SPEED:
                x1, v1 = x1 + v1 * tau, 0.0     # where the coasting ends (the lag's limit)
            d.position, d.speed = x1, v1
            d.at_stop = d.at_stop and x1 in (low, high)
        in_range = self.working[0] <= d.position <= self.working[1]
        if d.in_range and not in_range:
            self.event("out_of_range", f"link {k} ({LINKS[k]}) left the working range "
                                       f"{self.working[0]:g}..{self.working[1]:g} "
                                       f"at {d.position:.0f}")
        d.in_range = in_range

    def _code(self, k: int) -> int:
        """What sensor k puts on the bus: its absolute code, or a dead sensor's constant."""
        dead = self.faults.get("dead_sensor")
        if dead is not None and dead["axis"] == k:
            return int(dead["value"])
        return min(max(math.floor(self.drives[k].position), 0), FULL_SCALE)

    def _bus_value(self, selected: tuple[int, ...]) -> int:
        """Pulled up to all ones; every enabled sensor pulls its zero bits down (wired AND)."""
        value = FULL_SCALE
        for k in selected:
            value &= self._code(k)
        return value


def _axis(axis: Any) -> int:
    """Axis number 1..5 (sensor / drive number of Table 1), or a link name from LINKS."""
    for k, name in LINKS.items():
        if axis == name:
            return k
    if isinstance(axis, int) and not isinstance(axis, bool) and axis in AXES:
        return axis
    raise PlantError(f"axis must be 1..5 or a link name ({', '.join(LINKS.values())}), "
                     f"got {axis!r}")


def create(**params: Any) -> Tur10:
    """The TUR-10 plant with the defaults of docs/tur10.md; keywords override (see Tur10.__init__)."""
    return Tur10(**params)
