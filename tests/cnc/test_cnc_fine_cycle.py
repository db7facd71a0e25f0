"""The stand at the fine cycle OpenPLC runs (`--fine-cycle MS`, docs/cnc.md "Fine cycle and
reachable feeds"): every frame's time in virtual time against its closed form, per method
and drive, at 1 ms and 5 ms -- lines on and off the axes, an arc, a rapid; and a feed the
stand cannot reach is said, with why.

Closed forms (PRG_CncStand, T = 4 fine cycles, h = 0.01 mm, V the programmed feed):
- evaluation function: one iteration per fine cycle at most, at the rate of eq. (5):
  max(L / V, N fine), N the iterations (|dx| + |dy| steps of a line; every step of an arc);
  a rapid N fine;
- DDA: L over the path feed min(V, one step per fine cycle) (step/direction drive) or
  min(V, PULSE_FEED_MAX) (pulse counts);
- digital integration: eq. (10)-(11) in quanta of T from rest to rest, the speed rising and
  falling by Accel T^2 per quantum (the textbook's recurrence counted here);
- arcs of DDA and digital integration: L / V + V / Accel (a trapezoid).
Tolerance: a fine cycle for the start, plus: for an evaluation-function arc one fine cycle
(saturated) or one step's time at the feed (eq. (9) step by step) per quadrant frame; one
interpolation cycle T where the frame ends inside a cycle (DDA, digital integration), two
for an arc (its last quantum ends on the end point); and with the pulse-count drive two T
more where the net steps of T are counted and then spread over the next T.
"""
from __future__ import annotations

import math
import re

import pytest

from plclab.cli import main
from plclab.nc.gcode import parse
from plclab.stands import cnc

H = 0.01                  # mm: the drives' step
ACCEL = 200.0             # mm/s^2: GVL_CNC.Accel
PULSE_MAX = 15_000.0      # steps/s: PRG_CncStand.PULSE_FEED_MAX
COMBOS = [("evalfn", "step"), ("evalfn", "pulse"), ("dda", "step"), ("dda", "pulse"), ("integration", "step"),
          ("integration", "pulse")]


def shapes(fine_ms: int) -> dict[str, str]:
    """Part programs: a feed half the evaluation function's 45-degree cap (unsaturated) and
    one far above every cap of the step drive (saturated)."""
    slow = {1: 200, 5: 40}[fine_ms]
    return {"axis": f"G01 X2 F{slow}", "off axis (3:4)": f"G01 X1.5 Y2 F{slow}", "45 degrees fast": "G01 X2 Y2 F3000",
            "arc": f"G03 X0 Y0 I1 J0 F{slow}", "rapid": "G00 X1.5 Y-2"}


def integration_quanta(length: float, vmax: float, a: float) -> int:
    """Eq. (10)-(11) from rest to rest: quanta of T until the path S reaches `length`
    (steps; vmax steps per quantum, a steps per quantum^2), braking once the rest is within
    V^2 / (2a), never below a."""
    s = v = 0.0
    n = 0
    while s < length:
        new = max(v - a, a) if length - s <= v * v / (2 * a) else min(v + a, vmax)
        s += (v + new) / 2
        v = new
        n += 1
    return n


def closed_form(frame, method: str, drive: str, fine: float) -> tuple[float, float]:
    """(time s, tolerance s) of `frame` run alone from the machine zero."""
    t = 4 * fine                                        # the interpolation cycle
    d = [round(e / H) - round(s / H) for s, e in zip(frame.start, frame.end)]
    length = 2 * math.pi * math.hypot(frame.i, frame.j) / H if frame.is_arc else math.hypot(*d)   # steps
    rapid = frame.kind == 0
    v = frame.feed / 60.0 / H                           # steps/s
    if method == "evalfn":
        late = 2 * t if drive == "pulse" else 0.0      # the counts of T, spread over the next T
        if frame.is_arc:
            r = round(math.hypot(frame.i, frame.j) / H)
            n = 8 * r                                   # a full circle: 2 R steps per axis per half turn
            if n * fine >= length / v:
                return n * fine, 5 * fine + late       # one fine cycle per quadrant frame, and the start
            return length / v, 4 / v + fine + late     # eq. (9) step by step: a step's time per quadrant
        n = abs(d[0]) + abs(d[1])
        return (n * fine if rapid else max(length / v, n * fine)), 2 * fine + late
    top = PULSE_MAX if drive == "pulse" else 1.0 / fine
    v = top if rapid else min(v, top)
    if frame.is_arc:                                    # the last quantum ends on the end point
        return length / v + v * H / ACCEL, 2 * t + fine
    if method == "dda":
        return length / v, t + fine
    quanta = integration_quanta(length, v * t, ACCEL / H * t * t)
    return quanta * t, t + fine


def frame_time(text: str, method: str, drive: str, fine_ms: int) -> tuple[float, object]:
    s = cnc.session(fine_ms=fine_ms)
    assert s.tick == pytest.approx(fine_ms / 1000)      # the task runs the fine cycle
    frames = parse("G21 G90 G17\n" + text + "\n").frames
    run = cnc.run_part(s, frames, method, drive=drive, timeout=60.0)
    assert run.finished and not any(run.missed.values())
    assert run.points[-1][2:] == tuple(round(v / H) for v in frames[0].end)
    return run.points[-1][0] - run.start, frames[0]


