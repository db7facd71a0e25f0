"""TUR-10 requirement sets: Tasks 1-3 of the positional robot lab (docs/tur10.md), judged by I/O alone.

Every scenario runs the student's program on a fresh robot and console, in virtual time, and
looks only at the located I/O by their console and wiring labels (SA1_FWD..SA5_BWD, SA6, SB1,
SA7, I15, BUS1..BUS15, RE1..RE5, HL1, DRIVE1..DRIVE5). Where the links are, the grader knows
from its own plant: the true link positions are recorded into the trace as `plant.pos1` ..
`plant.pos5` (sensor codes), so the trace files show them next to the references. A frame is
what the grader taught: the link positions at the moment it pressed SB1. In automatic mode a
frame starts with the first nonzero speed reference and is reached when every reference is
back to 0 with every link within the admissible error (16 codes) of its recorded position;
the pause after it lasts until the next nonzero reference. Times are compared with a
tolerance of one scan of the student's slowest task (plus the 50 ms debounce where an SB1
press is involved).

Requirements T1.x, T2.x, T3.x are the task's own; G1..G11 are the baseline behaviour every
solution must keep (Appendix 2), checked with drive 1 (the shoulder) alone so that they hold
for every task: Tasks 1-3 regulate drive 1 only in automatic mode.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional

from plclab.plants.base import signed16
from plclab.plants.tur10 import Tur10
from plclab.scenario import ScenarioFailure, Session
from plclab.stands.exploration import TUR10_RULES
from plclab.stands.tur10 import STAND, labels
from plclab.trace import Trace

from .common import (DEBOUNCE, EPS, NEXT_WAIT, NO_FAULT, FrameRun, Op, basics_flow, enable_flow, lag_words,
                     lamp_requirements, last_pause_flow, no_fault, pauses_flow, register_tasks, restart_flow,
                     task2_requirements, task3_requirements)
from .registry import EVERY, Checks, Requirement, Scenario

AXES = (1, 2, 3, 4, 5)
DRIVES = tuple(f"DRIVE{k}" for k in AXES)
ENABLES = tuple(f"RE{k}" for k in AXES)          # read enable of sensor k, active low
POS = tuple(f"plant.pos{k}" for k in AXES)        # true link positions (grader's plant), codes

LOW = 500                # manual reference at low speed (SA6 = 1)
NORMAL = 1500            # manual reference at normal speed (SA6 = 0)
REF_LIMIT = 1500         # beyond this the DAC overvolts the drive
ADMISSIBLE = 16          # codes: a frame is reached when every link is this close
FRAME_TIMEOUT = 20.0     # a frame not reached in this time stops execution
TIMEOUT_TOL = 0.1        # s: on 20 s, more than one scan (the watchdog may start a scan late)
HOLD = 0.4               # s a jog button is held in the Task 1 checks
SETTLE = 0.3             # s for a link to stop after its reference went to 0 (lag 50 ms)
TRAVEL = 0.3             # +/- share of the expected jog distance a link may miss
STILL = 2                # codes a link not driven may drift
READ_WINDOW = 1.0        # s in which every sensor must be selected alone (Task 1)
LATE_LOOK = 8.0          # s: how much longer a missed frame start is looked for, to measure it
DONE_WAIT = 5.0          # a frame is reached within this after it started (longest ~1.7 s)
QUIET = 2.0              # "nothing happens": every reference 0 for this long
STEP = 0.1               # s the grader runs on between looks at the trace while it waits


# --------------------------------------------------------------------------- the stand

_OFF = (None,) * len(Tur10.outputs)      # the outputs of a PLC switched off (a restart)


class TracedTur10(Tur10):
    """The TUR-10 plant recording each link's true position (code) into a trace.

    The grader owns the plant, so where the links really are is part of what it observes;
    the student's program only sees the sensor bus."""

    def __init__(self, **params: Any) -> None:
        super().__init__(**params)
        self.trace: Optional[Trace] = None
        self.clock: Callable[[], float] = lambda: self.time
        self._codes: tuple[int, ...] = ()          # the codes last recorded, AXES order
        self._recorded = -1                        # state_changes when they were worked out

    def attach(self, trace: Trace, clock: Callable[[], float]) -> None:
        """Record into `trace`, stamped with `clock()` (the time of the scan the step precedes)."""
        self.trace, self.clock = trace, clock
        for k, name in zip(AXES, POS):
            trace.declare(name, "int", self.true_code(k), 0, width=16)
        self._codes = self.true_codes()

    def true_code(self, k: int) -> int:
        return min(max(math.floor(self.drives[k].position), 0), 0x7FFF)

    def true_codes(self) -> tuple[int, ...]:
        """true_code of every link, AXES order."""
        return tuple([min(max(math.floor(d.position), 0), 0x7FFF) for d in self.drives.values()])

    def step_values(self, outputs: tuple[Any, ...], dt: float) -> tuple[int, ...]:
        inputs = super().step_values(outputs, dt)
        if self.trace is not None and outputs != _OFF and self.state_changes != self._recorded:
            # (no outputs: the PLC is off, a restart; no change of a link: nothing to record)
            self._recorded = self.state_changes
            codes = self.true_codes()
            if codes != self._codes:                # links at rest (most scans): nothing to record
                t_ns = round(self.clock() * 1e6) * 1000
                for name, code, last in zip(POS, codes, self._codes):
                    if code != last:
                        self.trace.change(t_ns, name, code)
                self._codes = codes
        return inputs


