"""The MP-9C pneumatic robot stand: program variants, labels, timeline and scenarios.

Scenarios are written like the lab instructions (docs/contributing.md) and check what they claim: a
scenario that does not see what the manual says raises ScenarioFailure with the time and
the reason. None may ever show a valve conflict (both coils of one valve energized).

A scenario decides from the console, the valves, the switches and HL1 only, as an observer at
the stand would: a frame is its valve pattern (the valve byte goes to the valves while it
plays), a recorded frame shows as HL1 off, the frame timeout as HL1 blinking. So every
scenario runs on a student's program of any structure; the observables (frame pointer,
frame count) are only shown, "absent" when the program has no such variable.
"""
from __future__ import annotations

from typing import Callable, Optional

from plclab.plants.mp9c import FACE
from plclab.scenario import ABSENT, ScenarioFailure, Session
from plclab.stands import Stand, Task, Variant, gvl_labels
from plclab.stands import exploration
from plclab.stands.base import Fault, FaultParam, StandSpec, StartPress

# the starting program (Appendix 1: main program, manual / automatic / continuous /
# step-by-step subroutines), shipped; every task's reference is this program with the task's
# edits (solutions/mp9c.toml, a checkout only)
STARTING = ("FC_PackBits7", "FC_BitOf", "FB_Sb1Button", "FB_PauseTimer", "FB_FrameWatchdog", "FB_Blink",
            "FB_ResetIndicator", "T_Playback", "FB_Mp9cManual", "FB_Mp9cContinuous", "FB_Mp9cStep",
            "FB_Mp9cAutomatic", "PRG_Mp9cBaseline")


def _variant(name: str, doc: str, reference: bool = True) -> Variant:
    return Variant(name, STARTING, (Task("MainTask", "T#10ms", 1, (("Main", "PRG_Mp9cBaseline"),)),), doc,
                   reference, edited=reference)


STAND = Stand(
    name="mp9c",
    title="MP-9C pneumatic robot",
    gvl=("GVL_MP9C",),
    types=("T_ControlProgram",),
    variants={
        "baseline": _variant("baseline", "Appendix 1: only the lift in manual mode.", reference=False),
        "task1": _variant("task1", "Task 1: all four mechanisms in manual mode."),
        "task2": _variant("task2", "Task 2: I0.7 selects the recorded pause."),
        "task3": _variant("task3", "Task 3: I0.7 enables automatic execution."),
        "full": _variant("full", "Tasks 1 + 2 + 3."),
    },
)

VALVES = [f"L{i}" for i in range(1, 8)]
SENSORS = [f"SQ{i}" for i in range(1, 8)]
CONSOLE = FACE.switches          # the console face's table (docs/openplc.md) is the one order
FRAME_PTR = "FramePtr"
FRAME_COUNT = "FrameCount"
RUNNING = "Running"
FAULT = "FrameFault"

# What scenarios, timelines and traces may read of the program's inside: the one place
# that knows the shipped programs' instance paths.
OBSERVABLES = {
    FRAME_PTR: "Main.Robot.Sequencer.Ptr",        # the frame being played (automatic mode)
    FRAME_COUNT: "Main.Cp.Count",                 # frames recorded
    RUNNING: "Main.Robot.Sequencer.Running",      # automatic execution running
    FAULT: "Main.Robot.Sequencer.Fault",          # stopped by the frame watchdog
}

FAULTS = (
    Fault("jammed", "a cylinder stops where it is",
          (FaultParam("mechanism", "lift | rotation | extension | gripper"),)),
    Fault("stuck_switch", "a limit switch reads a constant whatever the link does",
          (FaultParam("switch", "SQ1..SQ7"), FaultParam("state", "1 on / 0 off", 1))),
    Fault("dead_coil", "energizing a valve coil does nothing", (FaultParam("coil", "L1..L7"),)),
    Fault("low_pressure", "every travel time multiplied by factor",
          (FaultParam("factor", "> 0 (default: the plant's, 3)", None),)),
    Fault("bounce", "each console input change chatters for up to duration s",
          (FaultParam("duration", "s", 0.02), FaultParam("seed", "of the reproducible chatter", 0))),
)


def labels() -> dict[str, str]:
    """Console and wiring labels -> addresses, read from the GVL (the single source)."""
    return gvl_labels(STAND)


# --------------------------------------------------------------------------- timeline

def bits(trace, names: list[str], t: float) -> str:
    return "".join("1" if trace.value_at(n, t) else "0" for n in names)


