"""The pulse-count drive at full speed (the paper's position-control module): with DDA and
digital integration PRG_CncStand sends each interpolation cycle's increments as counts
(FB_CncDdaPulses with Counts), so the feed is not capped by the 1 ms fine cycle; the pulse
generator spreads them. Property: a cycle's count is its increment in pulses, rounded with
the remainder carried (running error within half a pulse, no drift over 10^5 cycles); on
the stand a part at 6 m/min keeps every frame within its bound and takes L / V."""
from __future__ import annotations

import math
from functools import lru_cache

from hypothesis import given, settings, strategies as st

from cnc_st import Runner, pou
from plclab.nc.gcode import parse
from plclab.nc.toolpath import check_blocks
from plclab.plants.base import signed16
from plclab.stands import cnc

EPS = 0.01
CYCLES = 200
T = 0.004                    # PRG_CncStand: the interpolation cycle


@lru_cache(maxsize=None)
def counts_program() -> Runner:
    """FB_CncDdaPulses with Counts: one Cycle call per cycle, then the cycle's other three
    fine steps (which must issue nothing); records the counts."""
    return Runner(pou("FB_CncDdaPulses") + f"""
PROGRAM main
VAR
    Dda : FB_CncDdaPulses;
    Go : BOOL; Cycles : DINT; Eps : LREAL := 0.01; D : LREAL; Long : BOOL;
    IncX : ARRAY[1..{CYCLES}] OF LREAL;
    IncY : ARRAY[1..{CYCLES}] OF LREAL;
    CX : ARRAY[1..{CYCLES}] OF DINT;
    CY : ARRAY[1..{CYCLES}] OF DINT;
    Stray : BOOL;              (* a step output, an overrun or a count outside a Cycle call *)
    Sum : LREAL; Issued : DINT; MaxError : LREAL;
    c : DINT; k : INT;
END_VAR
IF Go THEN
    Go := FALSE;
    Stray := FALSE;
    Sum := 0.0; MaxError := 0.0;
    Dda(Reset := TRUE, Cycle := FALSE, Counts := TRUE, DX := 0.0, DY := 0.0, DZ := 0.0, N := 4, Eps := Eps);
    Dda(Reset := FALSE);
    FOR c := 1 TO Cycles DO
        IF Long THEN
            Dda(Cycle := TRUE, DX := D, DY := -D / 3.0);
            Sum := Sum + D;
            MaxError := MAX(MaxError, ABS(Sum / Eps - DINT_TO_LREAL(Dda.PulsesX)));
        ELSE
            Dda(Cycle := TRUE, DX := IncX[c], DY := IncY[c]);
            CX[c] := Dda.CountX; CY[c] := Dda.CountY;
        END_IF;
        Stray := Stray OR Dda.StepX OR Dda.StepY OR Dda.Overrun;
        FOR k := 2 TO 4 DO
            Dda(Cycle := FALSE);
            Stray := Stray OR Dda.StepX OR Dda.StepY OR Dda.Overrun OR Dda.CountX <> 0 OR Dda.CountY <> 0;
        END_FOR;
    END_FOR;
END_IF;
END_PROGRAM
""")


increments = st.floats(-0.8, 0.8)      # up to 80 pulses a cycle: 20 m/min at 10 um


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(increments, increments), min_size=1, max_size=CYCLES))
def test_a_cycles_count_is_its_increment_rounded_with_the_remainder_carried(incs):
    run = counts_program().run(Long=False, Cycles=len(incs), **{f"IncX[{c + 1}]": x for c, (x, _) in enumerate(incs)},
                               **{f"IncY[{c + 1}]": y for c, (_, y) in enumerate(incs)})
    assert not run["Stray"], "a step output or a count outside the cycle's call"
    for axis, counts in ((0, run["CX"]), (1, run["CY"])):
        commanded, issued = 0.0, 0
        for c, inc in enumerate(i[axis] for i in incs):
            count = counts[c]
            assert count == 0 or (count > 0) == (inc > 0), f"cycle {c + 1}: count {count} against increment {inc}"
            commanded += inc
            issued += count
            assert abs(commanded / EPS - issued) <= 0.5 + 1e-6, \
                f"axis {axis} after cycle {c + 1}: running error {commanded / EPS - issued:.4f} pulses"


def test_counts_do_not_drift_over_100000_cycles():
    d = 0.271828                         # 27.18 pulses a cycle on X, -9.06 on Y
    run = counts_program().run(Long=True, Cycles=100_000, D=d)
    assert not run["Stray"]
    assert run["MaxError"] <= 0.5 + 1e-6, f"running error reached {run['MaxError']:.6f} pulses"
    assert run["Dda.PulsesX"] == round(100_000 * d / EPS)
    assert run["Dda.PulsesY"] == round(-100_000 * d / 3 / EPS)


PART = """(6 m/min: a line, a full circle, a diagonal back)
G21 G90 G17 F6000
G01 X20 Y0
G03 X20 Y0 I-10 J0
G01 X0 Y0
"""


def _run(method: str, drive: str):
    s = cnc.session()
    run = cnc.run_part(s, parse(PART).frames, method, drive=drive)
    assert run.finished and run.missed == {"X": 0, "Y": 0, "Z": 0}
    return s, run


def test_the_pulse_counts_carry_6_m_min_within_every_bound():
    for method in ("dda", "integration"):
        s, run = _run(method, "pulse")
        blocks = check_blocks(run.executed, run.points, EPS, method, run.start, drive="pulse")
        assert all(b.ok for b in blocks), [b.row() for b in blocks if not b.ok]
        assert run.points[-1][2:] == (0, 0, 0)
        largest = max(abs(signed16(v)) for _t, v in s.trace.changes("PULSES_X"))
        assert largest > 4 * T * 1000, f"at most {largest} pulses a cycle: capped by the fine cycle"
        if method == "dda":                    # DDA's lines run at the feed from the first cycle
            assert abs(blocks[0].time_s - 20.0 / 100.0) <= 2 * T, blocks[0].row()
            assert abs(blocks[2].time_s - 20.0 / 100.0) <= 2 * T, blocks[2].row()
        # the arc, with digital integration's acceleration to 100 mm/s and back (200 mm/s^2)
        ramp = 100.0 / 200.0
        assert 2 * math.pi * 10 / 100.0 <= blocks[1].time_s <= 2 * math.pi * 10 / 100.0 + ramp + 2 * T


def test_the_step_drive_stays_at_one_step_per_fine_cycle():
    s, run = _run("dda", "step")
    blocks = check_blocks(run.executed, run.points, EPS, "dda", run.start)
    assert all(b.ok for b in blocks)
    assert blocks[0].time_s >= 20.0 / 10.0 - 2 * T       # 600 mm/min: 10 mm/s at most
    assert not s.trace.changes("PULSES_X")[1:]            # no counts sent