def make_session(sources: list[tuple[str, str]], retain_path: Optional[Path], checked: Any = None) -> Session:
    plant = TracedTur10()
    s = Session(sources, plant, labels(), watch=(), retain_path=retain_path, name="tur10 program",
                checked=checked)
    plant.attach(s.trace, lambda: s.now)
    return s


# --------------------------------------------------------------------------- reading the I/O

def ref(st: Any, k: int) -> int:
    """DRIVEk as the signed reference the PLC wrote (from a trace state or live)."""
    return signed16(int(st[DRIVES[k - 1]]))


def moving(st: Any) -> bool:
    return any(ref(st, k) != 0 for k in AXES)


def still(st: Any) -> bool:
    return not moving(st)


def fmt_ref(v: int) -> str:
    return f"{v:+d}" if v else "0"


def fmt_refs(refs: dict[int, int]) -> str:
    return " ".join(f"DRIVE{k}={fmt_ref(v)}" for k, v in refs.items())


@dataclass(frozen=True)
class Frame:
    """A frame as the grader records it: the five link positions when SB1 was pressed, and
    I1.5 at that moment."""

    codes: tuple[int, ...]
    i15: int = 0

    def reached(self, st: Any) -> bool:
        return still(st) and all(abs(st[POS[k - 1]] - self.codes[k - 1]) <= ADMISSIBLE for k in AXES)

    def where(self, axes: tuple[int, ...] = (1,)) -> str:
        return ", ".join(f"link {k} at {self.codes[k - 1]}" for k in axes)


# --------------------------------------------------------------------------- the operator

