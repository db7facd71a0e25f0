"""What the robot stands' requirement sets share (MP-9C, TUR-10): the operator, the frame
checks, the lamp/reset, restart, Task 2 and Task 3 flows, and registration.

Both labs teach a robot the same way: in manual mode a short SB1 press records a frame; in
automatic mode an SB1 press plays the frames back, frame 1 following the last, with a pause
after each frame chosen by an input at recording time (Task 2) that also gates the start
(Task 3); HL1 is ON while the program is empty and a long press empties it. What differs is
the robot: what a frame is, how its start and its end are seen, and the console's names.
A stand module supplies that as a subclass of `Op` (its hooks) and small callables that
teach frames; the flows here keep every requirement text and every failure message as each
stand words it, so that one flow judges both and a fix reaches both.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, Callable, ClassVar, Generic, Optional, Self, Sequence, TypeVar

from plclab.scenario import ScenarioFailure, Session
from plclab.stands import Stand
from plclab.stands.exploration import Rules

from .registry import EVERY, Checks, Requirement, RequirementSet, Scenario, SessionFactory, register

DEBOUNCE = 0.05          # SB1 closures shorter than this are contact bounce
LONG_PRESS = 3.0         # SB1 held this long resets the program
PAUSE_SHORT = 0.5        # Task 2: frame recorded with the pause input = 0
PAUSE_LONG = 3.0         # Task 2: frame recorded with the pause input = 1
NEXT_WAIT = PAUSE_LONG + 1.0   # the next frame starts within this after one is done
REFUSED = 2.0            # s watched for a start that must not happen
TAP_PERIOD = 0.1         # step mode: the grader taps SB1 this often to find when a pause ends
TAP_HOLD = 0.07          # s each tap is held (over the 50 ms debounce plus a scan)
BLINK_GAP = 1.0          # s: two HL1 changes this close while playing are a blinking HL1
EPS = 1e-6

F = TypeVar("F")         # a stand's frame, as its grader teaches it
Hook = Callable[[Session, Checks], None]   # a scenario's run, or a check after every scenario


@dataclass(frozen=True)
class FrameRun:
    """When a played-back frame started and when the stand showed it done (plant time, s)."""

    start: float      # the program first drove the robot towards the frame
    done: float       # the stand showed the frame reached


# --------------------------------------------------------------------------- the operator

@dataclass
class Op(ABC, Generic[F]):
    """The lab operator and observer on one session: console actions, waits, trace reads.
    A PLC fault stops the scenario (G1 reports it).

    A stand's subclass names its console (the class variables) and supplies the hooks that
    depend on what the robot is: `start_manual`, `wait`, `motion`, `what_moved`, `follow`.
    The shared checks (`press_starts`, `quiet`) and flows below see the robot only through
    them.
    """

    s: Session
    c: Checks
    runs: list[FrameRun] = field(default_factory=list)  # every frame seen played, in order
    step: bool = False             # step mode: the flows tap SB1 to go on to the next frame

    auto: ClassVar[str]            # the mode switch: 0 manual, 1 automatic
    enable: ClassVar[str]          # the pause / run-enable input by its console name ("I07")
    enable_label: ClassVar[str]    # ... and as the requirements write it ("I0.7")
    wind_down: ClassVar[float]     # s run on after a scenario's last step (the trace shows the stop)
    press_window: ClassVar[str]    # the start tolerance and ...
    started: ClassVar[str]         # ... how a start is seen, as the stand's failure messages word them
    watchdog: ClassVar[str]        # the frame-timeout requirement ("G10")
    frame_timeout: ClassVar[float]  # s a frame may take before the watchdog stops execution
    timeout_tol: ClassVar[str]     # its tolerance as rows print it ("+/- 0.1 s")
    rules: ClassVar[Rules]         # the stand's freedoms, shared with exploration (stands.exploration)

    @classmethod
    def begin(cls, s: Session, c: Checks) -> Self:
        """The operator of a fresh scenario, the stand put in manual mode first."""
        op = cls(s, c)
        op.start_manual()
        return op

    @property
    def now(self) -> float:
        return self.s.now

    @property
    def scan(self) -> float:
        """One scan of the student's program (the timing tolerance): the base tick."""
        return self.s.tick

    @property
    def tol(self) -> float:
        return self.scan + EPS

    @property
    def lag(self) -> float:
        """How much later than the model answer a program may be at one start, stop or pause
        (`Rules.lag_scans` scans), on top of a row's own one-scan tolerance."""
        return self.rules.lag_scans * self.scan

    def _fault(self) -> None:
        f = self.s.fault
        if f is not None:
            raise ScenarioFailure(str(f) if f.internal else "the PLC stopped with a runtime fault (see G1)")

    def set(self, **switches: int) -> float:
        """Set console switches now; returns the time they were set."""
        t = self.now
        self.s.console.set(**switches)
        return t

    def set_enable(self, value: int) -> float:
        return self.set(**{self.enable: value})

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

    def hl1(self, at: Optional[float] = None) -> int:
        """The program lamp now, or at time `at` from the trace."""
        v = self.s.io.HL1 if at is None else self.s.trace.value_at("HL1", at)
        return int(bool(v))

    def start_auto(self, enable: int = 1) -> float:
        """Automatic mode with the enable input as given; returns when the mode switch went to 1."""
        t = self.set(**{self.auto: 1, self.enable: enable})
        self.run(0.3)
        return t

    def back_to_manual(self) -> None:
        """A scenario's last step: manual mode, and the stand run on to show the stop."""
        self.set(**{self.auto: 0})
        self.run(self.wind_down)

    def stop_playback(self) -> None:
        """A scenario's last step: an SB1 press stops playback, and the stand runs on to show it."""
        self.press()
        self.run(self.wind_down)

    # ----------------------------------------------------------------- stand hooks

    @abstractmethod
    def start_manual(self) -> None:
        """Manual mode with every switch and the enable input at 0, seen by the program."""

    @abstractmethod
    def wait(self, cond: Callable[[Any], Any], timeout: float) -> Optional[float]:
        """Run on until `cond` holds: its time, or None after `timeout` s. `cond` reads the I/O
        by label (`x.HL1`)."""

    @abstractmethod
    def motion(self, after: float, until: float) -> Optional[float]:
        """The first time in [after, until] the program drives the robot (from the trace)."""

    @abstractmethod
    def what_moved(self, t: float) -> str:
        """What the program drove at `t` (a `motion` time), the words before the delay in a
        `quiet` failure."""

    @abstractmethod
    def follow(self, rid: str, frame: F, label: str, since: float, timeout: float,
               on_start: Optional[Callable[[], object]] = None) -> Optional[FrameRun]:
        """Expect the next motion at or after `since` (within `timeout`) to start `frame`, then
        the robot to reach it; `on_start` runs once it started. A failure is charged to `rid`."""

    # ----------------------------------------------------------------- shared checks

    @property
    def mode(self) -> str:
        """How the rows name the playback mode: '' (continuous) or 'step mode: '."""
        return "step mode: " if self.step else ""

    def ran(self, run: FrameRun) -> FrameRun:
        """Note a frame seen played (for the story of a fault stop); returns it."""
        self.runs.append(run)
        return run

    def fault_blink(self, after: float) -> Optional[float]:
        """When HL1 began blinking at or after `after` (two changes less than 1 s apart, which
        while playing back only a fault stop does), or None."""
        edges = self.s.trace.edges("HL1", "any", after=after, until=self.now)
        return next((a for a, b in zip(edges, edges[1:]) if b - a <= BLINK_GAP), None)

    def missed(self, rid: str, expected: str, observed: str, since: float) -> None:
        """`rid` fails: the frame expected after `since` did not come. If the program had
        stopped with a fault (HL1 blinking), the row says so and the watchdog requirement gets
        the fault's story, so a fault stop is never taken for the task's input mistake."""
        if not self.fault_explains(rid, expected, observed, since):
            self.c.fail(rid, expected, observed, since)

    def fault_explains(self, rid: str, expected: str, observed: str, since: float) -> bool:
        """If the program stopped with a fault (HL1 blinking) since the last frame started or
        `since`: `rid` fails saying so, the watchdog requirement gets the story; True."""
        look = min([since] + [r.start for r in self.runs[-1:]])
        self.run_until(max(self.now, since + BLINK_GAP + 0.2))
        blink = self.fault_blink(look)
        if blink is None:
            return False
        self.c.fail(rid, expected, f"{observed}: execution had stopped with a fault at t = {blink:.2f} s "
                    f"(HL1 blinking; see {self.watchdog})", blink)
        self.fault_story(blink)
        return True

    def fault_story(self, blink: float) -> None:
        """The watchdog requirement fails with what the fault stop at `blink` interrupted:
        the frame in progress, how long frames took, how long playback had run."""
        w = self.frame_timeout
        runs = [r for r in self.runs if r.start <= blink]
        chain = runs[-1:]
        for r in reversed(runs[:-1]):       # the run of frames played one after the other
            if chain[0].start - r.done > NEXT_WAIT + 0.5:
                break
            chain.insert(0, r)
        seen = [f"a fault stop (HL1 blinking) at t = {blink:.2f} s"]
        if chain:
            last, began = chain[-1], chain[0].start
            longest = max(r.done - r.start for r in chain)
            seen.append(f"{blink - last.start:.2f} s after the last frame started at t = {last.start:.2f} s "
                        f"(every frame was reached within {longest:.2f} s)")
            seen.append(f"{blink - began:.2f} s after playback began at t = {began:.2f} s")
            if abs(blink - began - w) <= 0.5 and blink - last.start < w - 0.5:
                seen.append(f"the watchdog timed the whole run ({w:g} s from the start), not each frame")
        self.c.fail(self.watchdog, f"no fault stop while every frame is reached in time: the watchdog times "
                    f"each frame, {w:g} s from its start ({self.timeout_tol})", "; ".join(seen), blink)

    def advance(self, rid: str, frame: F, label: str, since: float,
                on_start: Optional[Callable[[], object]] = None) -> Optional[FrameRun]:
        """The next frame after the one done at `since`: in continuous mode it follows by
        itself; in step mode the grader taps SB1 every 0.1 s from `since` until it starts
        (presses during the pause are ignored), so the pause is measured to 0.1 s."""
        if self.step:
            self.tap(since, NEXT_WAIT)
        return self.follow(rid, frame, f"{self.mode}{label}", since, NEXT_WAIT, on_start)

    def tap(self, since: float, seconds: float) -> None:
        """Tap SB1 every TAP_PERIOD from `since` until the robot is driven or `seconds` are over."""
        self.run_until(since)
        t0 = self.now
        while self.now < since + seconds and self.motion(t0, self.now) is None:
            self.press(TAP_HOLD)
            self.run(TAP_PERIOD - TAP_HOLD)

    def quiet_after(self, rid: str, after: float, seconds: float, expected: str, what: str) -> bool:
        """`quiet`, in step mode with SB1 tapped every 0.1 s meanwhile (no press may start a frame)."""
        if self.step:
            self.tap(after, seconds)
            expected += " (SB1 tapped every 0.1 s)"
        return self.quiet(rid, after, seconds, f"{self.mode}{expected}", what)

    def press_starts(self, rid: str, frame: F, label: str, pressed: float) -> Optional[FrameRun]:
        """The SB1 press at `pressed` must start `frame` on the debounced press (50 ms + one scan)."""
        run = self.follow(rid, frame, label, pressed, DEBOUNCE + 1.0)
        if run is None:
            return None
        late = run.start - pressed
        if not self.c.check(rid, -EPS <= late <= DEBOUNCE + self.tol + self.lag,
                            f"{label} starts on the press ({self.press_window}{lag_words(self)})",
                            f"{self.started} {late:.2f} s after the press", run.start):
            return None
        return run

    def quiet(self, rid: str, after: float, seconds: float, expected: str, what: str) -> bool:
        """Nothing driven in [after, after + seconds]; else a failure of `rid`."""
        self.run_until(after + seconds)
        t = self.motion(after, after + seconds)
        if t is None:
            return True
        self.c.fail(rid, expected,
                    f"{what}: {self.what_moved(t)} {t - after:.2f} s after t = {after:.2f} s", t)
        return False


