"""The CNC stand (docs/cnc.md): an X-Y-Z table with step/direction drives run by
PRG_CncStand in a 1 ms fine-cycle task (or another: with_fine_cycle, `--fine-cycle MS`),
executing a part program's frames with the evaluation-function, DDA or digital-integration
interpolators of textbook chapter 4.

`run_part` loads a part program's frames into the PLC's frame table (GVL_CNC), presses
SB1 and records the table's path, frame by frame; `plclab cnc` and the scenarios use it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Optional, Sequence

from plclab.nc.gcode import Frame, parse
from plclab.scenario import ScenarioFailure, Session
from plclab.stands import Stand, Task, Variant
from plclab.stands.base import Fault, FaultParam, StandSpec
from plclab.trace import Trace

POUS = ("FC_CncArcQuadrant", "FC_CncAngle", "FB_CncEvalLinear", "FB_CncEvalCircular", "FB_CncDdaPulses",
        "FB_CncDdaLinear", "FB_CncIntegLinear", "FB_CncIntegCircular", "FB_CncToolCorner", "FB_CncToolRadius",
        "FB_CncProbeHole", "FB_CncBlankSetup", "FB_CncBlankTransform", "FB_CncBacklash", "PRG_CncStand")
FINE_CYCLE_S = 0.001          # the shipped program's fine cycle (its FineTask, FINE_MS)
FINE_MS_RANGE = (1, 20)        # --fine-cycle MS: whole milliseconds (5: the OpenPLC build's)
NFINE = 4                      # PRG_CncStand: fine cycles per interpolation cycle T
MAX_FRAMES = 200
METHODS = {"evalfn": 0, "dda": 1, "integration": 2}

TASKS = (Task("FineTask", "T#1ms", 0, (("Main", "PRG_CncStand"),)),)
STAND = Stand(
    name="cnc",
    title="CNC stand (X-Y-Z table, step/direction drives)",
    gvl=("GVL_CNC",),
    variants={
        "baseline": Variant("baseline", POUS, TASKS,
                            "The students' start: FB_CncEvalLinear is theirs to write, Task 4."),
        "full": Variant("full", POUS, TASKS,
                        "Part program from the frame table; interpolators of textbook chapter 4.",
                        reference=True),
    },
)


def session(variant: str = "full", program: Optional[list[tuple[str, str]]] = None,
            retain_path=None, step_mm: float = 0.01, fine_ms: Optional[int] = None, checked=None,
            **plant_params) -> Session:
    """A fresh stand (SPEC.session): the table at the machine zero, drives of `step_mm`;
    with `fine_ms` the program (the variant's, or `program`) runs that fine cycle
    (with_fine_cycle) and the plant knows it (fine_cycle_params)."""
    if fine_ms is not None:
        from plclab.stands import sources
        program = with_fine_cycle(list(program) if program is not None else sources(STAND, variant), fine_ms)
        checked = None
        plant_params = {**fine_cycle_params(fine_ms), **plant_params}
    return SPEC.session(variant, program, retain_path, step_mm=step_mm, checked=checked, **plant_params)


def check_fine_ms(fine_ms: float) -> int:
    """`--fine-cycle MS`: whole milliseconds in FINE_MS_RANGE, or one clear error."""
    lo, hi = FINE_MS_RANGE
    if fine_ms != int(fine_ms) or not lo <= fine_ms <= hi:
        from plclab.errors import PlcLabError
        raise PlcLabError(f"--fine-cycle {fine_ms:g}: the fine cycle is {lo}..{hi} whole ms "
                          f"(1 the stand's default, 5 the OpenPLC build's)")
    return int(fine_ms)


def fine_cycle_params(fine_ms: int) -> dict[str, float]:
    """The plant for a program of fine cycle `fine_ms`: its period (what the harness reads
    back as the fine cycle, fine_cycle_s) and the pulse generator spreading a cycle's counts
    over the program's interpolation cycle T = NFINE fine cycles."""
    return {"period": fine_ms / 1000.0, "pulse_cycle": NFINE * fine_ms / 1000.0}


def fine_cycle_s(s: Session) -> float:
    """The fine cycle the stand runs (s): the plant's period, set with the program's."""
    return float(getattr(s.plant, "period", FINE_CYCLE_S))


_FINE_TASK = r"(TASK FineTask \(INTERVAL := )T#\d+ms(, )"
_FINE_MS = r"(FINE_MS : LREAL := )\d+(?:\.\d*)?;"


def with_fine_cycle(srcs: Sequence[tuple[str, str]], fine_ms: int) -> list[tuple[str, str]]:
    """The program `srcs` (file name, text) running PRG_CncStand every `fine_ms` ms: its
    FineTask's interval and PRG_CncStand's FINE_MS constant (feeds, the interpolation cycle
    T and the rapids' rate follow it), the same edit `plclab build cnc --fine-cycle` makes.
    A program without exactly one of each is refused by name."""
    import re

    from plclab.errors import PlcLabError

    fine_ms = check_fine_ms(fine_ms)
    out, found = [], {"the FineTask's INTERVAL": 0, "PRG_CncStand's FINE_MS constant": 0}
    for name, text in srcs:
        text, n_task = re.subn(_FINE_TASK, rf"\g<1>T#{fine_ms}ms\g<2>", text)
        text, n_ms = re.subn(_FINE_MS, rf"\g<1>{fine_ms}.0;", text)
        found["the FineTask's INTERVAL"] += n_task
        found["PRG_CncStand's FINE_MS constant"] += n_ms
        out.append((name, text))
    for what, n in found.items():
        if n != 1:
            raise PlcLabError(f"--fine-cycle: the program has {n} of {what} (TASK FineTask (INTERVAL := T#1ms, "
                              f"...) and FINE_MS : LREAL := 1.0;), one expected")
    return out


STUDENT_BLOCK = "FB_CncEvalLinear"      # Task 4: the block a student writes (the package ships its stub)


def program_sources(files: Sequence[str]) -> list[tuple[str, str]]:
    """The program a student runs with `--program FILES`: a complete program (the files hold a
    CONFIGURATION, e.g. the handed-out bundle) as it is; otherwise the blocks the files declare
    (their FB_CncEvalLinear, and any helper of their own) replace the stand's blocks of the
    same names in the students' starting program, so one file with their Task 4 block runs
    on the shipped stand. A file that does not parse raises CompileError, its
    `file:line:col: error:` lines."""
    from plclab.errors import CompileError
    from plclab.frontend import read_sources
    from plclab.frontend.parser import parse_source
    from plclab.stands import sources

    given = read_sources(files)
    declared: set[str] = set()
    complete = False
    for name, text in given:
        unit, errors = parse_source(text, name)
        if errors:
            raise CompileError(errors)
        declared |= {pou.name.upper() for pou in unit.pous}
        complete = complete or bool(unit.configs)
    if complete:
        return given
    stand = [(name, text) for name, text in sources(STAND, STAND.starting_variant)
             if Path(name).stem.upper() not in declared]
    return stand[:-1] + given + stand[-1:]             # the configuration stays last


def _setup(s: Session) -> None:
    """The PLC's step size is the drives' (GVL_CNC.StepMm)."""
    s.plc.write("StepMm", s.plant.step_mm)


DRIVES = ("step", "pulse")     # step/direction bits on %QX, or pulse counts per cycle on %QW


FRAME_ARRAYS = ("FrameKind", "FrameX", "FrameY", "FrameZ", "FrameI", "FrameJ", "FrameFeed", "FrameComp",
                "FrameRadius")


def frame_table(frames: list[Frame], step_mm: float, method: str = "evalfn", diagonal: bool = False,
                drive: str = "step") -> dict[str, object]:
    """The PLC's frame table (GVL_CNC) for `frames`, in steps of `step_mm`: each of FRAME_ARRAYS
    as the list of its first len(frames) elements, and FrameCount, Method, Diagonal and
    PulseDrive. One source for load_frames (the harness writes it) and for the OpenPLC bundle
    (plclab.cnc.openplc: its initial values)."""
    if len(frames) > MAX_FRAMES:
        raise ScenarioFailure(f"{len(frames)} frames: the frame table holds {MAX_FRAMES}")
    if method not in METHODS:
        raise ScenarioFailure(f"unknown method {method!r} (one of {', '.join(METHODS)})")
    if drive not in DRIVES:
        raise ScenarioFailure(f"unknown drive {drive!r} (one of {', '.join(DRIVES)})")
    h = step_mm
    table: dict[str, list[int]] = {name: [] for name in FRAME_ARRAYS}
    for f in frames:
        table["FrameKind"].append(f.kind)
        for axis, v in zip("XYZ", f.end):
            table[f"Frame{axis}"].append(round(v / h))
        cx, cy = f.centre
        table["FrameI"].append(round(cx / h) - round(f.start[0] / h) if f.is_arc else 0)
        table["FrameJ"].append(round(cy / h) - round(f.start[1] / h) if f.is_arc else 0)
        table["FrameFeed"].append(round(f.feed / 60.0 / h))
        table["FrameComp"].append(f.comp)
        table["FrameRadius"].append(round(f.tool_radius / h))
    return {**table, "FrameCount": len(frames), "Method": METHODS[method], "Diagonal": bool(diagonal),
            "PulseDrive": drive == "pulse"}


def load_frames(s: Session, frames: list[Frame], method: str = "evalfn", diagonal: bool = False,
                drive: str = "step") -> None:
    """Write the frame table into the PLC (GVL_CNC), in steps of the drives, and the drive
    interface the program uses (GVL_CNC.PulseDrive)."""
    write = s.plc.write
    for name, value in frame_table(frames, s.plant.step_mm, method, diagonal, drive).items():
        if isinstance(value, list):
            for k, v in enumerate(value, start=1):
                write(f"{name}[{k}]", v)
        else:
            write(name, value)
    s.log(f"{len(frames)} frames loaded ({method})")


@dataclass
class PartRun:
    """What the table did: positions (steps) after each fine cycle with the frame they belong to."""

    frames: list[Frame]
    step_mm: float
    points: list[tuple[float, int, int, int, int]] = field(default_factory=list)   # t, frame, x, y, z
    missed: dict[str, int] = field(default_factory=dict)
    finished: bool = False
    start: float = 0.0         # s: when SB1 started the program
    executed: list[Frame] = field(default_factory=list)   # the frames as the PLC ran them (corrected)
    prep_error: int = 0        # frame whose tool-radius correction the PLC could not build
    origin: tuple[int, int, int] = (0, 0, 0)   # steps: where frame 1 started (after a measuring cycle)
    frames_start: float = 0.0  # s: when frame 1 started
    method: str = "evalfn"
    drive: str = "step"
    fine_s: float = FINE_CYCLE_S   # the program's fine cycle


SB1_HOLD_S = 0.005          # run_part's press of SB1


def run_part(s: Session, frames: list[Frame], method: str = "evalfn", diagonal: bool = False,
             timeout: float = 600.0, drive: str = "step") -> PartRun:
    """Load the frames, press SB1 and run until the program ends (or `timeout` s) and the
    pulse generator has spread its last counts. Every move is recorded, from the first scan
    that sees SB1 (the press is held SB1_HOLD_S while the recording runs)."""
    load_frames(s, frames, method, diagonal, drive)
    run = PartRun(frames, s.plant.step_mm, start=s.now, frames_start=s.now, method=method, drive=drive,
                  origin=tuple(s.plant.axes[a].steps for a in "XYZ"), fine_s=fine_cycle_s(s))
    s.plant.press("SB1")                 # held 5 ms, recorded from the first scan that sees it
    s.log("SB1 pressed (0.005 s)")
    record_until(s, run, "ProgramEnd", timeout, release=("SB1", s.now + SB1_HOLD_S))
    before = [p for p in run.points if p[1] == 0]          # a measuring cycle's moves
    if before:
        run.frames_start, run.origin = before[-1][0], before[-1][2:]
    run.finished = bool(s.plc.read("ProgramEnd"))
    run.executed = executed_frames(s, frames, run.origin)
    run.prep_error = s.plc.read("PrepError")
    return run


def executed_frames(s: Session, frames: list[Frame], origin: tuple[int, ...] = (0, 0, 0)) -> list[Frame]:
    """The frames the PLC ran, read back from its executed table (ExecX/ExecY/ExecI/ExecJ:
    after FB_CncToolRadius and the blank's correction), in mm on the steps' grid; frame 1
    starts at `origin` (steps)."""
    h = s.plant.step_mm
    out, start = [], tuple(v * h for v in origin)
    for k, f in enumerate(frames, start=1):
        end = (s.plc.read(f"ExecX[{k}]") * h, s.plc.read(f"ExecY[{k}]") * h, s.plc.read(f"FrameZ[{k}]") * h)
        out.append(replace(f, start=start, end=end, i=s.plc.read(f"ExecI[{k}]") * h if f.is_arc else 0.0,
                           j=s.plc.read(f"ExecJ[{k}]") * h if f.is_arc else 0.0))
        start = end
    return out


def record_until(s: Session, run: PartRun, flag: str, timeout: float,
                 release: Optional[tuple[str, float]] = None) -> None:
    """Scan fine cycle by fine cycle until the global `flag` is TRUE, recording each move of
    the table with the frame it belongs to; `release` (button, time s): release that push
    button once the time is reached (a press held while recording)."""
    axes = [s.plant.axes[a] for a in "XYZ"]
    ax, ay, az = axes
    frame_at, frame_key = s.plc.resolve("Frame")          # resolved once: read every cycle
    flag_at, flag_key = s.plc.resolve(flag)
    last = tuple(a.steps for a in axes)
    frame = getattr(frame_at, frame_key)
    step = s.sim.step
    counts = bool(s.plc.read("PulseDrive"))
    cycle_at, cycle_key = s.plc.resolve("PULSE_CYCLE")
    cycle_frame: dict[int, int] = {}        # pulse-count drive: the frame each message (cycle) was sent in
    pending = s.plant.pulses_pending
    scans, ending = round(timeout / s.tick) + 1, False
    while True:
        if release is not None and s.now >= release[1] - 1e-9:
            s.plant.release(release[0])
            release = None
        step(1)                             # the plant took the previous scan's steps first
        pos = (ax.steps, ay.steps, az.steps)
        if pos != last:
            run.points.append((s.now, cycle_frame.get(s.plant.last_cycle, frame) if counts else frame, *pos))
            last = pos
        if ending:                          # the last scan's steps; the generator's last pulses
            if not pending():
                break
            continue
        if counts:
            cycle_frame.setdefault(getattr(cycle_at, cycle_key), getattr(frame_at, frame_key))
        if getattr(flag_at, flag_key) and frame == getattr(frame_at, frame_key):
            ending = True
            continue
        frame = getattr(frame_at, frame_key)
        scans -= 1
        ending = scans == 0                 # timeout
    s._copy_trace()
    run.missed = s.plant.missed()


# --------------------------------------------------------------------------- scenarios

SQUARE = """(square 20 mm, evaluation function)
G21 G90 G17
G01 X20 Y0 F300
Y20
X0
Y0
"""
CIRCLE = """(full circle R10 around X10 Y0, then a half circle back by R)
G21 G90 G17 F300
G01 X20 Y0
G03 X20 Y0 I-10 J0
G02 X0 Y0 R10
"""
STAR = """(five-pointed star, lines in every quadrant)
G21 G90 F400
G01 X10 Y0
X-8.09 Y5.878
X3.09 Y-9.511
X3.09 Y9.511
X-8.09 Y-5.878
X10 Y0
"""
POCKET = """(pocket wall 10 x 6 with a rounded corner R2, cutter D1 = 1 mm: G41 going CCW is inside)
G21 G90 G17 F600
G00 X-3 Y-3
G41 D1 G01 X0 Y0
X10
Y4
G03 X8 Y6 I-2 J0
G01 X0
Y0
G40 G01 X-3 Y-3
"""
POCKET_TOOLS = {1: 1.0}


def _part(text: str, method: str, tools: Optional[dict[int, float]] = None):
    """A scenario running part program `text`: it passes when the program ends with every
    frame within its bound and at its end point (a student's interpolator is judged here)."""
    def scenario(s: Session) -> None:
        run = run_part(s, parse(text, f"<{method}>", tools).frames, method)
        _require_on_contour(s, run, method)
    return scenario


BACKLASH = """(a square and a full circle: every axis reverses several times)
G21 G90 G17 F600
G01 X5 Y0
Y5
X0
Y0
G02 X0 Y0 I2.5 J0
"""
PLAY_STEPS = 5                 # the backlash scenario's play in every transmission


def backlash(s: Session) -> None:
    """The drives have PLAY_STEPS of play; FB_CncBacklash compensates it (GVL_CNC.Backlash):
    the tool path stays within the evaluation function's bound and ends at the end point."""
    s.plant.set_backlash(PLAY_STEPS)
    s.plc.write("Backlash", PLAY_STEPS)
    s.log(f"play of {PLAY_STEPS} steps in every transmission, compensated by FB_CncBacklash")
    run = run_part(s, parse(BACKLASH, "<backlash>").frames, "evalfn")
    _require_on_contour(s, run, "evalfn")


BLANK = """(a 10 x 6 rectangle on the blank, drawn in the part's coordinates)
G21 G90 G17 F600
G01 X10 Y10
X20
Y16
X10
Y10
"""
BASE_HOLES = ((0.0, 0.0), (40.0, 0.0))      # the base holes in the part's coordinates, mm
HOLE_RADIUS = 2.0
BLANK_PLACEMENT = (0.8, -0.5, math.radians(1.5))   # where the blank lies: shift X, Y (mm), turn


def blank_to_machine(p: tuple[float, ...], placement=BLANK_PLACEMENT) -> tuple[float, float]:
    """A point of the part program on the machine, for a blank at `placement` (eq. 28)."""
    x0, y0, alpha = placement
    c, sn = math.cos(alpha), math.sin(alpha)
    return x0 + p[0] * c - p[1] * sn, y0 + p[0] * sn + p[1] * c


def place_blank(s: Session, placement=BLANK_PLACEMENT, holes=BASE_HOLES) -> None:
    """Lay the blank on the table (the plant's base holes) and give the PLC the drawn holes."""
    h = s.plant.step_mm
    s.plant.set_blank([blank_to_machine(p, placement) for p in holes], HOLE_RADIUS)
    s.plc.write("BlankMeasure", True)
    for k, (x, y) in enumerate(holes, start=1):
        s.plc.write(f"BaseX[{k}]", round(x / h))
        s.plc.write(f"BaseY[{k}]", round(y / h))


def blank(s: Session) -> None:
    """The blank lies shifted and turned: SB1 measures its two base holes with the probe
    (FB_CncProbeHole), solves the correction (FB_CncBlankSetup) and runs the part turned
    onto the blank (FB_CncBlankTransform, eq. 28)."""
    place_blank(s)
    x0, y0, alpha = BLANK_PLACEMENT
    s.log(f"blank shifted by ({x0:g}, {y0:g}) mm and turned by {math.degrees(alpha):g} degrees")
    run = run_part(s, parse(BLANK, "<blank>").frames, "evalfn")
    error = s.plc.read("BlankError")
    if error:
        raise ScenarioFailure(f"t={s.now:.2f} s: the measuring cycle failed (BlankError {error})")
    _require_on_contour(s, run, "evalfn")
    h = s.plant.step_mm
    for f, e in zip(run.frames, run.executed):
        want = blank_to_machine(f.end)
        off = math.dist(want, e.end[:2])
        if off > BLANK_TOLERANCE_STEPS * h:
            raise ScenarioFailure(f"frame line {f.line}: ends {off:.4f} mm from the blank's point "
                                  f"(tolerance {BLANK_TOLERANCE_STEPS * h:g} mm)")


BLANK_TOLERANCE_STEPS = 3      # the holes' centres are measured within a step: the turn adds a little


def _require_on_contour(s: Session, run: "PartRun", method: str) -> None:
    """Every frame of `run` within its bound and at its end point (the scenario's verdict)."""
    from plclab.nc.toolpath import check_blocks

    if not run.finished:
        raise ScenarioFailure(f"t={s.now:.2f} s: the part program did not end")
    s.cnc_run = run                        # type: ignore[attr-defined]
    for block in check_blocks(run.executed, run.points, run.step_mm, method, run.frames_start, run.origin,
                              fine_s=run.fine_s):
        if not block.ok:
            raise ScenarioFailure(f"frame {block.index} (line {block.line}): contour error "
                                  f"{block.error_mm:.4f} mm (bound {block.bound_mm:.4f} mm), "
                                  f"end point off by {block.end_error_mm:.4f} mm{_stub_hint(s, method)}")


def _stub_hint(s: Session, method: str) -> str:
    """Why an evaluation-function run of the shipped students' program goes nowhere, and what to do."""
    from plclab.stands import pou_path

    if method == "evalfn" and str(pou_path(STUDENT_BLOCK)) in {name for name, _ in s.sources}:
        return (f" ({STUDENT_BLOCK} in this program is the students' stub, Task 4: run yours with "
                f"--program {STUDENT_BLOCK}.st)")
    return ""


def estop(s: Session) -> None:
    """SB3 in the middle of a frame: the drives stop at once, HL2 lights, KM1 drops."""
    load_frames(s, parse(SQUARE).frames, "evalfn")
    s.console.press("SB1", hold=0.005)
    s.run(1.0)
    s.console.hold("SB3")
    s.run(0.01)
    where = (s.plant.axes["X"].steps, s.plant.axes["Y"].steps)
    s.run(0.5)
    if (s.plant.axes["X"].steps, s.plant.axes["Y"].steps) != where:
        raise ScenarioFailure(f"t={s.now:.2f} s: the table moved after the emergency stop")
    if not s.value("HL2") or s.value("KM1"):
        raise ScenarioFailure(f"t={s.now:.2f} s: HL2 not lit or KM1 still closed after the emergency stop")
    s.console.release("SB3")
    s.run(0.1)


SCENARIOS: dict[str, Callable[[Session], None]] = {
    "demo": _part(SQUARE, "evalfn"), "square": _part(SQUARE, "evalfn"), "circle": _part(CIRCLE, "evalfn"),
    "star": _part(STAR, "dda"), "pocket": _part(POCKET, "integration", POCKET_TOOLS), "backlash": backlash,
    "blank": blank, "estop": estop,
}
PLOT_SIGNALS = ("SB1", "SB3", "HL1", "HL2", "STEP_X", "DIR_X", "STEP_Y", "DIR_Y", "CNT_X", "CNT_Y", "Frame")


def check_never(s: Session) -> None:
    """No step lost to the drives' rate limit in any scenario."""
    lost = {a: n for a, n in s.plant.missed().items() if n}
    if lost:
        raise ScenarioFailure(f"missed steps: {lost}")


def timeline(s: Session) -> list[str]:
    rows = [f"{'time s':>8}  event"]
    rows += [f"{a.time:8.3f}  {a.text}" for a in s.actions]
    axes = s.plant.axes
    rows.append(f"{s.now:8.3f}  table at X {axes['X'].steps * s.plant.step_mm:.3f} "
                f"Y {axes['Y'].steps * s.plant.step_mm:.3f} Z {axes['Z'].steps * s.plant.step_mm:.3f} mm")
    return rows


SUMMARY_SIGNALS = ("SB1", "SB3", "HL1", "HL2", "KM1", "Frame", "ProgramEnd", "DIR_X", "DIR_Y")


def summary_trace(s: Session) -> Trace:
    """A scenario's trace without the step lines (a change every fine cycle): the console, the
    lamps, KM1, the frame, the directions, and TableX / TableY, the table's position (steps)
    whenever the frame changes. What the golden traces keep (tests/cnc/test_cnc_golden.py)."""
    src = s.trace
    out = Trace()
    for name in SUMMARY_SIGNALS:
        if name not in src:
            continue
        changes = src.changes(name)
        info = src.info(name)
        out.declare(name, info.kind, changes[0][1], changes[0][0], width=info.width)
        for t, v in changes[1:]:
            out.change(t, name, v)
    for axis in "XY":
        counter = f"CNT_{axis}"
        out.declare(f"Table{axis}", "int", src.value_at_ns(counter, 0), width=16)
        for t, _frame in src.changes("Frame")[1:]:
            out.change(t, f"Table{axis}", src.value_at_ns(counter, t))
    out.advance(src.end_ns)
    return out


SPEC = StandSpec(
    stand=STAND,
    console=("SB1", "SB2", "SA1", "SB3", "RP1"),
    lamps=("HL1", "HL2"),
    sensors=("SQ1", "SQ2", "SQ3", "SQ4", "SQ5", "SQ6", "B1", "CNT_X", "CNT_Y", "CNT_Z"),
    actuators=("STEP_X", "DIR_X", "STEP_Y", "DIR_Y", "STEP_Z", "DIR_Z", "KM1"),
    faults=(Fault("slow_drive", "that drive's maximum step rate drops: steps beyond it are missed",
                  (FaultParam("axis", "X|Y|Z"), FaultParam("rate", "steps per second"))),),
    observables={"Frame": "Frame", "ProgramEnd": "ProgramEnd"},
    scenarios=SCENARIOS, timeline=timeline, check_never=check_never, plot_signals=PLOT_SIGNALS,
    setup=_setup, program_sources=program_sources,
)
