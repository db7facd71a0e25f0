"""Standard function blocks called from ST, run in virtual time.

Reference: OpenPLC v3's library, `utils/matiec_src/lib/*.txt` (bistable.txt,
edge_detection.txt, counter.txt, timer.txt) compiled into `webserver/core/lib/iec_std_FB.h`.
Timers read `__CURRENT_TIME`, which is the same for the whole scan and advances by one tick
between scans (webserver/core/main.cpp `updateTime()`); the first scan runs at t = 0.
The facts are collected in docs/openplc-stdlib-notes.md.
"""
from __future__ import annotations

import pytest

from st_helpers import MS, program, scan_until, val

pytestmark = pytest.mark.usefixtures("compile_mode")


# --------------------------------------------------------------------------- bistables

def test_sr_set_dominant():
    # bistable.txt SR: Q1 := S1 OR (NOT R AND Q1)
    sim = program("VAR s : BOOL; r : BOOL; q : BOOL; f : SR; END_VAR",
                  "f(S1 := s, R := r, Q1 => q);")
    sim.step(1)
    assert val(sim, "q") is False
    sim.set("main.s", True); sim.set("main.r", True); sim.step(1)
    assert val(sim, "q") is True            # both: set wins
    sim.set("main.s", False); sim.step(1)
    assert val(sim, "q") is False           # reset alone clears
    sim.set("main.r", False); sim.set("main.s", True); sim.step(1)
    sim.set("main.s", False); sim.step(3)
    assert val(sim, "q") is True            # latched


def test_rs_reset_dominant():
    # bistable.txt RS: Q1 := NOT R1 AND (S OR Q1)
    sim = program("VAR s : BOOL; r : BOOL; q : BOOL; f : RS; END_VAR",
                  "f(S := s, R1 := r); q := f.Q1;")
    sim.set("main.s", True); sim.step(1)
    assert val(sim, "q") is True
    sim.set("main.s", False); sim.step(2)
    assert val(sim, "q") is True            # latched
    sim.set("main.s", True); sim.set("main.r", True); sim.step(1)
    assert val(sim, "q") is False           # both: reset wins


# --------------------------------------------------------------------------- edges

def test_r_trig_pulse_lasts_one_scan():
    sim = program("VAR x : BOOL; q : BOOL; n : INT; f : R_TRIG; END_VAR",
                  "f(CLK := x); q := f.Q; IF f.Q THEN n := n + 1; END_IF;")
    sim.step(2)
    assert val(sim, "n") == 0
    sim.set("main.x", True); sim.step(1)
    assert val(sim, "q") is True
    sim.step(1)
    assert val(sim, "q") is False           # only one scan
    sim.step(5)
    sim.set("main.x", False); sim.step(2)
    sim.set("main.x", True); sim.step(1)
    assert val(sim, "n") == 2


def test_r_trig_fires_on_first_scan_when_clk_already_true():
    # edge_detection.txt: M starts FALSE, so Q := CLK AND NOT M is TRUE on the first call
    sim = program("VAR x : BOOL := TRUE; q : BOOL; f : R_TRIG; END_VAR",
                  "f(CLK := x, Q => q);")
    sim.step(1)
    assert val(sim, "q") is True
    sim.step(1)
    assert val(sim, "q") is False


def test_f_trig_does_not_fire_on_first_scan():
    # OpenPLC's edge_detection.txt F_TRIG: Q := NOT CLK AND M; M := CLK (M starts FALSE).
    # Upstream matiec (Q := NOT CLK AND NOT M; M := NOT CLK) would fire here.
    sim = program("VAR x : BOOL; q : BOOL; n : INT; f : F_TRIG; END_VAR",
                  "f(CLK := x, Q => q); IF q THEN n := n + 1; END_IF;")
    sim.step(3)
    assert val(sim, "n") == 0


def test_f_trig_fires_once_on_falling_edge():
    sim = program("VAR x : BOOL := TRUE; q : BOOL; n : INT; f : F_TRIG; END_VAR",
                  "f(CLK := x, Q => q); IF q THEN n := n + 1; END_IF;")
    sim.step(3)
    assert val(sim, "n") == 0
    sim.set("main.x", False); sim.step(1)
    assert val(sim, "q") is True
    sim.step(3)
    assert val(sim, "q") is False
    assert val(sim, "n") == 1


# --------------------------------------------------------------------------- counters

CTU_DECLS = "VAR cu : BOOL; r : BOOL; q : BOOL; cv : INT; c : CTU; END_VAR"
CTU_BODY = "c(CU := cu, R := r, PV := 3, Q => q, CV => cv);"