def timeline(s: Session) -> list[str]:
    """Rows: time, console action or event, valves L1..L7, switches SQ1..SQ7, frame, HL1.
    A row is printed for every console action and every change of valves, switches, frame
    or HL1 (a blinking HL1 is one row per blink)."""
    tr = s.trace
    times = {a.time for a in s.actions}
    for name in VALVES + SENSORS + ["HL1"]:
        times.update(t / 1e9 for t, _v in tr.changes(name)[1:])
    if FRAME_PTR in tr:
        times.update(t / 1e9 for t, _v in tr.changes(FRAME_PTR)[1:])
    acts: dict[float, list[str]] = {}
    for a in s.actions:
        acts.setdefault(round(a.time, 6), []).append(a.text)
    rows = [f"{'time s':>8}  {'console / event':<36} {'L1..L7':<8} {'SQ1..SQ7':<8} {'frame':>5}  HL1"]
    last = None
    for t in sorted(times):
        valves, sensors = bits(tr, VALVES, t), bits(tr, SENSORS, t)
        hl1 = "on" if tr.value_at("HL1", t) else "-"
        auto = bool(tr.value_at("SA1", t))
        frame = str(tr.value_at(FRAME_PTR, t)) if auto and FRAME_PTR in tr else "-"   # ABSENT if the program lacks it
        text = "; ".join(acts.get(round(t, 6), []))
        if not text and last is not None and auto and valves != last[0]:
            text = "a frame starts" if frame == ABSENT else f"frame {frame} starts"
        key = (valves, sensors, frame, hl1)
        if not text and key == last:
            continue
        last = key
        rows.append(f"{t:8.2f}  {text[:36]:<36} {valves:<8} {sensors:<8} {frame:>5}  {hl1}")
    return rows


def check_never(s: Session) -> None:
    """What no scenario of any variant may ever show: a valve conflict."""
    conflicts = [e for e in s.plant.events if e.kind == "valve_conflict"]
    if conflicts:
        e = conflicts[0]
        raise ScenarioFailure(f"t={e.time:.2f} s: valve conflict: {e.detail}")


# --------------------------------------------------------------------------- lab steps

def move(s: Session, what: str, timeout: float = 5.0, **switches: int) -> float:
    """Set switches and wait until the sensors show the robot got there."""
    s.console.set(**switches)
    targets = {"SA5": ("SQ2", "SQ1"), "SA3": ("SQ5", "SQ4"), "SA4": ("SQ6", "SQ7"), "SA2": (None, "SQ3")}

    def arrived(io) -> bool:
        for sw, value in switches.items():
            on, off = targets.get(sw, (None, None))
            want = on if value else off
            if sw == "SA2":
                if value and io.SQ3:
                    return False
                if not value and not io.SQ3:
                    return False
                continue
            if want and not io[want]:
                return False
        return True
    t = s.wait_until(arrived, timeout, what)
    if "SA2" in switches:
        s.run(0.4)   # the gripper has no "clamped" switch: give it its 0.3 s
    return t


def valves(s: Session) -> tuple[bool, ...]:
    """The valve pattern now (L1..L7): what a frame recorded now plays back."""
    return tuple(bool(s.io[v]) for v in VALVES)


def pattern_text(p: tuple[bool, ...]) -> str:
    return "".join("1" if b else "0" for b in p)


def record(s: Session, pause_select: Optional[int] = None) -> tuple[bool, ...]:
    """A short SB1 press records a frame (optionally choosing the pause with I0.7 first):
    HL1 is off afterwards (the program is not empty). Returns the frame's valve pattern;
    that the press recorded exactly one frame shows when the frames are played back."""
    if pause_select is not None:
        s.console.set(I07=pause_select)
    frame = valves(s)
    s.console.press("SB1", hold=0.2)
    s.run(0.05)
    if s.io.HL1:
        raise ScenarioFailure(f"t={s.now:.2f} s: HL1 still on after a short SB1 press: no frame recorded")
    return frame


def teach_pick_and_place(s: Session, pause_select: int = 0) -> list[tuple[bool, ...]]:
    """Manual mode: four frames of a pick-and-place (Task 1 needs all four mechanisms);
    returns their valve patterns."""
    s.console.set(SA1=0, SA6=0, I07=pause_select)
    s.run(0.1)
    move(s, "arm down at the pick position", SA5=1)
    frames = [record(s)]
    move(s, "gripper clamped, arm up", SA2=1, SA5=0)
    frames.append(record(s))
    move(s, "rotated right, forward, down", SA3=1, SA4=1, SA5=1)
    frames.append(record(s))
    move(s, "released, up, backward, left", SA2=0, SA5=0, SA4=0, SA3=0)
    frames.append(record(s))
    return frames