@dataclass
class Tur10Op(Op[Frame]):
    """The operator of the positional robot: a frame starts with the first nonzero speed
    reference and is reached when every reference is back to 0 with every link within 16
    codes of it. The timing tolerance is one scan of the student's slowest task."""

    taught: list[Frame] = field(default_factory=list)   # in order: a missed frame is compared with them

    auto = "SA7"
    enable = "I15"
    enable_label = "I1.5"
    wind_down = 0.5
    press_window = "50 ms debounce + one scan"
    started = "its first nonzero reference came"
    watchdog = "G11"
    frame_timeout = FRAME_TIMEOUT
    timeout_tol = f"+/- {TIMEOUT_TOL:g} s + one scan"
    rules = TUR10_RULES

    @property
    def scan(self) -> float:
        """The student's slowest task interval (one scan of it is the timing tolerance)."""
        intervals = [i.interval_ns for i in self.s.plc.instances if i.interval_ns]
        return (max(intervals) if intervals else self.s.plc.tick_ns) / 1e9

    @property
    def plant(self) -> TracedTur10:
        return self.s.plant

    def start_manual(self) -> None:
        self.set(SA7=0, SA6=0, I15=0)
        self.run(0.2)

    def refs(self, at: Optional[float] = None) -> dict[int, int]:
        st = self.s.io if at is None else self.s.trace.state_at(at)
        return {k: ref(st, k) for k in AXES}

    def ref(self, k: int, at: float) -> int:
        return signed16(int(self.s.trace.value_at(DRIVES[k - 1], at)))

    def positions(self) -> dict[int, int]:
        return {k: self.plant.true_code(k) for k in AXES}

    def when(self, cond: Callable[[Any], Any], after: float, timeout: float) -> Optional[float]:
        """The first time at or after `after` when `cond` (over a trace state) holds, from the
        trace and then running on in steps of STEP s (the session may end up to one step past
        the time returned); None if not by `after + timeout`."""
        end = after + timeout
        looked = after
        tr = self.s.trace
        while True:
            t = tr.first(cond, after=looked, until=end, default=None)
            if t is not None:
                return t
            if tr.end_s >= end - EPS:
                return None
            looked = max(looked, tr.end_s)
            self.run(min(STEP, end - tr.end_s))

    def wait(self, cond: Callable[[Any], Any], timeout: float) -> Optional[float]:
        """`when`, from now."""
        return self.when(cond, after=self.now, timeout=timeout)

    def motion(self, after: float, until: float) -> Optional[float]:
        """The first nonzero reference in [after, until] (from the trace)."""
        return self.s.trace.first(moving, after=after, until=until, default=None)

    def what_moved(self, t: float) -> str:
        """The references at `t`."""
        return fmt_refs(self.refs(at=t))

    def record(self, i15: Optional[int] = None) -> Frame:
        """Record a frame with a short SB1 press (I1.5 set first if given)."""
        if i15 is not None:
            self.set(I15=i15)
        frame = Frame(tuple(self.positions().values()), int(self.s.plant.console["I15"]))
        self.press(0.2)
        self.run(0.2)
        self.taught.append(frame)
        return frame

    def jog_to(self, axis: int, code: int, timeout: float = 3.0) -> None:
        """Hold drive `axis`'s forward or backward button (SA6 = 0) until the link passes `code`,
        then let it stop: the frames taught do not depend on the jog speed."""
        direction = 1 if code > self.plant.true_code(axis) else -1
        button = f"SA{axis}_{'FWD' if direction > 0 else 'BWD'}"
        start = self.set(SA6=0, **{button: 1})
        while (self.plant.true_code(axis) - code) * direction < 0 and self.now < start + timeout:
            self.run(self.s.tick)
        self.set(**{button: 0})
        self.run(0.4)
        if (self.plant.true_code(axis) - code) * direction < 0:
            raise ScenarioFailure(f"t={start:.2f} s: {button} held {timeout:g} s did not bring link {axis} "
                                  f"to {code} (it is at {self.plant.true_code(axis)}): the frames cannot "
                                  "be taught")

    def follow(self, rid: str, frame: Frame, label: str, since: float, timeout: float,
               on_start: Optional[Callable[[], object]] = None) -> Optional[FrameRun]:
        """The next nonzero reference starts `frame`; it is reached when every reference is back
        to 0 with the links at its positions."""
        start = self.when(moving, after=since, timeout=timeout)
        if start is None:
            pos = self.positions()
            # how long the references really stayed 0: a pause too long is measured, not only missed
            later = self.when(moving, after=since, timeout=timeout + LATE_LOOK)
            waited = (f"; the next nonzero reference came at t = {later:.2f} s, {later - since:.2f} s after "
                      f"t = {since:.2f} s" if later is not None else
                      f"; still none {timeout + LATE_LOOK:g} s after t = {since:.2f} s")
            self.missed(rid, f"{label} starts within {timeout:g} s of t = {since:.2f} s (a nonzero reference "
                        f"towards {frame.where()})", f"every reference stayed 0 (link 1 at {pos[1]}){waited}", since)
            return None
        if on_start is not None:
            on_start()
        expected = (f"{label} reached within {DONE_WAIT:g} s: {frame.where()} (+/- {ADMISSIBLE} codes), every "
                    "reference back to 0")
        stop = self.when(still, after=start, timeout=DONE_WAIT)
        if stop is not None and not frame.reached(self.s.trace.state_at(stop)) and self.stays_still(stop):
            if not self.fault_explains(rid, expected, f"every reference 0 at t = {stop:.2f} s", start):
                self.c.fail(rid, f"{label}: every reference back to 0 only once every link is within "
                            f"{ADMISSIBLE} codes of the frame ({frame.where()})", self.stopped_short(frame, stop),
                            stop)
            return None
        done = self.when(frame.reached, after=start, timeout=DONE_WAIT)
        if done is None:
            if not self.fault_explains(rid, expected, self.explain_miss(frame, start), start):
                self.c.fail(rid, expected, self.explain_miss(frame, start), start)
            return None
        return self.ran(FrameRun(start, done))

    def stays_still(self, t: float) -> bool:
        """Every reference stays 0 for a while from `t` (more than a zero crossing)."""
        return self.when(moving, after=t + EPS, timeout=SETTLE) is None

    def stopped_short(self, frame: Frame, t: float) -> str:
        """Where the links were when every reference went to 0 at `t`, short of `frame`."""
        tr = self.s.trace
        at = tr.state_at(t)
        later = tr.state_at(t + SETTLE)
        off = [k for k in AXES if abs(at[POS[k - 1]] - frame.codes[k - 1]) > ADMISSIBLE]
        where = ", ".join(f"link {k} at {at[POS[k - 1]]} ({at[POS[k - 1]] - frame.codes[k - 1]:+d} codes from "
                          f"the target, beyond the admissible {ADMISSIBLE})" for k in off)
        moving_links = [k for k in AXES if abs(later[POS[k - 1]] - at[POS[k - 1]]) > STILL]
        if moving_links:
            k = moving_links[0]
            where += f"; the link was still moving (link {k} at {later[POS[k - 1]]} {SETTLE:g} s later)"
        return f"every reference 0 at t = {t:.2f} s with {where}"

    def explain_miss(self, frame: Frame, start: float) -> str:
        """Why `frame` was not reached: where the links are and what the references did."""
        tr = self.s.trace
        pos = self.positions()
        off = [k for k in AXES if abs(pos[k] - frame.codes[k - 1]) > ADMISSIBLE]
        where = ", ".join(f"link {k} at {pos[k]} ({pos[k] - frame.codes[k - 1]:+d} from the target)"
                          for k in off) or "every link within 16 codes"
        for j, other in enumerate(self.taught, 1):
            if other is not frame and off and all(abs(pos[k] - other.codes[k - 1]) <= ADMISSIBLE for k in AXES):
                where += f" = the position of frame {j}"
                break
        refs = self.refs()
        if any(refs.values()):
            return f"after {self.now - start:.2f} s: {where}; {fmt_refs(refs)}"
        zero = tr.first(still, after=start, default=None)
        since = start
        while zero is not None:          # the start of the last stretch of zero references
            nxt = tr.first(moving, after=zero, default=None)
            if nxt is None:
                since = zero
                break
            zero = tr.first(still, after=nxt, default=None)
        return f"every reference 0 from t = {since:.2f} s with {where}"


