"""MP-9C requirement sets: Tasks 1-3 of the pneumatic robot lab (docs/mp9c.md), judged by I/O alone.

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
from plclab.stands.exploration import MP9C_RULES
from plclab.stands.mp9c import STAND, labels

from .common import (DEBOUNCE, NEXT_WAIT, NO_FAULT, REFUSED, FrameRun, Op, basics_flow, enable_flow,
                     lamp_requirements, last_pause_flow, no_fault, pauses_flow, register_tasks, restart_flow,
                     task2_requirements, task3_requirements, within_scan)
from .registry import EVERY, Checks, Requirement, Scenario

VALVES = tuple(f"L{i}" for i in range(1, 8))
CONFLICTS = (("L2", "L3", "lift"), ("L4", "L5", "rotation"), ("L6", "L7", "extension"))

FRAME_TIMEOUT = 10.0     # a frame not done in this time is a fault
TIMEOUT_TOL = 0.1        # s on the frame timeout
FAULT_BLINK_HZ = 2.0     # HL1 after a frame timeout
CAPACITY = 32            # frames
MARGIN = 0.5             # s of slack on plant travel times
DONE_WAIT = 3.0          # a frame's links all arrive within this (longest travel 1.2 s)
QUIET = 3.0              # "nothing happens": no valve change for this long


# --------------------------------------------------------------------------- the stand

def make_session(sources: list[tuple[str, str]], retain_path: Optional[Path], checked: Any = None) -> Session:
    return Session(sources, STAND.make_plant(), labels(), watch=(), retain_path=retain_path,
                   name="mp9c program", checked=checked)


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


# --------------------------------------------------------------------------- the operator

class Mp9cOp(Op[Frame]):
    """The operator of the pneumatic robot: a frame starts with a valve change and is done
    when the limit switches show the robot there."""

    auto = "SA1"
    enable = "I07"
    enable_label = "I0.7"
    wind_down = 1.0
    press_window = "50 ms debounce, +/- one scan"
    started = "it started"
    watchdog = "G10"
    frame_timeout = FRAME_TIMEOUT
    timeout_tol = f"+/- {TIMEOUT_TOL:g} s"
    rules = MP9C_RULES

    def start_manual(self) -> None:
        self.set(SA1=0, SA2=0, SA3=0, SA4=0, SA5=0, SA6=0, I07=0)
        self.run(0.1)

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

    def spools(self, names: Any, at: float) -> dict[str, int]:
        """The valves at `at` as their spools stand (`spools_at`), as coil values."""
        got = spools_at(self.s.trace, at)
        return {n: got[n] for n in names}

    def motion(self, after: float, until: Optional[float] = None) -> Optional[float]:
        """The first change at or after `after` (up to `until`, default: now) of where a valve
        sends its mechanism: a coil dropped once its mechanism has arrived changes nothing
        (both coils of a valve off keep its spool), so it never reads as a frame starting."""
        names = list(VALVES)
        t = self.s.trace.next_change(names, after=after, until=until, default=None)
        if t is None:
            return None
        before = spools_at(self.s.trace, t - 1e-9)
        while t is not None:
            now = spools_at(self.s.trace, t)
            if now != before:
                return t
            before = now
            t = self.s.trace.next_change(names, after=t + 1e-9, until=until, default=None)
        return None

    def what_moved(self, t: float) -> str:
        """The valves one scan after they changed at `t`."""
        return f"the valves changed to {fmt(self.spools(VALVES, t + self.tol))},"

    def settled(self, t: float, names: Any) -> dict[str, int]:
        """Where the valves send their mechanisms one scan after `t` (the tolerance on when
        outputs follow), as coil values (`spools`)."""
        self.run_until(t + self.tol + self.s.tick)
        return self.spools(names, t + self.tol)

    def follow(self, rid: str, frame: Frame, label: str, since: float, timeout: float,
               on_start: Optional[Callable[[], object]] = None) -> Optional[FrameRun]:
        """The next valve change (within `timeout` of `since`) starts `frame` if the valves are
        the frame's one scan later; the frame is done when the sensors show it."""
        start = self.motion(since, until=since + timeout)
        while start is None and self.now < since + timeout:
            before = self.values(VALVES)
            if self.wait(lambda io: _changed(io, before), since + timeout - self.now) is None:
                break
            start = self.motion(since, until=self.now)      # a coil dropped after arriving is no start
        if start is None:
            self.missed(rid, f"{label} starts within {timeout:g} s of t = {since:.2f} s: valves {fmt(frame.valves)}",
                        f"no valve changed: the valves stayed {fmt(self.spools(frame.valves, self.now))}", since)
            return None
        got = self.settled(start, frame.valves)
        if got != frame.valves:
            self.c.fail(rid, f"{label}: valves {fmt(frame.valves)}", f"valves {fmt(got)}", start)
            return None
        if on_start is not None:
            on_start()
        done = self.when(lambda io: matches(io, frame.sensors), after=start, timeout=DONE_WAIT)
        if done is None:
            self.c.fail(rid, f"{label} done: sensors {fmt(frame.sensors)} within {DONE_WAIT:g} s",
                        f"sensors {fmt(self.values(frame.sensors))}", start)
            return None
        return self.ran(FrameRun(start, done))


