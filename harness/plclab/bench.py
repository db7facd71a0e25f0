"""`plclab bench`: the performance figures (targets live here, not in timed tests).

Goals (issues 2, 3, 4): parse + check of a 5,000-line program under 0.5 s; a 10 ms-tick
program of about 300 statements at least 500 times faster than real time in virtual time;
Modbus requests per second and latency for 1 and 10 clients, and scan jitter under that load;
`plclab serve mp9c` flooded by 10 client processes: ticks missed (goal 0, issue #25).
Also reported: each stand's closed loop as the grader runs it (issue 30: scans per second of
one core, and what one scan's PLC scan, plant step, I/O exchange, observation and trace
recording cost), each stand's memory (loaded, and trace growth per simulated hour), and the
virtual lab's page update rate, lag and server CPU per page (plclab.lab.bench).
"""
from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable, Optional

from plclab.errors import PlcLabError

PROGRAMS_DIR = Path(__file__).resolve().parent / "benchprograms"   # package data: `plclab bench` runs installed


def bench_program(path: Path, sim_seconds: float = 10.0, sources=None, plant_factory=None,
                  name: str = "", runs: int = 5, native: bool = False) -> dict:
    """Microseconds per scan and virtual-time speed-up of one program, with its plant model
    when it has one: the best of `runs` runs, the figure least disturbed by other load on the
    machine (shared machines here swing by up to 2x between identical runs). On the Python
    path, or (`native`) on the native one (report_native)."""
    from plclab.frontend import check_sources, load_files
    from plclab.runtime.compiler import compile_unit
    from plclab.runtime.plc import PLC
    from plclab.runtime.sim import Simulation

    import gc

    checked = check_sources(sources) if sources is not None else load_files([path])
    gc.collect()          # no collection of earlier benchmarks' garbage inside the timed runs
    best = None
    for _ in range(runs):
        plc = PLC(compile_unit(checked), native=native)
        sim = Simulation(plc, plants=[plant_factory()] if plant_factory else ())
        t0 = time.perf_counter()
        sim.run(sim_seconds)
        elapsed = time.perf_counter() - t0
        best = elapsed if best is None or elapsed < best else best
    scans = round(sim_seconds * 1e9 / plc.tick_ns)
    return {"program": name or path.name, "tick_ms": plc.tick_ns / 1e6, "scans": scans,
            "us_per_scan": best / scans * 1e6, "speedup": sim_seconds / best}


def bench_memory(stand_name: str, sim_seconds: float = 600.0) -> dict:
    """Memory of one stand's richest available program (`full` in a checkout) with its plant:
    what loading takes, and how much the trace grows per simulated hour (a long `plclab sim` or scenario must stay small)."""
    import tracemalloc

    from plclab.frontend import check_sources
    from plclab.runtime.compiler import compile_unit
    from plclab.runtime.plc import PLC
    from plclab.runtime.sim import Simulation
    from plclab.stands import get_stand, sources

    stand = get_stand(stand_name)
    checked = check_sources(sources(stand, stand.richest_variant))
    tracemalloc.start()
    try:
        sim = Simulation(PLC(compile_unit(checked)), plants=[stand.make_plant()])
        loaded = tracemalloc.get_traced_memory()[0]
        sim.run(sim_seconds)
        grown = tracemalloc.get_traced_memory()[0] - loaded
    finally:
        tracemalloc.stop()
    changes = sum(sim.trace.change_count(n) for n in sim.trace.signals())
    return {"stand": stand_name, "loaded_mb": loaded / 1e6, "mb_per_hour": grown / 1e6 * 3600 / sim_seconds,
            "changes_per_hour": changes * 3600 / sim_seconds}


