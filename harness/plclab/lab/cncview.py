"""What the lab shows of the CNC stand (`plclab lab cnc`, docs/lab.md) beyond its console: the
feed override and backlash settings' actions, the part program it runs, and the table's state
for the drawing -- the contour, the tool path as it is cut, the contour error against the
interpolator's bound, the drives' step counters and missed steps. Its look (labels, hints,
knobs) is in lab/panels.py with the other stands' looks, which uses this module and not the
other way round.

The part program is parsed and loaded into the PLC's frame table as `plclab cnc` does
(plclab.stands.cnc.load_frames); the tool path is the table's positions the session's trace
recorded (the step counters CNT_X / CNT_Y), read incrementally; the error of each visited
point is its distance to the frame being executed (as the PLC got it, after tool-radius
correction), and each frame's bound is the one `plclab cnc` checks (plclab.nc.toolpath).
"""
from __future__ import annotations

import math
from typing import Any

from plclab.scenario import Session

MAX_PATH_POINTS = 400       # tool path points sent per snapshot (the rest thinned out)


def _signed(v: int) -> int:
    v = int(v) & 0xFFFF
    return v - 0x10000 if v >= 0x8000 else v


class CncPart:
    """Part programs for the lab: parse, load into the frame table, describe."""

    methods = ("evalfn", "dda", "integration")

    def describe(self) -> dict:
        from plclab.stands.cnc import SQUARE
        return {"methods": list(self.methods), "example": SQUARE}

    def load(self, s: Session, text: str, name: str, method: str) -> str:
        from plclab.nc.gcode import parse
        from plclab.stands.cnc import load_frames
        if method not in self.methods:
            raise ValueError(f"method {method!r}: one of {', '.join(self.methods)}")
        if s.plc.state == "RUN" and _read(s, "HL1", False):
            raise ValueError("the table is running a part program: stop it (SB2) or let it end first")
        program = parse(text, name)               # GcodeError: `name:line:col: error: ...`
        if not program.frames:
            raise ValueError(f"{name}: no motion in the part program")
        load_frames(s, program.frames, method)
        st = _state(s)
        st.update(frames=program.frames, method=method, name=name, executed=None, err={}, bound={},
                  origin=tuple(s.plant.axes[a].steps for a in "XYZ"), contour_id=st.get("contour_id", 0) + 1,
                  ix=_count(s, "CNT_X"), iy=_count(s, "CNT_Y"), path_all=[],
                  missed0=s.plant.missed(),            # missed steps counted from this part on
                  fresh=True)                          # not started yet: the PLC's Frame and ProgramEnd are the last part's
        return f"{len(program.frames)} frames of {name} loaded ({method})"


def _count(s: Session, name: str) -> int:
    return s.trace.change_count(name) if name in s.trace else 0


def _state(s: Session) -> dict:
    return s.__dict__.setdefault("lab_cnc", {"frames": [], "contour_id": 0, "err": {}, "bound": {}, "path_all": []})


MAX_KEPT_POINTS = 20000     # tool path points kept for a page that (re)connects (thinned beyond)

# The shipped program's cycle state (PRG_CncStand.State): what the drawing says the table does.
CYCLE_STATES = {0: "idle", 1: "running", 2: "feed hold (SB1 continues)", 3: "single block: stopped after the frame (SB1 continues)",
                4: "stopped: emergency stop or limit (SB1 restarts)", 5: "measuring the blank"}


def _keep_path(st: dict, path: list) -> None:
    kept = st.setdefault("path_all", [])
    kept.extend(path)
    if len(kept) > MAX_KEPT_POINTS:
        del kept[1:-1:2]


def _read(s: Session, name: str, default: Any) -> Any:
    try:
        return s.value(name)
    except Exception:        # noqa: BLE001 - a student's program need not have it
        return default


def _geometry(f: Any, h: float) -> tuple:
    """A frame in steps: ('line', start, end) or ('arc', centre, radius)."""
    start = (f.start[0] / h, f.start[1] / h)
    if f.is_arc:
        cx, cy = f.centre[0] / h, f.centre[1] / h
        return ("arc", (cx, cy), math.hypot(start[0] - cx, start[1] - cy))
    return ("line", start, (f.end[0] / h, f.end[1] / h))


def _distance(g: tuple, q: tuple[float, float]) -> float:
    from plclab.nc.toolpath import segment_distance
    if g[0] == "arc":
        return abs(math.dist(q, g[1]) - g[2])
    return segment_distance(g[1], g[2], q)


def _bound(s: Session, st: dict, k: int, f: Any, h: float) -> float:
    """Frame k's error bound, as `plclab cnc` checks it (plclab.nc.toolpath.check_blocks)."""
    if k not in st["bound"]:
        from plclab.nc.toolpath import check_blocks
        origin = tuple(round(v / h) for v in f.start)
        from plclab.stands.cnc import fine_cycle_s
        st["bound"][k] = check_blocks([f], [], h, st["method"], origin=origin, fine_s=fine_cycle_s(s))[0].bound_mm
    return st["bound"][k]