def teach_two(op: Tur10Op, first_i15: Optional[int] = None,
              second_i15: Optional[int] = None) -> tuple[Frame, Frame]:
    """Two frames of drive 1: where it is (16000), then 3000 codes forward (I1.5 set first if
    given)."""
    f1 = op.record(i15=first_i15)
    op.jog_to(1, f1.codes[0] + 3000)
    return f1, op.record(i15=second_i15)


def teach_three(op: Tur10Op, i15: tuple[Optional[int], ...] = (None, None, None)) -> list[Frame]:
    """Three frames of drive 1: where it is (16000), 3000 codes forward, 1000 back (I1.5 set
    first where `i15` gives it)."""
    f1, f2 = teach_two(op, i15[0], i15[1])
    op.jog_to(1, f2.codes[0] - 1000)
    return [f1, f2, op.record(i15=i15[2])]


# --------------------------------------------------------------------------- every scenario

def no_overvoltage(s: Session, c: Checks) -> None:
    with c.requirement(G2) as rid:
        t = s.trace.first(lambda st: any(abs(ref(st, k)) > REF_LIMIT for k in AXES), default=None)
        if t is not None:
            st = s.trace.state_at(t)
            bad = {k: ref(st, k) for k in AXES if abs(ref(st, k)) > REF_LIMIT}
            c.fail(rid, f"|DRIVE1..DRIVE5| <= {REF_LIMIT} always", f"{fmt_refs(bad)}: overvoltage, the drive trips",
                   t)


