"""The DDA pulse distribution of the position-control module (paper eq. (8)-(11)) and its
coarse linear interpolator (eq. (4)-(5)) in the soft PLC: no pulse lost, no drift over
10^5 cycles, at most one pulse per fine step, pulses evenly spread inside a cycle."""
from __future__ import annotations

import math

from hypothesis import example, given, settings, strategies as st

from cnc_st import Runner, dda, dda_long, pou

N, EPS = 4, 0.01             # fine steps per cycle, mm per pulse (the test programs' values)
LIMIT = N * EPS              # the largest increment per cycle with one pulse per fine step


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.floats(-LIMIT, LIMIT), st.floats(-LIMIT, LIMIT)), min_size=1, max_size=120))
def test_pulses_per_cycle_are_the_increment_rounded_with_the_remainder_carried(incs):
    run = dda().run(Cycles=len(incs), **{f"IncX[{c + 1}]": x for c, (x, _) in enumerate(incs)},
                    **{f"IncY[{c + 1}]": y for c, (_, y) in enumerate(incs)})
    assert not run["Overrun"]
    sx, sy = run["SX"], run["SY"]
    for axis, steps, counts in ((0, sx, run["CountX"]), (1, sy, run["CountY"])):
        commanded, issued = 0.0, 0
        for c, inc in enumerate(i[axis] for i in incs):
            cycle = steps[c * N:(c + 1) * N]
            carry = commanded / EPS - issued
            pulses = sum(cycle)
            want = inc / EPS + carry
            assert math.floor(want - 1e-9) <= pulses <= math.ceil(want + 1e-9), \
                f"axis {axis} cycle {c + 1}: {pulses} pulses for {want:.4f} pulses commanded (carry included)"
            assert all(s == 0 or (s > 0) == (inc > 0) for s in cycle), \
                f"axis {axis} cycle {c + 1}: a pulse against the direction of the increment {inc}"
            commanded += inc
            issued += pulses
            assert counts[c] == issued
            assert abs(commanded / EPS - issued) < 1.0, \
                f"axis {axis} after cycle {c + 1}: running error {commanded / EPS - issued:.4f} pulses"
            moves = [k for k, s in enumerate(cycle) if s]
            gaps = [b - a for a, b in zip(moves, moves[1:])]
            assert not gaps or max(gaps) - min(gaps) <= 1, f"axis {axis} cycle {c + 1}: uneven pulses {cycle}"


def test_no_loss_and_no_drift_over_100000_cycles():
    d = 0.0271828                           # 2.71828 pulses per cycle on X, -0.906 on Y
    run = dda_long().run(Cycles=100_000, D=d)
    assert run["MaxError"] < 1.0, f"running error reached {run['MaxError']:.6f} pulses"
    assert run["Dda.PulsesX"] == round(100_000 * d / EPS)
    assert run["Dda.PulsesY"] == round(-100_000 * d / 3 / EPS)
    assert run["MaxGap"] - run["MinGap"] <= 1, "pulses of a constant speed are not evenly spread"


def test_an_increment_beyond_one_pulse_per_fine_step_is_reported():
    run = dda().run(Cycles=2, **{"IncX[1]": 1.5 * LIMIT, "IncX[2]": 0.0, "IncY[1]": 0.0, "IncY[2]": 0.0})
    assert run["Overrun"]
    assert max(abs(s) for s in run["SX"][:2 * N]) == 1     # still one pulse per fine step at most


COARSE = pou("FB_CncDdaLinear") + """
PROGRAM main
VAR
    Coarse : FB_CncDdaLinear;
    Go : BOOL; DX : LREAL; DY : LREAL; DZ : LREAL; V : LREAL; T : LREAL;
    SumX : LREAL; SumY : LREAL; SumZ : LREAL; Cycles : DINT; MaxStep : LREAL; Off : LREAL;
END_VAR
IF Go THEN
    Go := FALSE;
    Coarse(Load := TRUE, DX := DX, DY := DY, DZ := DZ, V := V, T := T);
    SumX := 0.0; SumY := 0.0; SumZ := 0.0; Cycles := 0; MaxStep := 0.0; Off := 0.0;
    WHILE Coarse.Busy AND Cycles < 100000 DO
        Coarse(Load := FALSE);
        SumX := SumX + Coarse.IncX; SumY := SumY + Coarse.IncY; SumZ := SumZ + Coarse.IncZ;
        Cycles := Cycles + 1;
        MaxStep := MAX(MaxStep, SQRT(Coarse.IncX * Coarse.IncX + Coarse.IncY * Coarse.IncY + Coarse.IncZ * Coarse.IncZ));
        (* distance of the point reached from the line *)
        Off := MAX(Off, ABS(SumX * DY - SumY * DX) / Coarse.Length);
    END_WHILE;
END_IF;
END_PROGRAM
"""


@settings(max_examples=25, deadline=None)
@given(dx=st.integers(-50_000, 50_000), dy=st.integers(-50_000, 50_000), dz=st.integers(-5000, 5000),
       v=st.floats(20, 200), t=st.sampled_from([2.0, 4.0, 8.0]))
@example(dx=0, dy=25000, dz=0, v=20.0, t=2.0)     # 625 cycles of 0.04 mm: the sum falls short by rounding
def test_coarse_increments_follow_eq_4_and_add_up_to_the_segment(dx, dy, dz, v, t):
    dx, dy, dz = dx / 1000, dy / 1000, dz / 1000          # mm, to the micrometre
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    run = _coarse().run(DX=dx, DY=dy, DZ=dz, V=v, T=t)
    if length == 0:
        assert run["Cycles"] == 0
        return
    assert (run["SumX"], run["SumY"], run["SumZ"]) == (dx, dy, dz) or \
        max(abs(run["SumX"] - dx), abs(run["SumY"] - dy), abs(run["SumZ"] - dz)) < 1e-9
    dl = t * v / 1000.0
    assert run["Cycles"] == max(1, math.ceil(length / dl - 1e-6))   # a remainder < 1e-6 cycle is rounding
    assert run["MaxStep"] <= dl + 1e-9
    assert run["Off"] < 1e-9


_runner: list[Runner] = []


def _coarse() -> Runner:
    if not _runner:
        _runner.append(Runner(COARSE))
    return _runner[0]