# --------------------------------------------------------------------------- every scenario

NO_FAULT = Requirement("G1", "The program runs without a PLC fault (division by zero, array index out of "
                       "range, scan watchdog).", EVERY)


def no_fault(s: Session, c: Checks) -> None:
    with c.requirement(NO_FAULT) as rid:
        f = s.fault
        if f is None or f.internal:  # a bug of the harness is not charged: the rows it stopped say so
            return
        offset = s.now - s.plc.now_ns / 1e9
        c.fail(rid, "no runtime fault", str(f), offset + f.time_ns / 1e9)


# --------------------------------------------------------------------------- general flows

def lamp_requirements(lamp: str, bounce: str, reset: str) -> tuple[Requirement, ...]:
    """The program lamp, contact bounce and the long-press reset, checked by `basics_flow`."""
    return (
        Requirement(lamp, "HL1 is ON while the program is empty (at power-up) and OFF once a frame is "
                    "recorded with a short SB1 press.", "basics"),
        Requirement(bounce, f"A press of SB1 shorter than {DEBOUNCE * 1000:.0f} ms is contact bounce: it "
                    "records nothing.", "basics"),
        Requirement(reset, f"Holding SB1 resets the program at {LONG_PRESS:.1f} s, while it is still held "
                    "(HL1 ON); the release records nothing and a start then finds the program empty.",
                    "basics"),
    )