PAIRS = (("L2", "L3"), ("L4", "L5"), ("L6", "L7"))


def spools_at(trace: Any, at: float) -> dict[str, int]:
    """L1..L7 as the valves' spools stand at `at`: a double valve (L2/L3, L4/L5, L6/L7) with
    both coils off stays where its last coil sent it, so a coil dropped once its mechanism has
    arrived reads as held (docs/grading.md: one rule set with exploration, which compares the
    spools). L1 (the gripper, one coil) is as it is."""
    out = {n: int(bool(trace.value_at(n, at))) for n in VALVES}
    for a, b in PAIRS:
        if out[a] or out[b]:
            continue
        times = sorted({t for n in (a, b) for t, _v in trace.changes(n) if t / 1e9 <= at + 1e-12}, reverse=True)
        for t_ns in times:                        # back to the latest moment one coil was on alone
            va, vb = bool(trace.value_at_ns(a, t_ns)), bool(trace.value_at_ns(b, t_ns))
            if va != vb:
                out[a if va else b] = 1
                break
    return out


def _changed(io: Any, before: dict[str, int]) -> bool:
    return any(int(bool(io[k])) != v for k, v in before.items())


def teach(op: Mp9cOp, frames: list[Frame]) -> list[float]:
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


def step_mode(op: Mp9cOp) -> Mp9cOp:
    """The operator plays back in step mode (SA6 = 1): SB1 taps go on to each next frame."""
    op.set(SA6=1)
    op.step = True
    return op


# --------------------------------------------------------------------------- every scenario

def no_conflict(s: Session, c: Checks) -> None:
    with c.requirement(G2) as rid:
        t = s.trace.first(lambda st: any(st[a] and st[b] for a, b, _ in CONFLICTS), default=None)
        if t is not None:
            a, b, mech = next(p for p in CONFLICTS if s.trace.value_at(p[0], t) and s.trace.value_at(p[1], t))
            c.fail(rid, f"never {a} and {b} ON together", f"{a}=1 and {b}=1 at once (the {mech} valve)", t)


# --------------------------------------------------------------------------- general (G3..G11)

DOWN, UP = lift(True), lift(False)


def teach_one(op: Mp9cOp, frame: Frame) -> float:
    """Teach `frame` alone and run on 0.2 s; returns the SB1 release."""
    released = teach(op, [frame])[0]
    op.run(0.2)
    return released


def sc_basics(s: Session, c: Checks) -> None:
    """Empty-program lamp, bounce, long-press reset (manual mode, lift only)."""
    op = Mp9cOp.begin(s, c)
    basics_flow(op, ("G3", "G4", "G5"), record=lambda: teach_one(op, DOWN),
                record_another=lambda: teach(op, [UP]))