def no_contention(s: Session, c: Checks) -> None:
    with c.requirement(G3) as rid:
        t = s.trace.first_values(ENABLES, lambda enables: sum(not e for e in enables) >= 2, default=None)
        if t is not None:
            off = [e for e in ENABLES if not s.trace.value_at(e, t)]
            c.fail(rid, "at most one read enable OFF at a time (one sensor on the bus)",
                   f"{' and '.join(off)} OFF together: sensors {', '.join(e[2:] for e in off)} drive the bus "
                   "at once", t)


def no_collision(s: Session, c: Checks) -> None:
    with c.requirement(G4) as rid:
        hits = [e for e in s.plant.events if e.kind == "collision"]
        if hits:
            c.fail(rid, "no link driven into a mechanical stop", hits[0].detail, hits[0].time)


# --------------------------------------------------------------------------- general (G5..G11)

def record_here(op: Tur10Op) -> float:
    """Record a frame where the links are; returns the SB1 release (`record` runs 0.2 s on)."""
    op.record()
    return op.now - 0.2


def record_further(op: Tur10Op) -> None:
    """Jog link 1 1500 codes forward and record a frame there."""
    op.jog_to(1, op.plant.true_code(1) + 1500)
    op.record()


def sc_basics(s: Session, c: Checks) -> None:
    """Empty-program lamp, bounce, long-press reset (manual mode, drive 1 only)."""
    op = Tur10Op.begin(s, c)
    basics_flow(op, ("G5", "G6", "G7"), record=lambda: record_here(op),
                record_another=lambda: record_further(op))


def sc_automatic(s: Session, c: Checks) -> None:
    """Three frames of drive 1 played continuously, wrapped, stopped and started again."""
    op = Tur10Op.begin(s, c)
    f1, f2, f3 = teach_three(op)
    with c.requirement(G8) as rid:
        entered = op.start_auto()
        op.run(0.7)
        if not op.quiet(rid, entered, 1.0, "every reference stays 0 on entering automatic mode (SA7 := 1), "
                        "before any SB1 press", "in automatic mode, before any SB1 press"):
            return
        r1 = op.press_starts(rid, f1, "frame 1", op.press())
        r2 = r1 and op.follow(rid, f2, "frame 2 after frame 1", r1.done, NEXT_WAIT)
        r3 = r2 and op.follow(rid, f3, "frame 3 after frame 2", r2.done, NEXT_WAIT)
        r4 = r3 and op.follow(rid, f1, "frame 1 after frame 3 (the last)", r3.done, NEXT_WAIT)
        if not r4:
            return
    stops_on_press(op, f1, r4.done)


def stops_on_press(op: Tur10Op, f1: Frame, done: float) -> None:
    """G9: an SB1 press 0.2 s into frame 2 of the second cycle (which follows the frame done at
    `done`) stops playback; the next press starts frame 1 (and one more stops it again)."""
    c = op.c
    with c.requirement(G9) as rid:
        start = op.when(moving, after=done, timeout=NEXT_WAIT)
        if start is None:
            c.fail(rid, "frame 2 (second cycle) starts", "every reference stayed 0", done)
            return
        op.run(0.2)
        pressed = op.press(0.1)
        settled = pressed + DEBOUNCE + op.tol + op.lag
        op.run_until(settled + op.tol)
        refs = op.refs(at=settled)
        if not c.check(rid, not any(refs.values()), f"every reference 0 within {DEBOUNCE * 1000:.0f} ms + "
                       f"one scan ({op.scan * 1000:.0f} ms{lag_words(op)}) of the stop press (SB1 at t = "
                       f"{pressed:.2f} s during frame 2)", fmt_refs(refs), settled):
            return
        if not op.quiet(rid, settled, QUIET, "every reference stays 0 after the stop", "execution went on"):
            return
        op.press_starts(rid, f1, "frame 1 (SB1 pressed again after the stop)", op.press())
    op.stop_playback()


def sc_restart(s: Session, c: Checks) -> None:
    """The recorded program survives a PLC restart."""
    op = Tur10Op.begin(s, c)
    f1, f2 = teach_two(op)
    if restart_flow(op, G10.id, f1, f2, off_time=1.0, lamp="G5"):
        op.stop_playback()