def within_scan(op: "Op[Any]") -> str:
    """The timing tolerance as a row prints it: '+/- one scan (10 ms)'."""
    return f"+/- one scan ({op.scan * 1000:.0f} ms)"


def lag_words(op: "Op[Any]") -> str:
    """The lag a program may have on the model answer, as a row prints it after its tolerance
    (inside the tolerance's parentheses): ', and one scan more a program may lag'."""
    n = op.rules.lag_scans
    return f", and {'one scan' if n == 1 else f'{n} scans'} more a program may lag" if n else ""


def basics_flow(op: Op[Any], ids: tuple[str, str, str], record: Callable[[], float],
                record_another: Callable[[], object]) -> None:
    """The `lamp_requirements` (`ids`), in manual mode from power-up: `record` records a frame
    where the robot is with a 0.2 s press and returns when SB1 was released, `record_another`
    moves the robot and records a second frame, so that the reset has a program to empty."""
    lamp, bounce, reset = ids
    c = op.c
    with c.requirement(lamp):
        c.check(lamp, op.hl1() == 1, "HL1=1 at power-up (no frame recorded)", "HL1=0", op.now)
        with c.requirement(bounce):
            lit = op.hl1() == 1
            t = op.press(0.03)
            op.run(0.5)
            off = op.s.trace.first(lambda st: not st.HL1, after=t, default=None)
            if lit:
                c.check(bounce, off is None, "HL1 stays 1 after a 30 ms SB1 press (nothing recorded)",
                        "HL1 went 0: the bounce recorded a frame", off)
            else:                    # a dark HL1 cannot show what the bounce did
                c.not_checked(bounce, f"HL1 is 0 at power-up (see {lamp}), so it cannot show whether "
                              "the 30 ms press recorded a frame", t)
        released = record()
        # HL1 going OFF while SB1 is still held (a lit lamp's falling edge: where the bounce
        # already recorded a frame, HL1 is OFF before this press and says nothing of it)
        fell = op.s.trace.edges("HL1", "falling", after=released - 0.2 - op.tol, until=released + 2 * op.tol)
        went_off = fell[0] if fell else None
        if went_off is not None and went_off < released - op.tol:
            c.fail(lamp, "HL1=0 once a frame is recorded, at the release of a short SB1 press (+/- one scan)",
                   f"HL1 went 0 at t = {went_off:.2f} s, {released - went_off:.2f} s before SB1 was released: "
                   "the frame was recorded on the press, not at its release", went_off)
        c.check(lamp, op.hl1(at=released + 2 * op.tol) == 0,
                "HL1=0 once a frame is recorded (short SB1 press), within two scans of the release", "HL1 still 1",
                released + 2 * op.tol)
    record_another()
    with c.requirement(reset):
        _long_press_resets(op, reset, lamp)
    op.set(**{op.auto: 0})
    op.run(0.2)


