"""The thermostabilization stand (textbook section 5.3, docs/thermo.md): a Twido PLC keeping a
radiator's temperature with a heater or a fan, operated from SCADA through %MW0..%MW6.

One program, `full` (PRG_Thermo), in one 100 ms TASK. Scenarios are written like the lab
work: SCADA writes the mode, the setpoint and the manual commands into the registers (through
the Twido map, so a write the stand refuses over Modbus is refused here too), the operator
flips the disturbance toggle switch, and the trend (temperature, setpoint, heater, fan) is
checked against the goals of docs/thermo.md. No scenario may ever show a command outside its range, the
heater on with an open sensor, or an automatic-mode report (%MW1/%MW2) that differs from
what is output (check_never).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Iterable, Iterator, Optional

from plclab.modbus.maps import TwidoMap
from plclab.modbus.profiles import AUTO1, AUTO2, MANUAL, THERMO_MODES, THERMO_RULES, valid_range
from plclab.modbus.protocol import ModbusException, Table
from plclab.plants.base import signed16
from plclab.plants.thermo import FACE, ThermoParams
from plclab.scenario import ScenarioFailure, Session
from plclab.stands import twido_profile
from plclab.stands import Stand, Task, Variant, gvl_labels
from plclab.stands.base import Fault, StandSpec

POUS = ("FC_ScaleAdc", "FB_TemperatureSensor", "FB_FrequencyMeter", "FB_PIRegulator", "PRG_Thermo")

# 100 ms: a Twido periodic task (5..255 ms) that acts on a SCADA write or an open sensor
# within 0.1 s and fits 10 scans in the fan speed meter's 1 s gate; the regulators sample
# every 1 s inside it, against thermal time constants of 200..500 s.
STAND = Stand(
    name="thermo",
    title="Thermostabilization stand (Twido + SCADA)",
    gvl=("GVL_THERMO",),
    variants={
        "full": Variant("full", POUS, (Task("MainTask", "T#100ms", 1, (("Main", "PRG_Thermo"),)),),
                        "Modes 0/1/2 on %MW0, PI regulators on the heater (automatic-1) and the fan "
                        "(automatic-2)."),
    },
    register_map="twido",
)

# The register contract is GVL_THERMO plus the Twido rules of plclab.modbus.profiles; the
# scaling of the I/O is the plant model's (its defaults are the stand of docs/thermo.md).
MODE_NAMES = THERMO_MODES
FAN_MAX = valid_range(THERMO_RULES, "FAN_CTRL").high
HEATER_MAX = valid_range(THERMO_RULES, "HEATER_CTRL").high
_MODEL = ThermoParams()
ADC_FULL = _MODEL.adc_max          # counts at full scale (100.0 C); also what an open sensor reads
ADC_PER_C = _MODEL.adc_max / _MODEL.adc_span_c                  # 10 counts per C
FULL_SPEED_PPS = _MODEL.fan_max_rpm * _MODEL.pulses_per_rev / 60  # fan pulses per second at FAN_MAX
CELSIUS = "Celsius"                # the regulators' measurement, 0.1 C (an observable)
BAND = 1.0                         # C: "within +/-1 C"
FINE_BAND = 0.2                    # C: steady (two ADC steps), the integral action's work done

# The goals for the default model (docs/thermo.md, "Control program").
STEP_SETTLE_S = 300.0
STEP_OVERSHOOT_C = 2.0
DISTURBANCE_DEVIATION_C = 1.5
AUTO2_RECOVERY_S = 300.0
# A mode change is bumpless when no single step of the command in the 5 s after it is
# larger than 1/10 of its range: a regulator's ordinary move (Kp x one 0.1 C ADC step plus
# one sample of integral action) is well under that, taking over without tracking is Kp x
# the whole error (thousands of units, the command slams to a limit).
BUMP_FRACTION = 10


def labels() -> dict[str, str]:
    """Wiring labels and register names -> addresses, read from the GVL (the single source)."""
    return gvl_labels(STAND)


REGISTERS = {name: int(addr[3:]) for name, addr in labels().items() if addr.startswith("%MW")}
OBSERVABLES = {CELSIUS: "Main.Sensor.Celsius"}
FAULTS = (
    Fault("sensor_open", "temperature sensor open circuit: the ADC %IW0 reads full scale"),
    Fault("fan_stalled", "fan rotor jammed: speed 0 whatever the command, no pulses, no airflow"),
    Fault("heater_dead", "heater burnt out: no heat whatever the command"),
)


def attach_scada(s: Session) -> None:
    """`s.scada`: the SCADA client of a fresh session."""
    s.scada = Scada(s)          # type: ignore[attr-defined]


# --------------------------------------------------------------------------- SCADA and console

class Scada:
    """SCADA's side of the stand: holding registers n = %MWn through the Twido map (the same
    validation as the Modbus face: a refused write raises and changes nothing)."""

    def __init__(self, s: Session):
        self.s = s

    def _map(self) -> TwidoMap:
        return TwidoMap(self.s.plc.image, twido_profile(STAND.name))    # the image of the PLC running now

    def write(self, **registers: int) -> None:
        """Write registers by name, one request each, in order (`MODE=0, HEATER_CTRL=2000`).
        Each write is applied by the next scan, which runs before the next write."""
        self._started()
        for name, value in registers.items():
            try:
                self._map().write(Table.HOLDING_REGISTERS, REGISTERS[name], (int(value) & 0xFFFF,))
            except ModbusException as e:
                raise ScenarioFailure(f"t={self.s.now:.2f} s: SCADA write {name} (%MW{REGISTERS[name]}) "
                                      f"= {value} refused: {e}") from None
            self.s.log(f"SCADA {name}={value}")
            self.s.run(self.s.tick)

    def refused(self, name: str, value: int) -> Optional[int]:
        """Try a write that should be refused: the exception code, or None if it was accepted."""
        self._started()
        try:
            self._map().write(Table.HOLDING_REGISTERS, REGISTERS[name], (int(value) & 0xFFFF,))
        except ModbusException as e:
            self.s.log(f"SCADA {name}={value} refused ({int(e.code):02d})")
            return int(e.code)
        self.s.log(f"SCADA {name}={value}")
        self.s.run(self.s.tick)
        return None

    def _started(self) -> None:
        """SCADA talks to a running PLC: the first scan has put the registers' initial values
        (%MW6 = 40) into the image. (A write queued before it would be applied over an image
        that does not hold them yet.)"""
        if self.s.plc.ticks == 0:
            self.s.run(self.s.tick)

    def read(self, name: str) -> int:
        """A register as SCADA reads it (signed INT)."""
        self._started()
        raw = self._map().read(Table.HOLDING_REGISTERS, REGISTERS[name], 1)[0]
        return twido_profile(STAND.name).register(REGISTERS[name]).as_value(raw)


def disturbance(s: Session, on: bool) -> None:
    """Flip the console's disturbance toggle switch (%IX0.0)."""
    s.plant.set_disturbance(on)
    s.log(f"DISTURBANCE={int(on)}")