def sc_automatic(s: Session, c: Checks) -> None:
    """Continuous start/stop, step mode, back to manual (lift only, two frames)."""
    op = Mp9cOp.begin(s, c)
    teach(op, [DOWN, UP])
    with c.requirement(G6) as rid:
        entered = op.set(SA1=1, I07=1)
        op.run(0.5)
        op.set(SA5=1)
        op.run(0.5)
        if not op.quiet(rid, entered, 1.0, "no valve change on entering automatic mode (SA1 := 1) and "
                        "moving SA5 there, before any SB1 press", "in automatic mode, before any SB1 press"):
            op.set(SA5=0)
            op.run(2.0)                        # let a switch-following arm come back up
        op.set(SA5=0)
        op.run(0.3)
        r1 = op.press_starts(rid, DOWN, "frame 1", op.press())
        r2 = r1 and op.follow(rid, UP, "frame 2 after frame 1", r1.done, NEXT_WAIT)
        r3 = r2 and op.follow(rid, DOWN, "frame 1 after the last frame", r2.done, NEXT_WAIT)
        stop: list[float] = []
        r4 = r3 and op.follow(rid, UP, "frame 2 (second cycle)", r3.done, NEXT_WAIT,
                              on_start=lambda: stop.append(op.press(0.1)))
        if not r4:
            return
        if not op.quiet(rid, stop[0], QUIET, "no frame starts after the stop press (SB1 at t = "
                        f"{stop[0]:.2f} s during frame 2)", "execution went on"):
            return

    with c.requirement(G7) as rid:
        op.set(SA6=1)
        op.run(0.3)
        sequence = ((DOWN, "frame 1 (first step press)"), (UP, "frame 2 (second step press)"),
                    (DOWN, "frame 1 (third step press, after the last frame)"))
        for frame, label in sequence:
            run = op.press_starts(rid, frame, label, op.press())
            if run is None or not op.quiet(rid, run.done + op.tol, QUIET,
                                           f"after {label} and its pause, no frame starts without a press",
                                           "a frame started without a press"):
                return

    with c.requirement(G8) as rid:
        for value, frame in ((None, UP), (1, DOWN), (0, UP)):
            t = op.set(SA1=0, SA6=0) if value is None else op.set(SA5=value)
            got = op.settled(t, frame.valves)
            what = "SA1 := 0 with SA5 = 0" if value is None else f"SA5 := {value}"
            if not c.check(rid, got == frame.valves, f"after {what}: {fmt(frame.valves)} (one scan)",
                           fmt(got), t):
                return
            op.run(1.0)


def sc_restart(s: Session, c: Checks) -> None:
    """The recorded program survives a PLC restart."""
    op = Mp9cOp.begin(s, c)
    teach(op, [DOWN, UP])
    restart_flow(op, G9.id, DOWN, UP, off_time=1.0, lamp="G3")


def sc_timeout(s: Session, c: Checks) -> None:
    """A jammed lift: the frame times out after 10 s, HL1 blinks 2 Hz until manual mode."""
    op = Mp9cOp.begin(s, c)
    teach(op, [DOWN, UP])
    s.inject("jammed", mechanism="lift")
    op.start_auto()
    with c.requirement(G10) as rid:
        pressed = op.press()
        start = op.motion(pressed)
        if start is None:
            start = op.wait(lambda io: io.L3, 1.0)
        if start is None or op.spools(DOWN.valves, start + op.tol) != DOWN.valves:
            c.fail(rid, f"frame 1 starts ({fmt(DOWN.valves)})", "it did not start", pressed)
            return
        lit = op.hl1(at=start) == 1        # a lamp already ON (G3's failure) shows a blink as its first OFF
        if lit:
            fall = op.when(lambda io: not io.HL1, after=start, timeout=FRAME_TIMEOUT + 2.0)
            half = 1 / (2 * FAULT_BLINK_HZ)       # an inverted blink goes OFF at once, a normal one after half a period
            blink = None if fall is None else min((fall, fall - half), key=lambda b: abs(b - start - FRAME_TIMEOUT))
        else:
            blink = op.when(lambda io: io.HL1, after=start, timeout=FRAME_TIMEOUT + 2.0)
        # a blink may begin in either phase or run from a free-running clock (Rules): its first
        # flash comes up to half a period after the fault
        late = 1 / (2 * FAULT_BLINK_HZ) + op.tol if op.rules.blink_start_tol else 0.0
        if not c.check(rid, blink is not None and -TIMEOUT_TOL <= blink - start - FRAME_TIMEOUT <= TIMEOUT_TOL + late,
                       f"HL1 starts blinking {FRAME_TIMEOUT:g} s (+/- {TIMEOUT_TOL:g} s) after frame 1 started "
                       f"(the frame is not done); its first flash within half a period ({late - op.tol:g} s) of "
                       "that: a blink may begin in either phase or run from a free-running clock",
                       f"HL1 stayed {int(lit)}" if blink is None else
                       f"HL1 started blinking {blink - start:.2f} s after the start",
                       blink or start + FRAME_TIMEOUT):
            return
        op.run_until(blink + 2.0)
        edges = s.trace.edges("HL1", "rising", after=blink, until=blink + 2.0 - op.tol)
        flashes = len(edges) + lit
        if not c.check(rid, 3 <= flashes <= 5, f"HL1 blinks at {FAULT_BLINK_HZ:g} Hz: "
                       f"{2 * FAULT_BLINK_HZ:g} flashes in 2 s (3..5)", f"{flashes} flashes in 2 s", blink):
            return
        cleared = op.now
        s.clear_faults()
        if not op.quiet(rid, cleared, QUIET, "execution stays stopped after the timeout (no frame 2 "
                        "even once the lift gets free and reaches SQ2)", "a frame started"):
            return
        manual = op.set(SA1=0)
        op.run(1.5)
        late = s.trace.edges("HL1", "rising", after=manual + 2 * op.tol)
        c.check(rid, not late and (op.hl1() == 0 or lit), "HL1 stops blinking (0) once SA1 = 0 (manual mode)",
                f"HL1 {'still blinking' if late else '=1'} in manual mode", manual)