def _long_press_resets(op: Op[Any], rid: str, lamp: str) -> None:
    """SB1 held: the program is reset at 3.0 s while still held (HL1 ON then), the release
    records nothing, and an SB1 press in automatic mode then finds nothing to play. What HL1
    shows is judged with the reset only where the lamp works: an HL1 that never shows the
    reset of a program that was emptied is the lamp's failure (`lamp`), not the reset's."""
    c, s = op.c, op.s
    pressed = op.now
    lit_before = op.hl1() == 1
    s.console.hold("SB1")
    on = op.wait(lambda st: st.HL1, LONG_PRESS + 1.0)
    lamp_seen = ""
    if lit_before:
        lamp_seen = "HL1 was already 1 before SB1 was held (see the lamp requirement)"
        op.run_until(pressed + LONG_PRESS + 0.5)
    elif on is None:
        lamp_seen = f"HL1 still 0 after holding SB1 {LONG_PRESS + 1:g} s"
        op.run_until(pressed + LONG_PRESS + 1.5)
    else:
        held = on - pressed
        c.check(rid, LONG_PRESS - op.tol <= held <= LONG_PRESS + DEBOUNCE + op.tol + op.lag,
                f"the reset (HL1=1) {LONG_PRESS:.1f} s after SB1 is pressed (+ up to {DEBOUNCE * 1000:.0f} ms "
                f"debounce, {within_scan(op)}{lag_words(op)}), while it is held",
                f"HL1=1 {held:.2f} s after the press", on)
        op.run_until(pressed + LONG_PRESS + 0.5)
    released = op.now
    s.console.release("SB1")
    op.run(0.5)
    if on is not None and not lit_before:
        off = s.trace.first(lambda st: not st.HL1, after=released, default=None)
        c.check(rid, off is None, "HL1 stays 1 after the release (the release records nothing)",
                "HL1 went 0: a frame was recorded (or the reset never happened)", off or released)
    late = None if on is not None or lit_before else s.trace.first(lambda st: st.HL1, after=released, default=None)
    if late is not None:
        c.fail(rid, f"the reset (HL1=1) {LONG_PRESS:.1f} s after SB1 is pressed (+ up to {DEBOUNCE * 1000:.0f} ms "
               f"debounce, {within_scan(op)}), while it is held",
               f"HL1=1 only when SB1 was released (t = {late:.2f} s, {late - pressed:.2f} s after the press): "
               "the program was reset at the release, not while SB1 was held", late)
        return
    op.start_auto()
    emptied = op.quiet(rid, op.press(), REFUSED, "after the reset an SB1 press in automatic mode starts nothing",
                       "a frame started: the program was not empty")
    if emptied and on is None and not lit_before:
        c.fail(lamp, "HL1=1 once the program is reset (SB1 held 3.0 s)",
               f"{lamp_seen}, although the program was emptied (an SB1 press in automatic mode then started "
               "nothing)", pressed + LONG_PRESS)
    elif not emptied and lamp_seen:
        c.fail(rid, f"the program reset {LONG_PRESS:.1f} s after SB1 is pressed", lamp_seen, pressed + LONG_PRESS)


