"""Checks of a tool path against the programmed contour and the interpolators' error
bounds (textbook 4.2.1, docs/cnc.md): per frame its length, time, largest contour error,
end-point error. The contour is the frame as the PLC got it (end points and centre on the
steps' grid); how far that grid frame is from the programmed one is reported apart.

Bounds: one step h for the evaluation-function method (every visited point within h of the
line, radial error within h); for the DDA and digital-integration methods the pulses keep
within half a pulse per axis of the interpolated point (h / sqrt 2 from the contour), and
an arc by digital integration adds the accumulated error of eq. (19), N R dphi^3 / 3!, and
the chord's sag R (1 - cos(dphi / 2)) between interpolation cycles. With the pulse-count
drive (the paper's module) the table passes the interpolator's points at the cycles' ends and
between them follows the staircase of the generator's evenly spread pulses: half a pulse per
axis more, h / sqrt 2.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from plclab.nc.gcode import Frame

INTERPOLATION_CYCLE_S = 0.004      # PRG_CncStand: T = 4 fine cycles of 1 ms
STEP_DRIVE_FEED = 600.0            # mm/min: the top feed the arcs' bound assumes with step/direction bits
PULSE_FEED_MAX_STEPS = 15_000.0    # PRG_CncStand.PULSE_FEED_MAX: steps/s with the pulse counts (DDA, integration)


@dataclass(frozen=True)
class BlockResult:
    index: int                 # 1-based frame number
    line: int                  # source line of the block
    kind: int
    length_mm: float
    time_s: float
    error_mm: float            # largest contour error of the visited points
    bound_mm: float
    end_error_mm: float
    grid_mm: float             # programmed frame -> the steps' grid

    @property
    def ok(self) -> bool:
        return self.error_mm <= self.bound_mm + 1e-9 and self.end_error_mm <= 1e-9

    def row(self) -> str:
        verdict = "ok" if self.ok else "OUT OF BOUND"
        return (f"{self.index:>5} {self.line:>5}  G{self.kind:02d} {self.length_mm:9.3f} {self.time_s:8.3f} "
                f"{self.error_mm:9.4f} {self.bound_mm:9.4f} {self.end_error_mm:9.4f}  {verdict}")


HEADER = f"{'frame':>5} {'line':>5}  {'G':3} {'length mm':>9} {'time s':>8} {'error mm':>9} {'bound mm':>9} {'end mm':>9}"


def grid(v: float, h: float) -> int:
    return round(v / h)


def check_blocks(frames: Sequence[Frame], points: Sequence[tuple[float, int, int, int, int]], h: float,
                 method: str, start_time: float = 0.0,
                 origin: tuple[int, ...] = (0, 0, 0), drive: str = "step",
                 fine_s: float = 0.001) -> list[BlockResult]:
    """One result per frame; `points` are (time, frame, x, y, z) in steps, in time order;
    frame 1 starts at `origin` (steps) at `start_time`; `drive` "pulse": the pulse-count drive;
    `fine_s` the program's fine cycle (the interpolation cycle is 4 of them)."""
    results = []
    prev_end = tuple(origin)
    prev_time = start_time
    for k, f in enumerate(frames, start=1):
        pts = [p for p in points if p[1] == k]
        start = prev_end
        end = tuple(grid(v, h) for v in f.end)
        visited = [start] + [p[2:] for p in pts]
        error = max((_error(f, start, end, q, h) for q in visited), default=0.0) * h
        reached = visited[-1]
        end_error = math.dist(reached, end) * h
        t_end = pts[-1][0] if pts else prev_time
        results.append(BlockResult(k, f.line, f.kind, _length(f), t_end - prev_time, error,
                                   _bound(f, method, h, drive, fine_s) + (h / math.sqrt(2) if drive == "pulse" else 0.0),
                                   end_error, _grid_error(f, start, end, h)))
        prev_end, prev_time = reached, t_end
    return results


def _error(f: Frame, start, end, q, h: float) -> float:
    """Contour error of point q, in steps, against the grid frame."""
    if f.is_arc:
        cx, cy = start[0] + grid(f.centre[0], h) - grid(f.start[0], h), start[1] + grid(f.centre[1], h) - grid(f.start[1], h)
        r = math.hypot(start[0] - cx, start[1] - cy)
        return abs(math.hypot(q[0] - cx, q[1] - cy) - r)
    return segment_distance(start, end, q)


