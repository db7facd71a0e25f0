"""The path feed the CNC stand can reach (docs/cnc.md, "Fine cycle and reachable feeds"),
and why a frame ran below its programmed feed: what `plclab cnc` says under a frame whose
reached feed (path length over the frame's time) is more than REACHED_TOLERANCE below the
programmed one.

What caps the feed is PRG_CncStand's, one fine cycle of `fine_s` at a time:
- evaluation function: at most one iteration per fine cycle, each one step of one axis:
  a line of N = |dx| + |dy| iterations over a path of L steps runs at most L / N steps per
  fine cycle -- 1 along an axis, 1 / sqrt 2 at 45 degrees; on an arc the point at (x, y)
  from the centre needs (|x| + |y|) / R iterations per step of arc. The diagonal variant
  (and a line moving Z) steps every moving axis in one iteration, and then the feed's own
  limit holds: one step of path per fine cycle. The drive does not change this (with the
  pulse-count drive the net steps of T's fine cycles are the count);
- DDA and digital integration on the step/direction drive: the path feed is limited to one
  step per fine cycle (PRG_CncStand's FeedMax), whatever the direction;
- DDA and digital integration on the pulse-count drive: PULSE_FEED_MAX steps/s, not the fine
  cycle (the pulse generator spreads a cycle's counts);
- digital integration accelerates and decelerates (GVL_CNC.Accel), and so do DDA's arcs
  (FB_CncIntegCircular): a short frame may not reach the feed at all.
A rapid (G00) runs at that top rate; it has no programmed feed to miss.

`measure_table` runs the twin (the shipped program) for the table of docs/cnc.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

REACHED_TOLERANCE = 0.02         # a frame's reached feed this far below the programmed one is said
PULSE_FEED_MAX_STEPS = 15_000.0  # PRG_CncStand.PULSE_FEED_MAX: steps/s with the pulse counts (DDA, integration)
ACCEL_MM_S2 = 200.0              # GVL_CNC.Accel: digital integration's path acceleration


@dataclass(frozen=True)
class Cap:
    """The top path feed of one frame: `low`..`high` mm/min (an evaluation-function arc's
    cap changes along it) and the sentence that says why."""

    low: float
    high: float
    why: str


def iterations(dx: int, dy: int, dz: int, diagonal: bool) -> int:
    """The evaluation function's iterations for a line of (dx, dy, dz) steps (PRG_CncStand)."""
    if diagonal or dz:
        return max(abs(dx), abs(dy), abs(dz))
    return abs(dx) + abs(dy)


def top_feed(frame, method: str, drive: str, diagonal: bool, fine_s: float, h: float) -> Cap:
    """The cap on `frame`'s path feed (mm/min) on the stand, and why."""
    per_fine = 60.0 * h / fine_s                 # mm/min: one step per fine cycle
    ms = f"{fine_s * 1000:g} ms"
    if method == "evalfn":
        each = "one step of one axis" if not diagonal else "one step of each axis that moves"
        head = (f"the evaluation function makes one iteration per fine cycle ({ms}) on either drive, {each}: "
                f"{1 / fine_s:.0f} steps/s for all axes together")
        faster = (f" (DDA or digital integration on the pulse-count drive: up to "
                  f"{PULSE_FEED_MAX_STEPS * h * 60.0:.0f} mm/min)")
        if diagonal:                              # a diagonal iteration goes up to sqrt 2 steps of path,
            return Cap(per_fine, per_fine, f"{head}; the feed is limited to one step of path per fine "
                                           f"cycle: {per_fine:.0f} mm/min{faster}")      # the feed's own limit
        if frame.is_arc:                          # (|x| + |y|) / R iterations per step of arc
            low, high = per_fine / math.sqrt(2), per_fine
            return Cap(low, high, f"{head}; on an arc {low:.0f} mm/min at 45 degrees to {high:.0f} mm/min "
                                  f"on the axes (--diagonal: {per_fine:.0f} mm/min everywhere){faster}")
        d = [round(e / h) - round(s / h) for s, e in zip(frame.start, frame.end)]
        n = iterations(*d, diagonal)
        length = math.hypot(*d)
        top = min(per_fine, per_fine * length / n) if n else per_fine
        hint = f" (--diagonal: {per_fine:.0f} mm/min)" if top < per_fine * 0.99 else ""
        return Cap(top, top, f"{head}; this line needs {n} iterations for {length * h:.3f} mm: "
                             f"at most {top:.0f} mm/min{hint}{faster}")
    name = "DDA" if method == "dda" else "digital integration"
    if drive == "pulse":
        top = PULSE_FEED_MAX_STEPS * h * 60.0
        return Cap(top, top, f"{name} on the pulse-count drive runs at most PULSE_FEED_MAX, "
                             f"{PULSE_FEED_MAX_STEPS:.0f} steps/s: {top:.0f} mm/min")
    return Cap(per_fine, per_fine, f"{name} on the step/direction drive takes at most one step per fine cycle "
                                   f"({ms}) along the path: {per_fine:.0f} mm/min (--drive pulse: up to "
                                   f"{PULSE_FEED_MAX_STEPS * h * 60.0:.0f} mm/min)")