def bench_realtime(seconds: float = 10.0, clients: int = 10) -> dict:
    """A 10 ms task in real time for `seconds` while `clients` Modbus clients read holding
    registers as fast as they can: scan period jitter (start lateness) and overruns."""
    import threading

    from plclab.frontend import load_files
    from plclab.modbus.maps import OpenPlcMap
    from plclab.modbus.rawclient import RawModbusClient
    from plclab.modbus.server import ModbusTcpServer
    from plclab.runtime.compiler import compile_unit
    from plclab.runtime.plc import PLC
    from plclab.runtime.realtime import RealTimeRunner

    plc = PLC(compile_unit(load_files([PROGRAMS_DIR / "bench300.st"])))
    server = ModbusTcpServer(OpenPlcMap(plc.image), "127.0.0.1", 0).start()
    stop = threading.Event()
    counts = [0] * clients

    def hammer(i: int) -> None:
        with RawModbusClient("127.0.0.1", server.port, timeout=5.0) as c:
            while not stop.is_set():
                c.read_holding_registers(0, 10)
                counts[i] += 1
    threads = [threading.Thread(target=hammer, args=(i,), daemon=True) for i in range(clients)]
    for t in threads:
        t.start()
    runner = RealTimeRunner(plc)
    try:
        runner.run_for(seconds)
    finally:
        stop.set()
        for t in threads:
            t.join(5)
        server.stop()
    p50, p99 = runner.stats.jitter_s()
    return {"seconds": seconds, "tick_ms": plc.tick_ns / 1e6, "scans": runner.stats.ticks,
            "overruns": runner.stats.overruns, "jitter_p50_ms": p50 * 1e3, "jitter_p99_ms": p99 * 1e3,
            "max_lateness_ms": runner.stats.max_lateness_s * 1e3, "modbus_requests": sum(counts)}


FLOOD_CLIENT = r"""
import socket, struct, sys, time
port, seconds, batch = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
s = socket.create_connection(("127.0.0.1", port), timeout=10)
s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
request = b"".join(struct.pack(">HHHBBHH", i, 0, 6, 1, 3, 0, 10) for i in range(batch))
reply = batch * (9 + 20)
end = time.monotonic() + seconds
while time.monotonic() < end:
    s.sendall(request)
    got = 0
    while got < reply:
        data = s.recv(65536)
        if not data:
            sys.exit(1)
        got += len(data)
"""
"""A Modbus client process that reads 10 holding registers as fast as the face answers,
`batch` requests per write: a flood from outside the PLC's process, as SCADA clients are."""


def bench_serve_load(seconds: float = 10.0, clients: int = 10, batch: int = 20) -> dict:
    """`plclab serve mp9c` (its 10 ms task, its plant, its Modbus face with the face's admission
    control) while `clients` client processes flood the face: the scan's own tick accounting
    over `seconds`, measured once every client is connected and answered (starting the client
    processes is a burst of CPU of its own). Issue #25: the scan first."""
    import dataclasses
    import subprocess
    import sys

    from plclab import config
    from plclab.plants import make_plant
    from plclab.serve import FACE_MAX_REQUESTS_PER_S, ServeOptions, Service
    from plclab.stands import get_stand, sources

    conf = config.defaults()
    stand = conf.stand("mp9c")
    opts = ServeOptions(sources(get_stand("mp9c"), stand.variant), stand, dataclasses.replace(conf.modbus, port=0),
                        make_plant("mp9c"), stand.profile, None, None)
    svc = Service(opts, report=lambda line: None)
    svc.start()
    flood: list[subprocess.Popen] = []
    try:
        flood = [subprocess.Popen([sys.executable, "-c", FLOOD_CLIENT, str(svc.server.port), str(seconds + 60),
                                   str(batch)]) for _ in range(clients)]
        give_up = time.monotonic() + 30
        while (svc.server.active_clients < clients or svc.server.stats["requests"] < 20 * batch * clients) \
                and time.monotonic() < give_up:
            time.sleep(0.05)
        time.sleep(0.5)
        connected = svc.server.active_clients
        before, served_before = dataclasses.replace(svc.runner.stats), svc.server.stats["requests"]
        time.sleep(seconds)
        after, served = svc.runner.stats, svc.server.stats["requests"] - served_before
        still = sum(p.poll() is None for p in flood)
    finally:
        for p in flood:
            p.kill()
            p.wait()
        svc.stop()
    return {"seconds": seconds, "tick_ms": svc.plc.tick_ns / 1e6, "clients": connected, "clients_at_end": still,
            "expected_scans": round(seconds * 1e9 / svc.plc.tick_ns), "scans": after.ticks - before.ticks,
            "overruns": after.overruns - before.overruns, "missed_ticks": after.skipped_ticks - before.skipped_ticks,
            "requests_per_s": served / seconds, "face_limit_per_s": FACE_MAX_REQUESTS_PER_S,
            "fault": svc.plc.fault}


