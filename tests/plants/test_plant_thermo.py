"""The thermostabilization stand's plant model (docs/thermo.md, textbook section 5.3).

Numbers come from the defaults of docs/thermo.md: 40 W heater, 400 J/K, loss 0.8 W/K + 1.2 W/K at full fan,
so full heat settles at 72 C with the fan off (time constant 500 s) and 42 C with it full
(200 s); the fan reaches 3000 rpm with a 1 s lag and gives 2 pulses per revolution.
"""
from __future__ import annotations

import math

import pytest

from plclab.plants import make_plant
from plclab.plants.base import PlantError
from plclab.plants.thermo import ThermoPlant, create

FAN_FULL, HEATER_FULL = 1000, 2000


def cmd(fan: int = 0, heater: int = 0) -> dict[str, int]:
    return {"QW0": fan & 0xFFFF, "QW1": heater & 0xFFFF}


def run(plant: ThermoPlant, seconds: float, dt: float, **commands: int) -> dict[str, int]:
    """Hold the commands for `seconds` of plant time in ticks of dt; return the last inputs."""
    steps = round(seconds / dt)
    inputs = plant.step(cmd(**commands), 0.0)
    for _ in range(steps):
        inputs = plant.step(cmd(**commands), dt)
    return inputs


def heating_curve(t: float, ambient: float, watts: float, k: float, capacity: float) -> float:
    return ambient + watts / k * (1 - math.exp(-t * k / capacity))


def fan_pulses(t: float, rpm: float, lag: float = 1.0, per_rev: int = 2) -> float:
    """Exact pulse count of a fan started from rest at t = 0 towards rpm."""
    return per_rev * rpm / 60 * (t - lag * (1 - math.exp(-t / lag)))


# --- power-up and the contract -----------------------------------------------------------

def test_power_up_reads_ambient_with_everything_off():
    plant = make_plant("thermo")
    assert plant.step({}, 0.0) == {"IX0.0": 0, "IX0.1": 0, "IW0": 220, "IW1": 0}
    snap = plant.snapshot()
    assert snap["temperature_c"] == 22.0 and snap["fan_rpm"] == 0.0 and snap["heater_w"] == 0.0
    assert snap["faults"] == [] and snap["disturbance"] is False


def test_declares_the_io_map_of_the_spec():
    plant = create()
    assert sorted(plant.outputs) == ["QW0", "QW1"]
    assert sorted(plant.inputs) == ["IW0", "IW1", "IX0.0", "IX0.1"]
    assert set(plant.step(cmd(), 0.1)) == set(plant.inputs)
    assert plant.period > 0


def test_nothing_moves_with_everything_off():
    plant = create()
    inputs = run(plant, 100.0, 0.1)
    assert inputs == {"IX0.0": 0, "IX0.1": 0, "IW0": 220, "IW1": 0}
    assert plant.temperature == pytest.approx(22.0, abs=1e-9)


def test_dt_zero_only_reports_and_takes_the_commands():
    plant = create()
    run(plant, 50.0, 0.1, fan=FAN_FULL, heater=HEATER_FULL)
    before = plant.snapshot()
    inputs = plant.step(cmd(fan=0, heater=0), 0.0)
    after = plant.snapshot()
    assert after["time_s"] == before["time_s"]
    assert after["temperature_c"] == before["temperature_c"]
    assert after["fan_rpm"] == before["fan_rpm"]
    assert after["heater_w"] == 0.0                       # the new command is taken
    assert inputs == plant.step(cmd(), 0.0)


def test_negative_dt_is_refused():
    with pytest.raises(PlantError, match="dt"):
        create().step(cmd(), -0.01)


def test_parameters_are_configurable_and_checked():
    plant = create(ambient=30.0, heater_max_w=20.0, loss_base=1.0, loss_fan=0.0)
    run(plant, 5000.0, 0.5, heater=HEATER_FULL)
    assert plant.temperature == pytest.approx(30.0 + 20.0 / 1.0, abs=0.01)
    with pytest.raises(PlantError, match="unknown parameter"):
        create(heat_capacty=400.0)
    with pytest.raises(PlantError, match="heat_capacity"):
        create(heat_capacity=0.0)