# --------------------------------------------------------------------------- measurements

def celsius(s: Session, t: Optional[float] = None) -> float:
    """The measured temperature (ADC %IW0, 0.1 C) at time t (default: now)."""
    if t is None:
        return s.value("TEMP_ADC") / ADC_PER_C
    return s.trace.value_at("TEMP_ADC", t) / ADC_PER_C


def samples(s: Session, name: str, after: float, until: Optional[float] = None) -> list[tuple[float, int]]:
    """(time, value) of `name` in [after, until]: the value in effect at `after`, then each change."""
    end = s.trace.end_s if until is None else until
    out = [(after, signed16(s.trace.value_at(name, after)))]
    out += [(t / 1e9, signed16(v)) for t, v in s.trace.changes(name) if after * 1e9 < t <= end * 1e9]
    return out


@dataclass(frozen=True)
class Response:
    """How the measured temperature answered a setpoint step or a disturbance."""

    start: float                  # s: when the step / disturbance happened
    target: float                 # C
    settle: Optional[float]       # s after start until it stays within +/-BAND (None: never)
    overshoot: float              # C beyond the target, in the direction of a step (>= 0; 0 if no step)
    deviation: float              # C: largest |temperature - target| after start
    steady: Optional[float]       # s after start until it stays within +/-FINE_BAND (None: never)
    direction: int = 0            # +1 / -1: a setpoint step up / down; 0: a disturbance

    def text(self) -> str:
        settled = f"within +/-{BAND:g} C after {self.settle:.0f} s" if self.settle is not None \
            else f"not within +/-{BAND:g} C"
        steady = f"+/-{FINE_BAND:g} C after {self.steady:.0f} s" if self.steady is not None \
            else f"not within +/-{FINE_BAND:g} C"
        if self.direction:
            return f"{settled} ({steady}), overshoot {self.overshoot:.1f} C"
        return f"{settled} ({steady}), largest deviation {self.deviation:.1f} C"


