"""MP-9C requirement sets: Tasks 1-3 of the pneumatic robot lab (mp9c.md), judged by I/O alone.

Every scenario runs the student's program on a fresh robot and console, in virtual time, and
looks only at the located I/O by their console and wiring labels (SQ1..SQ7, SA1..SA6, SB1,
I07, L1..L7, HL1). What a frame is, the grader knows from the switches it set while teaching:
frame k must drive the valves those switches select and is done when the sensors show the
robot there. Times are compared with a tolerance of one scan (plus the 50 ms debounce where
an SB1 press is involved).

Requirements T1.x, T2.x, T3.x are the task's own; G1..G11 are the baseline behaviour every
solution must keep (Appendix 1), checked with the lift alone so that they hold for every task.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Optional

from plclab.scenario import ScenarioFailure, Session
from plclab.stands.mp9c import STAND, labels

from .registry import EVERY, Checks, Requirement, RequirementSet, Scenario, register

VALVES = tuple(f"L{i}" for i in range(1, 8))
CONFLICTS = (("L2", "L3", "lift"), ("L4", "L5", "rotation"), ("L6", "L7", "extension"))

DEBOUNCE = 0.05          # SB1 closures shorter than this are contact bounce
LONG_PRESS = 3.0         # SB1 held this long resets the program
PAUSE_SHORT = 0.5        # Task 2: frame recorded with I0.7 = 0
PAUSE_LONG = 3.0         # Task 2: frame recorded with I0.7 = 1
FRAME_TIMEOUT = 10.0     # a frame not done in this time is a fault
CAPACITY = 32            # frames
MARGIN = 0.5             # s of slack on plant travel times
DONE_WAIT = 3.0          # a frame's links all arrive within this (longest travel 1.2 s)
NEXT_WAIT = PAUSE_LONG + 1.0   # the next frame starts within this after one is done
QUIET = 3.0              # "nothing happens": no valve change for this long
EPS = 1e-6


# --------------------------------------------------------------------------- the stand

def make_session(sources: list[tuple[str, str]], retain_path: Optional[Path]) -> Session:
    return Session(sources, STAND.make_plant(), labels(), watch=(), retain_path=retain_path,
                   name="mp9c program")


# --------------------------------------------------------------------------- frames

@dataclass(frozen=True)
class Frame:
    """A frame as the grader teaches it: the switches set, the valves it must drive, the
    sensors that show it done, and I0.7 at the moment it is recorded."""

    switches: dict[str, int]
    valves: dict[str, int]
    sensors: dict[str, int]
    i07: int = 0


def lift(down: bool, i07: int = 0) -> Frame:
    """A lift-only frame (every task's program moves the lift); only L2/L3, SQ1/SQ2 judged."""
    d = int(down)
    return Frame({"SA5": d}, {"L2": 1 - d, "L3": d}, {"SQ1": 1 - d, "SQ2": d}, i07)


def arm(sa2: int, sa3: int, sa4: int, sa5: int, i07: int = 0) -> Frame:
    """A frame using all four switches (Task 1): every valve and every sensor judged."""
    valves = {"L1": sa2, "L2": 1 - sa5, "L3": sa5, "L4": 1 - sa3, "L5": sa3, "L6": sa4, "L7": 1 - sa4}
    sensors = {"SQ1": 1 - sa5, "SQ2": sa5, "SQ3": 1 - sa2, "SQ4": 1 - sa3, "SQ5": sa3,
               "SQ6": sa4, "SQ7": 1 - sa4}
    return Frame({"SA2": sa2, "SA3": sa3, "SA4": sa4, "SA5": sa5}, valves, sensors, i07)


def fmt(values: dict[str, Any]) -> str:
    return " ".join(f"{k}={int(bool(v))}" for k, v in values.items())


def matches(io: Any, want: dict[str, int]) -> bool:
    return all(int(bool(io[k])) == v for k, v in want.items())


@dataclass(frozen=True)
class FrameRun:
    start: float      # the valves changed to the frame's
    done: float       # the sensors showed the frame reached


# --------------------------------------------------------------------------- the operator

@dataclass
class Op:
    """The lab operator and observer on one session: console actions, waits, trace reads.
    A PLC fault stops the scenario (G1 reports it)."""

    s: Session
    c: Checks

    @property
    def now(self) -> float:
        return self.s.now

    @property
    def tol(self) -> float:
        """One scan of the student's program."""
        return self.s.tick + EPS

    def _fault(self) -> None:
        if self.s.fault is not None:
            raise ScenarioFailure("the PLC stopped with a runtime fault (see G1)")

    def set(self, **switches: int) -> float:
        t = self.now
        self.s.console.set(**switches)
        return t

    def run(self, seconds: float) -> None:
        if seconds > 0:
            self.s.run(seconds)
        self._fault()

    def run_until(self, t: float) -> None:
        self.run(t - self.now + EPS)

    def press(self, hold: float = 0.2) -> float:
        """A press of SB1 held `hold` s; returns the time it was pressed."""
        t = self.now
        self.s.console.press("SB1", hold=hold)
        self._fault()
        return t

    def values(self, names: Any, at: Optional[float] = None) -> dict[str, int]:
        if at is None:
            return {n: int(bool(self.s.io[n])) for n in names}
        return {n: int(bool(self.s.trace.value_at(n, at))) for n in names}

    def wait(self, cond: Callable[[Any], Any], timeout: float) -> Optional[float]:
        """Scan until `cond(io)` holds: its time, or None after `timeout` s."""
        try:
            t = self.s.wait_until(lambda io: self.s.fault is not None or cond(io), max(timeout, 0.0))
        except ScenarioFailure:
            return None
        self._fault()
        return t

    def when(self, cond: Callable[[Any], Any], after: float, timeout: float) -> Optional[float]:
        """The first time at or after `after` when `cond` holds (from the trace, then waiting),
        or None if not by `after + timeout`."""
        t = self.s.trace.first(cond, after=after, until=after + timeout, default=None)
        if t is not None:
            return t
        if self.now >= after + timeout:
            return None
        return self.wait(cond, after + timeout - self.now)

    def valve_change(self, after: float, until: Optional[float] = None) -> Optional[float]:
        """The first change of any valve at or after `after` (up to `until`, default: now)."""
        return self.s.trace.next_change(list(VALVES), after=after, until=until, default=None)

    def settled(self, t: float, names: Any) -> dict[str, int]:
        """The values one scan after `t` (the tolerance on when outputs follow)."""
        self.run_until(t + self.tol + self.s.tick)
        return self.values(names, at=t + self.tol)


def follow(op: Op, rid: str, frame: Frame, label: str, since: float, timeout: float,
           on_start: Optional[Callable[[], None]] = None) -> Optional[FrameRun]:
    """Expect the next valve change at or after `since` (within `timeout`) to start `frame`,
    then the sensors to show it done. A failure is charged to requirement `rid`."""
    start = op.valve_change(since, until=since + timeout)
    if start is None and op.now < since + timeout:
        before = op.values(VALVES)
        start = op.wait(lambda io: _changed(io, before), since + timeout - op.now)
    if start is None:
        op.c.fail(rid, f"{label} starts within {timeout:g} s of t = {since:.2f} s: "
                  f"valves {fmt(frame.valves)}",
                  f"no valve changed: the valves stayed {fmt(op.values(frame.valves))}", since)
        return None
    got = op.settled(start, frame.valves)
    if got != frame.valves:
        op.c.fail(rid, f"{label}: valves {fmt(frame.valves)}", f"valves {fmt(got)}", start)
        return None
    if on_start is not None:
        on_start()
    done = op.when(lambda io: matches(io, frame.sensors), after=start, timeout=DONE_WAIT)
    if done is None:
        op.c.fail(rid, f"{label} done: sensors {fmt(frame.sensors)} within {DONE_WAIT:g} s",
                  f"sensors {fmt(op.values(frame.sensors))}", start)
        return None
    return FrameRun(start, done)


def _changed(io: Any, before: dict[str, int]) -> bool:
    return any(int(bool(io[k])) != v for k, v in before.items())


def teach(op: Op, frames: list[Frame]) -> list[float]:
    """Manual mode: set each frame's switches, wait for the robot to get there, record it with
    a short SB1 press (I0.7 as the frame says). Returns the release times."""
    releases = []
    for f in frames:
        op.set(**f.switches, I07=f.i07)
        op.wait(lambda io, f=f: matches(io, f.sensors), DONE_WAIT)
        op.run(0.4)                          # the gripper has no "clamped" switch: its 0.3 s
        releases.append(op.press(0.2) + 0.2)
        op.run(0.2)
    return releases


def quiet(op: Op, rid: str, after: float, seconds: float, expected: str, what: str) -> bool:
    """No valve change in [after, after + seconds]; else a failure of `rid`."""
    op.run_until(after + seconds)
    t = op.valve_change(after, until=after + seconds)
    if t is None:
        return True
    got = op.values(VALVES, at=t + op.tol)
    op.c.fail(rid, expected, f"{what}: the valves changed to {fmt(got)}, {t - after:.2f} s after "
              f"t = {after:.2f} s", t)
    return False


def press_starts(op: Op, rid: str, frame: Frame, label: str, pressed: float) -> Optional[FrameRun]:
    """The SB1 press at `pressed` must start `frame` on the debounced press (50 ms + one scan)."""
    run = follow(op, rid, frame, label, pressed, DEBOUNCE + 1.0)
    if run is None:
        return None
    late = run.start - pressed
    if not op.c.check(rid, -EPS <= late <= DEBOUNCE + op.tol,
                      f"{label} starts on the press (50 ms debounce, +/- one scan)",
                      f"it started {late:.2f} s after the press", run.start):
        return None
    return run


# --------------------------------------------------------------------------- every scenario

def no_fault(s: Session, c: Checks) -> None:
    f = s.fault
    if f is None:
        c.ok("G1")
        return
    offset = s.now - s.plc.now_ns / 1e9
    c.fail("G1", "no runtime fault", str(f), offset + f.time_ns / 1e9)


def no_conflict(s: Session, c: Checks) -> None:
    t = s.trace.first(lambda st: any(st[a] and st[b] for a, b, _ in CONFLICTS), default=None)
    if t is None:
        c.ok("G2")
        return
    a, b, mech = next(p for p in CONFLICTS if s.trace.value_at(p[0], t) and s.trace.value_at(p[1], t))
    c.fail("G2", f"never {a} and {b} ON together", f"{a}=1 and {b}=1 at once (the {mech} valve)", t)


# --------------------------------------------------------------------------- general (G3..G11)

DOWN, UP = lift(True), lift(False)


def start_manual(op: Op) -> None:
    op.set(SA1=0, SA2=0, SA3=0, SA4=0, SA5=0, SA6=0, I07=0)
    op.run(0.1)


def sc_basics(s: Session, c: Checks) -> None:
    """Empty-program lamp, bounce, long-press reset (manual mode, lift only)."""
    op = Op(s, c)
    start_manual(op)
    c.check("G3", op.values(["HL1"])["HL1"] == 1, "HL1=1 at power-up (no frame recorded)", "HL1=0", op.now)
    t = op.press(0.03)
    op.run(0.5)
    off = s.trace.first(lambda st: not st.HL1, after=t, default=None)
    if c.check("G4", off is None, "HL1 stays 1 after a 30 ms SB1 press (nothing recorded)",
               "HL1 went 0: the bounce recorded a frame", off):
        c.ok("G4")
    rel = teach(op, [DOWN])[0]
    op.run(0.2)
    if c.check("G3", op.values(["HL1"], at=rel + 2 * op.tol)["HL1"] == 0,
               "HL1=0 once a frame is recorded (short SB1 press)", "HL1 still 1", rel + 2 * op.tol):
        c.ok("G3")
    teach(op, [UP])
    pressed = op.now
    s.console.hold("SB1")
    on = op.wait(lambda io: io.HL1, LONG_PRESS + 1.0)
    if on is None:
        c.fail("G5", "HL1=1 (program reset) 3.0 s after SB1 is pressed, while it is held",
               f"HL1 still 0 after holding SB1 {LONG_PRESS + 1:g} s", pressed + LONG_PRESS)
        op.run_until(pressed + LONG_PRESS + 1.5)
    else:
        held = on - pressed
        c.check("G5", LONG_PRESS - op.tol <= held <= LONG_PRESS + DEBOUNCE + op.tol,
                "the reset (HL1=1) 3.0 s after SB1 is pressed, while it is held",
                f"HL1=1 {held:.2f} s after the press", on)
        op.run_until(pressed + LONG_PRESS + 0.5)
    released = op.now
    s.console.release("SB1")
    op.run(0.5)
    off = s.trace.first(lambda st: not st.HL1, after=released, default=None)
    c.check("G5", off is None, "HL1 stays 1 after the release (the release records nothing)",
            "HL1 went 0: a frame was recorded (or the reset never happened)", off or released)
    op.set(SA1=1, I07=1)
    op.run(0.3)
    t = op.press()
    if quiet(op, "G5", t, 2.0, "after the reset an SB1 press in automatic mode starts nothing",
             "a frame started: the program was not empty"):
        c.ok("G5")
    op.set(SA1=0)
    op.run(0.2)


def sc_automatic(s: Session, c: Checks) -> None:
    """Continuous start/stop, step mode, back to manual (lift only, two frames)."""
    op = Op(s, c)
    start_manual(op)
    teach(op, [DOWN, UP])
    entered = op.set(SA1=1, I07=1)
    op.run(0.5)
    op.set(SA5=1)
    op.run(0.5)
    if not quiet(op, "G6", entered, 1.0, "no valve change on entering automatic mode (SA1 := 1) and "
                 "moving SA5 there, before any SB1 press", "in automatic mode, before any SB1 press"):
        op.set(SA5=0)
        op.run(2.0)                        # let a switch-following arm come back up
    op.set(SA5=0)
    op.run(0.3)
    r1 = press_starts(op, "G6", DOWN, "frame 1", op.press())
    r2 = r1 and follow(op, "G6", UP, "frame 2 after frame 1", r1.done, NEXT_WAIT)
    r3 = r2 and follow(op, "G6", DOWN, "frame 1 after the last frame", r2.done, NEXT_WAIT)
    stop: list[float] = []
    r4 = r3 and follow(op, "G6", UP, "frame 2 (second cycle)", r3.done, NEXT_WAIT,
                       on_start=lambda: stop.append(op.press(0.1)))
    if not r4:
        return
    if not quiet(op, "G6", stop[0], QUIET, "no frame starts after the stop press (SB1 at t = "
                 f"{stop[0]:.2f} s during frame 2)", "execution went on"):
        return
    c.ok("G6")

    op.set(SA6=1)
    op.run(0.3)
    sequence = ((DOWN, "frame 1 (first step press)"), (UP, "frame 2 (second step press)"),
                (DOWN, "frame 1 (third step press, after the last frame)"))
    for frame, label in sequence:
        run = press_starts(op, "G7", frame, label, op.press())
        if run is None or not quiet(op, "G7", run.done + op.tol, QUIET,
                                    f"after {label} and its pause, no frame starts without a press",
                                    "a frame started without a press"):
            return
    c.ok("G7")

    for value, frame in ((None, UP), (1, DOWN), (0, UP)):
        t = op.set(SA1=0, SA6=0) if value is None else op.set(SA5=value)
        got = op.settled(t, frame.valves)
        what = "SA1 := 0 with SA5 = 0" if value is None else f"SA5 := {value}"
        if not c.check("G8", got == frame.valves, f"after {what}: {fmt(frame.valves)} (one scan)",
                       fmt(got), t):
            return
        op.run(1.0)
    c.ok("G8")


def sc_restart(s: Session, c: Checks) -> None:
    """The recorded program survives a PLC restart."""
    op = Op(s, c)
    start_manual(op)
    teach(op, [DOWN, UP])
    t = op.now
    s.restart_plc(off_time=1.0)
    op.run(0.3)
    if not c.check("G9", op.values(["HL1"])["HL1"] == 0, "HL1=0 after the restart (the program is kept)",
                   "HL1=1: the program is empty after the restart", t):
        return
    op.set(SA1=1, I07=1)
    op.run(0.3)
    r1 = press_starts(op, "G9", DOWN, "frame 1 after the restart", op.press())
    if r1 and follow(op, "G9", UP, "frame 2 after the restart", r1.done, NEXT_WAIT):
        c.ok("G9")


def sc_timeout(s: Session, c: Checks) -> None:
    """A jammed lift: the frame times out after 10 s, HL1 blinks 2 Hz until manual mode."""
    op = Op(s, c)
    start_manual(op)
    teach(op, [DOWN, UP])
    s.inject("jammed", mechanism="lift")
    op.set(SA1=1, I07=1)
    op.run(0.3)
    pressed = op.press()
    start = op.valve_change(pressed)
    if start is None:
        start = op.wait(lambda io: io.L3, 1.0)
    if start is None or op.values(DOWN.valves, at=start + op.tol) != DOWN.valves:
        c.fail("G10", f"frame 1 starts ({fmt(DOWN.valves)})", "it did not start", pressed)
        return
    blink = op.when(lambda io: io.HL1, after=start, timeout=FRAME_TIMEOUT + 2.0)
    if not c.check("G10", blink is not None and abs(blink - start - FRAME_TIMEOUT) <= 0.1,
                   "HL1 starts blinking 10 s after frame 1 started (the frame is not done)",
                   "HL1 stayed 0" if blink is None else f"HL1=1 {blink - start:.2f} s after the start",
                   blink or start + FRAME_TIMEOUT):
        return
    op.run_until(blink + 2.0)
    edges = s.trace.edges("HL1", "rising", after=blink, until=blink + 2.0 - op.tol)
    if not c.check("G10", 3 <= len(edges) <= 5, "HL1 blinks at 2 Hz: 4 flashes in 2 s",
                   f"{len(edges)} flashes in 2 s", blink):
        return
    cleared = op.now
    s.clear_faults()
    if not quiet(op, "G10", cleared, QUIET, "execution stays stopped after the timeout (no frame 2 "
                 "even once the lift gets free and reaches SQ2)", "a frame started"):
        return
    manual = op.set(SA1=0)
    op.run(1.5)
    late = s.trace.edges("HL1", "rising", after=manual + 2 * op.tol)
    hl1 = op.values(["HL1"])["HL1"]
    if c.check("G10", not late and hl1 == 0, "HL1 stops blinking (0) once SA1 = 0 (manual mode)",
               f"HL1 {'still blinking' if late else '=1'} in manual mode", manual):
        c.ok("G10")


def sc_memory(s: Session, c: Checks) -> None:
    """32 frames fit; the 33rd blinks HL1 at 1 Hz for 2 s."""
    op = Op(s, c)
    start_manual(op)
    first = op.press(0.1)
    for _ in range(CAPACITY - 1):
        op.run(0.1)
        op.press(0.1)
    op.run(0.3)
    flash = s.trace.first(lambda st: st.HL1, after=first + 0.1 + 2 * op.tol, default=None)
    if not c.check("G11", flash is None, "HL1 stays 0 while frames 1..32 are recorded",
                   "HL1 went 1", flash):
        return
    released = op.press(0.1) + 0.1
    op.run(3.0)
    edges = s.trace.edges("HL1", "rising", after=released - op.tol, until=released + 2.0 - op.tol)
    after = s.trace.edges("HL1", "rising", after=released + 2.0, until=op.now)
    ok = len(edges) == 2 and edges[0] - released <= 2 * op.tol and not after \
        and op.values(["HL1"])["HL1"] == 0
    seen = f"{len(edges)} flash(es) in 2 s"
    if edges:
        seen += f" starting {edges[0] - released:.2f} s after the release"
    if after:
        seen += f", {len(after)} more after 2 s"
    if c.check("G11", ok, "after the 33rd short press: HL1 flashes at 1 Hz for 2 s (2 flashes from "
               "the release), then 0", seen, released):
        c.ok("G11")


GENERAL = (
    Requirement("G1", "The program runs without a PLC fault (division by zero, array index out of "
                "range, scan watchdog).", EVERY),
    Requirement("G2", "Never a valve conflict: the two coils of one valve (L2/L3, L4/L5, L6/L7) are "
                "never ON together.", EVERY),
    Requirement("G3", "HL1 is ON while the program is empty (at power-up) and OFF once a frame is "
                "recorded with a short SB1 press.", "basics"),
    Requirement("G4", "A press of SB1 shorter than 50 ms is contact bounce: it records nothing.", "basics"),
    Requirement("G5", "Holding SB1 resets the program at 3.0 s, while it is still held (HL1 ON); the "
                "release records nothing and a start then finds the program empty.", "basics"),
    Requirement("G6", "Continuous mode: entering automatic mode (or moving a switch there) changes no "
                "valve; an SB1 press starts frame 1, the frames follow one another, frame 1 follows "
                "the last one; another press stops execution.", "automatic"),
    Requirement("G7", "Step mode (SA6 = 1): each SB1 press runs exactly one frame and its pause, then "
                "execution waits for the next press.", "automatic"),
    Requirement("G8", "Back in manual mode (SA1 = 0) the valves follow the switches again.", "automatic"),
    Requirement("G9", "The recorded program survives a PLC restart (power cycle of the controller).",
                "restart"),
    Requirement("G10", "A frame not done within 10 s (lift jammed) stops execution; HL1 blinks at 2 Hz "
                "until manual mode.", "timeout"),
    Requirement("G11", "Memory full: the 33rd short press records nothing and HL1 blinks at 1 Hz for "
                "2 s.", "memory"),
)
GENERAL_SCENARIOS = (
    Scenario("basics", sc_basics), Scenario("automatic", sc_automatic),
    Scenario("restart", sc_restart, needs_retain=True), Scenario("timeout", sc_timeout),
    Scenario("memory", sc_memory),
)


# --------------------------------------------------------------------------- Task 1

MECHANISMS = (
    # requirement, switch, what, (valves, sensors) for switch = 1, then for switch = 0, travel time
    ("T1.1", "SA2", "the gripper", ({"L1": 1}, {"SQ3": 0}), ({"L1": 0}, {"SQ3": 1}), 0.3),
    ("T1.2", "SA3", "the rotation", ({"L5": 1, "L4": 0}, {"SQ5": 1, "SQ4": 0}),
     ({"L4": 1, "L5": 0}, {"SQ4": 1, "SQ5": 0}), 1.2),
    ("T1.3", "SA4", "the extension", ({"L6": 1, "L7": 0}, {"SQ6": 1, "SQ7": 0}),
     ({"L7": 1, "L6": 0}, {"SQ7": 1, "SQ6": 0}), 1.0),
    ("T1.4", "SA5", "the lift", ({"L3": 1, "L2": 0}, {"SQ2": 1, "SQ1": 0}),
     ({"L2": 1, "L3": 0}, {"SQ1": 1, "SQ2": 0}), 0.8),
)


def sc_manual(s: Session, c: Checks) -> None:
    """Each switch moves its mechanism both ways in manual mode."""
    op = Op(s, c)
    start_manual(op)
    op.run(0.5)
    for rid, switch, _what, on, off, travel in MECHANISMS:
        for value, (valves, sensors) in ((1, on), (0, off)):
            t = op.set(**{switch: value})
            got = op.settled(t, valves)
            if not c.check(rid, got == valves, f"after {switch} := {value}: {fmt(valves)} (within one scan)",
                           fmt(got), t):
                break
            reached = op.when(lambda io, w=sensors: matches(io, w), after=t, timeout=travel + MARGIN)
            if not c.check(rid, reached is not None, f"after {switch} := {value}: {fmt(sensors)} "
                           f"within {travel + MARGIN:g} s", fmt(op.values(sensors)), t):
                break
            op.run(0.5)
        else:
            c.ok(rid)
        op.set(**{switch: 0})
        op.run(travel + MARGIN)


PICK_AND_PLACE = (arm(0, 0, 0, 1), arm(1, 0, 0, 0), arm(1, 1, 1, 1), arm(0, 0, 0, 0))


def sc_playback(s: Session, c: Checks) -> None:
    """A pick-and-place taught with all four switches plays back."""
    op = Op(s, c)
    start_manual(op)
    teach(op, list(PICK_AND_PLACE))
    op.set(SA1=1, I07=1)
    op.run(0.3)
    since = op.press()
    for k, frame in enumerate(PICK_AND_PLACE + PICK_AND_PLACE[:1]):
        label = f"frame {k % 4 + 1}" + (" after frame 4" if k == 4 else "")
        run = follow(op, "T1.5", frame, label, since, DEBOUNCE + 1.0 if k == 0 else NEXT_WAIT)
        if run is None:
            return
        since = run.done
    c.ok("T1.5")
    op.press()
    op.run(1.0)


TASK1 = (
    Requirement("T1.1", "Manual mode: SA2 = 1 clamps the gripper (L1 = 1, SQ3 goes OFF), SA2 = 0 "
                "releases it (L1 = 0, SQ3 ON).", "manual"),
    Requirement("T1.2", "Manual mode: SA3 = 1 rotates the arm right (L5 = 1, L4 = 0, SQ5 reached), "
                "SA3 = 0 rotates it left (L4 = 1, L5 = 0, SQ4 reached).", "manual"),
    Requirement("T1.3", "Manual mode: SA4 = 1 moves the arm forward (L6 = 1, L7 = 0, SQ6 reached), "
                "SA4 = 0 backward (L7 = 1, L6 = 0, SQ7 reached).", "manual"),
    Requirement("T1.4", "Manual mode: SA5 = 1 lowers the arm (L3 = 1, L2 = 0, SQ2 reached), SA5 = 0 "
                "raises it (L2 = 1, L3 = 0, SQ1 reached).", "manual"),
    Requirement("T1.5", "A 4-frame pick-and-place taught with all four switches plays back in "
                "automatic mode: each frame drives the valves its switches selected and waits for "
                "the sensors; frame 1 follows frame 4.", "playback"),
)


# --------------------------------------------------------------------------- Task 2

def sc_pauses(s: Session, c: Checks) -> None:
    """Frame 1 recorded with I0.7 = 1 (3 s), frame 2 with I0.7 = 0 (0.5 s); a cycle with I0.7 = 1,
    then a cycle during which I0.7 is 0 (frame 1) and 1 again (frame 2)."""
    op = Op(s, c)
    start_manual(op)
    f1, f2 = lift(True, i07=1), lift(False, i07=0)
    teach(op, [f1, f2])
    op.set(SA1=1, I07=1)
    op.run(0.3)
    r1 = follow(op, "T2.2", f1, "frame 1", op.press(), DEBOUNCE + 1.0)
    r2 = r1 and follow(op, "T2.2", f2, "frame 2", r1.done, NEXT_WAIT)
    if not r1 or not r2:
        return
    p1 = r2.start - r1.done
    if c.check("T2.2", abs(p1 - PAUSE_LONG) <= op.tol,
               "a 3.0 s pause after frame 1 (recorded with I0.7 = 1)", f"{p1:.2f} s", r1.done):
        c.ok("T2.2")
    r3 = follow(op, "T2.1", f1, "frame 1 after frame 2", r2.done, NEXT_WAIT,
                on_start=lambda: op.set(I07=0))
    if not r3:
        return
    p2 = r3.start - r2.done
    if c.check("T2.1", abs(p2 - PAUSE_SHORT) <= op.tol,
               "a 0.5 s pause after frame 2 (recorded with I0.7 = 0)", f"{p2:.2f} s", r2.done):
        c.ok("T2.1")
    r4 = follow(op, "T2.3", f2, "frame 2 (second cycle)", r3.done, NEXT_WAIT, on_start=lambda: op.set(I07=1))
    if not r4:
        return
    p3 = r4.start - r3.done
    if not c.check("T2.3", abs(p3 - p1) <= op.tol, f"the pause after frame 1 is {p1:.2f} s as in the first "
                   "cycle although I0.7 is now 0", f"{p3:.2f} s", r3.done):
        return
    r5 = follow(op, "T2.3", f1, "frame 1 (third cycle)", r4.done, NEXT_WAIT)
    if not r5:
        return
    p4 = r5.start - r4.done
    if c.check("T2.3", abs(p4 - p2) <= op.tol, f"the pause after frame 2 is {p2:.2f} s as in the first "
               "cycle although I0.7 is now 1", f"{p4:.2f} s", r4.done):
        c.ok("T2.3")
    op.press()
    op.run(1.0)


TASK2 = (
    Requirement("T2.1", "A frame recorded with I0.7 = 0 is followed by a 0.5 s pause (from the sensors "
                "showing the frame done to the next valve change).", "pauses"),
    Requirement("T2.2", "A frame recorded with I0.7 = 1 is followed by a 3.0 s pause.", "pauses"),
    Requirement("T2.3", "I0.7 changes nothing in automatic mode: switched during execution, every frame "
                "keeps the pause recorded with it.", "pauses"),
)


# --------------------------------------------------------------------------- Task 3

def sc_enable(s: Session, c: Checks) -> None:
    """Four lift frames; start refused / accepted, wrap with I0.7 = 1, I0.7 dropped in frame 2."""
    op = Op(s, c)
    start_manual(op)
    frames = [DOWN, UP, DOWN, UP]
    teach(op, frames)
    op.set(SA1=1, I07=0)
    op.run(0.3)
    if not quiet(op, "T3.1", op.press(), 2.0, "an SB1 press with I0.7 = 0 starts nothing",
                 "the program started"):
        op.set(SA1=0)                       # manual mode stops it; the arm goes back up (SA5 = 0)
        op.run(2.0)
        op.set(SA1=1)
        op.run(0.3)
    else:
        c.ok("T3.1")
    op.set(I07=1)
    op.run(0.3)
    run = press_starts(op, "T3.2", frames[0], "frame 1 (SB1 pressed with I0.7 = 1)", op.press())
    if run is None:
        return
    c.ok("T3.2")
    for k in (1, 2, 3):
        run = follow(op, "T3.3", frames[k], f"frame {k + 1}", run.done, NEXT_WAIT)
        if run is None:
            return
    run = follow(op, "T3.3", frames[0], "frame 1 after frame 4 (I0.7 = 1)", run.done, NEXT_WAIT)
    if run is None:
        return
    c.ok("T3.3")
    dropped: list[float] = []
    run = follow(op, "T3.4", frames[1], "frame 2 (second cycle)", run.done, NEXT_WAIT,
                 on_start=lambda: dropped.append(op.set(I07=0)))
    for k in (2, 3):
        if run is None:
            return
        run = follow(op, "T3.4", frames[k], f"frame {k + 1} (I0.7 dropped to 0 at t = {dropped[0]:.2f} s)",
                     run.done, NEXT_WAIT)
    if run is None:
        return
    c.ok("T3.4")
    if not quiet(op, "T3.5", run.done, PAUSE_LONG + 2.0, "no frame starts after frame 4 (the last) and its "
                 "pause, I0.7 being 0", "execution went on to frame 1"):
        c.fail("T3.6", "", "not checked: execution did not stop after the last frame (see T3.5)", None)
        return
    c.ok("T3.5")
    if not quiet(op, "T3.6", op.press(), 2.0, "after the stop, an SB1 press with I0.7 = 0 starts nothing",
                 "the program started"):
        return
    if not quiet(op, "T3.6", op.set(I07=1), 2.0, "after the stop, I0.7 = 1 alone (no press) starts nothing",
                 "the program started"):
        return
    if press_starts(op, "T3.6", frames[0], "frame 1 (a new start: SB1 with I0.7 = 1)", op.press()):
        c.ok("T3.6")
    op.set(SA1=0)
    op.run(1.0)


TASK3 = (
    Requirement("T3.1", "Automatic mode: an SB1 press with I0.7 = 0 starts nothing.", "enable"),
    Requirement("T3.2", "An SB1 press with I0.7 = 1 starts frame 1.", "enable"),
    Requirement("T3.3", "With I0.7 = 1 the frames run in order and frame 1 follows the last frame and its "
                "pause.", "enable"),
    Requirement("T3.4", "I0.7 dropped to 0 during frame 2: frame 2 and the remaining frames 3 and 4 still "
                "run to completion.", "enable"),
    Requirement("T3.5", "Then, after the last frame and its pause, no transition to frame 1: execution "
                "stops there.", "enable"),
    Requirement("T3.6", "After that stop nothing restarts by itself or on a press with I0.7 = 0; an SB1 "
                "press with I0.7 = 1 starts again from frame 1.", "enable"),
)


# --------------------------------------------------------------------------- registration

def _set(task: str, requirements: tuple[Requirement, ...], scenarios: tuple[Scenario, ...]) -> RequirementSet:
    return register(RequirementSet(
        stand="mp9c", task=task,
        title=f"{STAND.title}, {STAND.variants[task].doc}",
        requirements=requirements + GENERAL, scenarios=scenarios + GENERAL_SCENARIOS,
        make_session=make_session, every=(no_fault, no_conflict)))


_set("task1", TASK1, (Scenario("manual", sc_manual), Scenario("playback", sc_playback)))
_set("task2", TASK2, (Scenario("pauses", sc_pauses),))
_set("task3", TASK3, (Scenario("enable", sc_enable),))
