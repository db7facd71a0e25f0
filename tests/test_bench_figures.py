"""`plclab bench`'s scan and memory figures: the functions run, report what they promise, and
stay above a recorded floor (below a recorded ceiling for memory). The targets themselves
(500x real time...) are `plclab bench`'s to report; the floors here are a tenth of what this
project's 2-core CI machine measured with the whole suite running beside it (2026-12-01),
so they never fail on a slow day and do fail when a change makes a figure ten times worse."""
from __future__ import annotations

from plclab.bench import PROGRAMS_DIR, bench_memory, bench_program
from plclab.frontend import check_sources
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.runtime.sim import Simulation
from plclab.stands import get_stand, sources

# recorded: bench300 45x real time (quick run, machine loaded); tur10 full loaded 0.39 MB,
# trace +31 MB per simulated hour
SPEEDUP_FLOOR = 4.5
LOADED_MB_CEILING = 3.9
MB_PER_HOUR_CEILING = 310.0


def test_bench_program_counts_the_scans_of_its_virtual_time():
    r = bench_program(PROGRAMS_DIR / "bench300.st", sim_seconds=0.5, runs=2)
    assert r["program"] == "bench300.st" and r["tick_ms"] == 10 and r["scans"] == 50
    assert r["speedup"] >= SPEEDUP_FLOOR, r
    assert abs(r["speedup"] * r["us_per_scan"] * 1e-6 - r["tick_ms"] / 1e3) < 1e-9   # one figure, two units


def test_bench_memory_reports_the_trace_of_the_run_it_measures():
    m = bench_memory("tur10", sim_seconds=6.0)
    stand = get_stand("tur10")
    sim = Simulation(PLC(compile_unit(check_sources(sources(stand, "full")))), plants=[stand.make_plant()])
    sim.run(6.0)
    changes = sum(sim.trace.change_count(n) for n in sim.trace.signals())
    assert m["stand"] == "tur10" and m["changes_per_hour"] == changes * 600
    assert 0 < m["loaded_mb"] <= LOADED_MB_CEILING and 0 < m["mb_per_hour"] <= MB_PER_HOUR_CEILING, m
