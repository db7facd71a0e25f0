"""MP-9C plant model (docs/mp9c.md, Plant and I/O map): valves, links, switches, console, faults."""
from __future__ import annotations

import pytest

from plclab.plants import make_plant
from plclab.plants.base import PlantError
from plclab.plants.mp9c import COILS, CONSOLE, MP9C, SENSORS, create

# mechanism -> (coil toward the far end, coil back, start switch, far-end switch, travel time)
CYLINDERS = {
    "lift": ("L3", "L2", "SQ1", "SQ2", 0.8),
    "rotation": ("L5", "L4", "SQ4", "SQ5", 1.2),
    "extension": ("L6", "L7", "SQ7", "SQ6", 1.0),
}


def out(*coils: str, hl1: int = 0) -> dict[str, int]:
    """The PLC output image with only `coils` energized."""
    image = {loc: int(name in coils) for name, loc in COILS.items()}
    image["QX1.0"] = hl1
    return image


def sq(inputs: dict[str, int], name: str) -> int:
    return inputs[SENSORS[name]]


def time_until(plant: MP9C, outputs: dict[str, int], switch: str, state: int = 1,
               dt: float = 0.001, limit: float = 10.0) -> float | None:
    """Step with `outputs` until `switch` reads `state`; plant seconds it took, None if never."""
    start = plant.time
    while plant.time - start < limit:
        if sq(plant.step(outputs, dt), switch) == state:
            return plant.time - start
    return None


def clamp_time(plant: MP9C, dt: float = 0.001) -> float:
    """Plant seconds until the gripper is fully clamped (no switch reports that end)."""
    start = plant.time
    while plant.gripper.position < 1.0:
        plant.step(out("L1"), dt)
    return plant.time - start


def console_sequence(plant: MP9C, name: str, value: int, seconds: float,
                     dt: float = 0.001) -> list[tuple[float, int]]:
    """Set console input `name` to `value`, then step for `seconds`: (time, value) of each change."""
    seen, last = [], plant.read()[CONSOLE[name]]
    plant.set_input(name, value)
    for _ in range(round(seconds / dt)):
        value = plant.step(out(), dt)[CONSOLE[name]]
        if value != last:
            seen.append((plant.time, value))
            last = value
    return seen


@pytest.fixture
def plant() -> MP9C:
    return create()


# -- power-up and I/O map ---------------------------------------------------------------------

def test_power_up_is_up_left_backward_released(plant):
    inputs = plant.step(out(), 0.0)
    on = {name for name in SENSORS if sq(inputs, name)}
    assert on == {"SQ1", "SQ3", "SQ4", "SQ7"}
    assert set(inputs) == set(MP9C.inputs), "the plant writes every %IX input of the stand"
    assert all(inputs[loc] == 0 for loc in CONSOLE.values())


def test_dt_zero_reports_without_moving(plant):
    for _ in range(5):
        inputs = plant.step(out("L3", "L5", "L6", "L1"), 0.0)
    assert plant.time == 0.0 and plant.lift.position == 0.0 and plant.gripper.position == 0.0
    assert sq(inputs, "SQ1") and sq(inputs, "SQ3")


def test_outputs_read_and_hl1(plant):
    assert plant.outputs == ["QX0.0", "QX0.1", "QX0.2", "QX0.3", "QX0.4", "QX0.5", "QX0.6", "QX1.0"]
    plant.step(out(hl1=1), 0.01)
    assert plant.hl1 == 1
    plant.step(out(hl1=0), 0.01)
    assert plant.hl1 == 0


# -- mechanisms -------------------------------------------------------------------------------

@pytest.mark.parametrize("mech", CYLINDERS)
def test_cylinder_reaches_end_in_travel_time_and_leaves_start_at_once(plant, mech):
    coil, _, start, end, travel = CYLINDERS[mech]
    first = plant.step(out(coil), 0.001)
    assert not sq(first, start), f"{start} still ON after the {mech} started moving"
    assert not sq(first, end)
    took = time_until(plant, out(coil), end)
    assert took is not None and took + 0.001 == pytest.approx(travel, abs=0.001)


@pytest.mark.parametrize("mech", CYLINDERS)
def test_cylinder_returns_to_start(plant, mech):
    coil, back, start, end, travel = CYLINDERS[mech]
    time_until(plant, out(coil), end)
    assert not sq(plant.step(out(back), 0.001), end)
    took = time_until(plant, out(back), start)
    assert took is not None and took + 0.001 == pytest.approx(travel, abs=0.001)