def sc_memory(s: Session, c: Checks) -> None:
    """32 frames fit; the 33rd blinks HL1 at 1 Hz for 2 s."""
    op = Mp9cOp.begin(s, c)
    with c.requirement(G11) as rid:
        first = op.press(0.1)
        for _ in range(CAPACITY - 1):
            op.run(0.1)
            op.press(0.1)
        op.run(0.3)
        lit = op.hl1() == 1                # a lamp stuck ON (G3's failure): flashes show as its OFF phases
        flash = s.trace.first(lambda st: st.HL1 != lit, after=first + 0.1 + 2 * op.tol, default=None)
        if not c.check(rid, flash is None, f"HL1 stays {int(lit)} while frames 1..{CAPACITY} are recorded",
                       f"HL1 went {int(not lit)}", flash):
            return
        pressed = op.press(0.1)
        released = pressed + 0.1
        op.run(3.0)
        early = s.trace.edges("HL1", "rising", after=pressed, until=released - op.tol)
        edges = s.trace.edges("HL1", "rising", after=released - op.tol, until=released + 2.0 - op.tol)
        after = s.trace.edges("HL1", "rising", after=released + 2.0 + 2 * op.tol * lit, until=op.now)
        flashes = len(edges) + (lit and op.hl1(at=released + op.tol) == 1)
        if early:
            c.fail(rid, f"after the {CAPACITY + 1}rd short press: HL1 flashes from the release of SB1 (+/- one scan)",
                   f"HL1 began flashing {released - early[0]:.2f} s before the release: the press was taken when SB1 "
                   "was pressed, not at its release", early[0])
            return
        if lit:
            ok = flashes == 2 and not after
            seen = f"{flashes} flash(es) in 2 s" + (f", {len(after)} more after 2 s" if after else "")
            c.check(rid, ok, f"after the {CAPACITY + 1}rd short press: HL1 flashes at 1 Hz for 2 s (2 flashes "
                    f"from the release, {within_scan(op)}), then 0", seen, released)
            return
        ok, seen = judge_blink(s.trace, released, hz=1.0, span=2.0, tol=2 * op.tol)
        c.check(rid, ok and op.hl1() == 0,
                f"after the {CAPACITY + 1}rd short press: HL1 blinks at 1 Hz for 2 s from the release, then 0 "
                f"(either phase first, or a free-running clock: each half 0.5 s, the first and the last up to "
                f"0.5 s, +/- two scans; the blink over 2 s +/- half a period after the release)", seen, released)


def judge_blink(trace: Any, cause: float, hz: float, span: float, tol: float) -> tuple[bool, str]:
    """HL1 blinking from `cause` for `span` s at `hz`, judged by its frequency and its span: a
    blink may begin in either phase and run from a free-running clock (stands.exploration.Rules),
    so its first change comes within half a period of `cause`, every half period inside it
    lasts 1/(2 hz) (the first and the last may be cut short by the gate), and its last change
    comes `span` s after `cause` within half a period; nothing after. (ok, what was seen)."""
    half = 1 / (2 * hz)
    changes = trace.edges("HL1", "any", after=cause - tol, until=trace.end_s)
    flashes = len(trace.edges("HL1", "rising", after=cause - tol, until=trace.end_s))
    if not changes:
        return False, "HL1 did not blink (it stayed 0)"
    phases = [b - a for a, b in zip(changes, changes[1:])]
    first, last = changes[0] - cause, changes[-1] - cause
    seen = (f"{flashes} flash(es), the first change {first:.2f} s after the release, the last {last:.2f} s after it"
            + (f"; halves of {', '.join(f'{p:.2f}' for p in phases)} s" if phases else ""))
    inner = phases[1:-1]
    ok = (first <= half + tol and abs(last - span) <= half + tol and len(changes) >= 3
          and all(p <= half + tol for p in phases) and all(abs(p - half) <= tol for p in inner))
    return ok, seen