def pulse(sim, name, n=1):
    for _ in range(n):
        sim.set(name, True); sim.step(1)
        sim.set(name, False); sim.step(1)


def test_ctu_counts_rising_edges_not_levels():
    sim = program(CTU_DECLS, CTU_BODY)
    sim.set("main.cu", True); sim.step(5)      # held high: one count
    assert val(sim, "cv") == 1
    sim.set("main.cu", False); sim.step(1)
    pulse(sim, "main.cu")
    assert val(sim, "cv") == 2
    assert val(sim, "q") is False


def test_ctu_q_at_pv_and_cv_saturates():
    # counter.txt CTU: counts only while CV < PV; Q := CV >= PV
    sim = program(CTU_DECLS, CTU_BODY)
    pulse(sim, "main.cu", 3)
    assert val(sim, "cv") == 3 and val(sim, "q") is True
    pulse(sim, "main.cu", 4)
    assert val(sim, "cv") == 3


def test_ctu_reset_has_priority_over_count():
    sim = program(CTU_DECLS, CTU_BODY)
    pulse(sim, "main.cu", 2)
    sim.set("main.r", True); sim.set("main.cu", True); sim.step(1)
    assert val(sim, "cv") == 0 and val(sim, "q") is False


def test_ctd_load_and_count_down_to_zero():
    # counter.txt CTD: LD loads PV; counts down while CV > 0; Q := CV <= 0
    sim = program("VAR cd : BOOL; ld : BOOL; q : BOOL; cv : INT; c : CTD; END_VAR",
                  "c(CD := cd, LD := ld, PV := 2, Q => q, CV => cv);")
    sim.step(1)
    assert val(sim, "q") is True              # CV = 0 initially
    sim.set("main.ld", True); sim.step(1); sim.set("main.ld", False)
    assert val(sim, "cv") == 2 and val(sim, "q") is False
    pulse(sim, "main.cd")
    assert val(sim, "cv") == 1 and val(sim, "q") is False
    pulse(sim, "main.cd", 3)
    assert val(sim, "cv") == 0 and val(sim, "q") is True   # never below 0


def test_ctud_up_down_simultaneous_and_reset():
    # counter.txt CTUD: R first, then LD; simultaneous CU and CD edges cancel
    sim = program("VAR cu, cd, r, ld : BOOL; qu, qd : BOOL; cv : INT; c : CTUD; END_VAR",
                  "c(CU := cu, CD := cd, R := r, LD := ld, PV := 2, QU => qu, QD => qd, CV => cv);")
    sim.step(1)
    assert val(sim, "qd") is True and val(sim, "qu") is False
    pulse(sim, "main.cu", 2)
    assert val(sim, "cv") == 2 and val(sim, "qu") is True and val(sim, "qd") is False
    sim.set("main.cu", True); sim.set("main.cd", True); sim.step(1)
    assert val(sim, "cv") == 2                 # both edges: no change
    sim.set("main.cu", False); sim.step(1)
    sim.set("main.cd", False); sim.step(1)
    pulse(sim, "main.cd")
    assert val(sim, "cv") == 1
    sim.set("main.r", True); sim.set("main.ld", True); sim.step(1)
    assert val(sim, "cv") == 0                 # R beats LD


# --------------------------------------------------------------------------- timers (10 ms tick)

TIMER_DECLS = "VAR x : BOOL; q : BOOL; et : TIME; t : {fb}; END_VAR"
TIMER_BODY = "t(IN := x, PT := T#100ms, Q => q, ET => et);"


def timer(fb: str):
    return program(TIMER_DECLS.format(fb=fb), TIMER_BODY, tick_ms=10)


def test_ton_q_rises_exactly_at_t0_plus_pt():
    sim = timer("TON")
    sim.step(3)                                 # t = 0, 10, 20 ms
    t0 = sim.plc.now_ns                         # 30 ms: the scan that sees IN rise
    sim.set("main.x", True)
    rise = scan_until(sim, "q", True)
    assert rise == t0 + 100 * MS
    assert val(sim, "et") == 100 * MS


def test_ton_et_runs_and_short_pulse_never_sets_q():
    sim = timer("TON")
    sim.set("main.x", True); sim.step(1)        # starts at t = 0; ET not updated on that call
    assert val(sim, "et") == 0
    sim.step(5)                                 # scans at 10..50 ms
    assert val(sim, "et") == 50 * MS and val(sim, "q") is False
    sim.set("main.x", False); sim.step(1)
    assert val(sim, "et") == 0
    sim.set("main.x", True); sim.step(9)        # restarted at 70 ms; at 150 ms only 80 ms ran
    assert val(sim, "q") is False
    sim.set("main.x", False); sim.step(20)
    assert val(sim, "q") is False