def test_bistable_valve_remembers_a_one_step_pulse(plant):
    plant.step(out("L3"), 0.01)                 # one scan of L3, then no coil at all
    took = time_until(plant, out(), "SQ2", dt=0.01)
    assert took is not None and took + 0.01 == pytest.approx(0.8, abs=0.01)
    for _ in range(50):                         # spool stays down: the arm stays down
        inputs = plant.step(out(), 0.1)
    assert sq(inputs, "SQ2") and not sq(inputs, "SQ1") and plant.lift.spool == 1


def test_reversal_midway_takes_the_distance_travelled(plant):
    for _ in range(300):
        plant.step(out("L5"), 0.001)            # 0.3 s of a 1.2 s rotation: a quarter
    took = time_until(plant, out("L4"), "SQ4")
    assert took == pytest.approx(0.3, abs=0.001)


def test_gripper_clamps_and_spring_opens(plant):
    assert not sq(plant.step(out("L1"), 0.001), "SQ3")
    assert clamp_time(plant) + 0.001 == pytest.approx(0.3, abs=0.001)
    took = time_until(plant, out(), "SQ3")      # coil off: the spring, no coil needed
    assert took is not None and took == pytest.approx(0.3, abs=0.001)


def test_valve_conflict_keeps_spool_and_is_recorded_once_per_episode(plant):
    for _ in range(50):
        inputs = plant.step(out("L2", "L3"), 0.01)
    assert plant.lift.spool == 0 and sq(inputs, "SQ1"), "spool must stay where it was (up)"
    conflicts = [e for e in plant.events if e.kind == "valve_conflict"]
    assert len(conflicts) == 1 and "lift" in conflicts[0].detail and conflicts[0].time == 0.0
    plant.step(out(), 0.01)
    plant.step(out("L2", "L3"), 0.01)
    assert len([e for e in plant.events if e.kind == "valve_conflict"]) == 2


def test_conflict_mid_travel_keeps_moving_toward_the_selected_end(plant):
    plant.step(out("L6"), 0.1)
    took = time_until(plant, out("L6", "L7"), "SQ6", dt=0.01)
    assert took == pytest.approx(0.9, abs=0.01)
    assert plant.extension.spool == 1
    assert [e.detail for e in plant.events if e.kind == "valve_conflict"] == [
        "extension valve: L7 and L6 both energized"]


def test_no_conflict_event_for_normal_operation(plant):
    for coils in (("L3", "L5", "L6", "L1"), (), ("L2", "L4", "L7")):
        for _ in range(200):
            plant.step(out(*coils), 0.01)
    assert plant.events == []


# -- faults -----------------------------------------------------------------------------------

def test_stuck_switch_on_and_off(plant):
    plant.inject("stuck_switch", switch="SQ2", state="on")
    inputs = plant.step(out(), 0.01)
    assert sq(inputs, "SQ2") and sq(inputs, "SQ1")
    plant.inject("stuck_switch", switch="sq1", state=0)
    assert not sq(plant.step(out(), 0.01), "SQ1") and plant.lift.position == 0.0
    plant.clear("stuck_switch")
    assert sq(plant.step(out(), 0.01), "SQ1")
    assert [e.kind for e in plant.events] == ["fault_injected", "fault_injected", "fault_cleared"]


def test_jammed_mechanism_stops_where_it_is_and_resumes_when_cleared(plant):
    for _ in range(40):
        plant.step(out("L3"), 0.01)
    plant.inject("jammed", mechanism="lift")
    assert time_until(plant, out("L3"), "SQ2", dt=0.01, limit=3.0) is None
    assert plant.lift.position == pytest.approx(0.5)
    assert plant.rotation.position == 0.0
    assert time_until(plant, out("L5"), "SQ5", dt=0.01) is not None, "other links still move"
    plant.clear()
    took = time_until(plant, out("L3"), "SQ2", dt=0.01)
    assert took == pytest.approx(0.4, abs=0.01)


def test_jammed_gripper_does_not_open(plant):
    for _ in range(30):
        plant.step(out("L1"), 0.01)
    plant.inject("jammed", mechanism="gripper")
    assert time_until(plant, out(), "SQ3", dt=0.01, limit=2.0) is None


@pytest.mark.parametrize("factor, expected", [(None, 2.4), (2.0, 1.6)])
def test_low_pressure_slows_every_link(plant, factor, expected):
    plant.inject("low_pressure", **({} if factor is None else {"factor": factor}))
    assert time_until(plant, out("L3"), "SQ2") == pytest.approx(expected, abs=0.001)
    assert clamp_time(plant) == pytest.approx(0.3 * (factor or 3.0), abs=0.001)


