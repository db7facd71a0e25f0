"""The TUR-10 positional robot stand: program variants, labels, timeline and scenarios.

The regulators run as their own PROGRAM in a 10 ms TASK (the S7-200's timer interrupt); the
main program runs in a 20 ms task. No scenario of any variant may show an overvoltage, a bus
contention or a collision (check_never).

A scenario decides from the console, the drive references, the indicator and the plant (where
the links are), as an observer at the stand would: a frame is the links' positions when it was
recorded, a recorded frame shows as HL1 off, the frame timeout as the references dropping to 0.
So every scenario runs on a student's program of any structure; the observables (frame
pointer, targets, the PLC's position buffer) are only shown, "absent" when the program lacks them.
"""
from __future__ import annotations

from typing import Callable, Optional

from plclab.plants.base import signed16
from plclab.plants.tur10 import FACE
from plclab.scenario import ScenarioFailure, Session
from plclab.stands import Stand, Task, Variant, gvl_labels
from plclab.stands import exploration
from plclab.stands.base import Fault, FaultParam, StandSpec, StartPress

# the starting program (Appendix 2: main program, manual / automatic subroutines, the timer
# interrupt routine PRG_Tur10Regulators), shipped; every task's reference is this program
# with the task's edits (solutions/tur10.toml, a checkout only)
STARTING = ("FC_PackBits7", "FC_BitOf", "FC_JogReference", "FB_Sb1Button", "FB_PauseTimer",
            "FB_FrameWatchdog", "FB_Blink", "FB_ResetIndicator", "FB_SensorBus", "FB_Tur10Sensors",
            "FB_PositionRegulator", "PRG_Tur10Regulators", "T_Playback", "FB_Tur10Manual", "FB_Tur10Automatic",
            "PRG_Tur10Baseline")


def _variant(name: str, doc: str, reference: bool = True) -> Variant:
    return Variant(name, STARTING, (
        Task("MainTask", "T#20ms", 1, (("Main", "PRG_Tur10Baseline"),)),
        Task("RegTask", "T#10ms", 0, (("Regulators", "PRG_Tur10Regulators"),)),
    ), doc, reference, edited=reference)


STAND = Stand(
    name="tur10",
    title="TUR-10 positional robot",
    gvl=("GVL_TUR10",),
    types=("T_ControlProgram",),
    variants={
        "baseline": _variant("baseline", "Appendix 2: drive 1 only.", reference=False),
        "task1": _variant("task1", "Task 1: manual control of all five drives."),
        "task2": _variant("task2", "Task 2: I1.5 selects the recorded pause."),
        "task3": _variant("task3", "Task 3: I1.5 enables automatic execution."),
        "full": _variant("full", "All five axes + Tasks 2 and 3."),
    },
)

AXES = (1, 2, 3, 4, 5)
DRIVES = [f"DRIVE{k}" for k in AXES]
CONSOLE = FACE.switches          # the console face's table (docs/openplc.md) is the one order
SENSOR_BUS = tuple(f"BUS{n}" for n in range(1, 16))
READ_ENABLES = tuple(f"RE{k}" for k in AXES)
FRAME_PTR = "FramePtr"
FRAME_COUNT = "FrameCount"
IN_FRAME = "InFrame"
FAULT = "FrameFault"
REG_AXES = "RegAxes"
POSITIONS = [f"Position{k}" for k in AXES]
TARGETS = [f"Target{k}" for k in AXES]
NEVER = ("overvoltage", "bus_contention", "collision")

# What scenarios, timelines and traces may read of the program's inside: the one place
# that knows the shipped programs' instance paths.
OBSERVABLES = {
    FRAME_PTR: "Main.Robot.Sequencer.Ptr",        # the frame being played (automatic mode)
    FRAME_COUNT: "Main.Cp.Count",                 # frames recorded
    IN_FRAME: "Main.Robot.Sequencer.InFrame",     # moving to a frame (not yet in its pause)
    FAULT: "Main.Robot.Sequencer.Fault",          # stopped by the frame watchdog
    REG_AXES: "RegAxes",                          # how many links the regulators control
    **{POSITIONS[k - 1]: f"Positions[{k}]" for k in AXES},   # link positions as the PLC read them
    **{TARGETS[k - 1]: f"Targets[{k}]" for k in AXES},       # the frame being executed
}