LOOP_PARTS = ("scan", "plant", "exchange", "observation", "record")


def bench_closed_loop(stand_name: str, seconds: float = 60.0, runs: int = 3, seed: int = 30) -> dict:
    """The closed loop of one stand as the grader runs it: the richest shipped program with
    its plant, played under a seeded random operator script of about `seconds` (the stand's
    exploration generator, what the stand shows observed every scan), or the stand's default
    scenario where the stand is not explored. Scans per second of one core (CPU time, best
    of `runs`: the figure least disturbed by other load), and as many runs with each part of every scan timed (each
    part's best): the PLC scan, the plant step, the I/O exchange (outputs out of the image,
    inputs into it), the observation (the grader's probe) and the trace recording, in
    microseconds per scan."""
    import gc
    import random

    from plclab.grader.explore import play
    from plclab.runtime.sim import Simulation
    from plclab.scenario import compiled_once
    from plclab.stands.base import stand_spec

    spec = stand_spec(stand_name)
    expl = spec.explore
    checked = spec.session().checked
    script = expl.generate(random.Random(seed), "task1", seconds) if expl is not None else None

    def once() -> None:
        with compiled_once(checked):
            s = spec.session(checked=checked)
            if script is not None:
                play(s, script, expl)
            else:
                spec.scenario(None)(s)

    best, costs = None, {}
    gc.collect()
    for _ in range(runs):
        t0 = time.process_time()      # CPU seconds: the machine's other load does not count
        once()
        elapsed = time.process_time() - t0
        best = elapsed if best is None or elapsed < best else best
        run_costs: dict[str, float] = {}
        with Simulation.profiling(run_costs):
            once()
        scans = int(run_costs.pop("scans"))
        costs = {part: min(costs.get(part, run_costs[part]), run_costs[part]) for part in run_costs}
    return {"stand": stand_name, "variant": spec.stand.richest_variant,
            "workload": f"a {script.duration:.0f} s operator script" if script is not None
            else f"scenario {spec.default_scenario}",
            "scans": scans, "scans_per_s": scans / best,
            "us_per_scan": {part: costs.get(part, 0.0) / scans * 1e6 for part in LOOP_PARTS},
            "total_us_per_scan": best / scans * 1e6}


def report_closed_loop(report: Callable[[str], None] = print, quick: bool = False) -> list[dict]:
    """`plclab bench`'s closed-loop section (issue 30): per stand, scans per second of the
    whole loop and what one scan costs, part by part."""
    from plclab.stands import STANDS

    out = []
    for stand_name in STANDS:
        try:
            r = bench_closed_loop(stand_name, 20.0 if quick else 60.0, runs=1 if quick else 3)
        except PlcLabError:
            continue
        out.append(r)
        split = ", ".join(f"{part} {r['us_per_scan'][part]:.1f}" for part in LOOP_PARTS)
        report(f"closed loop: {stand_name} {r['variant']} under {r['workload']}: {r['scans_per_s']:.0f} scans/s "
               f"of one core ({r['total_us_per_scan']:.1f} us per scan, of which {split}; "
               f"the rest: the script, the console, the session's trace)")
    return out


