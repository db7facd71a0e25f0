"""`plclab cnc PART.nc`: a part program through the G-code front end onto the CNC stand in
virtual time; per frame the contour error against its bound; the tool path as CSV, a plot
(matplotlib) and an SVG."""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Optional, Sequence

from plclab.cnc.feeds import REACHED_TOLERANCE, reached_feed, slow_reason
from plclab.nc.gcode import Frame, Program, parse_file
from plclab.nc.toolpath import HEADER, BlockResult, OffsetResult, check_blocks, check_offsets, path_mm
from plclab.errors import PlcLabError
from plclab.fileio import check_output, open_atomic, write_text


@dataclass
class CncResult:
    program: Program
    blocks: list[BlockResult]
    offsets: list[OffsetResult]
    missed: dict[str, int]
    finished: bool
    lines: list[str]
    files: list[Path]
    feeds: list["FrameFeed"] = field(default_factory=list)     # per frame: programmed and reached

    @property
    def slow(self) -> list["FrameFeed"]:
        """The frames whose reached feed is below the programmed one (by REACHED_TOLERANCE)."""
        return [f for f in self.feeds if f.slow]

    @property
    def ok(self) -> bool:
        return (self.finished and all(b.ok for b in self.blocks) and all(o.ok for o in self.offsets)
                and not any(self.missed.values()))


def run_cnc(part: str, method: str = "evalfn", step_mm: float = 0.01, feed: Optional[float] = None,
            csv: Optional[str] = None, vcd: Optional[str] = None, plot: Optional[str] = None,
            svg: Optional[str] = None, diagonal: bool = False,
            tools: Optional[dict[int, float]] = None, drive: str = "step",
            program: Optional[Sequence[str]] = None, fine_cycle: Optional[int] = None) -> CncResult:
    """Run part program `part` on the CNC stand: the shipped program (a checkout's model
    answer of FB_CncEvalLinear), or with `program` the student's files (their
    FB_CncEvalLinear in place of the stub, or a complete program: cnc.program_sources);
    `fine_cycle` ms: the program's fine cycle (default 1 ms; 5 is the OpenPLC build's)."""
    from plclab.stands import cnc
    from plclab.trace import write_vcd

    if method not in cnc.METHODS:
        raise PlcLabError(f"unknown method '{method}' (one of {', '.join(cnc.METHODS)})")
    if drive not in cnc.DRIVES:
        raise PlcLabError(f"unknown drive '{drive}' (one of {', '.join(cnc.DRIVES)})")
    if not 0.001 <= step_mm <= 1.0:
        raise PlcLabError(f"--step {step_mm}: the drives' step must be 0.001..1 mm")
    if feed is not None and feed <= 0:
        raise PlcLabError(f"--feed {feed}: the feed must be > 0 mm/min")
    if fine_cycle is not None:
        cnc.check_fine_ms(fine_cycle)    # else the program's own cycle (the shipped one's: 1 ms)
    for target in (csv, vcd, plot, svg):
        if target:
            check_output(target)         # a bad output is refused before the run
    srcs = cnc.program_sources(program) if program else None      # a bad ST file: file:line:col, nothing run
    variant = cnc.STAND.richest_variant
    if srcs is None and method == "evalfn" and not cnc.STAND.variant(variant).reference:
        raise PlcLabError(f"--method evalfn runs {cnc.STUDENT_BLOCK}, the students' Task 4 block, and this "
                          f"installed package ships only its stub: run yours with --program "
                          f"{cnc.STUDENT_BLOCK}.st (or use --method dda or integration)")
    gcode = parse_file(part, tools, step_mm)
    frames = gcode.frames
    if feed is not None:
        frames = [f if f.kind == 0 else replace(f, feed=feed) for f in frames]
    if not frames:
        raise PlcLabError(f"{part}: no motion in the part program")
    s = cnc.session(variant, program=srcs, step_mm=step_mm, fine_ms=fine_cycle)
    _check_travel(frames, s.plant)
    length = sum(math.dist(f.start, f.end) if not f.is_arc else 2 * math.pi * math.hypot(f.i, f.j)
                 for f in frames)
    fine_s = cnc.fine_cycle_s(s)
    slowest = min(min(f.feed, 60.0 * step_mm / fine_s / math.sqrt(2)) for f in frames) / 60.0
    run = cnc.run_part(s, frames, method, diagonal, timeout=10.0 + 3.0 * length / slowest, drive=drive)
    blocks = check_blocks(run.executed, run.points, step_mm, method, start_time=run.start, drive=drive,
                          fine_s=fine_s)
    offsets = check_offsets(frames, run.executed, step_mm)
    feeds = [frame_feed(f, b, method, drive, diagonal, fine_s, step_mm) for f, b in zip(run.executed, blocks)]
    lines = list(gcode.notes) + [f"{part}: {len(frames)} frames, method {method}, step {step_mm:g} mm, "
                                   f"drive {drive}, fine cycle {fine_s * 1000:g} ms", FRAME_HEADER]
    for b, fd in zip(blocks, feeds):
        lines.append(frame_row(b, fd))
        if fd.slow:
            lines.append(f"      frame {b.index} reached {fd.reached:.0f} of F{fd.programmed:g} mm/min "
                         f"({fd.reached / fd.programmed:.0%}): {fd.why}")
    if offsets:
        lines.append("tool-radius correction (frames on the equidistant):")
        lines += [o.row() for o in offsets]
    if run.prep_error:
        lines.append(f"the PLC could not build the tool-radius correction at frame {run.prep_error}")
    worst = max(blocks, key=lambda b: b.error_mm - b.bound_mm)
    lines.append(f"largest contour error {max(b.error_mm for b in blocks):.4f} mm "
                 f"(frame {worst.index}: bound {worst.bound_mm:.4f} mm); "
                 f"frames to the step grid: up to {max(b.grid_mm for b in blocks):.4f} mm; "
                 f"missed steps {sum(run.missed.values())}")
    if not run.finished:
        lines.append("the part program did not end (see the stand's timeline)")
    files = []
    points = path_mm(run.points, step_mm)
    if csv:
        files.append(_write_csv(csv, run.points, step_mm, feeds))
    if vcd:
        write_vcd(s.trace, vcd)
        files.append(Path(vcd))
    if plot:
        files.append(_plot(plot, frames, run.executed, points, blocks, step_mm, part, method))
    if svg:
        files.append(_svg(svg, frames, points))
    result = CncResult(gcode, blocks, offsets, run.missed, run.finished, lines, files, feeds)
    slow = f"; {len(result.slow)} of {len(blocks)} frames below their programmed feed (said above)" \
        if result.slow else ""
    lines.append(f"ok: every frame within its bound{slow}" if result.ok else f"FAILED: see the rows above{slow}")
    return result