def sc_timeout(s: Session, c: Checks) -> None:
    """A dead sensor 1 (stuck 30 codes past frame 1): the frame times out after 20 s."""
    op = Tur10Op.begin(s, c)
    f1, _ = teach_two(op)
    s.inject("dead_sensor", axis=1, value=f1.codes[0] + 30)
    op.start_auto()
    with c.requirement(G11) as rid:
        pressed = op.press()
        start = op.when(moving, after=pressed, timeout=DEBOUNCE + 1.0)
        if start is None:
            c.fail(rid, "frame 1 starts on the SB1 press", "every reference stayed 0", pressed)
            return
        stop = op.when(still, after=start, timeout=FRAME_TIMEOUT + 2.0)
        if not c.check(rid, stop is not None and abs(stop - start - FRAME_TIMEOUT) <= TIMEOUT_TOL + op.tol,
                       f"every reference 0 {FRAME_TIMEOUT:g} s (+/- {TIMEOUT_TOL:g} s + one scan) after frame 1 "
                       "started (the dead sensor keeps it from being reached)",
                       f"references still nonzero after {FRAME_TIMEOUT + 2:g} s" if stop is None else
                       f"every reference 0 {stop - start:.2f} s after the start", stop or start + FRAME_TIMEOUT):
            return
        op.run_until(stop + 2.0)
        blinks = s.trace.edges("HL1", "any", after=stop, until=stop + 2.0)
        if not c.check(rid, len(blinks) >= 2, "HL1 blinks after the timeout",
                       f"HL1 changed {len(blinks)} time(s) in 2 s", stop):
            return
        op.quiet(rid, stop + op.tol, QUIET + 1.0, "execution stays stopped after the timeout "
                 "(every reference 0)", "a reference came back")
    s.clear_faults()
    op.back_to_manual()


G2 = Requirement("G2", f"Never an overvoltage: no speed reference DRIVE1..DRIVE5 beyond +/-{REF_LIMIT} (a "
                 "larger DAC code damages the drive).", EVERY)
G3 = Requirement("G3", "Never a bus contention: at most one read enable RE1..RE5 is OFF at a time (one sensor on "
                 "the bus).", EVERY)
G4 = Requirement("G4", "Never a collision: no link is driven into a mechanical stop.", EVERY)
G8 = Requirement("G8", "Automatic mode (SA7 = 1): entering it moves nothing; an SB1 press starts frame 1; each "
                 f"frame brings the links to within {ADMISSIBLE} codes of the recorded positions with every "
                 "reference back to 0; the frames follow in order and frame 1 follows the last.", "automatic")
G9 = Requirement("G9", f"An SB1 press during playback stops it: every reference 0 (after the {DEBOUNCE * 1000:.0f} "
                 "ms debounce) and nothing moves; the next press starts again from frame 1.", "automatic")
G10 = Requirement("G10", "The recorded program survives a PLC restart (HL1 stays OFF and the frames play back).",
                  "restart")
G11 = Requirement("G11", f"A frame not reached within {FRAME_TIMEOUT:g} s (dead position sensor) stops "
                  "execution: every reference 0, HL1 blinks, nothing restarts by itself.", "timeout")
GENERAL = (NO_FAULT, G2, G3, G4, *lamp_requirements("G5", "G6", "G7"), G8, G9, G10, G11)
GENERAL_SCENARIOS = (
    Scenario("basics", sc_basics), Scenario("automatic", sc_automatic),
    Scenario("restart", sc_restart, needs_retain=True), Scenario("timeout", sc_timeout),
)


# --------------------------------------------------------------------------- Task 1

def selected_alone(k: int) -> Callable[[Any], bool]:
    return lambda st: not st[ENABLES[k - 1]] and all(st[e] for e in ENABLES if e != ENABLES[k - 1])


def sensors_read(op: Tur10Op, rid: str, after: float, until: float) -> bool:
    """Every sensor selected alone at least once in [after, until]."""
    tr = op.s.trace
    for k in AXES:
        if tr.first(selected_alone(k), after=after, until=until, default=None) is not None:
            continue
        enable = ENABLES[k - 1]
        off = tr.first(lambda st, e=enable: not st[e], after=after, until=until, default=None)
        if off is None:
            seen = f"{enable} stayed ON: sensor {k} is never read"
        else:
            others = [e for e in ENABLES if e != enable and not tr.value_at(e, off)]
            seen = f"{enable} is OFF only together with {' and '.join(others)} (t = {off:.2f} s)"
        op.c.fail(rid, f"sensor {k} selected alone ({enable} OFF, the other enables ON) at least once "
                  f"between t = {after:.2f} s and {until:.2f} s", seen, off if off is not None else after)
        return False
    return True