def restart_flow(op: Op[F], rid: str, first: F, second: F, off_time: float, lamp: str) -> bool:
    """Two taught frames, a PLC restart (power off `off_time` s): HL1 stays OFF and an SB1
    press plays the frames back. False if the program was lost (nothing was started). An HL1
    ON after the restart while the frames still play back is the lamp's failure (`lamp`)."""
    with op.c.requirement(rid):
        t = op.now
        op.s.restart_plc(off_time=off_time)
        op.run(0.3)
        lit = op.hl1() == 1
        op.start_auto()
        label = "frame 1 after the restart" + (" (HL1 is 1: is the program empty?)" if lit else "")
        r1 = op.press_starts(rid, first, label, op.press())
        if r1 is None:
            return False
        if lit:
            op.c.fail(lamp, "HL1=0 after the restart: the program is kept",
                      "HL1=1 although the program was kept (it plays back): HL1 does not show the program", t)
        op.follow(rid, second, "frame 2 after the restart", r1.done, NEXT_WAIT)
    return True


# --------------------------------------------------------------------------- Task 2

def task2_requirements(enable: str, measured: str, modes: str = "") -> tuple[Requirement, ...]:
    """Task 2 with the pause input `enable` ("I0.7"); `measured` says where the stand's pause
    starts and ends; `modes` where the textbook has both playback modes (" in continuous and
    in step mode"), checked in each."""
    return (
        Requirement("T2.1", f"A frame recorded with {enable} = 0 is followed by a {PAUSE_SHORT:.1f} s pause "
                    f"({measured}){modes}.", "pauses"),
        Requirement("T2.2", f"A frame recorded with {enable} = 1 is followed by a {PAUSE_LONG:.1f} s pause{modes}.",
                    "pauses"),
        Requirement("T2.3", f"{enable} changes nothing in automatic mode: switched at every phase of execution "
                    "(a frame's start, the frame reached, inside its pause), every frame keeps the pause "
                    f"recorded with it{modes}.", "pauses"),
    )


def pauses_flow(op: Op[F], frames: Sequence[F], recorded: Sequence[int], start_checked: bool = True) -> None:
    """Task 2 on the taught `frames`, recorded with the input at `recorded` (1: 3 s, 0: 0.5 s;
    a pattern where swapped pauses, the next frame's and the previous frame's pauses all
    differ): a cycle with the input at 1 checks each pause (T2.1, T2.2) and names the
    pattern of a wrong one; then cycles with the input switched at every phase boundary
    (T2.3) until playback has run longer than the frame watchdog. In step mode (`op.step`)
    the grader taps SB1 to go on. `start_checked=False` leaves out the check that frame 1
    starts on the press (a general requirement makes it)."""
    c, name, n = op.c, op.enable_label, len(frames)
    wanted = [PAUSE_LONG if r else PAUSE_SHORT for r in recorded]
    op.start_auto()
    label = f"{op.mode}frame 1"           # a frame that does not come fails the row of the pause before it
    if start_checked:
        run = op.press_starts("T2.2", frames[0], label, op.press())
    else:
        run = op.follow("T2.2", frames[0], label, op.press(), DEBOUNCE + 1.0)
    if run is None:
        return
    first = [run]
    for k in range(1, n + 1):
        run = op.advance(_pause_req(recorded[k - 1]), frames[k % n], f"frame {k % n + 1} after frame {k}", run.done)
        if run is None:
            return
        first.append(run)
    with c.requirement("T2.1", "T2.2"):
        seen = [b.start - a.done for a, b in zip(first, first[1:])]
        why = _pause_pattern(seen, wanted, op.tol + op.lag + (TAP_PERIOD if op.step else 0.0), name)
        for k in range(n):
            _paused(op, _pause_req(recorded[k]), first[k], first[k + 1], wanted[k],
                    f"after frame {k + 1} (recorded with {name} = {recorded[k]})", why)
    with c.requirement("T2.3"):
        _input_changes_nothing(op, frames, first, seen, wanted)
    op.stop_playback()


def _held(k: int, cycle: int) -> int:
    """T2.3: the input as frame k + 1 of `cycle` starts, is driven and is reached; it is switched
    to the other value inside the frame's pause. Frame 1 of cycle 2 is played with 1 (the first
    cycle's measurement); over cycles 2 and 3 every frame is reached once with each value."""
    return (k + cycle + 1) % 2