@pytest.mark.parametrize("fine_ms", [1, 5])
@pytest.mark.parametrize("method, drive", COMBOS)
def test_frame_times_are_the_closed_form_at_the_fine_cycle(fine_ms, method, drive):
    fine = fine_ms / 1000
    for shape, text in shapes(fine_ms).items():
        if shape == "arc" and drive == "pulse" and method == "evalfn":
            continue                                    # the same program as the step drive (net steps per T)
        took, frame = frame_time(text, method, drive, fine_ms)
        want, tolerance = closed_form(frame, method, drive, fine)
        assert abs(took - want) <= tolerance + 1e-9, (shape, method, drive, fine_ms, took, want, tolerance)


def test_the_45_degree_line_of_cnc_task_1_takes_what_openplc_measured(tmp_path, capsys):
    """The issue's measurement: G01 X20 Y20 F120 with the evaluation function, 14.14 s at
    1 ms (the feed), 20.0 s in OpenPLC's 5 ms (4000 iterations, one per fine cycle)."""
    part = tmp_path / "line.nc"
    part.write_text("G21 G90 G17\nG01 X20 Y20 F120\n", encoding="utf-8")
    times = {}
    for fine in (None, "5"):
        assert main(["cnc", str(part)] + (["--fine-cycle", fine] if fine else [])) == 0
        out = capsys.readouterr().out
        row = next(line for line in out.splitlines() if line.lstrip().startswith("1 "))
        times[fine] = float(row.split()[4])
        assert f"fine cycle {fine or 1} ms" in out
    assert times[None] == pytest.approx(28.284 / 2.0, abs=0.002 + 0.001)      # the start, a fine cycle
    assert 19.9 <= times["5"] <= 20.1


def test_a_feed_the_stand_cannot_reach_is_said_with_why(tmp_path, capsys):
    """F1200 at 45 degrees, evaluation function, 1 ms: 424 mm/min reached; the row is not
    "ok", a line says why, the CSV carries the same figures."""
    part = tmp_path / "fast.nc"
    part.write_text("G21 G90 G17\nG01 X20 Y20 F1200\nG00 X0 Y0\n", encoding="utf-8")
    csv = tmp_path / "path.csv"
    assert main(["cnc", str(part), "--csv", str(csv)]) == 0
    out = capsys.readouterr().out.splitlines()
    row = next(line for line in out if line.lstrip().startswith("1 "))
    programmed, reached, verdict = re.fullmatch(r".* G01 +28\.284 +4\.00\d .* (\S+) +(\S+)  (.*)", row).groups()
    assert programmed == "1200.0" and float(reached) == pytest.approx(424.3, abs=0.2)
    assert verdict == "in bound, BELOW THE FEED"
    why = out[out.index(row) + 1]
    assert why.strip().startswith("frame 1 reached 424 of F1200 mm/min (35%): the evaluation function makes one "
                                  "iteration per fine cycle (1 ms)")
    assert "4000 iterations for 28.284 mm: at most 424 mm/min" in why
    rapid = next(line for line in out if line.lstrip().startswith("2 "))
    assert rapid.split()[-3] == "rapid" and rapid.endswith(" ok")       # a rapid shows its rate
    assert float(rapid.split()[-2]) == pytest.approx(424.3, abs=0.5)
    assert out[-2] == "ok: every frame within its bound; 1 of 2 frames below their programmed feed (said above)"
    rows = csv.read_text(encoding="utf-8").splitlines()
    assert rows[0] == "time_s,X,Y,Z,frame,feed_mm_min,reached_mm_min"
    assert rows[1].split(",")[4:] == ["1", "1200.0", reached]
    assert rows[-1].split(",")[4:] == ["2", "", rapid.split()[-2]]


def test_a_reached_feed_is_ok_and_a_short_integration_frame_names_its_ramps(tmp_path, capsys):
    part = tmp_path / "ok.nc"
    part.write_text("G21 G90 G17\nG01 X2 F300\n", encoding="utf-8")
    assert main(["cnc", str(part), "--method", "dda"]) == 0          # 2 mm at 5 mm/s: 0.400 s
    row = next(line for line in capsys.readouterr().out.splitlines() if line.lstrip().startswith("1 "))
    assert re.fullmatch(r".* 0\.40\d .* 300\.0 +300\.\d  ok", row), row
    assert main(["cnc", str(part), "--method", "integration"]) == 0  # + V / A = 25 ms of ramps
    out = capsys.readouterr().out.splitlines()
    row = next(line for line in out if line.lstrip().startswith("1 "))
    assert row.endswith("  in bound, BELOW THE FEED")
    assert out[out.index(row) + 1].strip().startswith(
        "frame 1 reached 289 of F300 mm/min (96%): digital integration accelerates and decelerates at 200 mm/s^2")


