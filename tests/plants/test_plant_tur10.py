"""The TUR-10 plant model against docs/tur10.md: sensor bus, drives, stops, faults, console."""
from __future__ import annotations

import math

import pytest

from plclab.plants import make_plant
from plclab.plants.base import PlantError, unsigned16
from plclab.plants.tur10 import Tur10, create

IDLE = 31                                   # QB0 with every enable ON: no sensor selected
CODES = {1: 15, 2: 23, 3: 27, 4: 29, 5: 30}  # textbook Table 1
TAU = 0.05
GAIN = 4.0


def outputs(qb0: int = IDLE, refs: dict[int, int] | None = None, lamp: int = 0) -> dict[str, int]:
    """The PLC outputs as the image holds them: QB0 unpacked to bits, DAC words unsigned."""
    out = {f"QX0.{bit}": (qb0 >> bit) & 1 for bit in range(8)}
    out["QX1.0"] = lamp
    for k in range(1, 6):
        out[f"QW{k - 1}"] = unsigned16((refs or {}).get(k, 0))
    return out


def bus(inputs: dict[str, int]) -> int:
    """The 15-bit sensor code the PLC reads: bits 1..8 on I3.0..I3.7, bits 9..15 on I2.0..I2.6."""
    low = sum(inputs[f"IX3.{i}"] << i for i in range(8))
    high = sum(inputs[f"IX2.{i}"] << i for i in range(7))
    return low | high << 8


def run(plant: Tur10, seconds: float, dt: float = 0.001, **kw) -> dict[str, int]:
    """Hold the same outputs for `seconds` of plant time in steps of dt."""
    inputs = {}
    for _ in range(round(seconds / dt)):
        inputs = plant.step(outputs(**kw), dt)
    return inputs


def kinds(plant: Tur10) -> list[str]:
    return [e.kind for e in plant.events]


@pytest.fixture
def tur10() -> Tur10:
    """Links at distinct positions so a wrong sensor selection cannot go unnoticed."""
    return create(start=(10000, 12000, 14000, 20000, 24000))


# --- sensor bus ---------------------------------------------------------------------------

def test_power_up_every_link_at_16000_and_no_events():
    plant = make_plant("tur10")
    for k, code in CODES.items():
        assert bus(plant.step(outputs(code), 0.0)) == 16000, f"sensor {k} at power-up"
    assert plant.events == []


@pytest.mark.parametrize("axis, code", sorted(CODES.items()))
def test_table1_code_selects_that_sensor(tur10, axis, code):
    expected = tur10.snapshot()[f"code{axis}"]
    assert bus(tur10.step(outputs(code), 0.01)) == expected
    assert tur10.snapshot()["selected"] == (axis,)
    assert "bus_contention" not in kinds(tur10)


@pytest.mark.parametrize("axis, enable_bit", [(1, 4), (2, 3), (3, 2), (4, 1), (5, 0)])
def test_only_the_active_low_enable_matters(tur10, axis, enable_bit):
    """Sensor k drives the bus while its enable is OFF; Q0.5..Q0.7 are not enables."""
    qb0 = 0b11100000 | (IDLE & ~(1 << enable_bit))
    assert bus(tur10.step(outputs(qb0), 0.01)) == tur10.snapshot()[f"code{axis}"]


def test_no_enable_off_reads_all_ones(tur10):
    assert bus(tur10.step(outputs(IDLE), 0.01)) == 32767


def test_bus_bit_order_lsb_on_i3_0_and_bit15_on_i2_6():
    plant = create(start=0x4001)                   # bits 1 and 15 set
    inputs = plant.step(outputs(CODES[1]), 0.0)
    assert inputs["IX3.0"] == 1 and inputs["IX2.6"] == 1
    assert bin(bus(inputs)).count("1") == 2
    assert "IX2.7" not in inputs                   # not wired (Fig. 7)


