"""Thermostabilization stand: every scenario passes and never shows a command out of range,
the heater on with an open sensor or a wrong automatic-mode report; the control goals
(docs/thermo.md "Control program") measured from the trace; bumpless transfer and anti-windup are what
make the scenarios pass (a program without them fails); golden trace of the demo.

Regenerate the golden trace after an intended change of behaviour with
    PLCLAB_UPDATE_GOLDEN=1 .venv/bin/python -m pytest tests/stands/test_thermo.py
and review the diff of tests/stands/golden/ before committing it.
"""
from __future__ import annotations

from pathlib import Path

import pytest

from golden import check_golden

from plclab.frontend import check_sources
from plclab.stands import bundle, sources, thermo



def run(scenario: str, tmp_path: Path, program=None):
    s = thermo.session(program=program, retain_path=tmp_path / "retain.json")
    thermo.SCENARIOS[scenario](s)
    thermo.check_never(s)
    return s


class Runs(dict):
    """Each scenario run once on the shipped program: runs[name] is its session, or the
    scenario's failure, reported by the test that asks for it."""

    def __getitem__(self, name: str):
        result = super().__getitem__(name)
        if isinstance(result, thermo.ScenarioFailure):
            pytest.fail(f"scenario {name} failed: {result}")
        return result


@pytest.fixture(scope="module")
def traces(tmp_path_factory) -> Runs:
    out = tmp_path_factory.mktemp("thermo")
    runs = Runs()
    for name in thermo.SCENARIOS:
        try:
            runs[name] = run(name, out / name)
        except thermo.ScenarioFailure as e:
            runs[name] = e
    return runs


@pytest.mark.parametrize("scenario", sorted(thermo.SCENARIOS))
def test_every_scenario_passes_and_never_breaks_the_rules(traces, scenario):
    assert traces[scenario].fault is None


def test_the_program_is_one_openplc_loadable_bundle_with_a_100_ms_task():
    text = bundle(thermo.STAND, "full")
    unit = check_sources([("thermo_full.st", text)])
    assert unit.config.name == "Config0" and [r.name for r in unit.config.resources] == ["Res0"]
    assert "TASK MainTask (INTERVAL := T#100ms, PRIORITY := 1);" in text
    assert "PROGRAM Main WITH MainTask : PRG_Thermo;" in text
    assert thermo.STAND.register_map == "twido"


# --------------------------------------------------------------------------- the goals, from the trace

def temperature(trace, after: float, until: float) -> list[tuple[float, float]]:
    """(time, C) of the ADC %IW0 between two times: the value at `after`, then every change."""
    pts = [(after, trace.value_at("%IW0", after) / 10)]
    return pts + [(t / 1e9, v / 10) for t, v in trace.changes("%IW0") if after * 1e9 < t <= until * 1e9]


def last_outside(pts: list[tuple[float, float]], target: float, band: float) -> float:
    """The last time the temperature was outside target +/- band (the start if never)."""
    times = [t for t, c in pts if abs(c - target) > band]
    return times[-1] if times else pts[0][0]


def changes_to(trace, name: str, value: int) -> list[float]:
    return [t / 1e9 for t, v in trace.changes(name)[1:] if v == value]


def test_auto1_setpoint_step_40_to_50_settles_within_1_c_in_under_300_s_with_overshoot_under_2_c(traces):
    tr = traces["step"].trace
    step = changes_to(tr, "SETPOINT", 50)[0]
    back = changes_to(tr, "SETPOINT", 40)[-1]
    assert tr.value_at("MODE", step) == thermo.AUTO1 and abs(tr.value_at("%IW0", step - 1) - 400) <= 5
    pts = temperature(tr, step, back)
    settled = last_outside(pts, 50, 1.0)
    overshoot = max(c for _t, c in pts) - 50
    print(f"step 40 -> 50 C: within +/-1 C after {settled - step:.1f} s, overshoot {overshoot:.1f} C")
    assert settled - step < 300, f"settled after {settled - step:.1f} s"
    assert overshoot < 2.0
    # and it stays settled: the last 100 s before the step back are within +/-0.3 C
    assert all(abs(c - 50) <= 0.3 for t, c in pts if t > back - 100)


def test_auto1_fan_disturbance_deviates_less_than_1_5_c_and_returns_within_1_c(traces):
    tr = traces["disturbance"].trace
    on, off = tr.edges("DISTURBANCE", "rising")[0], tr.edges("DISTURBANCE", "falling")[0]
    assert tr.value_at("FAN", on + 0.1) == 500 and tr.value_at("FAN", off + 0.1) == 0
    for start, end in ((on, off), (off, tr.end_s)):
        pts = temperature(tr, start, end)
        deviation = max(abs(c - 40) for _t, c in pts)
        print(f"fan disturbance at {start:.0f} s: largest deviation {deviation:.1f} C")
        assert deviation < 1.5
        assert abs(pts[-1][1] - 40) <= 1.0
        assert all(abs(c - 40) <= 0.3 for t, c in pts if t > end - 100)     # the integral removed the offset