def run_bench(report: Callable[[str], None] = print, quick: bool = False,
              programs: Optional[list[Path]] = None) -> dict:
    results: dict = {}
    try:
        from plclab.frontend.bench import bench_frontend
        fe = bench_frontend(5000)
        results["frontend"] = fe
        report(f"front end: parse + check of {fe['lines']} lines: {fe['parse_check_s'] * 1000:.0f} ms "
               f"(goal < {fe['goal_s'] * 1000:.0f} ms)")
    except ImportError:
        report("front end: benchmark not available")
    results["programs"] = []
    for path in programs or sorted(PROGRAMS_DIR.glob("*.st")):
        r = bench_program(path, 2.0 if quick else 10.0)
        results["programs"].append(r)
        goal = "  (goal >= 500x)" if path.name == "bench300.st" else ""
        report(f"scan: {r['program']}: {r['us_per_scan']:.1f} us/scan at {r['tick_ms']:g} ms tick, "
               f"{r['speedup']:.0f}x real time{goal}")
    from plclab.stands import STANDS, get_stand, sources
    for stand_name in STANDS:
        try:
            stand = get_stand(stand_name)
        except PlcLabError:
            continue
        variant = stand.richest_variant
        r = bench_program(Path(stand_name), 2.0 if quick else 10.0, sources=sources(stand, variant),
                          plant_factory=stand.make_plant, name=f"{stand_name} {variant} (with its plant)")
        results["programs"].append(r)
        report(f"scan: {r['program']}: {r['us_per_scan']:.1f} us/scan at {r['tick_ms']:g} ms tick, "
               f"{r['speedup']:.0f}x real time")
    results["native"] = report_native(report, quick=quick)
    results["closed_loop"] = report_closed_loop(report, quick=quick)
    results["memory"] = []
    for stand_name in STANDS:
        try:
            m = bench_memory(stand_name, 60.0 if quick else 600.0)
        except PlcLabError:
            continue
        results["memory"].append(m)
        report(f"memory: {stand_name} {get_stand(stand_name).richest_variant} (with its plant): "
               f"{m['loaded_mb']:.1f} MB loaded, trace "
               f"+{m['mb_per_hour']:.1f} MB per simulated hour ({m['changes_per_hour']:.0f} changes)")
    try:
        from plclab.modbus.bench import bench_modbus
        mb = bench_modbus(1.0 if quick else 3.0)
        results["modbus"] = mb
        for key, value in mb.items():
            if isinstance(value, dict):
                report(f"modbus: {value['clients']} client(s) reading {mb.get('registers', 10)} holding registers: "
                       f"{value['requests_per_s']:.0f} requests/s, p50 {value['p50_ms']:.2f} ms, "
                       f"p99 {value['p99_ms']:.2f} ms, {value['errors']} errors")
    except ImportError:
        report("modbus: benchmark not available")
    from plclab.lab.bench import report_lab
    results["lab"] = report_lab(report, quick=quick)
    from plclab.cnc.bench import report_cnc
    results["cnc"] = report_cnc(report, quick=quick)
    from plclab.grader.explore import report_explore
    results["explore"] = report_explore(report, quick=quick)
    rt = bench_realtime(3.0 if quick else 10.0)
    results["realtime"] = rt
    report(f"real time: {rt['tick_ms']:g} ms task for {rt['seconds']:g} s under {rt['modbus_requests']} Modbus "
           f"requests: {rt['scans']} scans, {rt['overruns']} overruns, start jitter p50 "
           f"{rt['jitter_p50_ms']:.2f} ms, p99 {rt['jitter_p99_ms']:.2f} ms, max {rt['max_lateness_ms']:.2f} ms")
    sl = bench_serve_load(3.0 if quick else 10.0)
    results["serve_load"] = sl
    report(f"serve mp9c under Modbus load: {sl['clients']} client processes flooding the face, "
           f"{sl['requests_per_s']:.0f} requests/s answered (face limit {sl['face_limit_per_s']}/s): "
           f"{sl['scans']} of {sl['expected_scans']} scans of the {sl['tick_ms']:g} ms task in {sl['seconds']:g} s, "
           f"{sl['overruns']} overruns, {sl['missed_ticks']} ticks missed (goal 0)")
    return results


# --------------------------------------------------------------------------- the native scan path
# `plclab bench`'s native lines: the scan on the Python path and on the native path, side by
# side, per stand (issue #30). Three figures each:
#   * scan: microseconds in PLC.scan (input copy, the programs, output copy) while the stand's
#     demo scenario plays: the program under the load its lab gives it;
#   * closed loop: microseconds a scan of the whole loop (scan, plant, exchange, trace), the
#     stand at power-up with its plant (plclab.bench.bench_program);
#   * build: seconds to generate and compile the program's C, once per program (then cached).
# The best of a few runs each (shared machines swing by up to 2x between identical runs); the
# scan figure counts this thread's CPU time, so other processes' load stays out of it.

STANDS_SCENARIO = {"mp9c": "demo", "tur10": "demo", "thermo": "demo", "cnc": "square"}