def test_round_robin_select_in_one_scan_read_in_the_next(tur10):
    """Harness order: plant step (outputs of scan n) -> scan n+1 samples. One scan of latency."""
    expected = {k: tur10.snapshot()[f"code{k}"] for k in CODES}
    order = [1, 2, 3, 4, 5, 1, 2, 3]
    qb0, inputs = IDLE, tur10.step(outputs(IDLE), 0.0)
    read: list[tuple[int, int]] = []
    for n, axis in enumerate(order):
        if n:                                       # scan n reads what scan n-1 selected
            read.append((order[n - 1], bus(inputs)))
        qb0 = CODES[axis]                           # ... and selects the next sensor
        inputs = tur10.step(outputs(qb0), 0.01)     # plant step between scan n and n+1
    assert read == [(k, expected[k]) for k in order[:-1]]


def test_selection_is_not_visible_before_the_plant_has_stepped(tur10):
    before = tur10.step(outputs(CODES[1]), 0.01)
    assert bus(before) == 10000
    after = tur10.step(outputs(CODES[5]), 0.01)     # new selection shows after exactly one step
    assert bus(before) == 10000 and bus(after) == 24000


def test_contention_reads_the_and_and_is_recorded_once(tur10):
    both = CODES[1] & CODES[2]                      # Q0.3 and Q0.4 OFF
    inputs = run(tur10, 0.05, dt=0.01, qb0=both)
    assert bus(inputs) == 10000 & 12000
    assert kinds(tur10) == ["bus_contention"]
    event = tur10.events[0]
    assert event.time == 0.0 and "sensors 1, 2" in event.detail
    assert str(10000 & 12000) in event.detail
    run(tur10, 0.01, dt=0.01, qb0=CODES[3])         # clean selection ...
    run(tur10, 0.01, dt=0.01, qb0=both)             # ... then the same contention again
    assert kinds(tur10) == ["bus_contention", "bus_contention"]


def test_plc_safe_state_all_outputs_zero_is_contention_of_all_five(tur10):
    inputs = tur10.step(outputs(0), 0.01)
    assert bus(inputs) == 10000 & 12000 & 14000 & 20000 & 24000
    assert kinds(tur10) == ["bus_contention"]


# --- drives -------------------------------------------------------------------------------

def test_speed_reaches_63_percent_at_tau():
    plant = create()
    run(plant, TAU, refs={1: 1500})
    assert plant.snapshot()["speed1"] == pytest.approx(6000 * (1 - math.exp(-1)), rel=1e-9)
    assert plant.snapshot()["speed1"] == pytest.approx(0.632 * 6000, rel=1e-3)


@pytest.mark.parametrize("ref, speed", [(500, 2000), (-500, -2000), (1500, 6000), (-1500, -6000)])
def test_steady_speed_is_4_codes_per_second_per_dac_unit(ref, speed):
    plant = create()
    run(plant, 0.5, dt=0.01, refs={2: ref})
    snap = plant.snapshot()
    assert snap["speed2"] == pytest.approx(speed, rel=1e-4)
    assert snap["speed1"] == 0 and snap["pos1"] == 16000   # other links untouched


def test_position_is_the_exact_integral_of_the_lagged_speed():
    plant = create()
    run(plant, 0.3, dt=0.01, refs={3: -500})
    expected = 16000 - 2000 * (0.3 - TAU * (1 - math.exp(-0.3 / TAU)))
    assert plant.snapshot()["pos3"] == pytest.approx(expected, abs=1e-6)
    assert bus(plant.step(outputs(CODES[3]), 0.0)) == math.floor(expected)


def test_a_stopped_link_comes_to_rest_where_its_lag_tends_and_its_code_stays():
    """Told to stop from full speed, a link coasts speed x tau further and is then at rest:
    speed exactly 0 within a second, its code fixed (the exact lag only tends to zero, and a
    code that creeps by 1e-9 codes for half a minute is no sensor's)."""
    plant = create()
    run(plant, 0.5, dt=0.01, refs={1: 1500})
    x0, v0 = plant.snapshot()["pos1"], plant.snapshot()["speed1"]
    run(plant, 1.0, dt=0.01, refs={1: 0})
    snap = plant.snapshot()
    assert snap["speed1"] == 0.0
    assert snap["pos1"] == pytest.approx(x0 + v0 * TAU, abs=1e-3)
    run(plant, 5.0, dt=0.01, refs={1: 0})
    assert plant.snapshot()["pos1"] == snap["pos1"] and plant.snapshot()["code1"] == snap["code1"]