def response(s: Session, start: float, target: float, until: Optional[float] = None,
             direction: int = 0) -> Response:
    """Measure the temperature (%IW0) from `start` to `until` against `target`. `direction`
    is +1 / -1 for a setpoint step up / down (the overshoot is measured past the target in
    that direction), 0 for a disturbance (no overshoot, the deviation is what counts)."""
    pts = samples(s, "TEMP_ADC", start, until)
    errors = [(t, v / ADC_PER_C - target) for t, v in pts]
    settle = _last_entry(errors, start, BAND)
    steady = _last_entry(errors, start, FINE_BAND)
    if direction > 0:
        over = max(0.0, max(e for _t, e in errors))
    elif direction < 0:
        over = max(0.0, -min(e for _t, e in errors))
    else:
        over = 0.0
    return Response(start, target, settle, round(over, 3), round(max(abs(e) for _t, e in errors), 3), steady,
                    direction)


def _last_entry(errors: list[tuple[float, float]], start: float, band: float) -> Optional[float]:
    """Seconds after `start` from which the error stays within +/-band to the end (None: it
    ends outside the band)."""
    if abs(errors[-1][1]) > band + 1e-9:
        return None
    entry: Optional[float] = start
    for t, e in errors:
        if abs(e) > band + 1e-9:
            entry = None
        elif entry is None:
            entry = t
    return None if entry is None else entry - start


def jump(s: Session, name: str, at: float, window: float = 5.0) -> int:
    """The largest single step of a command `name` from the scan before `at` to `window`
    seconds after it: how much a mode change bumped it. A bumpless change only shows the
    regulator's ordinary moves (one sample's integral action, a few tens of units)."""
    values = [v for _t, v in samples(s, name, at - s.tick, at + window)]
    return max([abs(b - a) for a, b in zip(values, values[1:])] + [0])


# --------------------------------------------------------------------------- never

def _instants(s: Session, names: Iterable[str]) -> list[int]:
    times: set[int] = set()
    for n in names:
        times.update(t for t, _v in s.trace.changes(n))
    return sorted(times)