def test_auto2_heater_disturbance_is_back_within_1_c_in_under_300_s(traces):
    tr = traces["auto2"].trace
    on, off = tr.edges("DISTURBANCE", "rising")[0], tr.edges("DISTURBANCE", "falling")[0]
    assert tr.value_at("MODE", on) == thermo.AUTO2
    assert tr.value_at("HEATER", on + 0.1) == 2000 and tr.value_at("HEATER", off + 0.1) == 1000
    for start, end in ((on, off), (off, tr.end_s)):
        pts = temperature(tr, start, end)
        back = last_outside(pts, 45, 1.0) - start
        print(f"heater disturbance at {start:.0f} s: within +/-1 C after {back:.0f} s, "
              f"largest deviation {max(abs(c - 45) for _t, c in pts):.1f} C")
        assert back < 300
        assert all(abs(c - 45) <= 0.3 for t, c in pts if t > end - 100)
    # the fan regulated: it rose when the heater doubled and came back down after
    fan = [v for t, v in tr.changes("FAN") if on * 1e9 <= t <= off * 1e9]
    assert max(fan) > 600 and tr.value_at("FAN", tr.end_s) < 200


def test_commands_are_output_with_the_scan_and_reported_in_automatic_modes(traces):
    tr = traces["step"].trace
    for t, v in tr.changes("HEATER")[1:]:
        assert tr.value_at_ns("%MW2", t) == v         # %MW2 reports the heater command in automatic-1
    tr = traces["manual"].trace
    assert tr.value_at("HEATER", 0.25) == 2000          # %MW2 = 2000 written at 0.2 s, output by the next scan


def test_fan_speed_register_counts_pulses_per_second_across_the_counter_wrap(traces):
    s = traces["manual"]
    wraps = [t for (t, a), (_t2, b) in zip(s.trace.changes("FAN_COUNT"), s.trace.changes("FAN_COUNT")[1:])
             if b < a]
    assert wraps, "the 16-bit counter never wrapped in the manual scenario"
    w = wraps[0] / 1e9
    assert all(v == 100 for _t, v in thermo.samples(s, "FAN_SPEED", w - 5, w + 5))


def test_open_sensor_switches_the_heater_off_in_the_same_scan(traces):
    tr = traces["sensor_open"].trace
    opened = tr.first(lambda io: io["%IW0"] >= 1000)
    assert tr.value_at("HEATER", opened) == 0 and tr.value_at("HEATER", opened - 0.1) > 0
    assert tr.value_at("MODE", opened + 60) == thermo.AUTO1
    assert tr.value_at("TEMPERATURE", opened) == 100


def test_mode_changes_are_bumpless(traces):
    s = traces["modes"]
    bumps = [a.text for a in s.actions if "largest step" in a.text]
    assert len(bumps) == 6
    for text in bumps:
        assert int(text.split("largest step ")[1].split()[0]) <= 100, text


# --------------------------------------------------------------------------- negative controls

def patched(old: str, new: str) -> list[tuple[str, str]]:
    """The shipped program with one change in a POU (for the negative controls)."""
    out, hits = [], 0
    for name, text in sources(thermo.STAND, "full"):
        hits += text.count(old)
        out.append((name, text.replace(old, new)))
    assert hits == 1, f"{old!r} found {hits} times"
    return out


def test_without_tracking_a_mode_change_bumps_the_command(tmp_path):
    program = patched("Track := MODE <> MODE_AUTO1 OR Sensor.Open,", "Track := Sensor.Open,")
    with pytest.raises(thermo.ScenarioFailure, match="heater jumped by"):
        run("modes", tmp_path, program)


def test_without_anti_windup_the_setpoint_step_overshoots(tmp_path):
    program = patched("IF NOT ((Unclamped > OutMax AND Error > 0.0) OR (Unclamped < OutMin AND Error < 0.0)) THEN",
                      "IF TRUE THEN")
    with pytest.raises(thermo.ScenarioFailure, match="overshoot"):
        run("step", tmp_path, program)


def test_a_program_that_ignores_the_open_sensor_is_caught(tmp_path):
    program = patched("IF Sensor.Open THEN\n    HeaterCmd := 0;", "IF FALSE THEN\n    HeaterCmd := 0;")
    with pytest.raises(thermo.ScenarioFailure, match="with the sensor open: heater 1000"):
        run("sensor_open", tmp_path, program)


# --------------------------------------------------------------------------- SCADA writes in scenarios

def test_scenario_writes_go_through_the_twido_map(tmp_path):
    s = thermo.session(retain_path=tmp_path / "retain.json")
    assert s.scada.read("SETPOINT") == 40                       # power-up setpoint
    assert s.scada.refused("HEATER_CTRL", 2500) == 3            # outside 0..2000
    assert s.scada.refused("TEMPERATURE", 30) == 3              # read only
    assert s.scada.refused("SETPOINT", 80) == 3                 # outside 25..70
    assert s.scada.refused("MODE", 3) == 3
    s.scada.write(MODE=thermo.AUTO1)
    assert s.scada.refused("HEATER_CTRL", 100) == 3             # automatic mode: monitoring only
    with pytest.raises(thermo.ScenarioFailure, match=r"HEATER_CTRL \(%MW2\) = 100 refused"):
        s.scada.write(HEATER_CTRL=100)
    s.scada.write(MODE=thermo.MANUAL, HEATER_CTRL=100)
    assert s.value("HEATER") == 100


# --------------------------------------------------------------------------- golden trace

def test_demo_matches_its_golden_trace(traces):
    s = traces["demo"]
    check_golden(s.trace, "thermo-full-demo", s.tick)