def test_large_dt_does_not_overshoot_or_oscillate():
    plant = create()
    speeds = []
    for _ in range(10):
        plant.step(outputs(refs={1: 1500}), 0.1)
        speeds.append(plant.snapshot()["speed1"])
    assert all(a < b <= 6000 for a, b in zip(speeds, speeds[1:]))


def test_dt_zero_reports_without_advancing(tur10):
    before = tur10.snapshot()
    inputs = tur10.step(outputs(CODES[4], refs={4: 9999}), 0.0)
    assert bus(inputs) == 20000
    assert tur10.time == 0.0 and tur10.events == []
    assert {k: v for k, v in tur10.snapshot().items() if k not in ("selected", "bus")} == \
        {k: v for k, v in before.items() if k not in ("selected", "bus")}


def test_negative_dt_is_an_error(tur10):
    with pytest.raises(PlantError):
        tur10.step(outputs(), -0.01)


# --- stops and working range --------------------------------------------------------------

def test_upper_stop_collision_link_stays_there_one_event():
    plant = create(start=29000)
    run(plant, 1.0, dt=0.01, refs={1: 1500})        # 2000 codes to the stop take ~0.4 s
    snap = plant.snapshot()
    assert snap["pos1"] == 31000 and snap["speed1"] == 0 and snap["at_stop1"]
    assert kinds(plant) == ["out_of_range", "collision"]
    collision = plant.events[1]
    assert "link 1" in collision.detail and 0.3 < collision.time < 0.45
    assert bus(plant.step(outputs(CODES[1]), 0.0)) == 31000


def test_leaving_the_stop_and_hitting_it_again_is_a_new_collision():
    plant = create(start=1200)                        # outside the working range already
    run(plant, 0.3, dt=0.01, refs={5: -1500})
    assert plant.snapshot()["pos5"] == 1000 and kinds(plant) == ["collision"]
    run(plant, 0.2, dt=0.01)                          # resting at the stop: nothing new
    assert kinds(plant) == ["collision"]
    run(plant, 0.2, dt=0.01, refs={5: 500})           # drive away
    assert plant.snapshot()["pos5"] > 1000 and not plant.snapshot()["at_stop5"]
    run(plant, 0.5, dt=0.01, refs={5: -500})
    assert kinds(plant).count("collision") == 2


def test_a_reversal_that_touches_the_stop_mid_step_is_a_collision_at_any_dt():
    """Full speed up, reversed 50 codes before the stop: it coasts ~92 codes past the reversal."""
    for dt in (0.001, 0.1):
        plant = create(start=30950 - 6000 * 0.2)
        plant.drives[1].speed = 6000.0              # already at full forward speed
        run(plant, 0.2, dt=dt, refs={1: 1500})
        assert plant.snapshot()["pos1"] == pytest.approx(30950) and "collision" not in kinds(plant)
        run(plant, 0.1, dt=dt, refs={1: -1500})
        assert "collision" in kinds(plant), f"dt={dt}"


def test_leaving_the_working_range_is_reported_once():
    plant = create(start=29900)
    run(plant, 0.2, dt=0.01, refs={4: 500})
    assert kinds(plant) == ["out_of_range"]
    assert "link 4" in plant.events[0].detail and plant.snapshot()["pos4"] > 30000


# --- overvoltage --------------------------------------------------------------------------

@pytest.mark.parametrize("ref", [1501, -1501, 32767, -32768])
def test_overvoltage_beyond_1500_trips_that_drive(ref):
    plant = create()
    run(plant, 0.5, dt=0.01, refs={2: ref, 1: 1500})
    assert kinds(plant) == ["overvoltage"]
    event = plant.events[0]
    assert event.time == 0.0 and "drive 2" in event.detail and str(ref) in event.detail
    snap = plant.snapshot()
    assert snap["tripped2"] and snap["pos2"] == 16000 and snap["ref2"] == ref
    assert snap["pos1"] > 18000                      # the other drive keeps going