def jog_check(op: Tur10Op, k: int, direction: int, low: bool) -> None:
    """Hold one button of drive k: its reference, its motion, the other drives, the release."""
    c = op.c
    rid = "T1.1" if low else "T1.2"
    want = direction * (LOW if low else NORMAL)
    button = f"SA{k}_{'FWD' if direction > 0 else 'BWD'}"
    what = f"{button} held with SA6 = {int(low)}"
    before = op.positions()
    t = op.set(**{button: 1})
    op.run(HOLD)
    released = op.set(**{button: 0})
    op.run(SETTLE)
    after = op.positions()
    got = op.ref(k, t + op.tol)
    if c.check(rid, got == want, f"{what}: DRIVE{k} = {fmt_ref(want)} within one scan",
               f"DRIVE{k} = {fmt_ref(got)}" + (f" (drive {k} is not jogged)" if got == 0 else ""), t):
        change = op.s.trace.next_change(DRIVES[k - 1], after=t + op.tol + EPS, until=released - EPS,
                                        default=None)
        if change is not None:
            c.fail(rid, f"{what}: DRIVE{k} stays {fmt_ref(want)} while the button is held",
                   f"DRIVE{k} = {fmt_ref(op.ref(k, change))}", change)
        expected = want * op.plant.gain * HOLD
        moved = after[k] - before[k]
        c.check(rid, abs(moved - expected) <= TRAVEL * abs(expected),
                f"{what}: link {k} moves about {expected:+.0f} codes in {HOLD:g} s (+/- {TRAVEL:.0%})",
                f"link {k} moved {moved:+d} codes", t)
    others = [j for j in AXES if j != k]
    other_ref = op.s.trace.first(lambda st: any(ref(st, j) for j in others), after=t,
                                 until=released + op.tol, default=None)
    if other_ref is not None:
        refs = op.refs(at=other_ref)
        c.fail("T1.4", f"{what}: the other four references stay 0",
               fmt_refs({j: refs[j] for j in others if refs[j]}), other_ref)
    drifted = {j: after[j] - before[j] for j in others if abs(after[j] - before[j]) > STILL}
    if drifted:
        c.fail("T1.4", f"{what}: only link {k} moves",
               ", ".join(f"link {j} moved {d:+d} codes" for j, d in drifted.items()), t)
    zero = op.ref(k, released + op.tol)
    c.check("T1.3", zero == 0, f"{button} released: DRIVE{k} = 0 within one scan",
            f"DRIVE{k} = {fmt_ref(zero)}", released)


def both_check(op: Tur10Op, k: int) -> None:
    """Both buttons of drive k held: reference 0, the link stands still."""
    fwd, bwd = f"SA{k}_FWD", f"SA{k}_BWD"
    op.set(SA6=0)
    before = op.positions()
    t = op.set(**{fwd: 1, bwd: 1})
    op.run(HOLD)
    released = op.set(**{fwd: 0, bwd: 0})
    op.run(SETTLE)
    moved = op.positions()[k] - before[k]
    nonzero = op.s.trace.first(lambda st: ref(st, k) != 0, after=t, until=released + op.tol, default=None)
    if nonzero is not None:
        op.c.fail("T1.3", f"{fwd} and {bwd} held together: DRIVE{k} stays 0",
                  f"DRIVE{k} = {fmt_ref(op.ref(k, nonzero))}, link {k} moved {moved:+d} codes", nonzero)
    elif abs(moved) > STILL:
        op.c.fail("T1.3", f"{fwd} and {bwd} held together: link {k} stands still",
                  f"link {k} moved {moved:+d} codes", t)


def sc_jog(s: Session, c: Checks) -> None:
    """Every drive jogged both ways at both speeds, then with both buttons."""
    op = Tur10Op.begin(s, c)
    with c.requirement("T1.1", "T1.2", "T1.3", "T1.4", "T1.5"):
        op.run(READ_WINDOW)
        refs = op.refs()
        c.check("T1.3", not any(refs.values()), "every reference 0 in manual mode with no button held",
                fmt_refs(refs), op.now)
        first_window = sensors_read(op, "T1.5", op.now - READ_WINDOW, op.now)
        for k in AXES:
            for low in (True, False):
                op.set(SA6=int(low))
                op.run(0.1)
                jog_check(op, k, +1, low)
                jog_check(op, k, -1, low)
            both_check(op, k)
        op.run(READ_WINDOW)
        if first_window:                 # the first window's miss is T1.5's failure already
            sensors_read(op, "T1.5", op.now - READ_WINDOW, op.now)