G2 = Requirement("G2", "Never a valve conflict: the two coils of one valve (L2/L3, L4/L5, L6/L7) are never "
                 "ON together.", EVERY)
G6 = Requirement("G6", "Continuous mode: entering automatic mode (or moving a switch there) changes no valve; "
                 "an SB1 press starts frame 1, the frames follow one another, frame 1 follows the last "
                 "one; another press stops execution.", "automatic")
G7 = Requirement("G7", "Step mode (SA6 = 1): each SB1 press runs exactly one frame and its pause, then "
                 "execution waits for the next press.", "automatic")
G8 = Requirement("G8", "Back in manual mode (SA1 = 0) the valves follow the switches again.", "automatic")
G9 = Requirement("G9", "The recorded program survives a PLC restart (power cycle of the controller).",
                 "restart")
G10 = Requirement("G10", f"A frame not done within {FRAME_TIMEOUT:g} s (lift jammed) stops execution; HL1 "
                  f"blinks at {FAULT_BLINK_HZ:g} Hz until manual mode.", "timeout")
G11 = Requirement("G11", f"Memory full: the {CAPACITY + 1}rd short press records nothing and HL1 blinks at "
                  "1 Hz for 2 s.", "memory")
GENERAL = (NO_FAULT, G2, *lamp_requirements("G3", "G4", "G5"), G6, G7, G8, G9, G10, G11)
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


LONGEST_TRAVEL = 1.2      # s: the rotation


def sc_manual(s: Session, c: Checks) -> None:
    """Each switch moves its mechanism both ways in manual mode, with the other switches at 0
    and then at 1: a mechanism interlocked with another one (the extension only while the arm
    is up) fails its own row, with the other switches named, not only a playback frame."""
    op = Mp9cOp.begin(s, c)
    op.run(0.5)
    for rid, switch, _what, on, off, travel in MECHANISMS:
        with c.requirement(rid):
            for others in (0, 1):
                rest = {sw: others for _r, sw, *_ in MECHANISMS if sw != switch}
                if others:
                    op.set(**rest)
                    op.run(LONGEST_TRAVEL + MARGIN)
                context = f" (with {fmt(rest)})" if others else ""
                done = True
                for value, (valves, sensors) in ((1, on), (0, off)):
                    t = op.set(**{switch: value})
                    got = op.settled(t, valves)
                    if not c.check(rid, got == valves, f"after {switch} := {value}{context}: {fmt(valves)} "
                                   "(within one scan)", fmt(got), t):
                        done = False
                        break
                    reached = op.when(lambda io, w=sensors: matches(io, w), after=t, timeout=travel + MARGIN)
                    if not c.check(rid, reached is not None, f"after {switch} := {value}{context}: {fmt(sensors)} "
                                   f"within {travel + MARGIN:g} s", fmt(op.values(sensors)), t):
                        done = False
                        break
                    op.run(0.5)
                if others:
                    op.set(**{sw: 0 for sw in rest})
                    op.run(LONGEST_TRAVEL + MARGIN)
                if not done:
                    break
        op.set(**{switch: 0})
        op.run(travel + MARGIN)


PICK_AND_PLACE = (arm(0, 0, 0, 1), arm(1, 0, 0, 0), arm(1, 1, 1, 1), arm(0, 0, 0, 0))


def sc_playback(s: Session, c: Checks, step: bool = False) -> None:
    """A pick-and-place taught with all four switches plays back."""
    op = Mp9cOp.begin(s, c)
    teach(op, list(PICK_AND_PLACE))
    if step:
        step_mode(op)
    op.start_auto()
    with c.requirement("T1.5") as rid:
        run = op.follow(rid, PICK_AND_PLACE[0], f"{op.mode}frame 1", op.press(), DEBOUNCE + 1.0)
        for k, frame in enumerate(PICK_AND_PLACE[1:] + PICK_AND_PLACE[:1], 1):
            run = run and op.advance(rid, frame, f"frame {k % 4 + 1}" + (" after frame 4" if k == 4 else ""),
                                     run.done)
        if not run:
            return
    if step:
        op.back_to_manual()
    else:
        op.stop_playback()