def _input_changes_nothing(op: Op[F], frames: Sequence[F], first: Sequence[FrameRun], seen: Sequence[float],
                           wanted: Sequence[float]) -> None:
    """T2.3 from frame 1 of cycle 2 (`first[-1]`): the input held at one value through each
    frame's start, drive and arrival and switched to the other inside its pause, each frame
    with both values over two cycles, and on until playback has run longer than the frame
    watchdog. Each pause is judged against the pause the program should have had (the one
    recorded with the frame); where the first cycle (the input steady at 1) already gave
    another pause, that is T2.1's or T2.2's mistake, and T2.3 asks only that the input changes
    nothing (the first cycle's pause)."""
    name, n = op.enable_label, len(frames)
    tol = op.tol + op.lag + (TAP_PERIOD if op.step else 0.0)
    right = all(abs(a - b) <= tol for a, b in zip(seen, wanted))
    began, run, k, cycle = first[0].start, first[-1], 0, 2
    while not (k == 0 and cycle > 3 and run.done - began > op.frame_timeout + 1.0):
        nk, done, held = (k + 1) % n, run.done, _held(k, cycle)
        op.run_until(done + PAUSE_SHORT * 0.3)
        op.set_enable(1 - held)                              # inside its pause
        if nk == 0:                                          # 1 at the end of the last pause: a program
            op.run_until(done + PAUSE_SHORT * 0.7)           # that also does Task 3 goes on to frame 1
            op.set_enable(1)
        ncycle = cycle + (nk == 0)
        nxt = op.advance("T2.3", frames[nk], f"frame {nk + 1} (cycle {ncycle})", done,
                         on_start=lambda h=_held(nk, ncycle): op.set_enable(h))
        if nxt is None:
            return
        pause = nxt.start - done
        why = ""
        for value, when in ((held, "when the frame was reached"), (1 - held, "inside the pause")):
            live = PAUSE_LONG if value else PAUSE_SHORT
            if abs(pause - live) <= tol and abs(pause - (wanted[k] if right else seen[k])) > tol:
                why = (f"the pause followed {name} as it was {when} ({value}), not the pause recorded with "
                       "the frame")
                break
        recorded = int(wanted[k] == PAUSE_LONG)
        where = (f"after frame {k + 1} in cycle {cycle} (recorded with {name} = {recorded}), {name} being {held} "
                 f"as the frame started and was reached and {1 - held} inside its pause")
        if not right:
            where += (f": the same as in the first cycle, {name} steady at 1 (that it is not the "
                      f"{_secs(wanted[k])} s recorded with the frame is {_pause_req(recorded)}'s)")
        if not _paused(op, "T2.3", run, nxt, wanted[k] if right else seen[k], where, why):
            return
        run, k, cycle = nxt, nk, ncycle


def _pause_req(recorded: int) -> str:
    return "T2.2" if recorded else "T2.1"


def _pause_pattern(seen: Sequence[float], wanted: Sequence[float], tol: float, name: str) -> str:
    """What a cycle's wrong pauses `seen` (against `wanted`) look like: swapped, the next or
    the previous frame's pause, one fixed pause; '' if none of these."""
    n = len(wanted)

    def like(want: Sequence[float], ks: range) -> bool:
        return all(abs(seen[k] - want[k]) <= tol for k in ks)

    swapped = [PAUSE_SHORT if w == PAUSE_LONG else PAUSE_LONG for w in wanted]
    if like(wanted, range(n)):
        return ""
    if like(swapped, range(n)):
        return (f"the pauses are swapped: frames recorded with {name} = 0 got {_secs(PAUSE_LONG)} s, those "
                f"recorded with {name} = 1 got {_secs(PAUSE_SHORT)} s")
    if max(seen) - min(seen) <= 2 * tol:
        recorded = ", ".join("1" if w == PAUSE_LONG else "0" for w in wanted)
        return (f"every frame got the same {seen[0]:.2f} s pause, whatever {name} was when it was recorded "
                f"({recorded})")
    if like([wanted[(k + 1) % n] for k in range(n)], range(n - 1)):
        return ("off by one: after each frame came the pause recorded with the next frame (the pause read "
                "from the wrong frame, or stored on every manual scan instead of at the SB1 press, so that "
                f"each frame kept {name} as it was set for the next one)")
    if like([wanted[k - 1] for k in range(n)], range(1, n)):
        return "off by one: after each frame came the pause recorded with the frame before it"
    return ""


def _paused(op: Op[Any], rid: str, before: FrameRun, after: FrameRun, seconds: float, where: str,
            why: str = "") -> bool:
    """The pause from `before` done to `after` starting lasts `seconds` (+/- one scan; in step
    mode +/- the tap period too); the expected value names the pause, its tolerance and
    `where` it is, the observed one what the wrong pauses look like (`why`)."""
    pause = after.start - before.done
    tol = op.tol + op.lag + (TAP_PERIOD if op.step else 0.0)
    within = (f"+/- {TAP_PERIOD:g} s (SB1 tapped every {TAP_PERIOD:g} s) + one scan ({op.scan * 1000:.0f} ms)"
              if op.step else within_scan(op))
    if op.rules.lag_scans:
        within = f"({within}{lag_words(op)})"
    good = abs(pause - seconds) <= tol
    return op.c.check(rid, good, f"{op.mode}a {_secs(seconds)} s pause {within} {where}",
                      f"{pause:.2f} s" + (f": {why}" if why and not good else ""), before.done)