def _new_points(s: Session, st: dict) -> list[tuple[float, float]]:
    """The table's (x, y) in steps at each change the trace recorded since the last call."""
    trace = s.trace
    if "CNT_X" not in trace or "CNT_Y" not in trace:
        return []
    xs = trace.changes_from("CNT_X", max(0, st.get("ix", 0)))
    ys = trace.changes_from("CNT_Y", max(0, st.get("iy", 0)))
    st["ix"], st["iy"] = trace.change_count("CNT_X"), trace.change_count("CNT_Y")
    x = st.get("x", _signed(trace.value_at_ns("CNT_X", xs[0][0] if xs else 0) or 0))
    y = st.get("y", _signed(trace.value_at_ns("CNT_Y", ys[0][0] if ys else 0) or 0))
    events = sorted([(t, 0, v) for t, v in xs] + [(t, 1, v) for t, v in ys])
    out = []
    for i, (t, axis, v) in enumerate(events):
        if axis == 0:
            x = _signed(v)
        else:
            y = _signed(v)
        if i + 1 == len(events) or events[i + 1][0] != t:
            out.append((x, y))
    st["x"], st["y"] = x, y
    return out


def cnc_mimic(s: Session) -> dict[str, Any]:
    p = s.plant
    h = p.step_mm
    st = _state(s)
    frames = st["frames"]
    frame = int(_read(s, "Frame", 0) or 0)
    running = bool(_read(s, "HL1", False))
    if st.get("fresh") and running:
        st["fresh"] = False
    if st.get("fresh"):                  # loaded, not yet started: no frame of it executed, no end
        frame = 0
    if frames and frame >= 1 and st.get("executed") is None and running:   # as the PLC runs them
        from plclab.stands.cnc import executed_frames
        try:
            st["executed"] = executed_frames(s, frames, st["origin"])
        except Exception:    # noqa: BLE001 - a student's program need not have the executed table
            st["executed"] = frames
        st["contour_id"] += 1
    contour = st.get("executed") or frames
    points = _new_points(s, st)
    error_now = None
    if contour and 1 <= frame <= len(contour):
        ks = [k for k in (frame - 1, frame) if 1 <= k <= len(contour)]
        geos = {k: _geometry(contour[k - 1], h) for k in ks}
        for q in points:
            d = min(_distance(geos[k], q) for k in ks) * h
            st["err"][frame] = max(st["err"].get(frame, 0.0), d)
            error_now = d
    worst = max(st["err"].items(), key=lambda kv: kv[1], default=(None, 0.0))
    bound = _bound(s, st, worst[0], contour[worst[0] - 1], h) if worst[0] and contour else None
    step = max(1, len(points) // MAX_PATH_POINTS)
    path = [[round(x * h, 4), round(y * h, 4)] for x, y in points[::step]]
    if points and (len(points) - 1) % step:
        path.append([round(points[-1][0] * h, 4), round(points[-1][1] * h, 4)])
    _keep_path(st, path)
    # missed steps since the part was loaded or the faults were last cleared (a new start)
    if st.get("faulted") and not p.faults:
        st["missed0"] = p.missed()
    st["faulted"] = bool(p.faults)
    base = st.get("missed0") or {}
    missed = {a: n - base.get(a, 0) for a, n in p.missed().items()}
    cycle = _read(s, "State", None)
    return {
        "x": round(p.position_mm("X"), 4), "y": round(p.position_mm("Y"), 4), "z": round(p.position_mm("Z"), 4),
        "steps": {a: p.axes[a].steps for a in "XYZ"}, "missed": missed, "override": p.override,
        "cycle": CYCLE_STATES.get(cycle) if isinstance(cycle, int) else None,
        "frame": frame, "frames": len(frames), "end": not st.get("fresh") and bool(_read(s, "ProgramEnd", False)),
        "part": st.get("name"), "method": st.get("method"), "contour_id": st["contour_id"],
        "path": path,
        "error_mm": round(worst[1], 5), "error_frame": worst[0], "bound_mm": round(bound, 5) if bound else None,
        "error_now_mm": round(error_now, 5) if error_now is not None else None,
        "step_mm": h, "faults": sorted(p.faults), "travel_mm": [v * h for v in p.travel],
    }


def cnc_contour(s: Session) -> dict:
    """The contour drawn under the tool path (the page asks when `contour_id` changes)."""
    st = _state(s)
    frames = st.get("executed") or st["frames"]
    return {"contour_id": st["contour_id"], "contour": _polyline(frames) if frames else [],
            "path": list(st.get("path_all", []))}       # the path cut so far: a reloaded page draws it again


def _polyline(frames: list) -> list[list[float]]:
    from plclab.cnc.run import contour
    return [[round(x, 4), round(y, 4)] for x, y in contour(frames, per_mm=4)]


def set_override(s: Session, value: int) -> None:
    s.plant.set_override(value)
    s.log(f"RP1 feed override {value} %")


def set_backlash(s: Session, value: int) -> None:
    s.plant.set_backlash(value)
    s.log(f"backlash {value} steps")


def set_fine_cycle(s: Session, value: int) -> None:
    """PRG_CncStand's fine cycle, as `plclab cnc --fine-cycle` runs it (5 ms: the OpenPLC
    build's): the program's task and FINE_MS, downloaded again (a cold start; the table stays
    where it is), and the plant's pulse generator in step with it."""
    from plclab.errors import PlcLabError
    from plclab.plants.base import PlantError
    from plclab.stands.cnc import fine_cycle_params, with_fine_cycle

    try:
        srcs = with_fine_cycle(s.sources, value)
    except PlcLabError as e:
        raise PlantError(str(e)) from None
    s.tick_ns = None                          # the task's own interval
    s.load_program(srcs)
    for name, v in fine_cycle_params(value).items():
        setattr(s.plant, name, v)
    _state(s)["bound"] = {}                   # the arcs' bounds follow the interpolation cycle
    s.log(f"fine cycle {value} ms (FineTask and FINE_MS; the program restarted)")