FAULTS = (
    Fault("dead_sensor", "a position sensor reads a constant code",
          (FaultParam("axis", "1..5"), FaultParam("value", "0..32767 (default: its code now)", None))),
    Fault("stuck_drive", "a link does not move whatever its reference", (FaultParam("axis", "1..5"),)),
    Fault("slow_drive", "a link runs at factor times the normal speed",
          (FaultParam("axis", "1..5"), FaultParam("factor", ">= 0"))),
)


def labels() -> dict[str, str]:
    """Console and wiring labels -> addresses, read from the GVL (the single source)."""
    return gvl_labels(STAND)


def position(s: Session, axis: int) -> float:
    """The true position of link `axis` (plant), codes."""
    return s.plant.snapshot()[f"pos{axis}"]


def check_never(s: Session) -> None:
    """No overvoltage, bus contention or collision while the PLC runs (with the PLC off every
    output is de-energised, which enables every sensor at once: not the program's doing)."""
    bad = [e for e in s.plant.events if e.kind in NEVER and not s.plc_was_off(e.time)]
    if bad:
        e = bad[0]
        raise ScenarioFailure(f"t={e.time:.2f} s: {e.kind.replace('_', ' ')}: {e.detail}")


# --------------------------------------------------------------------------- lab steps

def jog(s: Session, axis: int, direction: int, seconds: float, low: bool = False) -> None:
    """Hold drive `axis`'s forward (+1) or backward (-1) button for `seconds`."""
    s.console.set(SA6=int(low))
    button = f"SA{axis}_{'FWD' if direction > 0 else 'BWD'}"
    s.plant.set_switch(button, 1)
    s.log(f"{button} held {seconds:g} s{' (low speed)' if low else ''}")
    s.run(seconds)
    s.plant.set_switch(button, 0)
    s.run(0.4)      # the link stops (50 ms lag) and the sensors are read again


Pose = tuple[float, ...]         # the links' positions (plant, codes), axes 1..5
REACHED = 40.0                   # codes: a link this close to its frame's position is there
                                 # (the regulators stop within 16, the sensor reads whole codes)


def pose(s: Session) -> Pose:
    """Where the links are now (the plant), axes 1..5."""
    snap = s.plant.snapshot()
    return tuple(snap[f"pos{k}"] for k in AXES)


def at_pose(s: Session, frame: Pose, axes: tuple[int, ...] = AXES) -> bool:
    now = pose(s)
    return all(abs(now[k - 1] - frame[k - 1]) <= REACHED for k in axes)


def record(s: Session, pause_select: Optional[int] = None) -> Pose:
    """A short SB1 press records a frame: HL1 is off afterwards (the program is not empty).
    Returns where the links are (the frame); that exactly one frame was recorded shows when
    the frames are played back."""
    if pause_select is not None:
        s.console.set(I15=pause_select)
    frame = pose(s)
    s.console.press("SB1", hold=0.2)
    s.run(0.1)
    if s.io.HL1:
        raise ScenarioFailure(f"t={s.now:.2f} s: the indicator still on after a short SB1 press: "
                              "no frame recorded")
    return frame


def driven(s: Session, since: float) -> tuple[int, ...]:
    """The axes whose drive reference was not 0 at some time since `since`: the links the
    program positions in automatic mode (the starting program regulates drive 1 only)."""
    after = round(since * 1e9)
    return tuple(k for k in AXES if any(v and t >= after for t, v in s.trace.changes(DRIVES[k - 1])))


def wait_pose(s: Session, frame: Pose, timeout: float, what: str, since: float) -> float:
    """Wait until the links the program drives (since `since`) are at `frame` (within
    REACHED codes)."""
    def there(io) -> bool:
        axes = driven(s, since)
        return bool(axes) and at_pose(s, frame, axes)
    return s.wait_until(there, timeout, f"{what} (links at {', '.join(f'{v:.0f}' for v in frame)})")


def start_automatic(s: Session, enable: int = 1) -> None:
    s.console.set(SA7=1, I15=enable)
    s.run(0.1)
    s.console.press("SB1", hold=0.2)


