"""The pulse-count drive (the paper's position-control module): the PLC sends each
interpolation cycle's steps as signed counts on %QW with the cycle's number, the pulse
generator in the plant spreads them evenly over the cycle, and the drives count what they
receive. Property: no pulse lost, no drift, even spreading; on the stand the same end
positions as with step/direction bits."""
from __future__ import annotations

import random

import pytest
from hypothesis import given, settings, strategies as st

from plclab.nc.gcode import parse
from plclab.nc.toolpath import check_blocks
from plclab.plants.base import unsigned16
from plclab.plants.cnc import AXES, ENABLE, PULSE_CYCLE, PULSES, CncTable
from plclab.stands import cnc

FINE = 0.001          # the PLC's fine cycle (s)
NFINE = 4             # fine cycles per interpolation cycle T: the generator's period
T = NFINE * FINE


def feed_counts(table: CncTable, cycles: list[tuple[int, int, int]]) -> list[float]:
    """Play `cycles` (counts per axis) into the table as PRG_CncStand does: a new cycle
    number every T; returns the times the messages were handed over."""
    sent = []
    outputs = {ENABLE: 1}
    for number, counts in enumerate(cycles, start=1):
        outputs.update({PULSES[a]: unsigned16(c) for a, c in zip(AXES, counts)})
        outputs[PULSE_CYCLE] = number % 10000
        for k in range(NFINE):
            if k == 0:
                sent.append(table.time)
            table.step(outputs, FINE)
    for _ in range(NFINE + 1):            # let the generator spread the last cycle
        table.step(outputs, FINE)
    return sent


counts = st.tuples(*(st.integers(-NFINE, NFINE),) * 3)


@settings(max_examples=40, deadline=None)
@given(st.lists(counts, min_size=1, max_size=120))
def test_no_pulse_lost_and_every_cycle_evenly_spread(cycles):
    table = CncTable()
    table.log_pulses()
    sent = feed_counts(table, cycles)
    for i, a in enumerate(AXES):
        axis = table.axes[a]
        assert axis.steps == sum(c[i] for c in cycles)                   # no drift
        assert axis.received == sum(abs(c[i]) for c in cycles)            # no pulse lost
        assert axis.missed == 0 and not axis.pending
        times = table.pulse_log[a]
        for t0, c in zip(sent, cycles):
            n = abs(c[i])
            inside = [t for t in times if t0 <= t < t0 + T]
            assert len(inside) == n                                       # each inside its cycle
            if n:
                # evenly spread: pulse k at (k + 1/2) T / n, all gaps equal
                assert inside == pytest.approx([t0 + (k + 0.5) * T / n for k in range(n)], abs=1e-9)


def test_no_drift_over_ten_thousand_cycles_of_random_counts():
    rng = random.Random(14)
    cycles = [tuple(rng.randint(-NFINE, NFINE) for _ in AXES) for _ in range(10_000)]
    table = CncTable()
    feed_counts(table, cycles)
    for i, a in enumerate(AXES):
        assert table.axes[a].steps == sum(c[i] for c in cycles)
        assert table.axes[a].received == sum(abs(c[i]) for c in cycles)
        assert table.axes[a].missed == 0


def test_a_cycle_arriving_early_still_issues_the_pulses_left():
    table = CncTable(max_rate=1e5)            # the generator's part: the drive takes any rate
    out = {ENABLE: 1, PULSES["X"]: 4, PULSE_CYCLE: 1}
    table.step(out, FINE)
    out.update({PULSE_CYCLE: 2, PULSES["X"]: 3})     # the next cycle after 1 ms, not T
    for _ in range(2 * NFINE):
        table.step(out, FINE)
    assert table.axes["X"].steps == 7 and table.axes["X"].received == 7


def test_counts_beyond_the_drive_rate_are_missed_and_counted():
    table = CncTable(max_rate=500.0)          # 2 per T at most
    feed_counts(table, [(4, 0, 0)] * 10)
    x = table.axes["X"]
    assert x.received == 40 and x.missed > 0 and x.steps == 40 - x.missed


PART = """(lines in every quadrant and arcs both ways)
G21 G90 G17 F600
G01 X3 Y1
X-1 Y2
G03 X-1 Y-1 I0 J-1.5
G01 X2 Y-2
G02 X0 Y0 R2.2
"""


@pytest.mark.parametrize("method", ["evalfn", "dda", "integration"])
def test_step_and_pulse_drives_reach_the_same_points(method):
    ends, received = {}, {}
    frames = parse(PART).frames
    for drive in ("step", "pulse"):
        s = cnc.session()
        run = cnc.run_part(s, frames, method, drive=drive)
        assert run.finished and run.missed == {"X": 0, "Y": 0, "Z": 0}
        blocks = check_blocks(run.executed, run.points, 0.01, method, run.start, drive=drive)
        assert all(b.ok for b in blocks), (drive, [b.row() for b in blocks if not b.ok])
        ends[drive] = run.points[-1][2:]
        received[drive] = {a: s.plant.axes[a].received for a in "XY"}
        if drive == "pulse":
            assert s.plc.read("PULSE_CYCLE") > 0
            assert not any(s.plant.axes[a].step_line for a in "XYZ"), "step lines used in pulse mode"
    assert ends["step"] == ends["pulse"] == (0, 0, 0)
    # a reversal inside one cycle nets out in its count: never more pulses than steps
    assert all(received["pulse"][a] <= received["step"][a] for a in "XY")


def test_backlash_compensation_works_through_the_pulse_counts():
    s = cnc.session()
    s.plant.set_backlash(cnc.PLAY_STEPS)
    s.plc.write("Backlash", cnc.PLAY_STEPS)
    run = cnc.run_part(s, parse(cnc.BACKLASH).frames, "dda", drive="pulse")
    assert run.finished and run.points[-1][2:] == (0, 0, 0)
    assert all(b.ok for b in check_blocks(run.executed, run.points, 0.01, "dda", run.start, drive="pulse"))


def test_cli_drive_option(tmp_path, capsys):
    from plclab.cli import main

    part = tmp_path / "part.nc"
    part.write_text("G21 G90 F600\nG01 X1 Y0.5\nX0 Y0\n")
    assert main(["cnc", str(part), "--drive", "pulse"]) == 0
    out = capsys.readouterr().out
    assert "drive pulse" in out and "ok: every frame within its bound" in out