# --- heat balance ----------------------------------------------------------------------

def test_full_heat_with_the_fan_off_settles_at_72_c():
    plant = create()
    inputs = run(plant, 6000.0, 0.1, heater=HEATER_FULL)
    assert plant.temperature == pytest.approx(72.0, abs=0.5)
    assert inputs["IW0"] == pytest.approx(720, abs=5)


def test_full_heat_with_the_fan_full_settles_at_42_c():
    plant = create()
    inputs = run(plant, 3000.0, 0.1, fan=FAN_FULL, heater=HEATER_FULL)
    assert plant.temperature == pytest.approx(42.0, abs=0.5)
    assert inputs["IW0"] == pytest.approx(420, abs=5)


def test_heater_power_is_proportional_to_its_command():
    plant = create()
    run(plant, 6000.0, 0.5, heater=HEATER_FULL // 2)     # 20 W, fan off
    assert plant.snapshot()["heater_w"] == pytest.approx(20.0)
    assert plant.temperature == pytest.approx(22.0 + 20.0 / 0.8, abs=0.5)


def test_heating_curve_has_the_time_constant_c_over_loss():
    """Fan off: tau = 400 / 0.8 = 500 s, 63 % of the 50 C rise after 500 s."""
    plant = create()
    run(plant, 500.0, 0.1, heater=HEATER_FULL)
    assert plant.temperature == pytest.approx(22.0 + 50.0 * (1 - math.exp(-1)), abs=0.02)
    run(plant, 500.0, 0.1, heater=HEATER_FULL)
    assert plant.temperature == pytest.approx(heating_curve(1000.0, 22.0, 40.0, 0.8, 400.0), abs=0.02)


def test_fan_full_shortens_the_time_constant_to_200_s():
    plant = create()
    run(plant, 200.0, 0.1, fan=FAN_FULL, heater=HEATER_FULL)
    # The fan's 1 s start-up costs a little airflow: well inside the tolerance.
    assert plant.temperature == pytest.approx(heating_curve(200.0, 22.0, 40.0, 2.0, 400.0), abs=0.05)


def test_cooling_back_to_ambient_when_the_heater_stops():
    plant = create()
    run(plant, 3000.0, 0.5, heater=HEATER_FULL)
    hot = plant.temperature
    run(plant, 200.0, 0.1, fan=FAN_FULL)
    # No heat: T - Ta decays as exp(-integral of k / C); the fan's 1 s lag costs 1 s of airflow.
    airflow_seconds = 200.0 - 1.0 * (1 - math.exp(-200.0))
    rise = (hot - 22.0) * math.exp(-(0.8 * 200.0 + 1.2 * airflow_seconds) / 400.0)
    assert plant.temperature == pytest.approx(22.0 + rise, abs=0.001)


def test_tick_from_1_ms_to_100_ms_gives_the_same_temperature():
    """A 600 s lab run with heater and fan changes, at 1 ms and at 100 ms ticks."""
    profile = [(150.0, dict(heater=HEATER_FULL)), (150.0, dict(fan=FAN_FULL, heater=HEATER_FULL)),
               (100.0, dict(fan=400, heater=700)), (200.0, dict(fan=FAN_FULL))]
    finals = []
    for dt in (0.001, 0.1):
        plant = create()
        for seconds, commands in profile:
            run(plant, seconds, dt, **commands)
        finals.append(plant.snapshot())
    fine, coarse = finals
    assert coarse["temperature_c"] == pytest.approx(fine["temperature_c"], abs=0.05)
    assert coarse["pulse_count"] == pytest.approx(fine["pulse_count"], abs=1)


def test_stiff_parameters_stay_stable_at_long_ticks():
    """Explicit Euler would oscillate and blow up here (k dt / C = 8); the exact step cannot."""
    plant = create(heat_capacity=0.01)
    temps = []
    for _ in range(50):
        plant.step(cmd(heater=HEATER_FULL), 0.1)
        temps.append(plant.temperature)
    assert all(22.0 <= t <= 72.0 + 1e-9 for t in temps)
    assert temps == sorted(temps)                         # heats monotonically, no overshoot
    assert temps[-1] == pytest.approx(72.0, abs=1e-6)


# --- fan and tacho -----------------------------------------------------------------------

@pytest.mark.parametrize("dt", [0.001, 0.01, 0.1])
def test_fan_reaches_63_percent_of_its_speed_after_1_s(dt):
    plant = create()
    run(plant, 1.0, dt, fan=FAN_FULL)
    assert plant.fan_rpm == pytest.approx(3000.0 * (1 - math.exp(-1)), abs=0.5)
    run(plant, 9.0, dt, fan=FAN_FULL)
    assert plant.fan_rpm == pytest.approx(3000.0, abs=0.5)


def test_fan_speed_is_proportional_to_its_command():
    plant = create()
    run(plant, 20.0, 0.05, fan=250)
    assert plant.snapshot()["fan_rpm"] == pytest.approx(750.0, abs=0.1)


def test_pulse_counter_counts_2_pulses_per_revolution():
    """3000 rpm = 50 rev/s = 100 pulses/s, read as the PLC's 1 s gate would."""
    plant = create()
    start = run(plant, 10.0, 0.01, fan=FAN_FULL)["IW1"]
    end = run(plant, 1.0, 0.01, fan=FAN_FULL)["IW1"]
    assert (end - start) & 0xFFFF == pytest.approx(2 * 3000 / 60, abs=1)
    start, end = end, run(plant, 10.0, 0.01, fan=FAN_FULL)["IW1"]
    assert (end - start) & 0xFFFF == pytest.approx(1000, abs=1)


def test_pulse_counter_includes_the_fans_start_up_exactly():
    plant = create()
    inputs = run(plant, 30.0, 0.1, fan=600)                # 1800 rpm, 60 pulses/s
    assert inputs["IW1"] == pytest.approx(fan_pulses(30.0, 1800.0), abs=1)


def test_pulse_counter_wraps_at_16_bits():
    plant = create()
    inputs = run(plant, 700.0, 0.1, fan=FAN_FULL)          # about 69900 pulses
    total = fan_pulses(700.0, 3000.0)
    assert total > 65536
    assert plant.pulse_count == pytest.approx(total, abs=1)
    assert inputs["IW1"] == plant.pulse_count - 65536
    assert 0 <= inputs["IW1"] <= 0xFFFF


@pytest.mark.parametrize("dt", [0.001, 0.1])
def test_pulse_count_is_exact_whatever_the_tick(dt):
    plant = create()
    run(plant, 100.0, dt, fan=777)
    assert plant.pulse_count == pytest.approx(fan_pulses(100.0, 2331.0), abs=1)


def test_raw_tacho_bit_shows_every_pulse_of_a_slow_fan_at_short_ticks():
    """300 rpm = 10 pulses/s, 1 ms ticks: each rising edge of %IX0.1 is one counted pulse."""
    plant = create()
    first = run(plant, 10.0, 0.001, fan=100)
    edges, last, start = 0, first["IX0.1"], first["IW1"]
    for _ in range(10_000):
        inputs = plant.step(cmd(fan=100), 0.001)
        edges += inputs["IX0.1"] and not last
        last = inputs["IX0.1"]
    assert edges == (inputs["IW1"] - start) == pytest.approx(100, abs=1)


def test_raw_tacho_bit_undercounts_a_fast_fan_at_long_ticks_but_the_counter_does_not():
    """Why the PLC must read the fast counter %IW1: 100 pulses/s seen every 100 ms."""
    plant = create()
    first = run(plant, 10.0, 0.1, fan=FAN_FULL)
    edges, last, start = 0, first["IX0.1"], first["IW1"]
    for _ in range(100):
        inputs = plant.step(cmd(fan=FAN_FULL), 0.1)
        edges += inputs["IX0.1"] and not last
        last = inputs["IX0.1"]
    assert (inputs["IW1"] - start) == pytest.approx(1000, abs=1)
    assert edges < 100


# --- ADC ---------------------------------------------------------------------------------

@pytest.mark.parametrize("celsius, counts", [(0.0, 0), (22.0, 220), (55.54, 555), (55.56, 556),
                                             (99.99, 1000), (100.0, 1000)])
def test_adc_reads_tenths_of_a_degree(celsius, counts):
    assert create(start_temperature=celsius).step(cmd(), 0.0)["IW0"] == counts


@pytest.mark.parametrize("celsius, counts", [(-5.0, 0), (130.0, 1000)])
def test_adc_clamps_to_its_range(celsius, counts):
    assert create(start_temperature=celsius).step(cmd(), 0.0)["IW0"] == counts


def test_commands_are_clamped_to_what_the_dac_can_give():
    plant = create()
    plant.step(cmd(fan=-200, heater=5000), 0.0)            # INT -200 arrives as 65336
    snap = plant.snapshot()
    assert snap["fan_command"] == 0 and snap["heater_command"] == HEATER_FULL
    assert snap["heater_w"] == pytest.approx(40.0)


# --- console -----------------------------------------------------------------------------

def test_disturbance_switch_is_the_plants_input_ix0_0():
    plant = create()
    plant.set_disturbance(True)
    assert plant.step(cmd(), 0.0)["IX0.0"] == 1
    assert plant.step(cmd(), 0.1)["IX0.0"] == 1
    plant.set_disturbance(False)
    assert plant.step(cmd(), 0.1)["IX0.0"] == 0


# --- faults ------------------------------------------------------------------------------

def test_sensor_open_reads_full_scale_and_recovers_when_cleared():
    plant = create()
    run(plant, 100.0, 0.1, heater=HEATER_FULL)
    healthy = plant.step(cmd(heater=HEATER_FULL), 0.0)["IW0"]
    plant.inject("sensor_open")
    assert plant.step(cmd(heater=HEATER_FULL), 0.1)["IW0"] == 1000
    assert plant.events[-1].kind == "fault_injected"
    assert plant.temperature > 22.0                        # the radiator itself is unaffected
    plant.clear("sensor_open")
    assert plant.step(cmd(heater=HEATER_FULL), 0.0)["IW0"] == pytest.approx(healthy, abs=1)


def test_fan_stalled_gives_no_speed_no_pulses_and_no_cooling():
    plant = create()
    run(plant, 10.0, 0.1, fan=FAN_FULL)
    plant.inject("fan_stalled")
    before = plant.step(cmd(fan=FAN_FULL), 0.0)
    assert plant.fan_rpm == 0.0
    after = run(plant, 3000.0, 0.5, fan=FAN_FULL, heater=HEATER_FULL)
    assert after["IW1"] == before["IW1"] and after["IX0.1"] == before["IX0.1"]
    assert plant.temperature == pytest.approx(72.0, abs=0.5)   # as with the fan off, not 42 C
    plant.clear("fan_stalled")
    run(plant, 1.0, 0.01, fan=FAN_FULL)
    assert plant.fan_rpm == pytest.approx(3000.0 * (1 - math.exp(-1)), abs=0.5)


def test_heater_dead_gives_no_heat():
    plant = create()
    plant.inject("heater_dead")
    inputs = run(plant, 1000.0, 0.5, heater=HEATER_FULL)
    assert inputs["IW0"] == 220 and plant.snapshot()["heater_w"] == 0.0
    plant.clear()
    run(plant, 500.0, 0.1, heater=HEATER_FULL)
    assert plant.temperature == pytest.approx(heating_curve(500.0, 22.0, 40.0, 0.8, 400.0), abs=0.02)


def test_unknown_fault_is_refused():
    with pytest.raises(PlantError, match="sensor_open"):
        create().inject("fan_on_fire")


# --- determinism -------------------------------------------------------------------------

def test_same_commands_give_the_same_inputs_every_time():
    def trace() -> list[dict[str, int]]:
        plant = create()
        out = []
        for i in range(3000):
            commands = cmd(fan=(i * 7) % 1001, heater=(i * 13) % 2001)
            if i == 1500:
                plant.set_disturbance(True)
                plant.inject("heater_dead")
            out.append(plant.step(commands, 0.01 + (i % 3) * 0.01))
        return out

    assert trace() == trace()