def check_never(s: Session) -> None:
    """What no scenario may ever show: a command outside its range, the heater on with an open
    sensor (ADC at full scale), a report in %MW1/%MW2 that differs from the commands output in
    an automatic mode, %MW3 not the ADC in whole degrees, %MW5 not 0."""
    tr = s.trace
    names = ["FAN", "HEATER", "TEMP_ADC", "MODE", "FAN_CTRL", "HEATER_CTRL", "TEMPERATURE", "RESERVED"]
    for t_ns in _instants(s, names):
        v = {n: signed16(tr.value_at_ns(n, t_ns)) for n in names}
        t = t_ns / 1e9
        if not 0 <= v["FAN"] <= FAN_MAX:
            raise ScenarioFailure(f"t={t:.2f} s: fan command {v['FAN']} outside 0..{FAN_MAX}")
        if not 0 <= v["HEATER"] <= HEATER_MAX:
            raise ScenarioFailure(f"t={t:.2f} s: heater command {v['HEATER']} outside 0..{HEATER_MAX}")
        if v["TEMP_ADC"] >= ADC_FULL and v["HEATER"] != 0:
            raise ScenarioFailure(f"t={t:.2f} s: heater {v['HEATER']} with the sensor open (ADC {v['TEMP_ADC']})")
        if v["MODE"] in (AUTO1, AUTO2) and (v["FAN_CTRL"], v["HEATER_CTRL"]) != (v["FAN"], v["HEATER"]):
            raise ScenarioFailure(f"t={t:.2f} s: {MODE_NAMES[v['MODE']]}: %MW1/%MW2 report "
                                  f"{v['FAN_CTRL']}/{v['HEATER_CTRL']}, output {v['FAN']}/{v['HEATER']}")
        whole = math.floor(min(max(v["TEMP_ADC"], 0), ADC_FULL) / ADC_PER_C + 0.5)
        if v["TEMPERATURE"] != whole:
            raise ScenarioFailure(f"t={t:.2f} s: %MW3 = {v['TEMPERATURE']}, ADC {v['TEMP_ADC']} is {whole} C")
        if v["RESERVED"] != 0:
            raise ScenarioFailure(f"t={t:.2f} s: %MW5 = {v['RESERVED']}, reserved must read 0")


# --------------------------------------------------------------------------- lab steps

def settle_at(s: Session, mode: int, setpoint: int, hold: float = 60.0, timeout: float = 1500.0) -> float:
    """Select `mode` with `setpoint` and wait until the temperature has stayed within +/-0.5 C
    of it for `hold` seconds; returns that time."""
    s.scada.write(SETPOINT=setpoint, MODE=mode)
    since = [None]

    def steady(io) -> bool:
        if abs(io.TEMP_ADC / ADC_PER_C - setpoint) > 0.5:
            since[0] = None
            return False
        if since[0] is None:
            since[0] = s.now
        return s.now - since[0] >= hold
    return s.wait_until(steady, timeout, f"{MODE_NAMES[mode]} steady at {setpoint} C")


def expect(s: Session, ok: bool, what: str) -> None:
    if not ok:
        raise ScenarioFailure(f"t={s.now:.2f} s: {what}")


def fan_speed_ok(s: Session, fan: int) -> None:
    """%MW4, pulses per second, for a fan command: 3000 rpm x 2 pulses / 60 s at 1000."""
    expected = round(fan * FULL_SPEED_PPS / FAN_MAX)
    speed = s.scada.read("FAN_SPEED")
    expect(s, abs(speed - expected) <= 1, f"fan {fan}: %MW4 = {speed} pulses/s, expected {expected}")


# --------------------------------------------------------------------------- scenarios

def manual(s: Session) -> None:
    """Manual mode: heater step to full power, fan steps to half and full speed, heater off.
    %MW3 follows the radiator, %MW4 the fan (also across the 16-bit counter's wrap, after
    65536 pulses = 655 s at full speed); the outputs are what SCADA wrote."""
    s.scada.write(MODE=MANUAL, HEATER_CTRL=HEATER_MAX)
    expect(s, s.value("HEATER") == HEATER_MAX, f"heater output {s.value('HEATER')} after %MW2 = {HEATER_MAX}")
    start = celsius(s)
    s.run(300.0)
    expect(s, celsius(s) - start > 20.0, f"heater full for 300 s: {start:.1f} -> {celsius(s):.1f} C")
    s.scada.write(FAN_CTRL=500)
    s.run(5.0)
    fan_speed_ok(s, 500)
    s.scada.write(FAN_CTRL=FAN_MAX)
    s.run(5.0)
    fan_speed_ok(s, FAN_MAX)
    full = s.now
    hot = celsius(s)
    s.run(300.0)                                   # 40 W with the fan at full settle at 42 C
    expect(s, celsius(s) < hot - 2.0, f"fan full for 300 s: {hot:.1f} -> {celsius(s):.1f} C")
    s.scada.write(HEATER_CTRL=0)
    s.run(400.0)                                   # the counter wraps at about 655 s of full speed
    expect(s, s.plant.pulse_count > 65536, f"only {s.plant.pulse_count} pulses: the counter did not wrap")
    slowest = min(v for _t, v in samples(s, "FAN_SPEED", full))
    expect(s, slowest >= 99, f"%MW4 dropped to {slowest} pulses/s at full fan speed")
    expect(s, celsius(s) < 30.0, f"heater off, fan full: still {celsius(s):.1f} C")
    s.scada.write(FAN_CTRL=0)
    s.run(10.0)                                    # the fan runs down (1 s lag), one more gate
    fan_speed_ok(s, 0)