def _secs(seconds: float) -> str:
    """3.0 -> '3.0', 0.5 -> '0.5', 1.23456 -> '1.23': a duration as the requirements write it."""
    return f"{seconds:.1f}" if abs(seconds * 10 - round(seconds * 10)) < 1e-9 else f"{seconds:.2f}"


# --------------------------------------------------------------------------- Task 3

def task3_requirements(enable: str, remaining: str, stops: str, restarts: str,
                       modes: str = "") -> tuple[Requirement, ...]:
    """Task 3 with the run-enable input `enable` ("I0.7"), in each stand's words for what runs
    after the input drops (`remaining`), how the stop shows (`stops`) and what must not
    restart it (`restarts`); `modes` where the textbook has both playback modes (" in
    continuous and in step mode"), checked in each."""
    return tuple(Requirement(r.id, r.text[:-1] + f"{modes}.", r.scenario) for r in (
        Requirement("T3.1", f"Automatic mode: an SB1 press with {enable} = 0 starts nothing.", "enable"),
        Requirement("T3.2", f"An SB1 press with {enable} = 1 starts frame 1.", "enable"),
        Requirement("T3.3", f"With {enable} = 1 the frames run in order and frame 1 follows the last frame "
                    "and its pause.", "enable"),
        Requirement("T3.4", f"{enable} dropped to 0 during frame 2 (also as frame 1 is reached or inside its "
                    f"pause): frame 2 and the remaining {remaining} still run to completion.", "enable"),
        Requirement("T3.5", f"Then, after the last frame and its pause, no transition to frame 1: {stops}.",
                    "enable"),
        Requirement("T3.6", f"After that stop nothing restarts {restarts}; an SB1 press with {enable} = 1 "
                    "starts again from frame 1.", "enable"),
        Requirement("T3.7", f"{enable} counts when the last frame's pause is over, not when the last frame is "
                    f"reached: switched to 0 inside that pause, execution stops after it (read as a level at "
                    f"the end of the pause, or latched from the moment it drops: both are right).", "last_pause"),
    ))


def enable_flow(op: Op[F], frames: Sequence[F], refused_start: Callable[[], None],
                dropped_labels: tuple[str, str]) -> None:
    """Task 3 on the taught `frames` (three or more). `refused_start` checks T3.1 (an SB1 press
    in automatic mode with the input at 0) and leaves the program waiting for a start. The
    second cycle drops the input as frame 2 starts; `dropped_labels` name its frame 2 and, as
    templates of `k` and `dropped` (when the input went to 0), its frames k = 3..."""
    op.start_auto(enable=0)
    refused_start()
    op.set_enable(1)
    op.run(0.3)
    run = _enabled_cycle(op, frames)
    run = run and _dropped_cycle(op, frames, run, dropped_labels)
    if run:
        _stops_after_last(op, frames, run.done)


def _enabled_cycle(op: Op[F], frames: Sequence[F]) -> Optional[FrameRun]:
    """T3.2 and T3.3: with the input at 1 an SB1 press starts frame 1, the frames run in order
    and frame 1 follows the last; that frame 1's run, or None."""
    c, name, n = op.c, op.enable_label, len(frames)
    with c.requirement("T3.2"):
        run = op.press_starts("T3.2", frames[0], f"{op.mode}frame 1 (SB1 pressed with {name} = 1)", op.press())
        if run is None:
            return None
    with c.requirement("T3.3"):
        for k in range(1, n):
            run = op.advance("T3.3", frames[k], f"frame {k + 1}", run.done)
            if run is None:
                return None
        return op.advance("T3.3", frames[0], f"frame 1 after frame {n} ({name} = 1)", run.done)


def _dropped_cycle(op: Op[F], frames: Sequence[F], first: FrameRun,
                   labels: tuple[str, str]) -> Optional[FrameRun]:
    """T3.4: the input dropped to 0 as frame 2 starts (after `first`, frame 1's run), frames 2
    to the last still run; the last frame's run, or None."""
    dropped: list[float] = []
    frame2, later = labels
    with op.c.requirement("T3.4"):
        run = op.advance("T3.4", frames[1], frame2, first.done, on_start=lambda: dropped.append(op.set_enable(0)))
        for k in range(2, len(frames)):
            if run is None:
                return None
            run = op.advance("T3.4", frames[k], later.format(k=k + 1, dropped=dropped[0]), run.done)
        return run


