"""`plclab bench`'s native lines: the scan on the Python path and on the native path, side by
side, per stand (issue #30). Three figures each:
  * scan: microseconds in PLC.scan (input copy, the programs, output copy) while the stand's
    demo scenario plays: the program under the load its lab gives it;
  * closed loop: microseconds a scan of the whole loop (scan, plant, exchange, trace), the
    stand at power-up with its plant (plclab.bench.bench_program);
  * build: seconds to generate and compile the program's C, once per program (then cached).
The best of a few runs each (shared machines swing by up to 2x between identical runs); the
scan figure counts this thread's CPU time, so other processes' load stays out of it.
"""
from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable, Optional

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
    from plclab.bench import bench_program
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


__all__ = ["bench_build", "bench_scan_in_scenario", "report_native"]