def start_automatic(s: Session, step: bool = False, enable: int = 1) -> None:
    s.console.set(SA1=1, SA6=int(step), I07=enable)
    s.run(0.1)
    s.console.press("SB1", hold=0.2)


def teach_down_up(s: Session) -> None:
    """Manual mode, I0.7 = 0: two lift frames, arm down then arm up (every variant can)."""
    s.console.set(SA1=0, I07=0)
    s.run(0.1)
    move(s, "arm down", SA5=1)
    record(s)
    move(s, "arm up", SA5=0)
    record(s)


def expect_nothing_starts(s: Session, what: str) -> None:
    """Automatic mode, SB1 pressed: for 2 s no valve moves and HL1 stays on (empty program)."""
    start_automatic(s)
    s.run(2.0)
    if s.trace.next_change(VALVES, after=s.now - 2.3, default=None) is not None:
        raise ScenarioFailure(f"t={s.now:.2f} s: a valve moved {what}")
    if not s.io.HL1:
        raise ScenarioFailure(f"t={s.now:.2f} s: HL1 off {what}")


# --------------------------------------------------------------------------- scenarios

def wait_frame(s: Session, frame: tuple[bool, ...], timeout: float, what: str) -> float:
    """Wait until the valves show `frame`'s pattern (the frame started)."""
    return s.wait_until(lambda io: valves(s) == frame, timeout, f"{what} (valves {pattern_text(frame)})")


def demo(s: Session) -> None:
    """Teach a 4-frame pick-and-place in manual mode (0.5 s pauses), run it continuously for
    3 cycles, stop it with SB1: no frame starts after the stop."""
    frames = teach_pick_and_place(s, pause_select=0)
    start_automatic(s)
    for _cycle in range(3):
        wait_frame(s, frames[3], 30, "frame 4")
        wait_frame(s, frames[0], 30, "back to frame 1")
    stop = s.now
    s.console.press("SB1", hold=0.2)
    s.run(3.0)
    moved = s.trace.next_change(VALVES, after=stop + 0.3, default=None)
    if moved is not None:
        raise ScenarioFailure(f"t={moved:.2f} s: a frame started after SB1 stopped continuous execution")


def step_mode(s: Session) -> None:
    """Teach two frames; in step mode each SB1 press runs exactly one frame and its pause."""
    teach_down_up(s)
    start_automatic(s, step=True)
    s.wait_until(lambda io: io.SQ2, 3, "frame 1 (arm down)")
    s.run(3.0)
    if not s.io.SQ2:
        raise ScenarioFailure(f"t={s.now:.2f} s: step mode went on to frame 2 without a press")
    s.console.press("SB1", hold=0.2)
    s.wait_until(lambda io: io.SQ1, 3, "frame 2 (arm up) after the step press")


def long_press_reset(s: Session) -> None:
    """Teach two frames, hold SB1: at 3.0 s the program is reset (HL1 on) while still held."""
    teach_down_up(s)
    if s.io.HL1:
        raise ScenarioFailure(f"t={s.now:.2f} s: HL1 on although the program has frames")
    pressed = s.now
    s.console.hold("SB1")
    t = s.wait_until(lambda io: io.HL1, 4, "HL1 after holding SB1")
    if abs((t - pressed) - 3.0) > 2 * s.tick:
        raise ScenarioFailure(f"t={t:.2f} s: reset {t - pressed:.2f} s after the press, expected 3.0 s")
    s.run(0.5)
    s.console.release("SB1")
    s.run(0.5)
    if not s.io.HL1:
        raise ScenarioFailure(f"t={s.now:.2f} s: HL1 off after the reset: the release recorded a frame")
    expect_nothing_starts(s, "after the reset emptied the program")


def bounce(s: Session) -> None:
    """With contact bounce on the console, each short press still records exactly one frame:
    three frames (arm down, up, down) recorded, then played in step mode, each press must
    start the next of the three (a doubled or lost frame shows as a wrong valve pattern)."""
    s.inject("bounce", duration=0.02)
    s.console.set(SA1=0, I07=0)
    s.run(0.1)
    frames = []
    for down in (1, 0, 1):
        move(s, "arm down" if down else "arm up", SA5=down)
        frames.append(record(s))
        s.run(0.2)
    start_automatic(s, step=True)
    for k in range(len(frames) + 2):
        frame = frames[k % len(frames)]
        s.wait_until(lambda io: io.SQ2 == bool(frame[2]) and io.SQ1 == bool(frame[1]), 3,
                     f"frame {k % len(frames) + 1} (arm {'down' if frame[2] else 'up'}) after step press {k + 1}")
        if valves(s) != frame:
            raise ScenarioFailure(f"t={s.now:.2f} s: step press {k + 1}: valves {pattern_text(valves(s))}, "
                                  f"frame {k % len(frames) + 1} is {pattern_text(frame)}")
        s.run(1.5)                      # its pause (1.0 s at most) is over
        if valves(s) != frame:
            raise ScenarioFailure(f"t={s.now:.2f} s: step mode went on without a press")
        s.console.press("SB1", hold=0.2)