def _stops_after_last(op: Op[F], frames: Sequence[F], done: float) -> None:
    """T3.5 and T3.6: with the input at 0, execution stops after the last frame (done at
    `done`) and its pause, and only an SB1 press with the input at 1 starts it again."""
    c, name, n = op.c, op.enable_label, len(frames)
    with c.requirement("T3.5"):
        if not op.quiet_after("T3.5", done, PAUSE_LONG + REFUSED, f"no frame starts after frame {n} (the last) "
                              f"and its pause, {name} being 0", "execution went on to frame 1"):
            c.not_checked("T3.6", "execution did not stop after the last frame (see T3.5)", None)
            return
    with c.requirement("T3.6"):
        if not op.quiet("T3.6", op.press(), REFUSED, f"{op.mode}after the stop, an SB1 press with {name} = 0 "
                        "starts nothing", "the program started"):
            return
        if not op.quiet("T3.6", op.set_enable(1), REFUSED, f"{op.mode}after the stop, {name} = 1 alone (no "
                        "press) starts nothing", "the program started"):
            return
        op.press_starts("T3.6", frames[0], f"{op.mode}frame 1 (a new start: SB1 with {name} = 1)", op.press())
    op.back_to_manual()


def last_pause_flow(op: Op[F], frames: Sequence[F]) -> None:
    """T3.7: a cycle with the input at 1 up to the last frame; the input switched to 0 inside
    the last frame's pause (halfway through the shortest pause): execution stops after it. A
    program that read the input when the last frame was reached goes on to frame 1."""
    c, name, n = op.c, op.enable_label, len(frames)
    op.start_auto()
    with c.requirement("T3.7") as rid:
        run = op.press_starts(rid, frames[0], f"{op.mode}frame 1 (SB1 pressed with {name} = 1)", op.press())
        for k in range(1, n):
            run = run and op.advance(rid, frames[k], f"frame {k + 1} ({name} = 1)", run.done)
        if not run:
            return
        op.run_until(run.done + PAUSE_SHORT / 2)
        dropped = op.set_enable(0)
        op.quiet_after(rid, run.done, PAUSE_LONG + REFUSED,
                       f"no frame after frame {n} (the last) and its pause, {name} being switched to 0 inside "
                       f"that pause (t = {dropped:.2f} s, {dropped - run.done:.2f} s after frame {n} was reached)",
                       "execution went on to frame 1 (it never stops after the last frame: see T3.5)"
                       if c.failed("T3.5") else f"{name} was read when frame {n} was reached, not when its "
                       "pause was over: execution went on to frame 1")
    for phase in ("as frame 1 was reached", "inside frame 1's pause"):
        op.set(**{op.auto: 0})                       # whatever happened, a fresh start from manual mode
        op.run(op.wind_down + 1.0)
        op.start_auto()
        _dropped_at(op, frames, phase)
    op.back_to_manual()


def _dropped_at(op: Op[F], frames: Sequence[F], phase: str) -> None:
    """T3.4 and T3.5 with the input dropped to 0 at another phase boundary of frame 1 (`phase`:
    as it is reached, or inside its pause): the remaining frames still run, then execution
    stops after the last one and its pause."""
    c, name, n = op.c, op.enable_label, len(frames)
    with c.requirement("T3.4"):
        run = op.press_starts("T3.4", frames[0], f"{op.mode}frame 1 (SB1 pressed with {name} = 1)", op.press())
        if run is None:
            return
        if phase.startswith("inside"):
            op.run_until(run.done + PAUSE_SHORT / 2)
        dropped = op.set_enable(0)
        for k in range(1, n):
            run = op.advance("T3.4", frames[k], f"frame {k + 1} ({name} dropped to 0 {phase}, t = {dropped:.2f} s)",
                             run.done)
            if run is None:
                return
    with c.requirement("T3.5"):
        op.quiet_after("T3.5", run.done, PAUSE_LONG + REFUSED, f"no frame starts after frame {n} (the last) and "
                       f"its pause, {name} having been dropped to 0 {phase}", "execution went on to frame 1")


# --------------------------------------------------------------------------- registration

TaskSets = dict[str, tuple[tuple[Requirement, ...], tuple[Scenario, ...]]]


def register_tasks(stand: Stand, tasks: TaskSets, general: tuple[Requirement, ...],
                   general_scenarios: tuple[Scenario, ...], make_session: SessionFactory,
                   every: tuple[Hook, ...]) -> None:
    """One requirement set per task: the task's own requirements and scenarios, then the
    general ones every solution must keep; the `every` checks run after each scenario."""
    for task, (requirements, scenarios) in tasks.items():
        register(RequirementSet(
            stand=stand.name, task=task, title=f"{stand.title}, {stand.variants[task].doc}",
            requirements=requirements + general, scenarios=scenarios + general_scenarios,
            make_session=make_session, every=every))
