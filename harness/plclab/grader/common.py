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
from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Generic, Optional, Self, Sequence, TypeVar

from plclab.scenario import ScenarioFailure, Session
from plclab.stands import Stand

from .registry import EVERY, Checks, Requirement, RequirementSet, Scenario, SessionFactory, register

DEBOUNCE = 0.05          # SB1 closures shorter than this are contact bounce
LONG_PRESS = 3.0         # SB1 held this long resets the program
PAUSE_SHORT = 0.5        # Task 2: frame recorded with the pause input = 0
PAUSE_LONG = 3.0         # Task 2: frame recorded with the pause input = 1
NEXT_WAIT = PAUSE_LONG + 1.0   # the next frame starts within this after one is done
REFUSED = 2.0            # s watched for a start that must not happen
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

    auto: ClassVar[str]            # the mode switch: 0 manual, 1 automatic
    enable: ClassVar[str]          # the pause / run-enable input by its console name ("I07")
    enable_label: ClassVar[str]    # ... and as the requirements write it ("I0.7")
    wind_down: ClassVar[float]     # s run on after a scenario's last step (the trace shows the stop)
    press_window: ClassVar[str]    # the start tolerance and ...
    started: ClassVar[str]         # ... how a start is seen, as the stand's failure messages word them

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

    def press_starts(self, rid: str, frame: F, label: str, pressed: float) -> Optional[FrameRun]:
        """The SB1 press at `pressed` must start `frame` on the debounced press (50 ms + one scan)."""
        run = self.follow(rid, frame, label, pressed, DEBOUNCE + 1.0)
        if run is None:
            return None
        late = run.start - pressed
        if not self.c.check(rid, -EPS <= late <= DEBOUNCE + self.tol,
                            f"{label} starts on the press ({self.press_window})",
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
    f = s.fault
    if f is None or f.internal:     # a bug of the harness is not charged: the rows it stopped say so
        c.ok("G1")
        return
    offset = s.now - s.plc.now_ns / 1e9
    c.fail("G1", "no runtime fault", str(f), offset + f.time_ns / 1e9)


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


def basics_flow(op: Op[Any], ids: tuple[str, str, str], record: Callable[[], float],
                record_another: Callable[[], object]) -> None:
    """The `lamp_requirements` (`ids`), in manual mode from power-up: `record` records a frame
    where the robot is and returns when SB1 was released, `record_another` moves the robot
    and records a second frame, so that the reset has a program to empty."""
    lamp, bounce, reset = ids
    c = op.c
    with c.requirement(lamp):
        c.check(lamp, op.hl1() == 1, "HL1=1 at power-up (no frame recorded)", "HL1=0", op.now)
        with c.requirement(bounce):
            t = op.press(0.03)
            op.run(0.5)
            off = op.s.trace.first(lambda st: not st.HL1, after=t, default=None)
            c.check(bounce, off is None, "HL1 stays 1 after a 30 ms SB1 press (nothing recorded)",
                    "HL1 went 0: the bounce recorded a frame", off)
        released = record()
        c.check(lamp, op.hl1(at=released + 2 * op.tol) == 0,
                "HL1=0 once a frame is recorded (short SB1 press)", "HL1 still 1", released + 2 * op.tol)
    record_another()
    with c.requirement(reset):
        _long_press_resets(op, reset)
    op.set(**{op.auto: 0})
    op.run(0.2)


def _long_press_resets(op: Op[Any], rid: str) -> None:
    """SB1 held: HL1 ON at 3.0 s while still held, the release records nothing, and an SB1
    press in automatic mode then finds nothing to play."""
    c, s = op.c, op.s
    pressed = op.now
    s.console.hold("SB1")
    on = op.wait(lambda st: st.HL1, LONG_PRESS + 1.0)
    if on is None:
        c.fail(rid, "HL1=1 (program reset) 3.0 s after SB1 is pressed, while it is held",
               f"HL1 still 0 after holding SB1 {LONG_PRESS + 1:g} s", pressed + LONG_PRESS)
        op.run_until(pressed + LONG_PRESS + 1.5)
    else:
        held = on - pressed
        c.check(rid, LONG_PRESS - op.tol <= held <= LONG_PRESS + DEBOUNCE + op.tol,
                f"the reset (HL1=1) {LONG_PRESS:.1f} s after SB1 is pressed (+ up to {DEBOUNCE * 1000:.0f} ms "
                f"debounce, {within_scan(op)}), while it is held",
                f"HL1=1 {held:.2f} s after the press", on)
        op.run_until(pressed + LONG_PRESS + 0.5)
    released = op.now
    s.console.release("SB1")
    op.run(0.5)
    off = s.trace.first(lambda st: not st.HL1, after=released, default=None)
    c.check(rid, off is None, "HL1 stays 1 after the release (the release records nothing)",
            "HL1 went 0: a frame was recorded (or the reset never happened)", off or released)
    op.start_auto()
    op.quiet(rid, op.press(), REFUSED, "after the reset an SB1 press in automatic mode starts nothing",
             "a frame started: the program was not empty")


def restart_flow(op: Op[F], rid: str, first: F, second: F, off_time: float) -> bool:
    """Two taught frames, a PLC restart (power off `off_time` s): HL1 stays OFF and an SB1
    press plays the frames back. False if the program was lost (nothing was started)."""
    with op.c.requirement(rid):
        t = op.now
        op.s.restart_plc(off_time=off_time)
        op.run(0.3)
        if not op.c.check(rid, op.hl1() == 0, "HL1=0 after the restart (the program is kept)",
                          "HL1=1: the program is empty after the restart", t):
            return False
        op.start_auto()
        r1 = op.press_starts(rid, first, "frame 1 after the restart", op.press())
        if r1:
            op.follow(rid, second, "frame 2 after the restart", r1.done, NEXT_WAIT)
    return True


# --------------------------------------------------------------------------- Task 2

def task2_requirements(enable: str, measured: str) -> tuple[Requirement, ...]:
    """Task 2 with the pause input `enable` ("I0.7"); `measured` says where the stand's pause
    starts and ends."""
    return (
        Requirement("T2.1", f"A frame recorded with {enable} = 0 is followed by a {PAUSE_SHORT:.1f} s pause "
                    f"({measured}).", "pauses"),
        Requirement("T2.2", f"A frame recorded with {enable} = 1 is followed by a {PAUSE_LONG:.1f} s pause.",
                    "pauses"),
        Requirement("T2.3", f"{enable} changes nothing in automatic mode: switched during execution, every "
                    "frame keeps the pause recorded with it.", "pauses"),
    )


def pauses_flow(op: Op[F], first: F, second: F, start_checked: bool = True) -> None:
    """Task 2 on two taught frames, `first` recorded with the input at 1 (3 s), `second` with 0
    (0.5 s): a cycle with the input at 1, then a cycle during which it is 0 (frame 1) and 1
    again (frame 2). `start_checked=False` leaves out the check that frame 1 starts on the
    press (MP-9C's Task 2 never made it; G6 does)."""
    c, name = op.c, op.enable_label
    op.start_auto()
    with c.requirement("T2.2"):
        if start_checked:
            r1 = op.press_starts("T2.2", first, "frame 1", op.press())
        else:
            r1 = op.follow("T2.2", first, "frame 1", op.press(), DEBOUNCE + 1.0)
        r2 = r1 and op.follow("T2.2", second, "frame 2", r1.done, NEXT_WAIT)
        if not r1 or not r2:
            return
        _paused(op, "T2.2", r1, r2, PAUSE_LONG, f"after frame 1 (recorded with {name} = 1)")
    with c.requirement("T2.1"):
        r3 = op.follow("T2.1", first, "frame 1 after frame 2", r2.done, NEXT_WAIT,
                       on_start=lambda: op.set_enable(0))
        if not r3:
            return
        _paused(op, "T2.1", r2, r3, PAUSE_SHORT, f"after frame 2 (recorded with {name} = 0)")
    with c.requirement("T2.3"):
        r4 = op.follow("T2.3", second, "frame 2 (second cycle)", r3.done, NEXT_WAIT,
                       on_start=lambda: op.set_enable(1))
        if not r4:
            return
        p1, p2 = r2.start - r1.done, r3.start - r2.done
        if not _paused(op, "T2.3", r3, r4, p1, f"after frame 1, as in the first cycle although {name} is now 0"):
            return
        r5 = op.follow("T2.3", first, "frame 1 (third cycle)", r4.done, NEXT_WAIT)
        if not r5:
            return
        _paused(op, "T2.3", r4, r5, p2, f"after frame 2, as in the first cycle although {name} is now 1")
    op.stop_playback()


def _paused(op: Op[Any], rid: str, before: FrameRun, after: FrameRun, seconds: float, where: str) -> bool:
    """The pause from `before` done to `after` starting lasts `seconds` (+/- one scan); the
    expected value names the pause, its tolerance and `where` it is."""
    pause = after.start - before.done
    return op.c.check(rid, abs(pause - seconds) <= op.tol, f"a {_secs(seconds)} s pause {within_scan(op)} {where}",
                      f"{pause:.2f} s", before.done)


def _secs(seconds: float) -> str:
    """3.0 -> '3.0', 0.5 -> '0.5', 1.23456 -> '1.23': a duration as the requirements write it."""
    return f"{seconds:.1f}" if abs(seconds * 10 - round(seconds * 10)) < 1e-9 else f"{seconds:.2f}"


# --------------------------------------------------------------------------- Task 3

def task3_requirements(enable: str, remaining: str, stops: str, restarts: str) -> tuple[Requirement, ...]:
    """Task 3 with the run-enable input `enable` ("I0.7"), in each stand's words for what runs
    after the input drops (`remaining`), how the stop shows (`stops`) and what must not
    restart it (`restarts`)."""
    return (
        Requirement("T3.1", f"Automatic mode: an SB1 press with {enable} = 0 starts nothing.", "enable"),
        Requirement("T3.2", f"An SB1 press with {enable} = 1 starts frame 1.", "enable"),
        Requirement("T3.3", f"With {enable} = 1 the frames run in order and frame 1 follows the last frame "
                    "and its pause.", "enable"),
        Requirement("T3.4", f"{enable} dropped to 0 during frame 2: frame 2 and the remaining {remaining} "
                    "still run to completion.", "enable"),
        Requirement("T3.5", f"Then, after the last frame and its pause, no transition to frame 1: {stops}.",
                    "enable"),
        Requirement("T3.6", f"After that stop nothing restarts {restarts}; an SB1 press with {enable} = 1 "
                    "starts again from frame 1.", "enable"),
    )


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
        run = op.press_starts("T3.2", frames[0], f"frame 1 (SB1 pressed with {name} = 1)", op.press())
        if run is None:
            return None
    with c.requirement("T3.3"):
        for k in range(1, n):
            run = op.follow("T3.3", frames[k], f"frame {k + 1}", run.done, NEXT_WAIT)
            if run is None:
                return None
        return op.follow("T3.3", frames[0], f"frame 1 after frame {n} ({name} = 1)", run.done, NEXT_WAIT)


def _dropped_cycle(op: Op[F], frames: Sequence[F], first: FrameRun,
                   labels: tuple[str, str]) -> Optional[FrameRun]:
    """T3.4: the input dropped to 0 as frame 2 starts (after `first`, frame 1's run), frames 2
    to the last still run; the last frame's run, or None."""
    dropped: list[float] = []
    frame2, later = labels
    with op.c.requirement("T3.4"):
        run = op.follow("T3.4", frames[1], frame2, first.done, NEXT_WAIT,
                        on_start=lambda: dropped.append(op.set_enable(0)))
        for k in range(2, len(frames)):
            if run is None:
                return None
            run = op.follow("T3.4", frames[k], later.format(k=k + 1, dropped=dropped[0]), run.done, NEXT_WAIT)
        return run


def _stops_after_last(op: Op[F], frames: Sequence[F], done: float) -> None:
    """T3.5 and T3.6: with the input at 0, execution stops after the last frame (done at
    `done`) and its pause, and only an SB1 press with the input at 1 starts it again."""
    c, name, n = op.c, op.enable_label, len(frames)
    with c.requirement("T3.5"):
        if not op.quiet("T3.5", done, PAUSE_LONG + REFUSED, f"no frame starts after frame {n} (the last) and "
                        f"its pause, {name} being 0", "execution went on to frame 1"):
            c.fail("T3.6", "", "not checked: execution did not stop after the last frame (see T3.5)", None)
            return
    with c.requirement("T3.6"):
        if not op.quiet("T3.6", op.press(), REFUSED, f"after the stop, an SB1 press with {name} = 0 starts "
                        "nothing", "the program started"):
            return
        if not op.quiet("T3.6", op.set_enable(1), REFUSED, f"after the stop, {name} = 1 alone (no press) "
                        "starts nothing", "the program started"):
            return
        op.press_starts("T3.6", frames[0], f"frame 1 (a new start: SB1 with {name} = 1)", op.press())
    op.back_to_manual()


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
