"""`plclab bench`'s CNC figures: how fast the CNC stand (PRG_CncStand and its table) runs in
virtual time -- steps per second of simulated drive output, fine and interpolation cycles
per second of wall time -- and how far that is from the goal of docs/cnc.md: a 100 mm circle
at 10 um steps and 6 m/min (10,000 steps/s of drive output) simulated 10x faster than real
time, i.e. 100,000 simulated steps per wall-clock second.

Two rows. The goal's own circle (R 50 mm at 6 m/min, DDA) on the pulse-count drive of the
paper's position-control module: every interpolation cycle the PLC writes the cycle's counts
and the plant's pulse generator spreads them, so the drive output is not capped by the fine
cycle. And the step/direction drive at its own top feed (one step per axis per 1 ms fine
cycle: 600 mm/min at 10 um), on a smaller circle: it cannot reach 6 m/min at all.
"""
from __future__ import annotations

import gc
import time

GOAL_STEPS_PER_S = 10_000          # 6 m/min at 10 um steps
GOAL_SPEEDUP = 10.0                # simulated this much faster than real time
NFINE = 4                          # PRG_CncStand: fine cycles per interpolation cycle T
GOAL_CIRCLE = (50.0, 6000.0)       # radius mm, feed mm/min: a 100 mm circle at 6 m/min
STEP_CIRCLE = (3.0, 600.0)         # the step drive's top feed


def bench_cnc(radius_mm: float = 3.0, feed_mm_min: float = 600.0, method: str = "dda", drive: str = "step",
              runs: int = 3) -> dict:
    """Run a line to (R, 0) and a full circle of `radius_mm` at `feed_mm_min` (0.01 mm steps)
    `runs` times on a fresh stand each; the best run's figures (the least disturbed by other
    load on the machine)."""
    from plclab.nc.gcode import parse
    from plclab.stands import cnc

    r = float(radius_mm)
    frames = parse(f"G21 G90 G17 F{feed_mm_min:g}\nG01 X{r:g}\nG03 X{r:g} Y0 I{-r:g} J0\n", "<bench circle>").frames
    best = None
    for _ in range(runs):
        s = cnc.SPEC.session(cnc.STAND.richest_variant)     # the compile is not timed
        gc.collect()
        t0 = time.perf_counter()
        run = cnc.run_part(s, frames, method, drive=drive)
        wall = time.perf_counter() - t0
        if not run.finished or any(run.missed.values()):
            raise RuntimeError(f"bench: the circle did not end cleanly (missed steps {run.missed})")
        steps = sum(axis.received for axis in s.plant.axes.values())
        if best is None or wall < best[0]:
            best = (wall, s.now - run.start, steps)
    wall, virtual, steps = best
    fine = virtual / cnc.FINE_CYCLE_S
    return {"method": method, "drive": drive, "radius_mm": r, "feed_mm_min": float(feed_mm_min),
            "virtual_s": virtual, "wall_s": wall, "speedup": virtual / wall, "steps": steps,
            "steps_per_virtual_s": steps / virtual, "steps_per_wall_s": steps / wall,
            "fine_cycles_per_wall_s": fine / wall, "interpolation_cycles_per_wall_s": fine / NFINE / wall,
            "goal_ratio": steps / wall / (GOAL_STEPS_PER_S * GOAL_SPEEDUP)}


def report_cnc(report, quick: bool = False) -> list[dict]:
    """The CNC lines of `plclab bench` (quick: smaller circles at the same feeds)."""
    out = []
    for drive, (radius, feed) in (("pulse", GOAL_CIRCLE), ("step", STEP_CIRCLE)):
        if quick:
            radius /= 5.0
        b = bench_cnc(radius_mm=radius, feed_mm_min=feed, drive=drive, runs=1 if quick else 3)
        out.append(b)
        report(f"cnc: circle R {b['radius_mm']:g} mm at {b['feed_mm_min']:g} mm/min, {b['method']}, {drive} drive: "
               f"{b['speedup']:.1f}x real time, {b['steps_per_wall_s']:.0f} simulated steps/s "
               f"({b['steps_per_virtual_s']:.0f} steps/s of drive output), {b['fine_cycles_per_wall_s']:.0f} fine / "
               f"{b['interpolation_cycles_per_wall_s']:.0f} interpolation cycles/s; goal "
               f"{GOAL_STEPS_PER_S * GOAL_SPEEDUP:.0f} steps/s (10,000 steps/s at 10x): "
               f"{b['goal_ratio']:.2f} of it")
    return out