def segment_distance(a, b, q) -> float:
    d = [bi - ai for ai, bi in zip(a, b)]
    dd = sum(c * c for c in d)
    if dd == 0:
        return math.dist(a, q)
    t = max(0.0, min(1.0, sum((qi - ai) * di for ai, qi, di in zip(a, q, d)) / dd))
    return math.dist([ai + t * di for ai, di in zip(a, d)], q)


def _length(f: Frame) -> float:
    if not f.is_arc:
        return math.dist(f.start, f.end)
    return abs(_sweep(f)) * math.hypot(f.i, f.j)


def _sweep(f: Frame) -> float:
    cx, cy = f.centre
    a0 = math.atan2(f.start[1] - cy, f.start[0] - cx)
    a1 = math.atan2(f.end[1] - cy, f.end[0] - cx)
    s = (a1 - a0) if f.kind == 3 else (a0 - a1)
    s %= 2 * math.pi
    return s if s > 1e-12 else 2 * math.pi


def _bound(f: Frame, method: str, h: float, drive: str = "step", fine_s: float = 0.001) -> float:
    if method == "evalfn":
        return h
    bound = h / math.sqrt(2)
    if f.is_arc:
        r = math.hypot(f.i, f.j)
        step_top = STEP_DRIVE_FEED * 0.001 / fine_s
        top = max(step_top, PULSE_FEED_MAX_STEPS * h * 60.0) if drive == "pulse" else step_top
        dphi = min(f.feed, top) / 60.0 * INTERPOLATION_CYCLE_S * fine_s / 0.001 / r
        n = math.ceil(_sweep(f) / dphi)
        bound += n * r * dphi ** 3 / 6 + r * (1 - math.cos(dphi / 2))
    return bound


def _grid_error(f: Frame, start, end, h: float) -> float:
    return max(math.dist(end, [v / h for v in f.end]), 0.0) * h


@dataclass(frozen=True)
class OffsetResult:
    """A frame on the equidistant: how far its executed ends are from the programmed contour."""

    index: int
    line: int
    wanted_mm: float           # the tool radius
    distance_mm: tuple[float, float]   # of the executed start and end from the programmed line / circle
    tolerance_mm: float        # the ends are rounded to the steps' grid

    @property
    def ok(self) -> bool:
        return all(abs(d - self.wanted_mm) <= self.tolerance_mm for d in self.distance_mm)

    def row(self) -> str:
        verdict = "ok" if self.ok else "NOT AT THE TOOL RADIUS"
        return (f"{self.index:>5} {self.line:>5}  equidistant at {self.distance_mm[0]:.4f} / "
                f"{self.distance_mm[1]:.4f} mm, tool radius {self.wanted_mm:g} mm  {verdict}")


def check_offsets(programmed: Sequence[Frame], executed: Sequence[Frame], h: float) -> list[OffsetResult]:
    """Textbook 4.2.2.1: every frame that runs fully on the equidistant (corrected, after a
    frame corrected to the same side) lies at the tool radius from its programmed line or
    circle (an arc's radius becomes R +/- the tool radius); the ends are on the steps' grid."""
    results = []
    for k in range(1, len(programmed)):
        f, prev = programmed[k], programmed[k - 1]
        if not f.comp or prev.comp != f.comp:
            continue
        e = executed[k]
        if f.is_arc:
            cx, cy = f.centre
            r = math.hypot(f.i, f.j)
            dist = tuple(abs(math.hypot(p[0] - cx, p[1] - cy) - r) for p in (e.start, e.end))
        else:
            dist = tuple(_line_distance(f.start[:2], f.end[:2], p[:2]) for p in (e.start, e.end))
        results.append(OffsetResult(k + 1, f.line, f.tool_radius, dist, h / math.sqrt(2) + 1e-9))
    return results


def _line_distance(a, b, q) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    return abs(dx * (q[1] - a[1]) - dy * (q[0] - a[0])) / math.hypot(dx, dy)


def path_mm(points, h: float) -> list[tuple[float, float, float, float]]:
    return [(t, x * h, y * h, z * h) for t, _k, x, y, z in points]