def setpoint_step(s: Session, low: int = 40, high: int = 50, watch: float = 600.0) -> Response:
    """Automatic-1 (the heater regulates, fan off), steady at `low`; the setpoint steps to
    `high`: settling within +/-1 C under 300 s, overshoot under 2 C (docs/thermo.md goals)."""
    settle_at(s, AUTO1, low)
    s.scada.write(SETPOINT=high)
    start = s.now - s.tick
    s.run(watch)
    r = response(s, start, high, direction=1 if high > low else -1)
    s.log(f"setpoint {low} -> {high} C: {r.text()}")
    expect(s, r.settle is not None and r.settle < STEP_SETTLE_S,
           f"setpoint step {low} -> {high} C: {r.text()}; the goal is +/-1 C in under {STEP_SETTLE_S:g} s")
    expect(s, r.overshoot < STEP_OVERSHOOT_C,
           f"setpoint step {low} -> {high} C: overshoot {r.overshoot:.1f} C, the goal is under {STEP_OVERSHOOT_C:g} C")
    return r


def auto1_step(s: Session) -> None:
    """Automatic-1 setpoint step 40 -> 50 C and back to 40 C."""
    setpoint_step(s, 40, 50)
    s.scada.write(SETPOINT=40)
    start = s.now - s.tick
    s.run(600.0)
    r = response(s, start, 40, direction=-1)
    s.log(f"setpoint 50 -> 40 C: {r.text()}")
    expect(s, r.settle is not None, f"setpoint step 50 -> 40 C: {r.text()}")


def disturbance_responses(s: Session, target: float, actuator: str,
                          values: dict[bool, int]) -> Iterator[tuple[str, Response]]:
    """Switch the disturbance on, then off, 600 s each: after each, the disturbing `actuator`
    must hold its value for the switch (`values`); yields ('on' / 'off', the response)."""
    for on in (True, False):
        switch = "on" if on else "off"
        disturbance(s, on)
        start = s.now
        s.run(600.0)
        r = response(s, start, target)
        s.log(f"{actuator.lower()} disturbance {switch}: {r.text()}")
        expect(s, s.value(actuator) == values[on], f"{actuator.lower()} {s.value(actuator)} with the switch {switch}")
        yield switch, r


def auto1_disturbance(s: Session) -> None:
    """Automatic-1 steady at 40 C; the fan disturbance is switched on (fan 500): the deviation
    stays under 1.5 C and the temperature returns within +/-1 C; switched off: the same."""
    settle_at(s, AUTO1, 40)
    for switch, r in disturbance_responses(s, 40, "FAN", {True: 500, False: 0}):
        expect(s, r.deviation < DISTURBANCE_DEVIATION_C,
               f"fan disturbance {switch}: deviation {r.deviation:.1f} C, the goal is under "
               f"{DISTURBANCE_DEVIATION_C:g} C")
        expect(s, r.settle is not None, f"fan disturbance {switch}: {r.text()}")