def retain(s: Session) -> None:
    """A recorded program survives a PLC restart (power cycle of the controller)."""
    teach_down_up(s)
    s.restart_plc(off_time=1.0)
    s.run(0.2)
    if s.io.HL1:
        raise ScenarioFailure(f"t={s.now:.2f} s: HL1 on after the restart: the recorded frames were lost")
    start_automatic(s)
    s.wait_until(lambda io: io.SQ2, 3, "frame 1 (arm down) played after the restart")
    s.wait_until(lambda io: io.SQ1, 5, "frame 2 (arm up) played after the restart")
    s.wait_until(lambda io: io.SQ2, 5, "frame 1 again after frame 2")


def jammed(s: Session) -> None:
    """A jammed cylinder: the frame times out after 10 s, execution stops, HL1 blinks 2 Hz
    until manual mode."""
    teach_down_up(s)
    s.inject("jammed", mechanism="lift")
    start_automatic(s)
    started = s.now
    s.wait_until(lambda io: io.HL1, 12, "the frame timeout (HL1 blinking)")
    if abs(s.now - started - 10.0) > 0.5:
        raise ScenarioFailure(f"t={s.now:.2f} s: timeout after {s.now - started:.2f} s, expected about 10 s")
    s.run(2.0)
    edges = s.trace.edges("HL1", "rising", after=s.now - 2.0)
    if not 3 <= len(edges) <= 5:
        raise ScenarioFailure(f"t={s.now:.2f} s: HL1 rose {len(edges)} times in 2 s, expected a 2 Hz blink")
    s.clear_faults()
    s.console.set(SA1=0)
    s.run(1.0)
    if s.trace.edges("HL1", "rising", after=s.now - 0.7):
        raise ScenarioFailure(f"t={s.now:.2f} s: HL1 still blinking in manual mode")


def empty_program(s: Session) -> None:
    """Automatic mode with an empty program: SB1 starts nothing, HL1 stays on."""
    expect_nothing_starts(s, "with an empty program")


def lift_cycle(s: Session) -> None:
    """For every variant: wiggle the rotation switch (only Task 1 wires it), record two lift
    frames (I0.7 = 0 then 1), play them with I0.7 = 1 for two cycles, then drop I0.7 and see
    what each variant does (Task 3 stops after the last frame, the others go on)."""
    s.console.set(SA1=0, SA6=0, I07=0)
    s.run(0.1)
    s.console.set(SA3=1)
    s.run(1.5)
    s.console.set(SA3=0)
    s.run(1.5)
    move(s, "arm down", SA5=1)
    record(s, pause_select=0)
    move(s, "arm up", SA5=0)
    record(s, pause_select=1)
    start_automatic(s, enable=1)
    s.run(12.0)
    s.console.set(I07=0)
    s.run(8.0)


SCENARIOS: dict[str, Callable[[Session], None]] = {
    "lift": lift_cycle,
    "demo": demo, "step": step_mode, "reset": long_press_reset, "bounce": bounce,
    "retain": retain, "jammed": jammed, "empty": empty_program,
}
PLOT_SIGNALS = ["SB1", "SA1", "I07"] + VALVES + SENSORS + ["HL1", FRAME_PTR]

SPEC = StandSpec(
    stand=STAND, console=CONSOLE, lamps=tuple(label for label, _ in FACE.lamps), sensors=tuple(SENSORS), actuators=tuple(VALVES),
    faults=FAULTS, observables=OBSERVABLES, scenarios=SCENARIOS, timeline=timeline,
    check_never=check_never, plot_signals=tuple(PLOT_SIGNALS),
    explore=exploration.MP9C,
    start=StartPress("SB1", ("SA1", 1), (("SA1", "manual", "automatic"), ("SA6", "continuous", "step by step"),
                                         ("I07", "off", "on")), tuple(VALVES)))
session = SPEC.session