def frame_results(s: Session, axes: tuple[int, ...] = AXES) -> list[str]:
    """Positioning result of each played frame, from the PLC's own sensor readings: time to
    reach, final error per axis when the pause starts, and overshoot (how far a link went past
    its target on the way). Shown only: a program without those variables has none."""
    tr = s.trace
    needed = [IN_FRAME, FRAME_PTR, REG_AXES] + POSITIONS + TARGETS
    if not all(s.has(n) for n in needed):
        return [f"(absent: the program has no {', '.join(n for n in needed if not s.has(n))})"]
    rows = [f"{'frame':>5} {'start s':>8} {'reached after s':>16}  final error / overshoot per axis (codes)"]
    spans = tr.pulses(IN_FRAME)
    regulated = axes[:max(1, min(len(axes), s.value(REG_AXES)))]
    for i, (start, end) in enumerate(spans):
        frame = tr.value_at(FRAME_PTR, start)
        until = spans[i + 1][0] if i + 1 < len(spans) else tr.end_s     # the frame and its pause
        parts, errors = [], []
        for k in regulated:
            target = signed16(tr.value_at(TARGETS[k - 1], start))
            begin = signed16(tr.value_at(POSITIONS[k - 1], start))
            final = signed16(tr.value_at(POSITIONS[k - 1], end if end is not None else until))
            direction = 1 if target >= begin else -1
            past = [(signed16(v) - target) * direction for t, v in tr.changes(POSITIONS[k - 1])
                    if start * 1e9 <= t <= until * 1e9]
            errors.append(abs(target - final))
            parts.append(f"{k}:{target - final:+d}/{max([0] + past)}")
        reached = end is not None and max(errors) < 16
        when = f"{end - start:16.2f}" if reached else f"{'stopped':>16}"
        rows.append(f"{frame:>5} {start:8.2f} {when}  {'  '.join(parts)}")
    return rows


# --------------------------------------------------------------------------- scenarios

def teach_four_frames(s: Session, axes: tuple[int, ...] = AXES) -> list[Pose]:
    """Manual mode: four frames, moving several links at once between them; returns them."""
    s.console.set(SA7=0, I15=0)
    s.run(0.2)
    frames = [record(s)]
    for k in axes:
        jog(s, k, +1, 0.6 if k % 2 else 0.4)
    frames.append(record(s))
    for k in axes[::2]:
        jog(s, k, -1, 0.9, low=True)
    frames.append(record(s))
    for k in axes[1::2]:
        jog(s, k, -1, 0.5)
    frames.append(record(s))
    return frames


def demo(s: Session) -> None:
    """Jog, teach 4 frames moving several links, play them back continuously for 2 cycles
    (the links reach frame 4, then frame 1 again), stop with SB1: references 0."""
    frames = teach_four_frames(s)
    started = s.now
    start_automatic(s)
    for _cycle in range(2):
        wait_pose(s, frames[3], 60, "frame 4", started)
        wait_pose(s, frames[0], 60, "back to frame 1", started)
    s.console.press("SB1", hold=0.2)
    s.run(1.0)
    if any(s.value(d) for d in DRIVES):
        raise ScenarioFailure(f"t={s.now:.2f} s: references not 0 after the stop")


def jog_all(s: Session) -> None:
    """Every drive at both speeds: forward at normal speed, backward at low speed."""
    s.console.set(SA7=0)
    s.run(0.1)
    for k in AXES:
        before = position(s, k)
        jog(s, k, +1, 0.5)
        if position(s, k) - before < 2500:
            raise ScenarioFailure(f"t={s.now:.2f} s: drive {k} moved {position(s, k) - before:.0f} codes "
                                  f"in 0.5 s at normal speed")
        before = position(s, k)
        jog(s, k, -1, 0.5, low=True)
        if not -1300 < position(s, k) - before < -700:
            raise ScenarioFailure(f"t={s.now:.2f} s: drive {k} moved {position(s, k) - before:.0f} codes "
                                  f"in 0.5 s at low speed")


def reset(s: Session) -> None:
    """Two frames, then SB1 held 3 s: program empty, indicator on."""
    s.console.set(SA7=0)
    s.run(0.2)
    record(s)
    jog(s, 1, +1, 0.3)
    record(s)
    s.console.hold("SB1")
    s.wait_until(lambda io: io.HL1, 4, "reset indicator after holding SB1")
    s.console.release("SB1")
    s.run(0.3)
    if not s.io.HL1:
        raise ScenarioFailure(f"t={s.now:.2f} s: the indicator off after the reset: the release recorded a frame")
    start_automatic(s)                      # an empty program does not start
    s.run(2.0)
    if s.trace.next_change(DRIVES, after=s.now - 2.3, default=None) is not None:
        raise ScenarioFailure(f"t={s.now:.2f} s: a drive moved after the reset emptied the program")