def auto2_disturbance(s: Session) -> None:
    """Preheat to 45 C in automatic-1, change to automatic-2 (the fan regulates, heater 1000),
    steady; the heater disturbance is switched on (heater 2000): back within +/-1 C in under
    300 s; switched off: back again."""
    settle_at(s, AUTO1, 45, hold=30.0)
    settle_at(s, AUTO2, 45, hold=120.0)
    for switch, r in disturbance_responses(s, 45, "HEATER", {True: 2000, False: 1000}):
        expect(s, r.settle is not None and r.settle < AUTO2_RECOVERY_S,
               f"heater disturbance {switch}: {r.text()}; the goal is back within +/-1 C in "
               f"under {AUTO2_RECOVERY_S:g} s")


def mode_changes(s: Session) -> None:
    """Mode changes without bumps: manual -> automatic-1 -> automatic-2 -> manual ->
    automatic-2 -> automatic-1. The regulated command starts from what the actuator had (no
    jump at the change); the other one becomes its mode's disturbance value; manual mode
    keeps the last automatic commands. %MW1/%MW2 cannot be written in automatic modes."""
    s.scada.write(MODE=MANUAL, SETPOINT=45, HEATER_CTRL=1300, FAN_CTRL=300)
    s.run(400.0)
    steps = [(AUTO1, "HEATER"), (AUTO2, "FAN"), (MANUAL, None), (AUTO2, "FAN"), (AUTO1, "HEATER")]
    for mode, regulated in steps:
        before = {n: s.value(n) for n in ("FAN", "HEATER")}
        s.scada.write(MODE=mode)
        at = s.now - s.tick
        s.run(300.0)
        for name in ("FAN", "HEATER"):
            if name == regulated or mode == MANUAL:
                bump = jump(s, name, at)
                s.log(f"to {MODE_NAMES[mode]}: {name.lower()} largest step {bump} in the 5 s after the change")
                limit = HEATER_MAX if name == "HEATER" else FAN_MAX
                expect(s, bump <= limit // BUMP_FRACTION,
                       f"{name.lower()} jumped by {bump} when changing to {MODE_NAMES[mode]} (from {before[name]})")
        if mode != MANUAL:
            expect(s, s.scada.refused("HEATER_CTRL", 500) == 3, f"%MW2 written in {MODE_NAMES[mode]}")
            expect(s, s.scada.refused("FAN_CTRL", 500) == 3, f"%MW1 written in {MODE_NAMES[mode]}")