@dataclass(frozen=True)
class FrameFeed:
    """A frame's feed: the programmed one (None for a rapid, which runs at the stand's top
    rate) and the one reached, path length over the frame's time, mm/min; `why` it is lower."""

    programmed: Optional[float]
    reached: Optional[float]
    why: str = ""

    @property
    def slow(self) -> bool:
        return bool(self.why)


def frame_feed(f: Frame, b: BlockResult, method: str, drive: str, diagonal: bool, fine_s: float,
               h: float) -> FrameFeed:
    """Frame `f`'s programmed and reached feed (its result `b`), and why it ran slower."""
    reached = reached_feed(b.length_mm, b.time_s)
    if f.kind == 0:
        return FrameFeed(None, reached)
    if reached is not None and reached < f.feed * (1 - REACHED_TOLERANCE):
        return FrameFeed(f.feed, reached, slow_reason(f, b.length_mm, f.feed, reached, method, drive, diagonal,
                                                      fine_s, h))
    return FrameFeed(f.feed, reached)


FRAME_HEADER = HEADER + f" {'F mm/min':>9} {'reached':>9}"


def frame_row(b: BlockResult, fd: FrameFeed) -> str:
    """A frame's row of the table: contour figures, the programmed and the reached feed, the
    verdict ("ok" only when within the bound and at the programmed feed)."""
    row = b.row()
    verdict = "ok" if b.ok else "OUT OF BOUND"
    figures = row[:row.rindex(verdict)].rstrip()
    programmed = "rapid" if fd.programmed is None else f"{fd.programmed:.1f}"
    reached = "-" if fd.reached is None else f"{fd.reached:.1f}"
    if fd.slow:
        verdict = "in bound, BELOW THE FEED" if b.ok else verdict + ", BELOW THE FEED"
    return f"{figures} {programmed:>9} {reached:>9}  {verdict}"


PLOTTED_SCENARIOS = ("square", "circle", "star", "pocket", "backlash", "blank")


def plot_scenario(name: str, path: str) -> Path:
    """Run scenario `name` of the CNC stand and draw its tool path, the error per frame and the
    feed (the pictures of docs/cnc.md: docs/img/cnc-NAME.png)."""
    from plclab.stands import cnc

    if name not in PLOTTED_SCENARIOS:
        raise PlcLabError(f"no tool path to plot in scenario '{name}' (one of {', '.join(PLOTTED_SCENARIOS)})")
    check_output(path)
    s = cnc.session()
    cnc.SCENARIOS[name](s)
    run = s.cnc_run                       # type: ignore[attr-defined]
    blocks = check_blocks(run.executed, run.points, run.step_mm, run.method, run.frames_start, run.origin,
                          drive=run.drive, fine_s=run.fine_s)
    return _plot(path, run.frames, run.executed, path_mm(run.points, run.step_mm), blocks, run.step_mm,
                 f"scenario {name}", run.method)


def _check_travel(frames: list[Frame], plant) -> None:
    lo, hi = plant.travel[0] * plant.step_mm, plant.travel[1] * plant.step_mm
    for f in frames:
        reach = [f.end]
        if f.is_arc:
            cx, cy = f.centre
            r = math.hypot(f.i, f.j)
            reach += [(cx - r, cy - r, 0.0), (cx + r, cy + r, 0.0)]
        for p in reach:
            if any(not lo < v < hi for v in p):
                raise PlcLabError(f"line {f.line}: the block leaves the table's travel ({lo:g}..{hi:g} mm)")


