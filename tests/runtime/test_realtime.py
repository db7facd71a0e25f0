"""Real time, on a fake clock: drift compensation, overrun counting, PLC time = wall time."""
from __future__ import annotations

from plclab.frontend import check_sources
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.runtime.realtime import RealTimeRunner

PROGRAM = """
PROGRAM main
VAR n AT %QW0 : INT; q AT %QX0.0 : BOOL; END_VAR
VAR t : TON; END_VAR
n := n + 1;
t(IN := TRUE, PT := T#100ms);
q := t.Q;
END_PROGRAM
CONFIGURATION Config0 RESOURCE Res0 ON PLC
TASK fast (INTERVAL := T#10ms, PRIORITY := 0);
PROGRAM inst WITH fast : main;
END_RESOURCE END_CONFIGURATION
"""


class FakeClock:
    """Wall time that only moves when the runner sleeps, or when a scan 'takes' time."""

    def __init__(self, scan_cost=lambda k: 0.0):
        self.t = 1000.0
        self.scans = 0
        self.scan_cost = scan_cost

    def now(self) -> float:
        return self.t

    def sleep(self, dt: float) -> None:
        self.t += dt


def make(clock: FakeClock) -> RealTimeRunner:
    plc = PLC(compile_unit(check_sources([("rt.st", PROGRAM)])))

    def after_scan(plc: PLC) -> None:
        clock.t += clock.scan_cost(clock.scans)
        clock.scans += 1
    return RealTimeRunner(plc, on_scan=after_scan, clock=clock.now, sleep=clock.sleep)


def test_scans_keep_their_period_without_drift_when_each_scan_takes_time():
    clock = FakeClock(scan_cost=lambda k: 0.004)       # every scan costs 4 ms of the 10 ms
    runner = make(clock)
    runner.run_for(1.0)
    assert runner.stats.ticks == 101                    # t = 0, 10 ms, ..., 1000 ms: no drift
    assert runner.stats.overruns == 0
    assert runner.plc.read("inst.n") == 101
    assert runner.stats.max_lateness_s < 1e-9


def test_a_long_scan_is_an_overrun_and_the_missed_ticks_are_skipped_not_caught_up():
    clock = FakeClock(scan_cost=lambda k: 0.035 if k == 10 else 0.001)
    runner = make(clock)
    runner.run_for(0.5)
    assert runner.stats.overruns == 1
    # the scan of t = 100 ms ends at 136 ms: ticks 11 and 12 are lost, tick 13 (130 ms) runs late
    assert runner.stats.skipped_ticks == 2
    assert runner.stats.ticks == 51 - 2
    assert round(runner.stats.max_lateness_s, 6) == 0.025


def test_plc_time_is_wall_time_since_start_so_timers_follow_the_clock():
    clock = FakeClock()
    runner = make(clock)
    runner.run_for(0.09)
    assert runner.plc.read("inst.q") is False
    runner2 = make(FakeClock())
    runner2.run_for(0.1)
    assert runner2.plc.read("inst.q") is True           # TON PT=100 ms on the scan at t = 100 ms
    assert runner2.plc.now_ns == 100_000_000