def bench_scan_in_scenario(stand_name: str, native: bool, scenario: Optional[str] = None, runs: int = 3) -> dict:
    """Microseconds per PLC.scan while `scenario` (the stand's default) plays, on one path."""
    from plclab.runtime import native as nat
    from plclab.runtime.compiler import compile_unit
    from plclab.scenario import compiled_once
    from plclab.stands import sources
    from plclab.stands.base import stand_spec
    from plclab.frontend import check_sources

    spec = stand_spec(stand_name)
    variant = spec.stand.richest_variant
    scenario = scenario or STANDS_SCENARIO.get(stand_name, spec.default_scenario)
    checked = check_sources(sources(spec.stand, variant))
    compiled = compile_unit(checked)
    if native and nat.program_for(compiled, wait=True) is None:
        raise RuntimeError("the native path cannot run this program here")
    best: Optional[float] = None
    scans = 0
    for _ in range(runs):
        spent = [0.0, 0]
        with compiled_once(checked, share=[checked, compiled]):
            with (nat.python_only() if not native else _nothing()):
                s = spec.session(variant, checked=checked)
                if (s.plc.native is not None) != native:
                    raise RuntimeError("the session did not take the path asked for")
                _time_scans(s.plc, spent)
                spec.scenario(scenario)(s)
        us = spent[0] / max(1, spent[1]) * 1e6
        scans = spent[1]
        best = us if best is None or us < best else best
    return {"stand": stand_name, "variant": variant, "scenario": scenario, "native": native,
            "scans": scans, "us_per_scan": best}


def _time_scans(plc: Any, spent: list) -> None:
    scan = plc.scan
    clock = time.thread_time       # CPU time of this thread: other processes' load left out

    def timed() -> bool:
        t0 = clock()
        ok = scan()
        spent[0] += clock() - t0
        spent[1] += 1
        return ok
    plc.scan = timed


class _nothing:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: Any) -> None:
        return None


def bench_build(stand_name: str) -> float:
    """Seconds to generate and compile a stand's C, in an empty cache."""
    import os
    import tempfile

    from plclab.frontend import check_sources
    from plclab.runtime import native as nat
    from plclab.runtime.cgen import emit_c
    from plclab.stands import get_stand, sources

    stand = get_stand(stand_name)
    checked = check_sources(sources(stand, stand.richest_variant))
    old = os.environ.get("XDG_CACHE_HOME")
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["XDG_CACHE_HOME"] = tmp
        try:
            t0 = time.perf_counter()
            cprog = emit_c(checked)
            cc = nat.c_compiler()
            if cc is None:
                return float("nan")
            modname, api, include, ext = nat._key(cprog, cc)
            out = Path(tmp) / "plclab" / "native"
            nat._compile(cprog, cc, api, include, modname, out, out / f"{modname}{ext}")
            return time.perf_counter() - t0
        finally:
            if old is None:
                os.environ.pop("XDG_CACHE_HOME", None)
            else:
                os.environ["XDG_CACHE_HOME"] = old


def report_native(report: Callable[[str], None] = print, quick: bool = False) -> list[dict]:
    from plclab.runtime import native as nat
    from plclab.stands import STANDS, get_stand, sources

    if nat.c_compiler() is None:
        report("native: no C compiler (cc): the native scan path is off on this machine")
        return []
    results = []
    runs = 2 if quick else 3
    for stand_name in STANDS:
        try:
            stand = get_stand(stand_name)
        except Exception:
            continue
        variant = stand.richest_variant
        py = bench_scan_in_scenario(stand_name, False, runs=runs)
        na = bench_scan_in_scenario(stand_name, True, runs=runs)
        loop = {}
        for native in (False, True):
            loop[native] = bench_program(Path(stand_name), 2.0 if quick else 10.0, sources=sources(stand, variant),
                                         plant_factory=stand.make_plant, name=stand_name, runs=runs,
                                         native=native)["us_per_scan"]
        build_s = bench_build(stand_name)
        r = {"stand": stand_name, "variant": variant, "scenario": py["scenario"],
             "scan_us_python": py["us_per_scan"], "scan_us_native": na["us_per_scan"],
             "loop_us_python": loop[False], "loop_us_native": loop[True], "build_s": build_s}
        results.append(r)
        report(f"native: {stand_name} {variant}: scan in the {r['scenario']} scenario "
               f"{r['scan_us_python']:.1f} us Python / {r['scan_us_native']:.1f} us native "
               f"(x{r['scan_us_python'] / r['scan_us_native']:.1f}); closed loop at power-up "
               f"{r['loop_us_python']:.1f} / {r['loop_us_native']:.1f} us a scan "
               f"(x{r['loop_us_python'] / r['loop_us_native']:.1f}); C build {build_s:.1f} s once per program")
    return results