def test_low_pressure_default_factor_from_create():
    plant = create(low_pressure_factor=1.5)
    plant.inject("low_pressure")
    assert time_until(plant, out("L6"), "SQ6") == pytest.approx(1.5, abs=0.001)


def test_dead_coil_does_nothing_other_coils_work(plant):
    plant.inject("dead_coil", coil="L3")
    assert time_until(plant, out("L3"), "SQ2", dt=0.01, limit=3.0) is None
    assert plant.lift.spool == 0
    plant.inject("dead_coil", coil="L1")
    for _ in range(100):
        inputs = plant.step(out("L1"), 0.01)
    assert sq(inputs, "SQ3") and plant.gripper.position == 0.0
    plant.clear("dead_coil")
    assert time_until(plant, out("L3"), "SQ2", dt=0.01) is not None


def test_bad_fault_requests_are_one_line_errors(plant):
    with pytest.raises(PlantError, match="unknown fault"):
        plant.inject("flat_tyre")
    with pytest.raises(PlantError, match="SQ9"):
        plant.inject("stuck_switch", switch="SQ9")
    with pytest.raises(PlantError, match="which mechanism"):
        plant.inject("jammed")
    with pytest.raises(PlantError, match="unknown parameter 'coils'"):
        plant.inject("dead_coil", coils="L1")
    with pytest.raises(PlantError, match="factor"):
        plant.inject("low_pressure", factor=0)
    assert plant.faults == {} and plant.events == []


# -- console and bounce -----------------------------------------------------------------------

def test_console_drives_its_inputs(plant):
    plant.console.set(SA1=1, SA5=1)
    plant.set_input("I07", 1)
    plant.set_switch("%IX1.5", True)
    plant.press("SB1")
    inputs = plant.step(out(), 0.01)
    on = {name for name, loc in CONSOLE.items() if inputs[loc]}
    assert on == {"SA1", "SA5", "I07", "SA6", "SB1"}
    plant.release()
    assert plant.step(out(), 0.01)[CONSOLE["SB1"]] == 0
    with pytest.raises(PlantError, match="console input 'SQ1'"):
        plant.set_input("SQ1", 1)


def test_console_change_without_bounce_is_one_clean_edge(plant):
    assert console_sequence(plant, "SB1", 1, 0.05) == [(pytest.approx(0.001), 1)]
    assert console_sequence(plant, "SB1", 0, 0.05) == [(pytest.approx(0.051), 0)]


@pytest.mark.parametrize("duration", [None, 0.005])
def test_bounce_chatters_briefly_then_settles(plant, duration):
    limit = duration or 0.02
    plant.inject("bounce", **({} if duration is None else {"duration": duration}))
    for name, value in (("SB1", 1), ("SB1", 0), ("SA5", 1)):
        changes = console_sequence(plant, name, value, 0.1, dt=0.0001)
        assert len(changes) >= 3, f"{name} -> {value}: expected chatter, saw {changes}"
        assert changes[-1][0] - changes[0][0] <= limit
        assert changes[-1][1] == value and plant.console.reported[name] == value