def test_build_and_the_twin_run_one_program_at_one_cycle(tmp_path):
    """`plclab build cnc --fine-cycle 2` writes the task and FINE_MS the twin runs with
    `--fine-cycle 2`; a cycle out of range is one line."""
    from plclab.build import build_outputs
    from plclab.cnc.openplc import plant_params
    from plclab.errors import PlcLabError
    from plclab.stands import bundle, sources

    text = build_outputs("cnc", "full", xml=False, fine_cycle=2).st_text
    assert "TASK FineTask (INTERVAL := T#2ms, PRIORITY := 0);" in text and "FINE_MS : LREAL := 2.0;" in text
    twin = cnc.with_fine_cycle(sources(cnc.STAND, "full"), 2)
    assert "TASK FineTask (INTERVAL := T#2ms, PRIORITY := 0);" in twin[-1][1]
    assert "FINE_MS : LREAL := 2.0;" in dict(twin)[next(n for n, _ in twin if n.endswith("PRG_CncStand.st"))]
    assert plant_params(2) == {"pulse_cycle": 0.008}
    from plclab.modbus.psm import psm_script
    assert "PLANT = {'pulse_cycle': 0.008}" in psm_script("cnc", fine_ms=2)    # the PSM script in step
    with pytest.raises(PlcLabError, match="--fine-cycle is for the cnc stand"):
        psm_script("mp9c", fine_ms=2)
    assert "T#5ms" in build_outputs("cnc", "full", xml=False).st_text            # the OpenPLC default
    with pytest.raises(PlcLabError, match=r"--fine-cycle 0: the fine cycle is 1\.\.20 whole ms"):
        cnc.with_fine_cycle(sources(cnc.STAND, "full"), 0)
    with pytest.raises(PlcLabError, match="0 of PRG_CncStand's FINE_MS constant"):
        cnc.with_fine_cycle([("cnc.st", bundle(cnc.STAND, "full").replace("FINE_MS : LREAL := 1.0;", ""))], 5)
    with pytest.raises(PlcLabError, match="--fine-cycle is for the cnc stand"):
        build_outputs("mp9c", "full", xml=False, fine_cycle=5)


def test_run_scenario_at_the_openplc_fine_cycle(tmp_path, capsys):
    """`plclab run cnc --fine-cycle 5`: the demo square (80 mm at F300) runs at one step per
    5 ms, 120 mm/min: 40 s of plant time."""
    assert main(["run", "cnc", "--fine-cycle", "5", "--csv", str(tmp_path / "t.csv")]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "scenario demo passed (40.0 s of plant time)"


def test_the_openplc_build_reaches_a_high_feed_on_the_pulse_count_drive(tmp_path):
    """What docs/openplc.md tells a user who needs more than 120 mm/min in OpenPLC: DDA on
    the pulse-count drive (`plclab build cnc full --part P --method dda --drive pulse`). The
    bundle, run as OpenPLC runs it (5 ms, the PSM script's pulse generator), cuts
    G01 X20 Y20 F6000 in L / V = 0.283 s; on the step drive the same bundle takes 28.28 mm
    at 120 mm/min, 14.1 s."""
    from plclab.build import build_outputs
    from plclab.cnc.openplc import plant_params

    part = tmp_path / "fast.nc"
    part.write_text("G21 G90 G17\nG01 X20 Y20 F6000\n", encoding="utf-8")
    frames = parse(part.read_text(encoding="utf-8")).frames
    took = {}
    for drive in ("pulse", "step"):
        text = build_outputs("cnc", "full", xml=False, part=str(part), method="dda", drive=drive).st_text
        assert ("PulseDrive : BOOL := TRUE;" in text) == (drive == "pulse")
        s = cnc.session(program=[("cnc_full.st", text)], **plant_params())
        run = cnc.PartRun(frames, s.plant.step_mm, start=s.now)
        s.plant.press("SB1")                                 # the operator, on the console face
        cnc.record_until(s, run, "ProgramEnd", timeout=30.0, release=("SB1", s.now + 0.02))
        assert s.plc.read("ProgramEnd") and run.points[-1][2:] == (2000, 2000, 0)
        assert not any(s.plant.missed().values())
        took[drive] = run.points[-1][0] - run.start
    t = 4 * 0.005
    assert abs(took["pulse"] - 28.2843 / 100.0) <= 2 * t + 0.005, took
    assert abs(took["step"] - 28.2843 / 2.0) <= t + 0.005, took


def test_the_docs_feed_tables_are_what_the_twin_measures():
    """docs/cnc.md and docs/openplc.md show the reachable feeds the twin measures now
    (plclab.cnc.feeds.measure_table), not numbers written by hand."""
    from pathlib import Path

    from plclab.cnc.feeds import measure_table

    measured = "\n".join(measure_table())
    docs = Path(__file__).resolve().parents[2] / "docs"
    for name in ("cnc.md", "openplc.md"):
        text = (docs / name).read_text(encoding="utf-8")
        block = text.split("<!-- feeds table: python -m plclab.cnc.feeds -->\n")[1]
        assert block.split("\n<!-- end of the feeds table -->")[0] == measured, name
