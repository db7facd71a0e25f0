"""Standard function blocks with OpenPLC's semantics (plclab.runtime.stdfb).

"FB.h" below is webserver/core/lib/iec_std_FB.h and "main.cpp" webserver/core/main.cpp in
thiagoralves/OpenPLC_v3. Timers are driven by a ScanClock advanced by one tick after every
scan, the way OpenPLC's updateTime() advances __CURRENT_TIME.
"""
from __future__ import annotations

import pytest

from plclab.iec.types import DINT, INT, TIME, UDINT, to_f32
from plclab.runtime import stdfb as F
from plclab.runtime.stdfb import (CTD, CTU, CTUD, F_TRIG, R_TRIG, RS, RTC, SR, TOF, TON, TP,
                                  ScanClock)

MS = 1_000_000
S_ = 1_000_000_000
TICK = 10 * MS


class Scans:
    """Runs one FB instance scan by scan in virtual time, recording (t_ms, Q, ET_ms)."""

    def __init__(self, fb_type, pt_ms: int, tick: int = TICK) -> None:
        self.clock = ScanClock()
        self.tick = tick
        self.fb = fb_type(clock=self.clock)
        self.fb.PT = pt_ms * MS

    def scan(self, IN: bool, n: int = 1) -> list[tuple[int, bool, int]]:
        out = []
        for _ in range(n):
            self.fb.IN = IN
            self.fb()
            out.append((self.clock.now // MS, self.fb.Q, self.fb.ET // MS))
            self.clock.advance(self.tick)      # main.cpp: updateTime() after config_run__()
        return out


# --------------------------------------------------------------------------- edges, bistables


def test_r_trig_pulses_for_one_call_on_each_rising_edge():
    r = R_TRIG()
    seen = []
    for clk in (False, True, True, False, True):
        r.CLK = clk
        r()
        seen.append(r.Q)
    assert seen == [False, True, False, False, True]


def test_r_trig_fires_on_the_first_call_when_clk_starts_true():
    # FB.h R_TRIG: M is initialised FALSE
    r = R_TRIG()
    r.CLK = True
    r()
    assert r.Q is True


def test_f_trig_does_not_fire_on_the_first_scan_with_clk_false():
    # OpenPLC PR #135: Q := NOT CLK AND M; M := CLK (upstream matiec stores NOT CLK)
    f = F_TRIG()
    f.CLK = False
    f()
    assert f.Q is False


def test_f_trig_pulses_once_after_true_to_false():
    f = F_TRIG()
    seen = []
    for clk in (False, True, False, False, True, False):
        f.CLK = clk
        f()
        seen.append(f.Q)
    assert seen == [False, False, True, False, False, True]


def test_sr_is_set_dominant_and_rs_reset_dominant():
    sr, rs = SR(), RS()
    sr.S1, sr.R = True, True
    rs.S, rs.R1 = True, True
    sr()
    rs()
    assert (sr.Q1, rs.Q1) == (True, False)


def test_sr_latches_until_reset():
    sr = SR()
    seen = []
    for s1, r in ((True, False), (False, False), (False, True), (False, False)):
        sr.S1, sr.R = s1, r
        sr()
        seen.append(sr.Q1)
    assert seen == [True, True, False, False]


# --------------------------------------------------------------------------- counters


def pulse(fb, name: str, times: int = 1) -> None:
    for _ in range(times):
        setattr(fb, name, True)
        fb()
        setattr(fb, name, False)
        fb()


def test_ctu_counts_rising_edges_and_stops_at_pv():
    c = CTU()
    c.PV = 3
    pulse(c, "CU", 2)
    assert (c.CV, c.Q) == (2, False)
    pulse(c, "CU", 5)
    assert (c.CV, c.Q) == (3, True)      # counter.txt: counts only while CV < PV


def test_ctu_counts_an_input_that_is_already_on_at_start_up():
    c = CTU()
    c.PV, c.CU = 10, True
    c()
    c()
    assert c.CV == 1


def test_ctu_reset_has_priority_over_counting():
    c = CTU()
    c.PV = 5
    pulse(c, "CU", 2)
    c.R, c.CU = True, True
    c()
    assert (c.CV, c.Q) == (0, False)


def test_ctu_q_is_true_with_pv_zero_before_any_count():
    c = CTU()
    c()
    assert c.Q is True                   # Q := CV >= PV with both 0


def test_ctd_loads_pv_and_counts_down_to_zero():
    c = CTD()
    c.PV, c.LD = 2, True
    c()
    c.LD = False
    assert (c.CV, c.Q) == (2, False)
    pulse(c, "CD", 5)
    assert (c.CV, c.Q) == (0, True)      # stops at 0, no wrap


def test_ctud_simultaneous_edges_cancel_and_reset_beats_load():
    c = CTUD()
    c.PV = 5
    pulse(c, "CU", 2)
    c.CU = c.CD = True
    c()
    assert c.CV == 2
    c.CU = c.CD = False
    c.R = c.LD = True
    c()
    assert (c.CV, c.QU, c.QD) == (0, False, True)


def test_ctud_counts_both_ways_with_qu_and_qd():
    c = CTUD()
    c.PV = 2
    pulse(c, "CU", 3)
    assert (c.CV, c.QU, c.QD) == (2, True, False)
    pulse(c, "CD", 1)
    assert (c.CV, c.QU, c.QD) == (1, False, False)


def test_typed_counters_exist_with_their_pv_types():
    assert dict(F.STANDARD_FBS["CTU_DINT"].INPUTS)["PV"] is DINT
    assert dict(F.STANDARD_FBS["CTUD_UDINT"].OUTPUTS)["CV"] is UDINT
    assert dict(CTU.INPUTS)["PV"] is INT
    c = F.STANDARD_FBS["CTU_LINT"]()
    c.PV = 2**40
    pulse(c, "CU")
    assert c.CV == 1


# --------------------------------------------------------------------------- timers


def test_ton_q_rises_exactly_on_the_scan_where_pt_has_elapsed():
    run = Scans(TON, pt_ms=100)
    trace = run.scan(True, 12)
    assert trace[9] == (90, False, 90)
    assert trace[10] == (100, True, 100)   # START + PT <= now at t = 100 ms
    assert trace[11] == (110, True, 100)   # ET stays at PT


def test_ton_first_scan_starts_without_updating_et():
    run = Scans(TON, pt_ms=100)
    assert run.scan(True, 2) == [(0, False, 0), (10, False, 10)]


def test_ton_resets_as_soon_as_in_falls():
    run = Scans(TON, pt_ms=50)
    run.scan(True, 8)
    assert run.scan(False) == [(80, False, 0)]
    assert run.scan(True, 2)[-1] == (100, False, 10)   # starts again from the new edge


def test_ton_with_pt_zero_needs_one_more_scan():
    run = Scans(TON, pt_ms=0)
    assert [q for _t, q, _et in run.scan(True, 2)] == [False, True]


def test_ton_is_driven_by_the_scan_clock_not_by_calls():
    run = Scans(TON, pt_ms=100, tick=50 * MS)
    assert [q for _t, q, _et in run.scan(True, 3)] == [False, False, True]


def test_tof_holds_q_for_pt_after_in_falls():
    run = Scans(TOF, pt_ms=30)
    assert run.scan(True) == [(0, True, 0)]
    assert run.scan(False, 5) == [(10, True, 0), (20, True, 10), (30, True, 20),
                                  (40, False, 30), (50, False, 30)]


def test_tof_is_retriggered_by_in_and_does_not_start_on_a_false_start_up():
    run = Scans(TOF, pt_ms=30)
    assert run.scan(False, 3)[-1][1] is False      # PREV_IN starts FALSE
    run.scan(True)
    run.scan(False, 2)
    run.scan(True)
    assert run.scan(False, 3)[-1] == (90, True, 20)  # restarted by the fall at 70 ms


def test_tp_gives_a_pulse_of_pt_even_if_in_falls_early():
    run = Scans(TP, pt_ms=30)
    seen = run.scan(True) + run.scan(False, 4)
    assert [q for _t, q, _et in seen] == [True, True, True, False, False]


def test_tp_is_not_retriggerable_while_pulsing():
    run = Scans(TP, pt_ms=30)
    run.scan(True)
    run.scan(False)
    seen = run.scan(True, 4)           # a new rising edge at 20 ms is ignored
    assert [q for _t, q, _et in seen] == [True, False, False, False]
    assert seen[-1][2] == 30           # ET holds PT while IN stays TRUE
    assert run.scan(False) == [(60, False, 0)]


def test_timers_need_a_clock():
    with pytest.raises(TypeError):
        TON()


def test_en_false_skips_the_body_and_clears_eno():
    run = Scans(TON, pt_ms=10)
    run.fb.EN = False
    run.scan(True, 5)
    assert (run.fb.ENO, run.fb.STATE, run.fb.Q) == (False, 0, False)


def test_instances_reject_misspelt_variables():
    with pytest.raises(AttributeError):
        TON(clock=ScanClock()).INN = True


# --------------------------------------------------------------------------- OpenPLC extras


def test_rtc_shows_plc_uptime_until_set_then_runs_from_pdt():
    clock = ScanClock()
    rtc = RTC(clock=clock)
    clock.advance(5 * S_)
    rtc()
    assert rtc.CDT == 5 * S_                 # 1970-01-01 + time since start
    rtc.IN, rtc.PDT = True, 1_000_000 * S_
    rtc()
    clock.advance(2 * S_)
    rtc()
    assert (rtc.Q, rtc.CDT) == (True, 1_000_002 * S_)


def test_hysteresis_switches_outside_the_band():
    h = F.HYSTERESIS()
    h.XIN2, h.EPS = 10.0, 1.0
    seen = []
    for x in (10.5, 11.5, 10.0, 9.5, 8.5):
        h.XIN1 = x
        h()
        seen.append(h.Q)
    assert seen == [False, True, True, True, False]


def test_sema_claims_until_released():
    s = F.SEMA()
    seen = []
    for claim, release in ((True, False), (False, False), (False, True)):
        s.CLAIM, s.RELEASE = claim, release
        s()
        seen.append(s.BUSY)
    assert seen == [True, True, False]


def test_integral_accumulates_xin_times_cycle_in_seconds():
    i = F.INTEGRAL()
    i.RUN, i.XIN, i.CYCLE = True, 2.0, 100 * MS
    for _ in range(5):
        i()
    assert i.XOUT == pytest.approx(1.0, rel=1e-6) and i.Q is True
    i.R1, i.X0 = True, 7.0
    i()
    assert (i.XOUT, i.Q) == (7.0, False)


def test_derivative_of_a_ramp_is_its_slope():
    d = F.DERIVATIVE()
    d.CYCLE = 100 * MS
    d.XIN = 0.0
    d()
    d.RUN = True
    for k in range(1, 6):
        d.XIN = float(k)          # +1 per 0.1 s
        d()
    assert d.XOUT == pytest.approx(10.0, rel=1e-5)


def test_pid_in_manual_outputs_kp_times_x0():
    p = F.PID()
    p.AUTO, p.KP, p.TR, p.X0, p.PV, p.SP, p.CYCLE = False, 2.0, 1.0, 5.0, 3.0, 1.0, 100 * MS
    p()
    assert p.XOUT == pytest.approx(10.0) and p.ERROR == 2.0   # ERROR is PV - SP


def test_ramp_moves_linearly_one_cycle_per_call():
    r = F.RAMP()
    r.X0, r.X1, r.TR, r.CYCLE = 0.0, 10.0, 1 * S_, 250 * MS
    r()
    r.RUN = True
    outs = []
    for _ in range(5):
        r()
        outs.append((r.XOUT, r.BUSY))
    assert outs == [(0.0, True), (2.5, True), (5.0, True), (7.5, True), (10.0, False)]


def test_registry_and_interfaces():
    assert {"SR", "RS", "R_TRIG", "F_TRIG", "CTU", "CTD", "CTUD", "TP", "TON", "TOF",
            "RTC", "PID"} <= set(F.STANDARD_FBS)
    assert [n for n, _t in TON.INPUTS] == ["IN", "PT"] and dict(TON.OUTPUTS)["ET"] is TIME
    assert F.create("ton", clock=ScanClock()).PT == 0
    assert R_TRIG.RETAIN == ("M",) and TON.NEEDS_CLOCK and not CTU.NEEDS_CLOCK


def test_real_outputs_are_single_precision():
    i = F.INTEGRAL()
    i.RUN, i.XIN, i.CYCLE = True, to_f32(0.1), 1 * S_
    i()
    assert i.XOUT == to_f32(0.1) and i.XOUT != 0.1