@pytest.mark.parametrize("ref", [1500, -1500])
def test_exactly_1500_is_not_overvoltage(ref):
    plant = create()
    run(plant, 0.5, dt=0.01, refs={3: ref})
    assert plant.events == [] and not plant.snapshot()["tripped3"]


def test_tripped_drive_stops_until_reset():
    plant = create()
    run(plant, 0.3, dt=0.01, refs={1: 1000})
    run(plant, 0.5, dt=0.01, refs={1: 2000})         # trips: speed decays to 0
    stopped_at = plant.snapshot()["pos1"]
    assert plant.snapshot()["speed1"] == pytest.approx(0, abs=5)
    run(plant, 0.3, dt=0.01, refs={1: 1000})         # a legal code: still tripped
    assert plant.snapshot()["pos1"] == pytest.approx(stopped_at, abs=1)
    plant.reset_trip(1)
    run(plant, 0.3, dt=0.01, refs={1: 1000})
    assert plant.snapshot()["pos1"] > stopped_at + 500
    assert kinds(plant) == ["overvoltage"]


# --- injected faults ----------------------------------------------------------------------

def test_dead_sensor_reads_a_constant_while_the_link_moves():
    plant = create()
    plant.inject("dead_sensor", axis=1)
    inputs = run(plant, 0.5, dt=0.01, qb0=CODES[1], refs={1: 1500})
    assert plant.snapshot()["pos1"] > 18000 and bus(inputs) == 16000
    plant.inject("dead_sensor", axis="hand", value=0)
    assert bus(plant.step(outputs(CODES[5]), 0.01)) == 0
    plant.clear("dead_sensor")
    assert bus(plant.step(outputs(CODES[5]), 0.01)) == 16000


def test_stuck_drive_does_not_move_and_moves_when_cleared():
    plant = create()
    plant.inject("stuck_drive", axis=4)
    run(plant, 0.5, dt=0.01, refs={4: 1500, 5: 1500})
    snap = plant.snapshot()
    assert snap["pos4"] == 16000 and snap["speed4"] == 0 and snap["pos5"] > 18000
    plant.clear("stuck_drive")
    run(plant, 0.5, dt=0.01, refs={4: 1500})
    assert plant.snapshot()["pos4"] > 18000


def test_slow_drive_runs_at_factor_times_the_speed():
    plant = create()
    plant.inject("slow_drive", axis=2, factor=0.25)
    run(plant, 0.5, dt=0.01, refs={1: 1000, 2: 1000})
    snap = plant.snapshot()
    assert snap["speed2"] == pytest.approx(0.25 * snap["speed1"], rel=1e-9)
    assert snap["pos2"] - 16000 == pytest.approx(0.25 * (snap["pos1"] - 16000), rel=1e-9)


@pytest.mark.parametrize("fault, params", [
    ("dead_sensor", {"axis": 6}), ("stuck_drive", {}), ("slow_drive", {"axis": 1}),
    ("slow_drive", {"axis": 1, "factor": -1}), ("dead_sensor", {"axis": 1, "value": 40000}),
    ("flat_tyre", {"axis": 1}),
])
def test_bad_fault_requests_are_plant_errors(fault, params):
    with pytest.raises(PlantError):
        create().inject(fault, **params)


def test_injection_is_logged_as_an_event():
    plant = create()
    plant.inject("stuck_drive", axis="shoulder")
    assert kinds(plant) == ["fault_injected"] and plant.faults["stuck_drive"]["axis"] == 1


# --- console ------------------------------------------------------------------------------

