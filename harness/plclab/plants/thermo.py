"""Thermostabilization stand (textbook section 5.3): a radiator heated by a transistor heater,
cooled by a fan, with a temperature sensor and the fan's pulse speed sensor, on a Twido PLC.

I/O map (docs/thermo.md):
  %IX0.0  disturbance toggle switch (console; set it with set_disturbance)
  %IX0.1  fan tacho pulse, raw
  %IW0    temperature ADC, 0..1000 = 0.0..100.0 C
  %IW1    fan pulse counter, 16-bit, wraps (the Twido fast counter on %I0.1)
  %QW0    fan command 0..1000
  %QW1    heater command 0..2000

Physics. The radiator is one lumped heat capacity C:
    C dT/dt = P_heater - k (T - T_ambient),   k = loss_base + loss_fan * airflow
where airflow is the fan speed as a fraction of full speed. docs/thermo.md writes the loss with
the fan *command*; we use the fan *speed* it produces, which is the same in steady state (the 1 s
fan lag is negligible against the 200..500 s thermal time constant) and makes a stalled fan
stop cooling, as a stalled fan does. The fan speed is a first-order lag on its command.

Integration. Between two steps the commands are constant, so both equations are linear with
constant coefficients and we use their exact solutions (exponentials), not explicit Euler: the
result does not depend on the tick (1 ms or 100 ms give the same curve) and stays stable for
any parameters. The thermal loss coefficient uses the fan speed averaged exactly over the step.

Pulses. The pulse count is the exact integral of the speed (integer part plus a fractional
phase carried between steps), so the counter %IW1 is right in the long run whatever dt is. The
raw bit %IX0.1 is high during the second half of each pulse period and the counter steps on its
rising edge. A 3000 rpm fan gives 100 pulses/s (an edge every 5 ms): with a longer tick the raw
bit cannot show every edge and a PLC counting edges of %IX0.1 in its scan would undercount.
As on the real stand, the fast counter %IW1, not the raw bit, is the reliable speed source.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any

from plclab.plants.base import ConsoleFace, PlantError, PlantModel, signed16, unsigned16


@dataclass(frozen=True)
class ThermoParams:
    """Model parameters; the defaults are the stand of docs/thermo.md."""

    ambient: float = 22.0              # C
    start_temperature: float | None = None   # C at power-up; None = ambient (the documented power-up)
    heat_capacity: float = 400.0       # J/K
    heater_max_w: float = 40.0         # W at full heater command
    heater_full_scale: int = 2000      # heater command giving heater_max_w
    loss_base: float = 0.8             # W/K with the fan stopped
    loss_fan: float = 1.2              # W/K added at full fan speed
    fan_full_scale: int = 1000         # fan command giving fan_max_rpm
    fan_max_rpm: float = 3000.0
    fan_lag: float = 1.0               # s, first-order time constant of the fan speed (0 = none)
    pulses_per_rev: int = 2
    adc_max: int = 1000                # ADC full scale (also what an open sensor reads)
    adc_span_c: float = 100.0          # temperature at ADC full scale; 0 counts = 0 C
    period: float = 0.01               # s between steps when run on its own (PSM)

    def __post_init__(self) -> None:
        positive = ("heat_capacity", "heater_full_scale", "fan_full_scale", "fan_max_rpm",
                    "pulses_per_rev", "adc_max", "adc_span_c", "period")
        for name in positive:
            if not getattr(self, name) > 0:
                raise PlantError(f"thermo: {name} must be > 0, got {getattr(self, name)!r}")
        for name in ("heater_max_w", "loss_base", "loss_fan", "fan_lag"):
            if not getattr(self, name) >= 0:
                raise PlantError(f"thermo: {name} must be >= 0, got {getattr(self, name)!r}")


def _phi(x: float) -> float:
    """(1 - e^-x) / x, the exact average of a decaying exponential over a step; 1 at x = 0.

    Written with expm1 so that tiny steps (1 ms against 500 s) lose no precision.
    """
    if x == 0.0:
        return 1.0
    if math.isinf(x):
        return 0.0
    return -math.expm1(-x) / x


# The console face (docs/openplc.md): the disturbance switch; no lamp; the true temperature.
FACE = ConsoleFace(switches=("DISTURBANCE",), lamps=(),
                   readouts=(("temperature", "tenths of a degree Celsius"),))


class ThermoPlant(PlantModel):
    """The thermostabilization stand's radiator, heater and fan; see the module docstring."""

    outputs = ["QW0", "QW1"]
    inputs = ["IX0.0", "IX0.1", "IW0", "IW1"]
    FACE = FACE
    FAULTS = {
        "sensor_open": "temperature sensor open circuit: the ADC %IW0 reads full scale",
        "fan_stalled": "fan rotor jammed: speed 0 whatever the command, no pulses, no airflow",
        "heater_dead": "heater burnt out: no heat whatever the command",
    }

    def __init__(self, params: ThermoParams | None = None) -> None:
        super().__init__()
        self.params = p = params or ThermoParams()
        self.period = p.period
        self.temperature = p.ambient if p.start_temperature is None else float(p.start_temperature)
        self.fan_rpm = 0.0
        self.fan_command = 0           # clamped commands last received
        self.heater_command = 0
        self.disturbance = False       # the console toggle switch, %IX0.0
        self._pulses = 0               # whole pulse periods completed
        self._phase = 0.0              # fraction of the current pulse period, 0 <= phase < 1

    # --- console -------------------------------------------------------------------------

    def set_disturbance(self, on: bool) -> None:
        """Flip the console's disturbance toggle switch (%IX0.0, seen from the next step).

        The plant owns it so that it is the single writer of every PLC input.
        """
        self.disturbance = bool(on)

    def set_switch(self, name: str, value: Any) -> None:
        """The console API every plant has: the only switch here is DISTURBANCE (%IX0.0)."""
        if name.strip().lstrip("%").upper() not in ("DISTURBANCE", "IX0.0"):
            raise PlantError(f"unknown console switch {name!r} (the thermo stand has DISTURBANCE)")
        self.set_disturbance(bool(int(value)))

    def readouts(self) -> list[int]:
        """The radiator's true temperature in tenths of a degree (the ADC may read otherwise)."""
        return [unsigned16(math.floor(self.temperature * 10 + 0.5))]

    # --- derived quantities --------------------------------------------------------------

    @property
    def heater_w(self) -> float:
        """Heat the heater gives now (0 if it is dead)."""
        if "heater_dead" in self.faults:
            return 0.0
        p = self.params
        return p.heater_max_w * self.heater_command / p.heater_full_scale

    @property
    def fan_target_rpm(self) -> float:
        """The speed the fan is heading to (0 when stalled)."""
        if "fan_stalled" in self.faults:
            return 0.0
        p = self.params
        return p.fan_max_rpm * self.fan_command / p.fan_full_scale

    def loss_w_per_k(self, rpm: float | None = None) -> float:
        """Loss coefficient to ambient at a fan speed (default: the current one)."""
        p = self.params
        rpm = self.fan_rpm if rpm is None else rpm
        return p.loss_base + p.loss_fan * rpm / p.fan_max_rpm

    @property
    def pulse_count(self) -> int:
        """Rising edges of the tacho since power-up (unwrapped; %IW1 is this modulo 2^16)."""
        return self._pulses + (1 if self._phase >= 0.5 else 0)

    # --- stepping ------------------------------------------------------------------------

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, int]:
        """Advance dt seconds with the commands in `outputs` held over the step; return inputs.

        dt = 0 only takes the commands and reports the state. Missing outputs read 0; commands
        are the PLC's INT values (negative ones clamp to 0, over-range ones to full scale).
        """
        if not dt >= 0 or math.isinf(dt):
            raise PlantError(f"thermo: dt must be a finite number >= 0, got {dt!r}")
        p = self.params
        self.fan_command = _clamp_command(outputs.get("QW0", 0), p.fan_full_scale)
        self.heater_command = _clamp_command(outputs.get("QW1", 0), p.heater_full_scale)
        if "fan_stalled" in self.faults:
            self.fan_rpm = 0.0         # a jammed rotor stops at once
        if dt > 0:
            self._advance(dt)
            self.time += dt
        return self._inputs()

    def _advance(self, dt: float) -> None:
        p = self.params
        # Fan: s(t) = target + (s0 - target) e^(-t/lag); its exact mean over the step drives
        # both the airflow and the pulses.
        target = self.fan_target_rpm
        x = math.inf if p.fan_lag == 0 else dt / p.fan_lag
        gap = self.fan_rpm - target
        mean_rpm = target + gap * _phi(x)
        self.fan_rpm = target + gap * math.exp(-x)
        # Radiator: exact solution of C dT/dt = P - k (T - Ta) with k and P constant.
        k = self.loss_w_per_k(mean_rpm)
        drive = self.heater_w - k * (self.temperature - p.ambient)
        self.temperature += drive * dt / p.heat_capacity * _phi(k * dt / p.heat_capacity)
        # Tacho: integrate the pulses, keeping the fraction for the next step.
        phase = self._phase + mean_rpm / 60.0 * p.pulses_per_rev * dt
        whole = math.floor(phase)
        self._pulses += whole
        self._phase = phase - whole

    def _inputs(self) -> dict[str, int]:
        return {
            "IX0.0": int(self.disturbance),
            "IX0.1": 1 if self._phase >= 0.5 else 0,
            "IW0": self.adc_reading(),
            "IW1": self.pulse_count & 0xFFFF,
        }

    def adc_reading(self) -> int:
        """The temperature ADC in counts, rounded and clamped to 0..full scale."""
        p = self.params
        if "sensor_open" in self.faults:
            return p.adc_max
        counts = math.floor(self.temperature * p.adc_max / p.adc_span_c + 0.5)
        return min(max(counts, 0), p.adc_max)

    def snapshot(self) -> dict[str, Any]:
        """The physical state in engineering units, for trends and reports."""
        return {
            "time_s": self.time,
            "temperature_c": self.temperature,
            "fan_rpm": self.fan_rpm,
            "fan_command": self.fan_command,
            "heater_command": self.heater_command,
            "heater_w": self.heater_w,
            "loss_w_per_k": self.loss_w_per_k(),
            "pulse_count": self.pulse_count,
            "disturbance": self.disturbance,
            "faults": sorted(self.faults),
        }


def _clamp_command(raw: int, full_scale: int) -> int:
    """A raw output word as the command the DAC can give: the PLC's INT clamped to 0..full."""
    return min(max(signed16(int(raw)), 0), full_scale)


PARAMETERS = tuple(f.name for f in fields(ThermoParams))


def create(**params: Any) -> ThermoPlant:
    """A thermo stand with default parameters, overridden by keyword (see ThermoParams)."""
    unknown = sorted(set(params) - set(PARAMETERS))
    if unknown:
        raise PlantError(f"thermo: unknown parameter(s) {', '.join(unknown)}; "
                         f"known: {', '.join(PARAMETERS)}")
    return ThermoPlant(ThermoParams(**params))


def default_params() -> dict[str, Any]:
    """The default parameters as a plain dict (for help texts and reports)."""
    return asdict(ThermoParams())