def sensor_open(s: Session) -> None:
    """Automatic-1 at 40 C; the sensor opens: heater off at once, %MW3 shows 100, the mode
    stays 1 and SCADA can still change the setpoint (to 42 C); automatic-2 runs the fan at
    full speed; back in automatic-1 the sensor is repaired: regulation resumes from heater 0
    without a jump and gets back to 42 C."""
    settle_at(s, AUTO1, 40, hold=30.0)
    s.inject("sensor_open")
    s.run(s.tick)
    expect(s, s.value("HEATER") == 0, f"heater {s.value('HEATER')} with the sensor open")
    s.run(60.0)
    expect(s, s.scada.read("TEMPERATURE") == 100, f"%MW3 = {s.scada.read('TEMPERATURE')} with the sensor open")
    expect(s, s.scada.read("MODE") == AUTO1, f"mode {s.scada.read('MODE')} after the sensor opened")
    expect(s, s.value("HEATER") == 0, f"heater {s.value('HEATER')} with the sensor open")
    s.scada.write(SETPOINT=42)
    s.run(30.0)
    expect(s, s.value("HEATER") == 0, "heater on with the sensor open after a setpoint change")
    s.scada.write(MODE=AUTO2)
    s.run(30.0)
    expect(s, s.value("HEATER") == 0 and s.value("FAN") == FAN_MAX,
           f"automatic-2 with the sensor open: heater {s.value('HEATER')}, fan {s.value('FAN')}")
    s.scada.write(MODE=AUTO1)
    s.run(10.0)
    s.clear_faults()
    at = s.now
    s.run(5.0)
    bump = jump(s, "HEATER", at)
    s.log(f"sensor back: largest heater step {bump} in the 5 s after")
    expect(s, bump <= HEATER_MAX // BUMP_FRACTION, f"heater jumped by {bump} when the sensor came back")
    s.wait_until(lambda io: abs(io.TEMP_ADC / ADC_PER_C - 42) <= BAND, 900, "back within +/-1 C of 42 C")


def demo(s: Session) -> None:
    """A short tour: manual heater step (full power for 150 s), then automatic-1 at 40 C and
    a setpoint step to 45 C."""
    s.scada.write(MODE=MANUAL, HEATER_CTRL=HEATER_MAX)
    s.run(150.0)
    s.scada.write(SETPOINT=40, MODE=AUTO1)
    s.wait_until(lambda io: abs(io.TEMP_ADC / ADC_PER_C - 40) <= 0.3, 600, "automatic-1 at 40 C")
    s.run(60.0)
    s.scada.write(SETPOINT=45)
    start = s.now - s.tick
    s.run(300.0)
    r = response(s, start, 45, direction=1)
    s.log(f"setpoint 40 -> 45 C: {r.text()}")
    expect(s, r.settle is not None and r.overshoot < STEP_OVERSHOOT_C, f"setpoint 40 -> 45 C: {r.text()}")


SCENARIOS: dict[str, Callable[[Session], None]] = {
    "demo": demo, "manual": manual, "step": auto1_step, "disturbance": auto1_disturbance,
    "auto2": auto2_disturbance, "modes": mode_changes, "sensor_open": sensor_open,
}
PLOT_SIGNALS = [CELSIUS, "SETPOINT", "HEATER", "FAN", "FAN_SPEED", "DISTURBANCE", "MODE"]


# --------------------------------------------------------------------------- timeline

TIMELINE_EVERY = 30.0          # s between rows when nothing happens


def timeline(s: Session) -> list[str]:
    """Rows: time, SCADA / console action, mode, setpoint, temperature (0.1 C from the ADC),
    %MW3, heater, fan, fan speed, disturbance. A row for every action and every 30 s."""
    tr = s.trace
    acts: dict[float, list[str]] = {}
    for a in s.actions:
        acts.setdefault(round(a.time, 6), []).append(a.text)
    times = set(acts)
    t = 0.0
    while t <= tr.end_s:
        times.add(round(t, 6))
        t += TIMELINE_EVERY
    rows = [f"{'time s':>8}  {'SCADA / console':<34} {'mode':>4} {'sp C':>4} {'temp C':>6} {'%MW3':>4} "
            f"{'heater':>6} {'fan':>5} {'pulse/s':>7} dist"]
    for t in sorted(times):
        v = {n: signed16(tr.value_at(n, t)) for n in
             ("MODE", "SETPOINT", "TEMP_ADC", "TEMPERATURE", "HEATER", "FAN", "FAN_SPEED", "DISTURBANCE")}
        text = "; ".join(acts.get(round(t, 6), []))
        rows.append(f"{t:8.1f}  {text[:34]:<34} {v['MODE']:>4} {v['SETPOINT']:>4} {v['TEMP_ADC'] / ADC_PER_C:>6.1f} "
                    f"{v['TEMPERATURE']:>4} {v['HEATER']:>6} {v['FAN']:>5} {v['FAN_SPEED']:>7} "
                    f"{'on' if v['DISTURBANCE'] else '-':>4}")
    results = [a.text for a in s.actions if ": within" in a.text or ": not within" in a.text
               or "largest" in a.text]
    if results:
        rows += ["", "measured:"] + [f"  {r}" for r in results]
    return rows


SPEC = StandSpec(
    stand=STAND, console=FACE.switches, lamps=tuple(label for label, _ in FACE.lamps), sensors=("TEMP_ADC", "FAN_COUNT"), actuators=("HEATER", "FAN"),
    faults=FAULTS, observables=OBSERVABLES, scenarios=SCENARIOS, timeline=timeline, check_never=check_never,
    plot_signals=tuple(PLOT_SIGNALS), setup=attach_scada)
session = SPEC.session