def sc_playback_step(s: Session, c: Checks) -> None:
    """The pick-and-place in step mode (SA6 = 1)."""
    sc_playback(s, c, step=True)


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
                "the sensors; frame 1 follows frame 4; in continuous and in step mode.", "playback"),
)


# --------------------------------------------------------------------------- Task 2

PAUSE_PATTERN = (1, 0, 0, 1)     # I0.7 when each frame is recorded: 3 s, 0.5 s, 0.5 s, 3 s


def pause_frames() -> list[Frame]:
    """Four lift frames (down, up, down, up) recorded with I0.7 as PAUSE_PATTERN says: swapped
    pauses, the next frame's and the previous frame's pause all give different pauses."""
    return [lift(k % 2 == 0, i07=v) for k, v in enumerate(PAUSE_PATTERN)]


def sc_pauses(s: Session, c: Checks, step: bool = False) -> None:
    """Four lift frames with the pauses 3, 0.5, 0.5, 3 s; a cycle with I0.7 = 1, then cycles
    with I0.7 switched at every phase boundary, longer than the frame watchdog."""
    op = Mp9cOp.begin(s, c)
    frames = pause_frames()
    teach(op, frames)
    pauses_flow(step_mode(op) if step else op, frames, PAUSE_PATTERN, start_checked=False)


def sc_pauses_step(s: Session, c: Checks) -> None:
    """The pauses in step mode (SA6 = 1)."""
    sc_pauses(s, c, step=True)


TASK2 = task2_requirements("I0.7", "from the sensors showing the frame done to the next valve change",
                           modes=", in continuous and in step mode")


# --------------------------------------------------------------------------- Task 3

def refused_start(op: Mp9cOp) -> None:
    """T3.1: an SB1 press with I0.7 = 0 starts nothing. A program that starts is stopped in
    manual mode, where the arm goes back up (SA5 = 0), before the enabled start."""
    with op.c.requirement("T3.1") as rid:
        if op.quiet(rid, op.press(), REFUSED, f"{op.mode}an SB1 press with I0.7 = 0 starts nothing",
                    "the program started"):
            return
    op.set(SA1=0)
    op.run(2.0)
    op.set(SA1=1)
    op.run(0.3)


def sc_enable(s: Session, c: Checks, step: bool = False) -> None:
    """Four lift frames; start refused / accepted, wrap with I0.7 = 1, I0.7 dropped in frame 2."""
    op = Mp9cOp.begin(s, c)
    frames = [DOWN, UP, DOWN, UP]
    teach(op, frames)
    enable_flow(step_mode(op) if step else op, frames, lambda: refused_start(op),
                ("frame 2 (second cycle)", "frame {k} (I0.7 dropped to 0 at t = {dropped:.2f} s)"))


def sc_enable_step(s: Session, c: Checks) -> None:
    """Task 3 in step mode (SA6 = 1)."""
    sc_enable(s, c, step=True)


def sc_last_pause(s: Session, c: Checks, step: bool = False) -> None:
    """Four lift frames; I0.7 switched to 0 inside the last frame's pause."""
    op = Mp9cOp.begin(s, c)
    frames = [DOWN, UP, DOWN, UP]
    teach(op, frames)
    last_pause_flow(step_mode(op) if step else op, frames)


def sc_last_pause_step(s: Session, c: Checks) -> None:
    """The last pause in step mode (SA6 = 1)."""
    sc_last_pause(s, c, step=True)


TASK3 = task3_requirements("I0.7", remaining="frames 3 and 4", stops="execution stops there",
                           restarts="by itself or on a press with I0.7 = 0",
                           modes=", in continuous and in step mode")


# --------------------------------------------------------------------------- registration

register_tasks(STAND, {
    "task1": (TASK1, (Scenario("manual", sc_manual), Scenario("playback", sc_playback),
                      Scenario("playback_step", sc_playback_step, repeats="playback"))),
    "task2": (TASK2, (Scenario("pauses", sc_pauses), Scenario("pauses_step", sc_pauses_step, repeats="pauses"))),
    "task3": (TASK3, (Scenario("enable", sc_enable), Scenario("enable_step", sc_enable_step, repeats="enable"),
                      Scenario("last_pause", sc_last_pause),
                      Scenario("last_pause_step", sc_last_pause_step, repeats="last_pause"))),
}, GENERAL, GENERAL_SCENARIOS, make_session, every=(no_fault, no_conflict))