def test_console_drives_its_inputs():
    plant = create()
    plant.set_switch("SA7", 1)
    plant.set_switch("SA6", True)
    plant.set_switch("I15", 1)
    plant.press("SB1")
    plant.jog(3, -1)
    inputs = plant.step(outputs(), 0.01)
    on = {loc for loc in ("IX0.0", "IX0.1", "IX0.2", "IX0.3", "IX0.4", "IX0.5", "IX0.6", "IX0.7",
                          "IX1.0", "IX1.1", "IX1.2", "IX1.3", "IX1.4", "IX1.5") if inputs[loc]}
    assert on == {"IX1.4", "IX1.2", "IX1.5", "IX1.3", "IX0.5"}
    plant.release("SB1")
    plant.jog(3, +1)
    inputs = plant.step(outputs(), 0.01)
    assert inputs["IX1.3"] == 0 and inputs["IX0.4"] == 1 and inputs["IX0.5"] == 0
    with pytest.raises(PlantError):
        plant.set_switch("SB2", 1)


def test_plant_writes_every_declared_input_and_reads_the_reset_lamp():
    plant = create()
    inputs = plant.step(outputs(lamp=1), 0.01)
    assert set(inputs) == set(plant.inputs) and len(plant.inputs) == 29
    assert set(outputs()) - {"QX0.5", "QX0.6", "QX0.7"} == set(plant.outputs)
    assert plant.snapshot()["reset_indicator"] == 1


# --- determinism and step size ------------------------------------------------------------

def profile(plant: Tur10, dt: float) -> None:
    """Jog, reverse, run into the upper stop; references change on 0.1 s boundaries."""
    run(plant, 0.3, dt=dt, refs={1: 1500, 2: -500, 3: 700})
    run(plant, 0.2, dt=dt, refs={1: -1500, 2: 500, 4: 1200})
    run(plant, 0.5, dt=dt, refs={5: 1500, 3: -1500})


def test_same_inputs_same_result():
    a, b = create(start=(16000, 16000, 16000, 16000, 29000)), \
        create(start=(16000, 16000, 16000, 16000, 29000))
    profile(a, 0.01)
    profile(b, 0.01)
    assert a.snapshot() == b.snapshot() and a.events == b.events


def test_result_does_not_depend_on_the_step_size():
    fine, coarse = (create(start=(16000, 16000, 16000, 16000, 29000)) for _ in range(2))
    profile(fine, 0.001)
    profile(coarse, 0.1)
    f, c = fine.snapshot(), coarse.snapshot()
    for k in range(1, 6):
        assert c[f"pos{k}"] == pytest.approx(f[f"pos{k}"], abs=1e-3), f"link {k}"
        assert c[f"speed{k}"] == pytest.approx(f[f"speed{k}"], abs=1e-3), f"link {k}"
    assert c["pos5"] == 31000
    assert kinds(fine) == kinds(coarse) == ["out_of_range", "collision"]
    assert coarse.events[-1].time == pytest.approx(fine.events[-1].time, abs=0.1)


def test_bad_parameters_are_plant_errors():
    for params in ({"tau": 0}, {"start": 500}, {"stops": (1000, 40000)}, {"start": (1, 2)}):
        with pytest.raises(PlantError):
            create(**params)


def act_on_both(rng, r: float, plants: tuple[Tur10, Tur10], faults: list[tuple[str, dict]],
                bands: tuple[tuple[float, str], ...]) -> None:
    """One random operator or maintenance action, the same on both plants: the action of the
    first of `bands` ((upper bound, action), rising) that `r` falls below, if any: a console
    contact set ('switch'), a fault of `faults` injected ('inject'), every fault cleared
    ('clear') or the drives' trips reset ('reset_trip')."""
    action = next((a for bound, a in bands if r < bound), None)
    if action is None:
        return
    if action == "switch":
        name, bit = rng.choice(sorted(plants[0].console_bits)), rng.randint(0, 1)
    elif action == "inject":
        fault, params = rng.choice(faults)
    for p in plants:
        if action == "switch":
            p.set_switch(name, bit)
        elif action == "inject":
            p.inject(fault, **dict(params))
        elif action == "clear":
            p.clear()
        else:
            p.reset_trip()