def slow_reason(frame, length_mm: float, feed: float, reached: float, method: str, drive: str,
                diagonal: bool, fine_s: float, h: float) -> str:
    """Why a frame of `length_mm` programmed at `feed` mm/min ran at `reached` mm/min."""
    cap = top_feed(frame, method, drive, diagonal, fine_s, h)
    if feed > cap.low * (1 + 1e-9):
        return cap.why
    if method == "integration" or (method == "dda" and frame.is_arc):
        ramp = (feed / 60.0) ** 2 / ACCEL_MM_S2
        who = "digital integration" if method == "integration" else \
            "DDA runs an arc by digital integration (FB_CncIntegCircular), which"
        return (f"{who} accelerates and decelerates at {ACCEL_MM_S2:g} mm/s^2 (GVL_CNC.Accel): "
                f"{ramp:.3f} mm of the {length_mm:.3f} mm go to reaching and leaving F{feed:g}")
    cycle = 4 * fine_s
    return (f"the frame is short: its time is rounded to the interpolation cycle ({cycle * 1000:g} ms) "
            f"and the fine cycles ({fine_s * 1000:g} ms)")


def reached_feed(length_mm: float, time_s: float) -> Optional[float]:
    """Path length over the frame's time, mm/min (None for a frame that took no time)."""
    return length_mm / time_s * 60.0 if time_s > 0 else None


# ------------------------------------------------------------------ the table of docs/cnc.md

SHAPES = {                 # shape: part program of size r mm
    "axis": "G21 G90 G17\nG01 X{r} F{f}\n",
    "45 degrees": "G21 G90 G17\nG01 X{r} Y{r} F{f}\n",
    "arc": "G21 G90 G17\nG03 X0 Y0 I{r} J0 F{f}\n",
}
ASKED_MM_MIN = 60_000.0    # far above every cap: the feed measured is the cap the stand holds


def measure(method: str, drive: str, fine_ms: int, shape: str, diagonal: bool = False) -> tuple[float, float]:
    """The path feed (mm/min) the twin holds for `shape` asked at ASKED_MM_MIN, from its speed
    over windows of 100 fine cycles (at least 0.1 s; 0.1 s for the
    pulse counts of DDA and digital integration) along the frame,
    the first and the last window (start, ramps) left out: the median window (the pulse
    counts: the fastest, between the ramps of their long frames); for the evaluation
    function's arc, whose cap changes along it, the slowest and the fastest window."""
    from plclab.nc.gcode import parse
    from plclab.stands import cnc

    counts = drive == "pulse" and method != "evalfn"        # not capped by the fine cycle
    size = {"axis": 140, "45 degrees": 100, "arc": 70}[shape] if counts else 10
    frames = parse(SHAPES[shape].format(r=size, f=f"{ASKED_MM_MIN:g}"), f"<{shape}>").frames
    s = cnc.session(fine_ms=fine_ms)
    run = cnc.run_part(s, frames, method, diagonal=diagonal, drive=drive, timeout=120.0)
    h = s.plant.step_mm
    pts = [p for p in run.points if p[1] == 1]
    window = 0.1 if counts else max(0.1, 100 * fine_ms / 1000.0)
    f = frames[0]
    if f.is_arc:                       # along the arc (the angle swept), not the staircase's chords
        cx, cy = f.centre[0] / h, f.centre[1] / h
        turn = [0.0]
        for p, q in zip(pts, pts[1:]):
            turn.append(turn[-1] + (math.atan2(q[3] - cy, q[2] - cx) - math.atan2(p[3] - cy, p[2] - cx)
                                    + math.pi) % (2 * math.pi) - math.pi)
        along = [abs(a) * math.hypot(f.i, f.j) / h for a in turn]
    else:
        along = [math.dist(pts[0][2:], p[2:]) for p in pts]
    speeds, k = [], 0
    t0 = pts[0][0]
    while True:
        a = next((i for i in range(k, len(pts)) if pts[i][0] >= t0 + window), None)
        b = next((i for i in range(a or 0, len(pts)) if pts[i][0] >= t0 + 2 * window), None) if a else None
        if a is None or b is None or pts[-1][0] - pts[b][0] < window:
            break
        speeds.append((along[b] - along[a]) * h / (pts[b][0] - pts[a][0]) * 60.0)
        k, t0 = a, pts[a][0]
    if not speeds:
        raise RuntimeError(f"measure: {shape} too short for a window of {window:g} s")
    if method == "evalfn" and f.is_arc and not diagonal:
        return min(speeds), max(speeds)          # the cap changes along the arc
    typical = max(speeds) if counts else sorted(speeds)[len(speeds) // 2]   # counts: the top between the ramps
    return typical, typical


ROWS = (("evalfn", "step", False), ("evalfn", "step", True), ("evalfn", "pulse", False), ("dda", "step", False),
        ("integration", "step", False), ("dda", "pulse", False), ("integration", "pulse", False))
FINE_MS = (1, 5)


def measure_table() -> list[str]:
    """The markdown table of docs/cnc.md (and docs/openplc.md): per method, drive and fine
    cycle the reachable path feed along an axis, at 45 degrees and on a full circle."""
    head = "| method | drive | fine cycle | along an axis | at 45 degrees | on an arc |"
    lines = [head, "|---|---|---|---|---|---|"]
    for method, drive, diagonal in ROWS:
        for fine in FINE_MS:
            cells = [_cell(*measure(method, drive, fine, shape, diagonal)) for shape in SHAPES]
            name = {"evalfn": "evaluation function", "dda": "DDA", "integration": "digital integration"}[method]
            if diagonal:
                name += " (diagonal)"
            lines.append(f"| {name} | {'step/direction' if drive == 'step' else 'pulse counts'} | {fine} ms | "
                         + " | ".join(cells) + " |")
    return lines


def _cell(low: float, high: float) -> str:
    """One figure, or low-high where the feed changes along the path (by more than 2 %)."""
    return f"{high:.0f}" if high <= low * (1 + REACHED_TOLERANCE) else f"{low:.0f}-{high:.0f}"


if __name__ == "__main__":          # python -m plclab.cnc.feeds: the table for the docs
    print("\n".join(measure_table()))