CSV_HEADER = "time_s,X,Y,Z,frame,feed_mm_min,reached_mm_min"


def _write_csv(path: str, points, h: float, feeds: list[FrameFeed]) -> Path:
    """The tool path, a row per move: time, position (mm), the frame it belongs to and that
    frame's programmed feed (empty for a rapid) and reached feed, the table's figures."""
    def cell(v: Optional[float]) -> str:
        return "" if v is None else f"{v:.1f}"

    with open_atomic(path) as fh:
        fh.write(CSV_HEADER + "\n")
        for t, k, x, y, z in points:
            fd = feeds[k - 1] if 1 <= k <= len(feeds) else FrameFeed(None, None)
            fh.write(f"{t:.6f},{x * h:.4f},{y * h:.4f},{z * h:.4f},{k},{cell(fd.programmed)},{cell(fd.reached)}\n")
    return Path(path)


def contour(frames: list[Frame], per_mm: int = 20) -> list[tuple[float, float]]:
    """The programmed contour as a dense polyline (mm)."""
    pts = [frames[0].start[:2]]
    for f in frames:
        if not f.is_arc:
            pts.append(f.end[:2])
            continue
        cx, cy = f.centre
        r = math.hypot(f.i, f.j)
        a0 = math.atan2(f.start[1] - cy, f.start[0] - cx)
        a1 = math.atan2(f.end[1] - cy, f.end[0] - cx)
        sweep = ((a1 - a0) if f.kind == 3 else (a0 - a1)) % (2 * math.pi) or 2 * math.pi
        n = max(8, int(sweep * r * per_mm))
        sign = 1 if f.kind == 3 else -1
        pts += [(cx + r * math.cos(a0 + sign * sweep * k / n), cy + r * math.sin(a0 + sign * sweep * k / n))
                for k in range(1, n + 1)]
    return pts


def _plot(path: str, frames, executed, points, blocks, h, part, method) -> Path:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 11))
    FigureCanvasAgg(fig)
    ax, ax_err, ax_feed = fig.subplots(3, 1, gridspec_kw={"height_ratios": [3, 1, 1]})
    cx, cy = zip(*contour(frames))
    ax.plot(cx, cy, "k--", lw=0.8, label="programmed contour")
    if any(f.comp for f in frames) or executed[-1].end != frames[-1].end:
        ex, ey = zip(*contour(executed))
        ax.plot(ex, ey, ":", color="tab:orange", lw=1.0, label="executed frames (corrected)")
    if points:
        ax.plot([p[1] for p in points], [p[2] for p in points], "b-", lw=0.8, label="tool path")
    ax.set_aspect("equal")
    ax.set_title(f"{Path(part).name}: {method}, step {h:g} mm")
    ax.set_xlabel("X mm")
    ax.set_ylabel("Y mm")
    ax.legend(loc="best")
    ax_err.bar([b.index for b in blocks], [b.error_mm for b in blocks], color="tab:blue", label="largest error")
    ax_err.step([b.index for b in blocks], [b.bound_mm for b in blocks], "r-", where="mid", label="bound")
    ax_err.set_xlabel("frame")
    ax_err.set_ylabel("contour error mm")
    ax_err.legend(loc="best")
    if len(points) > 1:
        window = max(1, len(points) // 400)
        ts, vs = [], []
        for a, b in zip(points[::window], points[window::window]):
            if b[0] > a[0]:
                ts.append(b[0])
                vs.append(math.dist(a[1:], b[1:]) / (b[0] - a[0]) * 60.0)
        ax_feed.plot(ts, vs, "g-", lw=0.8)
    ax_feed.set_xlabel("time s")
    ax_feed.set_ylabel("feed mm/min")
    fig.tight_layout()
    with open_atomic(path, binary=True) as fh:
        fig.savefig(fh, format="png")
    return Path(path)


def _svg(path: str, frames, points) -> Path:
    prog = contour(frames)
    path_pts = [(p[1], p[2]) for p in points] or prog[:1]
    xs = [x for x, _ in prog + path_pts]
    ys = [y for _, y in prog + path_pts]
    pad = 0.05 * max(max(xs) - min(xs), max(ys) - min(ys), 1.0)
    x0, y0, w, hgt = min(xs) - pad, min(ys) - pad, max(xs) - min(xs) + 2 * pad, max(ys) - min(ys) + 2 * pad

    def poly(pts, style):
        d = " ".join(f"{x:.4f},{-y:.4f}" for x, y in pts)
        return f'  <polyline fill="none" {style} points="{d}"/>'

    text = "\n".join([
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{x0:.4f} {-(y0 + hgt):.4f} {w:.4f} {hgt:.4f}" '
        f'width="800" height="{800 * hgt / w:.0f}">',
        poly(prog, f'stroke="black" stroke-dasharray="{w / 200:.4f}" stroke-width="{w / 800:.4f}"'),
        poly(path_pts, f'stroke="blue" stroke-width="{w / 800:.4f}"'),
        "</svg>", ""])
    return write_text(path, text)