def retain(s: Session) -> None:
    """Recorded frames survive a PLC restart and still play."""
    s.console.set(SA7=0)
    s.run(0.2)
    first = record(s)
    jog(s, 1, +1, 0.5)
    second = record(s)
    s.restart_plc(off_time=1.0)             # a power cycle: the controller off for a second
    s.run(0.2)
    if s.io.HL1:
        raise ScenarioFailure(f"t={s.now:.2f} s: the indicator on after the restart: the frames were lost")
    started = s.now
    start_automatic(s)
    wait_pose(s, first, 20, "frame 1 after the restart", started)
    wait_pose(s, second, 20, "frame 2 after the restart", started)


def dead_sensor(s: Session) -> None:
    """A dead sensor (stuck 30 codes past the first frame's target): the regulator creeps at a
    small reference, the frame is never reached, execution stops after 20 s with references 0."""
    s.console.set(SA7=0)
    s.run(0.2)
    record(s)
    target = s.plant.snapshot()["code1"]    # what frame 1 recorded: the link is at rest
    jog(s, 1, +1, 0.8)
    record(s)
    s.inject("dead_sensor", axis=1, value=target + 30)
    start_automatic(s)
    started = s.now
    s.wait_until(lambda io: io.DRIVE1 != 0, 2, "drive 1 moving towards frame 1")
    stopped = s.wait_until(lambda io: not any(io[d] for d in DRIVES), 45, "the frame timeout (references 0)")
    if abs(stopped - started - 20.0) > 1.0:
        raise ScenarioFailure(f"t={stopped:.2f} s: references 0 after {stopped - started:.2f} s, "
                              f"expected the 20 s frame timeout")
    s.run(2.0)
    if s.trace.next_change(DRIVES, after=stopped + s.tick, default=None) is not None:
        raise ScenarioFailure(f"t={s.now:.2f} s: a drive moved again after the frame timeout")
    if len(s.trace.edges("HL1", "rising", after=stopped)) < 1:
        raise ScenarioFailure(f"t={s.now:.2f} s: the indicator does not blink after the frame timeout")


SCENARIOS: dict[str, Callable[[Session], None]] = {
    "demo": demo, "jog": jog_all, "reset": reset, "retain": retain, "dead_sensor": dead_sensor,
}
# a link's position (as the PLC reads it) and its target share one subplot
PLOT_SIGNALS = ["SB1", "SA7"] + [(POSITIONS[k - 1], TARGETS[k - 1]) for k in AXES] + DRIVES + [FRAME_PTR]


def timeline(s: Session) -> list[str]:
    tr = s.trace
    times = {a.time for a in s.actions}
    if FRAME_PTR in tr:
        times.update(t / 1e9 for t, _v in tr.changes(FRAME_PTR)[1:])
    acts: dict[float, list[str]] = {}
    for a in s.actions:
        acts.setdefault(round(a.time, 6), []).append(a.text)
    rows = [f"{'time s':>8}  {'console / event':<30} " + " ".join(f"{'drive' + str(k):>6}" for k in AXES) + "  frame"]
    for t in sorted(times):
        refs = " ".join(f"{signed16(tr.value_at(d, t)):>6}" for d in DRIVES)
        frame = tr.value_at(FRAME_PTR, t) if FRAME_PTR in tr else ""      # ABSENT if the program lacks it
        rows.append(f"{t:8.2f}  {'; '.join(acts.get(round(t, 6), []))[:30]:<30} {refs}  {frame}")
    results = frame_results(s)
    if len(results) > 1 or (results and results[0].startswith("(absent")):
        rows += ["", "positioning result of each played frame:"] + results
    return rows


SPEC = StandSpec(
    stand=STAND, console=CONSOLE, lamps=tuple(label for label, _ in FACE.lamps), sensors=SENSOR_BUS, actuators=tuple(DRIVES) + READ_ENABLES,
    faults=FAULTS, observables=OBSERVABLES, scenarios=SCENARIOS, timeline=timeline,
    check_never=check_never, plot_signals=tuple(PLOT_SIGNALS),
    explore=exploration.TUR10,
    start=StartPress("SB1", ("SA7", 1), (("SA7", "manual", "automatic"), ("SA6", "normal speed", "low speed"),
                                         ("I15", "off", "on")), tuple(DRIVES)))
session = SPEC.session