def test_determinism_same_inputs_same_input_sequence():
    def run() -> list[tuple[int, ...]]:
        plant = create()
        plant.inject("bounce", seed=7)
        seen = []
        for k in range(3000):
            if k % 150 == 0:
                plant.set_input("SB1", (k // 150) % 2)
            if k % 400 == 0:
                plant.set_input("SA3", (k // 400) % 2)
            coils = ("L3", "L5", "L1") if (k // 1000) % 2 == 0 else ("L2", "L4", "L7")
            seen.append(tuple(plant.step(out(*coils), 0.001).values()))
        return seen

    assert run() == run()


def test_bounce_seed_changes_the_pattern():
    def changes(seed: int) -> list[tuple[float, int]]:
        plant = create()
        plant.inject("bounce", seed=seed)
        return console_sequence(plant, "SB1", 1, 0.05)

    assert changes(1) == changes(1)
    assert changes(1) != changes(2)


# -- time step --------------------------------------------------------------------------------

@pytest.mark.parametrize("mech", [*CYLINDERS, "gripper"])
def test_travel_time_independent_of_dt(mech):
    def travel(dt: float) -> float:
        plant = create()
        if mech == "gripper":
            return clamp_time(plant, dt)
        return time_until(plant, out(CYLINDERS[mech][0]), CYLINDERS[mech][3], dt=dt)

    assert travel(0.02) == pytest.approx(travel(0.001), abs=0.02)


def test_large_dt_is_stable(plant):
    for _ in range(20):
        inputs = plant.step(out("L3", "L5", "L6", "L1"), 0.1)
    assert all(p.position == 1.0 for p in plant.links.values())
    assert [sq(inputs, n) for n in ("SQ1", "SQ2", "SQ3", "SQ4", "SQ5", "SQ6", "SQ7")] == [0, 1, 0, 0, 1, 1, 0]
    with pytest.raises(PlantError):
        plant.step(out(), -0.01)


# -- construction and readable state ----------------------------------------------------------

def test_make_plant_with_parameters():
    plant = make_plant("mp9c", lift_time=0.5, period=0.005)
    assert isinstance(plant, MP9C) and plant.period == 0.005
    assert time_until(plant, out("L3"), "SQ2") == pytest.approx(0.5, abs=0.001)
    with pytest.raises(PlantError, match="unknown parameter 'lift'"):
        make_plant("mp9c", lift=0.5)
    with pytest.raises(PlantError, match="rotation_time"):
        make_plant("mp9c", rotation_time=-1)


def test_snapshot_shows_positions_spools_and_io(plant):
    plant.press("SB1")
    for _ in range(40):
        plant.step(out("L3", hl1=1), 0.01)
    snap = plant.snapshot()
    assert snap["time"] == pytest.approx(0.4)
    assert snap["lift"] == pytest.approx(0.5) and snap["lift.spool"] == 1
    assert snap["rotation"] == 0.0 and snap["rotation.spool"] == 0
    assert snap["SQ1"] == 0 and snap["SQ2"] == 0 and snap["SQ4"] == 1
    assert snap["SB1"] == 1 and snap["L3"] == 1 and snap["HL1"] == 1 and snap["faults"] == []


@pytest.mark.parametrize("seed", range(12))
def test_the_rest_shortcut_changes_nothing_a_full_step_would_not(seed):
    """A step at rest or on the way under unchanged outputs (and faults) moves the links only
    and returns what it returned before unless a switch changed (the closed loop's fast path):
    over random coil patterns held for random spans, console changes with and without bounce,
    faults injected and cleared and zero-length steps, the plant with the
    shortcut reports every input, event and snapshot as the plant computing every step."""
    import random
    rng = random.Random(seed)
    fast, full = MP9C(), MP9C()
    full.REST_SHORTCUT = False
    names = list(COILS)
    faults = [("jammed", {"mechanism": "rotation"}), ("stuck_switch", {"switch": "SQ2", "state": 1}),
              ("low_pressure", {"factor": 2.0}), ("dead_coil", {"coil": "L3"}), ("bounce", {"duration": 0.02})]
    outputs = out()
    calls = {"_step": 0, "_travel": 0, "faulted_step": 0}

    def counted(name):
        method = getattr(fast, name)

        def call(*args):
            calls[name] += 1
            calls["faulted_step"] += name == "_step" and bool(fast.faults)
            return method(*args)
        return call
    fast._step, fast._travel = counted("_step"), counted("_travel")
    steps = faulted_steps = 0
    for _ in range(400):
        r = rng.random()
        if r < 0.25:
            outputs = out(*rng.sample(names, rng.randint(0, 3)), hl1=rng.randint(0, 1))
        elif r < 0.35:
            name, value = rng.choice(list(CONSOLE)), rng.randint(0, 1)
            for p in (fast, full):
                p.set_input(name, value)
        elif r < 0.40:
            fault, params = rng.choice(faults)
            for p in (fast, full):
                p.inject(fault, **params)
        elif r < 0.45:
            for p in (fast, full):
                p.clear()
        for _ in range(rng.choice((0, 1, 5, 40, 150))):
            dt = rng.choice((0.01, 0.01, 0.01, 0.0))
            faulted_steps += bool(fast.faults)
            a, b = fast.step(outputs, dt), full.step(outputs, dt)
            steps += 1
            assert a == b
            assert fast.snapshot() == full.snapshot()
            assert fast.events == full.events
    # both shortcuts were taken, and often: at rest, and on the way
    assert steps - calls["_step"] - calls["_travel"] > 1000 and calls["_travel"] > 300
    # a fault that stays acts the same at every step: under one, the shortcuts are taken too
    assert faulted_steps - calls["faulted_step"] > 300