TASK1 = (
    Requirement("T1.1", "Manual mode (SA7 = 0), low speed (SA6 = 1): holding SAk forward gives drive k "
                f"the reference +{LOW}, backward -{LOW} (within one scan), for each of the five drives, and "
                "the link moves that way.", "jog"),
    Requirement("T1.2", f"Manual mode, normal speed (SA6 = 0): holding SAk forward gives drive k +{NORMAL}, "
                f"backward -{NORMAL}, for each of the five drives, and the link moves that way.", "jog"),
    Requirement("T1.3", "With no button, or with both buttons of a drive held, its reference is 0 and "
                "its link stands still.", "jog"),
    Requirement("T1.4", "Only the jogged drive moves: while one drive's button is held the other four "
                "references stay 0 and their links stand still.", "jog"),
    Requirement("T1.5", "Manual mode reads the position sensors round-robin, one at a time: each read "
                "enable RE1..RE5 is driven OFF alone (the others ON) at least once a second.", "jog"),
)


# --------------------------------------------------------------------------- Task 2

PAUSE_PATTERN = (1, 0, 0)        # I1.5 when each frame is recorded: 3 s, 0.5 s, 0.5 s


def sc_pauses(s: Session, c: Checks) -> None:
    """Three frames with the pauses 3, 0.5, 0.5 s (swapped, next-frame and previous-frame
    pauses all differ); a cycle with I1.5 = 1, then cycles with I1.5 switched at every phase
    boundary, longer than the frame watchdog."""
    op = Tur10Op.begin(s, c)
    pauses_flow(op, teach_three(op, PAUSE_PATTERN), PAUSE_PATTERN)


TASK2 = task2_requirements("I1.5", "from the frame being reached, every reference back to 0 with the links "
                           "within 16 codes, to the next frame's first nonzero reference")


# --------------------------------------------------------------------------- Task 3

def refused_start(op: Tur10Op) -> None:
    """T3.1: an SB1 press with I1.5 = 0 starts nothing (no nonzero reference). A program that
    starts is stopped in manual mode before the enabled start."""
    with op.c.requirement("T3.1") as rid:
        pressed = op.press(0.1)
        started = op.when(moving, after=pressed, timeout=QUIET)
        if started is None:
            return
        op.c.fail(rid, "an SB1 press with I1.5 = 0 starts nothing",
                  f"the program started: {fmt_refs(op.refs(at=started))} {started - pressed:.2f} s after the "
                  "press", started)
    op.run(0.1)                         # the release is seen in automatic mode (no record)
    op.set(SA7=0)                       # manual mode stops it
    op.run(0.5)
    op.start_auto(enable=0)


def sc_enable(s: Session, c: Checks) -> None:
    """Three frames; start refused / accepted, wrap with I1.5 = 1, I1.5 dropped in frame 2."""
    op = Tur10Op.begin(s, c)
    enable_flow(op, teach_three(op), lambda: refused_start(op),
                ("frame 2 (second cycle; I1.5 dropped to 0 as it starts)",
                 "frame {k} (the last; I1.5 dropped to 0 at t = {dropped:.2f} s)"))


def sc_last_pause(s: Session, c: Checks) -> None:
    """Three frames; I1.5 switched to 0 inside the last frame's pause."""
    op = Tur10Op.begin(s, c)
    last_pause_flow(op, teach_three(op))


TASK3 = task3_requirements("I1.5", remaining="frame 3 (the last)",
                           stops="execution stops there (every reference 0)",
                           restarts="by itself, on a press with I1.5 = 0 or on I1.5 = 1 alone")


# --------------------------------------------------------------------------- registration

register_tasks(STAND, {
    "task1": (TASK1, (Scenario("jog", sc_jog),)),
    "task2": (TASK2, (Scenario("pauses", sc_pauses),)),
    "task3": (TASK3, (Scenario("enable", sc_enable), Scenario("last_pause", sc_last_pause))),
}, GENERAL, GENERAL_SCENARIOS, make_session, every=(no_fault, no_overvoltage, no_contention, no_collision))
