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


CLOSED_LOOP_FLOOR = 1000.0    # scans/s of one core; measured ~30000 (mp9c, machine loaded, 2026-12-03)


def test_the_closed_loop_figures_split_the_scans_of_the_script_they_played():
    from plclab.bench import LOOP_PARTS, bench_closed_loop

    r = bench_closed_loop("mp9c", 8.0, runs=1)
    assert r["stand"] == "mp9c" and r["workload"].endswith("operator script")
    assert r["scans_per_s"] >= CLOSED_LOOP_FLOOR, r
    assert set(r["us_per_scan"]) == set(LOOP_PARTS) and r["us_per_scan"]["scan"] > 0
    assert sum(r["us_per_scan"].values()) < r["total_us_per_scan"] * 1.5, r   # parts of one whole
    assert abs(r["scans_per_s"] * r["total_us_per_scan"] * 1e-6 - 1) < 1e-9


def test_a_profiled_run_records_the_trace_of_a_plain_one():
    """`plclab bench` times the parts of each scan (Simulation.profiling): the same steps in the
    same order, so the same trace, scan for scan, also across a power cycle of the PLC."""
    import random

    from plclab.grader.explore import play
    from plclab.stands.base import stand_spec
    from plclab.stands.scripts import POWER, Event, Script

    spec = stand_spec("tur10")
    script = spec.explore.generate(random.Random(3), "task1", 12.0)
    script = Script(tuple(sorted([*script.events, Event(5.0, POWER, "0.5")], key=lambda e: e.time)),
                    script.duration)

    def played(costs=None):
        s = spec.session()
        if costs is None:
            play(s, script, spec.explore)
        else:
            with Simulation.profiling(costs):
                play(s, script, spec.explore)
        return {name: s.trace.changes(name) for name in s.trace.signals()}

    costs: dict = {}
    assert played(costs) == played()
    off = sum(float(e.value) for e in script.events if e.name == POWER)      # no scans while the PLC is off
    assert costs["scans"] == round((script.duration - off) / 0.01) and costs["observation"] > 0