def test_ton_q_drops_with_in():
    sim = timer("TON")
    sim.set("main.x", True); sim.step(15)
    assert val(sim, "q") is True
    sim.set("main.x", False); sim.step(1)
    assert val(sim, "q") is False and val(sim, "et") == 0


def test_tof_q_falls_exactly_pt_after_in_falls():
    sim = timer("TOF")
    sim.step(2)
    assert val(sim, "q") is False               # IN FALSE at start-up does not start it
    sim.set("main.x", True); sim.step(1)
    assert val(sim, "q") is True
    sim.step(4)
    t_fall = sim.plc.now_ns
    sim.set("main.x", False)
    off = scan_until(sim, "q", False)
    assert off == t_fall + 100 * MS
    assert val(sim, "et") == 100 * MS


def test_tof_retriggered_by_in_before_expiry():
    sim = timer("TOF")
    sim.set("main.x", True); sim.step(1)
    sim.set("main.x", False); sim.step(8)       # 80 ms off
    sim.set("main.x", True); sim.step(1)        # back on: ET cleared
    assert val(sim, "q") is True and val(sim, "et") == 0
    sim.set("main.x", False); sim.step(10)      # 10 scans: 0..90 ms after the fall
    assert val(sim, "q") is True
    sim.step(1)
    assert val(sim, "q") is False


def test_tp_pulse_has_exact_length_and_is_not_retriggerable():
    sim = timer("TP")
    sim.step(1)
    t0 = sim.plc.now_ns
    sim.set("main.x", True); sim.step(1)
    assert val(sim, "q") is True
    sim.set("main.x", False); sim.step(3)       # IN falls: pulse goes on
    sim.set("main.x", True); sim.step(1)        # a new rise during the pulse is ignored
    assert val(sim, "q") is True
    end = scan_until(sim, "q", False)
    assert end == t0 + 100 * MS
    assert val(sim, "et") == 100 * MS           # held while IN is still TRUE
    sim.set("main.x", False); sim.step(1)
    assert val(sim, "et") == 0


def test_timer_initialised_in_declaration():
    # an FB instance initialiser: t : TON := (PT := T#50ms)
    sim = program("VAR x : BOOL := TRUE; q : BOOL; t : TON := (PT := T#50ms); END_VAR",
                  "t(IN := x); q := t.Q;", tick_ms=10)
    assert scan_until(sim, "q", True) == 50 * MS


def test_timers_read_one_clock_per_scan():
    # two TONs started in the same scan with the same PT finish in the same scan, even if
    # one is called later in the body (the clock is __CURRENT_TIME, constant for a scan)
    sim = program("VAR a, b : BOOL; t1 : TON; t2 : TON; n : INT; END_VAR",
                  "t1(IN := TRUE, PT := T#30ms); n := n + 1; t2(IN := TRUE, PT := T#30ms);"
                  "a := t1.Q; b := t2.Q;", tick_ms=10)
    sim.step(3)
    assert (val(sim, "a"), val(sim, "b")) == (False, False)
    sim.step(1)
    assert (val(sim, "a"), val(sim, "b")) == (True, True)


def test_ton_in_slow_task_counts_time_not_scans():
    # a TON in a 50 ms task, base tick 10 ms: PT = 120 ms elapses on the task's scan at
    # 150 ms (the first one at or after 120 ms), not after 120 / 10 calls
    src = """
PROGRAM slow
VAR q : BOOL; t : TON; calls : INT; END_VAR
t(IN := TRUE, PT := T#120ms); q := t.Q; calls := calls + 1;
END_PROGRAM
PROGRAM fast
VAR n : INT; END_VAR
n := n + 1;
END_PROGRAM
CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK t_fast(INTERVAL := T#10ms, PRIORITY := 1);
    TASK t_slow(INTERVAL := T#50ms, PRIORITY := 2);
    PROGRAM f WITH t_fast : fast;
    PROGRAM s WITH t_slow : slow;
  END_RESOURCE
END_CONFIGURATION
"""
    from st_helpers import load
    sim = load(src)
    assert sim.plc.tick_ns == 10 * MS
    rise = None
    for _ in range(30):
        t = sim.plc.now_ns
        sim.step(1)
        if sim.plc.read("s.q"):
            rise = t
            break
    assert rise == 150 * MS
    assert sim.plc.read("s.calls") == 4          # scans at 0, 50, 100, 150 ms