@pytest.mark.parametrize("seed", range(8))
def test_an_idle_step_is_what_a_full_step_gives_and_a_fault_that_stays_keeps_it_idle(seed):
    """The plant contract's `idle` (the closed loop's shortcut): where it says a step under the
    same outputs changes nothing but the time, a full step indeed changes nothing else. Over
    random outputs (references, enables) held for random spans, console changes, faults
    injected and cleared: the plant that is stepped only where `idle` says no reports every
    input, snapshot and event as the plant stepped in full; and it stood idle often, also
    under a fault (a stuck drive, a dead sensor)."""
    import random
    rng = random.Random(seed)
    fast, full = create(), create()
    faults = [("stuck_drive", {"axis": 2}), ("dead_sensor", {"axis": 2, "value": 1234}),
              ("slow_drive", {"axis": 1, "factor": 0.5})]
    out = outputs()
    inputs = fast.step(out, 0.01)
    full.step(out, 0.01)
    idle = idle_faulted = 0
    for _ in range(300):
        r = rng.random()
        if r < 0.3:
            refs = {k: rng.choice((0, 0, 0, 200, -300)) for k in range(1, 6)}
            out = outputs(qb0=rng.choice((IDLE, 15, 23, 27)), refs=refs, lamp=rng.randint(0, 1))
        else:
            act_on_both(rng, r, (fast, full), faults, ((0.4, "switch"), (0.5, "inject"), (0.55, "clear")))
        values = tuple(out.get(loc, 0) for loc in fast.outputs)
        for _ in range(rng.choice((1, 5, 40, 120))):
            if fast.idle(values, 0.01):
                idle += 1
                idle_faulted += bool(fast.faults)
            else:
                inputs = fast.step(out, 0.01)
            assert inputs == full.step(out, 0.01)
            assert fast.snapshot() == full.snapshot() and fast.events == full.events
    assert idle > 200 and idle_faulted > 50, (idle, idle_faulted)


@pytest.mark.parametrize("seed", range(4))
def test_a_step_on_values_in_order_is_the_step_on_names_and_counts_each_change_of_a_link(seed):
    """`step_values` (the closed loop's form of the step: the outputs' values in `outputs`
    order, the inputs' values in `inputs` order) is `step`: over random outputs, some missing
    (a PLC switched off), steps of 0 s, console changes, faults and trip resets, both plants
    report the same inputs, snapshot and events. And `state_changes` moves wherever a link (its
    reference, trip, position or speed) or the reset lamp changed: a grader's probe does not
    look again while it and the console stay (only the sensor bus changed)."""
    import random
    rng = random.Random(seed)
    names, values = create(), create()
    faults = [("stuck_drive", {"axis": 3}), ("dead_sensor", {"axis": 1}), ("slow_drive", {"axis": 2, "factor": 0.3})]
    out: dict[str, int] = outputs()
    stayed = 0
    for _ in range(600):
        r = rng.random()
        if r < 0.25:
            refs = {k: rng.choice((0, 0, 0, 300, -700, 1600)) for k in range(1, 6)}
            out = outputs(qb0=rng.choice((IDLE, 15, 23, 27, 29, 30, 0)), refs=refs, lamp=rng.randint(0, 1))
        elif r < 0.3:
            out = {}                                          # the PLC off: no output given
        elif r < 0.4:                                         # links told to stop, the bus scanned
            out = outputs(qb0=rng.choice((15, 23, 27, 29, 30)))
        else:
            act_on_both(rng, r, (names, values), faults,
                        ((0.45, "switch"), (0.5, "inject"), (0.53, "clear"), (0.56, "reset_trip")))
        dt = rng.choice((0.01, 0.01, 0.01, 0.0, 0.05))
        links = [(d.reference, d.tripped, d.position, d.speed) for d in values.drives.values()]
        seen = (values.state_changes, values.console_changes, values.reset_indicator)
        got = values.step_values(tuple(map(out.get, values.outputs)), dt)
        assert dict(zip(values.inputs, got)) == names.step(out, dt)
        assert values.snapshot() == names.snapshot() and values.events == names.events
        if (values.state_changes, values.console_changes) == seen[:2]:
            stayed += 1
            assert values.reset_indicator == seen[2]
            assert [(d.reference, d.tripped, d.position, d.speed) for d in values.drives.values()] == links
    assert stayed > 50, stayed
