"""Operator scripts: what an operator at a stand's console does, in any order and at any moment.

The grader's exploration (plclab.grader.explore) plays the same seeded random operator script
on a student's program and on the task's model answer, each with its own plant, and compares
what the stands show. What an operator can do, what the stand shows and how exactly two
stands must agree are facts of the stand, not of the grader, so each robot declares them here
in one `Exploration` (referenced from its StandSpec as `explore`):

- `generate(rng, task, seconds)`: a random script of console actions -- switch flips in every
  mode, SB1 taps, short presses, contact bounces and 3-s holds, mode changes mid-frame and
  mid-pause, the spare input toggled at any time, PLC power cycles with retained memory, long
  playbacks (longer than every watchdog), the frame memory filled to its limit, and the plant
  faults the stand declares;
- `observe(plant)`: what the stand shows, read from the plant (valve spools and lamps of the
  MP-9C; the TUR-10's motion of each link and the position where it stops);
- `compared(task)`: which of those are compared for a task, with their tolerances (a few scans
  of timing; the TUR-10 positions within a band) and freedoms (a signal compared only while the
  console is in one mode: a don't-care outside that window).

- `aim(rng, task, script, times)`: the script again with actions added at the moments the
  model answer's stand changed in it (phase boundaries);
- lamps as the operator sees them (`lamp_pattern`: on, off or blinking) and the freedoms the
  tasks leave a blink.

Scripts themselves and their file form are plclab.stands.scripts.
"""
from __future__ import annotations

import random
from dataclasses import dataclass, field
from typing import Any, Callable, Optional, Sequence

from plclab.stands.scripts import FAULT, POWER, Event, Script, fault_params

# --------------------------------------------------------------------------- what is compared

@dataclass(frozen=True)
class Observed:
    """One thing the stand shows, compared between the student's stand and the model answer's.

    `show(value)` says a value in the console's words ('down (L3)'); `outputs` are the program's
    outputs that drive it (the report names the student's ST line that last wrote the first of
    them that differs); `same(a, b)` is the value tolerance (default: equal); `only_when =
    (switch, value, settle_s)` restricts the comparison to the time the console switch has had
    that value for settle_s (a freedom of the task: a don't-care outside that window)."""

    name: str
    show: Callable[[Any], str]
    outputs: tuple[str, ...]
    same: Optional[Callable[[Any, Any], bool]] = None
    only_when: Optional[tuple[str, int, float]] = None
    tolerance: str = ""                      # the value tolerance in words ('+/- 40 codes')
    # what the stand shows, read from the changes (a lamp: on, off or blinking), and the timing
    # tolerance of a change from one shown value to another where the task leaves it free
    # (None: the stand's timing_tol)
    pattern: Optional[Callable[[list[tuple[float, Any]]], list[tuple[float, Any]]]] = None
    timing: Optional[Callable[[Any, Any], Optional[float]]] = None
    freedom: str = ""                        # the timing freedom in words
    # (switch, value): while the console switch has that value, a blink of this lamp on either
    # stand, and BLINK_END_TOL after it, is not compared (how a blink answers more presses is free)
    free_blinks: Optional[tuple[str, int]] = None

    # a value tolerance that grows with how far apart in time the two stands are: `lag_band`
    # more per second of lag (a link stopped mid-travel by a program a scan later stands
    # a scan's travel further on)
    lag_band: float = 0.0
    # a value where the thing shown stands still (a link at rest): a rest value is judged with
    # the largest lag the two stands had since each last stood still (a link started a scan
    # later and stopped by a press in the same scan on both stands stands a scan's travel short)
    rest: Optional[Callable[[Any], bool]] = None
    # (switch, value, button, after_s): also compared from each change of the console switch to
    # that value until the button's first press after it and after_s more (the TUR-10's Task 1:
    # entering automatic mode moves nothing and a press starts frame 1; what playback then does
    # is not the task's subject)
    until_press: Optional[tuple[str, int, str, float]] = None

    def equal(self, a: Any, b: Any, lag: float = 0.0) -> bool:
        if self.same is None:
            return a == b
        if self.lag_band and lag > 0:
            return self.same(a, b, self.lag_band * lag)
        return self.same(a, b)

    def shown(self, changes: list[tuple[float, Any]]) -> list[tuple[float, Any]]:
        return self.pattern(changes) if self.pattern is not None else changes

    def timing_tol(self, before: Any, after: Any) -> Optional[float]:
        return self.timing(before, after) if self.timing is not None else None


BLINKING = "blinking"
BLINK_HALF_MAX = 0.6     # s: a lamp toggling again within this is blinking (1 Hz and 2 Hz blinks)
BLINK_START_TOL = 0.65   # s: a blink may begin in either phase (on first, or off first)
BLINK_END_TOL = 2.5      # s: how long a blink lasts after its last cause is the program's choice


def lamp_pattern(changes: list[tuple[float, Any]]) -> list[tuple[float, Any]]:
    """A lamp as an operator sees it: on, off or blinking. Three or more toggles each within
    BLINK_HALF_MAX of the one before are one blink, from its first toggle to its last (the
    lamp then stays as the last toggle left it)."""
    out = changes[:1]
    k = 1
    while k < len(changes):
        j = k
        while j + 1 < len(changes) and changes[j + 1][0] - changes[j][0] <= BLINK_HALF_MAX + 1e-9:
            j += 1
        if j - k + 1 >= 3:
            out.append((changes[k][0], BLINKING))
            out.append((changes[j][0], changes[j][1]))
        else:
            out.extend(changes[k:j + 1])
        k = j + 1
    merged = out[:1]
    for t, v in out[1:]:
        if v != merged[-1][1]:
            merged.append((t, v))
    return merged


def lamp_timing(before: Any, after: Any) -> Optional[float]:
    """The freedoms of a blinking lamp the tasks leave open: the phase it begins in, and how
    long it goes on (a refused press during the full-memory blink may restart its 2 s or not;
    the blink rate is the scenarios' to check)."""
    if after == BLINKING:
        return BLINK_START_TOL
    if before == BLINKING:
        return BLINK_END_TOL
    return None


def blink_spans(changes: list[tuple[float, Any]]) -> list[tuple[float, float]]:
    """The spans a lamp pattern (lamp_pattern) is blinking: (start, end)."""
    spans = []
    for k, (t, v) in enumerate(changes):
        if v == BLINKING:
            spans.append((t, changes[k + 1][0] if k + 1 < len(changes) else float("inf")))
    return spans


def show_lamp(v: Any) -> str:
    return "blinking" if v == BLINKING else "on" if v else "off"


@dataclass(frozen=True)
class Exploration:
    """What a stand declares for exploration (see the module docstring)."""

    generate: Callable[[random.Random, str, float], Script]
    observe: Callable[[Any, Any], dict[str, Any]]     # (plant, last values) -> observed and guard values
    compared: Callable[[str], tuple[Observed, ...]]   # task -> what is compared
    references: dict[str, str]                        # task -> the variant that is its model answer
    buttons: tuple[str, ...]                          # console inputs that are push buttons
    meaning: dict[str, tuple[str, str]]               # switch -> words for 0 and 1
    # the script again with actions aimed at the moments its model answer's stand changed
    # (rng, task, script, times) -> script; None: random scripts only
    aim: Optional[Callable[[random.Random, str, Script, list[float]], Script]] = None
    # task -> ((switch, ((console switch, value), ...)), ...): a change of `switch` while every
    # console switch listed has its value leaves what follows to the program until one of them
    # changes (and settle_s after): nothing is compared in between (the MP-9C's SA6 flipped
    # mid-run: "SA6 is read at frame boundaries" lets a program take it at the next pause's
    # start or end, or at a press)
    free_after: Callable[[str], tuple[tuple[str, tuple[tuple[str, int], ...]], ...]] = lambda task: ()
    settle_s: float = 0.5
    timing_tol: float = 0.06          # s: how much later or earlier a change may come
    max_drift: float = 1.0            # s: how far a program may lag the model answer in all
    drift_rate: float = 0.0           # s per s: how much more it may lag between two changes the
                                      # longer they are apart (frames nobody sees end: a link
                                      # already at the next frame's position)
    # ST paths of the model answer's inner state (mode, frame, phase, memory count, watchdog
    # fault): scripts that take it to states not seen before are kept and mutated (coverage-guided
    # exploration, plclab.grader.explore); paths a model answer lacks are left out
    state_paths: tuple[str, ...] = ()
    # plant -> a value that stays the same while what `observe` gives does (given its last
    # values): where it is as at the last look, the probe need not look again; None: look at
    # every scan the plant did not stand idle
    unchanged: Optional[Callable[[Any], Any]] = None
    episode_s: float = 45.0           # plant seconds of one random script
    episodes: int = 40                # default budget: scripts per task and program
    tick_s: float = 0.01

    def describe(self, e: Event) -> str:
        """One console step in words: `SA1 = 1 (automatic)`, `SB1 pressed 0.20 s`."""
        if e.name == POWER:
            return f"PLC switched off for {float(e.value):.2f} s, then on again (retained memory kept)"
        if e.name == FAULT:
            name, params = fault_params(e.value)
            args = ", ".join(f"{k} {v}" for k, v in params.items())
            return f"plant fault: {name}" + (f" ({args})" if args else "")
        if e.is_press:
            return f"{e.name} pressed {e.hold:.2f} s"
        words = self.meaning.get(e.name)
        v = e.value.strip()
        if words and v in ("0", "1"):
            return f"{e.name} = {v} ({words[int(v)]})"
        return f"{e.name} = {v}"


# --------------------------------------------------------------------------- the generator

@dataclass
class _Writer:
    """Builds one script: a clock, the console's switch states and the events so far."""

    rng: random.Random
    switches: dict[str, int]
    events: list[Event] = field(default_factory=list)
    t: float = 0.0

    def set(self, name: str, value: int) -> None:
        self.switches[name] = value
        self.events.append(Event(round(self.t, 2), name, str(value)))
        self.t += 0.1

    def flip(self, name: str) -> None:
        self.set(name, 1 - self.switches.get(name, 0))

    def press(self, name: str, hold: float, gap: float = 0.2) -> None:
        self.events.append(Event(round(self.t, 2), name, "1", round(hold, 2)))
        self.t += hold + gap

    def wait(self, seconds: float) -> None:
        self.t += seconds

    def at(self, t: float, name: str, value: str = "1", hold: float = 0.0) -> None:
        self.events.append(Event(round(t, 2), name, value, round(hold, 2)))


def hold_time(rng: random.Random, bounce_max: float = 0.03) -> float:
    """An SB1 hold, as operators press: mostly taps and short presses, sometimes a contact
    bounce (under the 50 ms debounce, up to `bounce_max`), a long press (released before 3 s)
    or a 3-s hold. Holds near a threshold are not drawn (a bounce stays more than a scan
    under 50 ms, the others 0.3 s off 3 s): there one scan decides."""
    r = rng.random()
    if r < 0.12:
        return rng.uniform(0.005, bounce_max)    # bounce
    if r < 0.65:
        return rng.uniform(0.1, 0.35)            # tap
    if r < 0.82:
        return rng.uniform(0.4, 1.5)             # short press
    if r < 0.9:
        return rng.uniform(1.6, 2.7)             # long press, still short of 3 s
    return rng.uniform(3.3, 4.5)                 # a 3-s hold (reset)


@dataclass(frozen=True)
class Console:
    """The console of a robot as the generator needs it."""

    mode: str                        # the mode switch: 0 manual, 1 automatic
    button: str                      # the multipurpose button
    spare: str                       # the spare input of Tasks 2 and 3
    step: Optional[str]              # continuous / step switch, if the stand has one
    teach: Callable[[_Writer, str], None]   # one manual move of the robot (task) before a frame
    faults: Callable[[random.Random, str], str]  # one fault (task) as `name k=v ...`
    capacity: int = 32
    watchdog: float = 10.0
    frame_s: float = 1.5             # s: a typical frame's travel in automatic mode (without its pause)
    bounce_max: float = 0.03         # s: the longest contact bounce drawn; holds are rounded to 10 ms, so
                                     # a bounce stays a scan under the 50 ms debounce


START_S = 0.5          # s: the first action after power-up (the PLC has read its sensors once)


@dataclass
class _Story:
    """What the script has done so far, as far as the generator can know it without the plant:
    the frames recorded since the last reset (an estimate: a bounce records nothing)."""

    frames: int = 0


def generate(console: Console, rng: random.Random, task: str, seconds: float) -> Script:
    """A random operator script of about `seconds`, told as stories an operator lives at the
    console: record a program (sometimes after a reset, the pause chosen per frame), run it and
    interrupt it (a stop and a second run, the spare input turned off and a stop, leaving
    automatic mode mid-frame or mid-pause, a power cycle and a press after it, step presses, a
    press of any length), a playback longer than the watchdog, the memory filled beyond its
    capacity, a plant fault. Interrupts come at any moment of a run, and often in the first
    scans of a frame or of a pause (a phase boundary), where a program's order of statements
    shows."""
    w = _Writer(rng, {console.mode: 0, console.spare: 0, console.button: 0})
    w.t = START_S
    story = _Story()
    faulted = False
    while w.t < seconds:
        r = rng.random()
        if story.frames < 2 or r < 0.22:
            _record(w, console, task, story)
        elif r < 0.62:
            _run(w, console, task, story)
        elif r < 0.70:
            _long_run(w, console)
        elif r < 0.76:
            _power_cycle(w, console)
        elif r < 0.81 and not faulted:
            faulted = True
            running = rng.random() < 0.6
            if running:
                _start(w, console)
                w.wait(rng.uniform(0.0, 2 * console.frame_s))
            w.events.append(Event(round(w.t, 2), FAULT, console.faults(rng, task)))
            # a run with a fault: long enough for the frame watchdog, mostly
            w.wait(rng.uniform(1.05, 1.5) * console.watchdog if running and rng.random() < 0.7
                   else rng.uniform(0.5, 1.5 * console.watchdog))
            if rng.random() < 0.6:                     # what the operator does about it: presses,
                for _ in range(rng.randint(1, 3)):     # in automatic mode or after leaving it
                    if rng.random() < 0.3:
                        w.flip(console.mode)
                        w.wait(rng.uniform(0.2, 1.5))
                    w.press(console.button, rng.uniform(0.1, 0.3), rng.uniform(0.5, 3.0))
        elif r < 0.83:
            _fill_memory(w, console, story)
        elif r < 0.90:                                 # a press of any length, in any mode
            if rng.random() < 0.5:
                w.flip(console.mode)
                w.wait(rng.uniform(0.1, 1.0))
            w.press(console.button, hold_time(rng, console.bounce_max), rng.uniform(0.2, 1.0))
            if w.switches.get(console.mode) == 0 and w.events[-1].hold >= 3.0:
                story.frames = 0
        elif r < 0.95:                                 # the spare input any time; the step switch in
            manual = w.switches.get(console.mode, 0) == 0  # manual mode (flipped mid-run it is free)
            w.flip(console.step if console.step and manual and rng.random() < 0.4 else console.spare)
            w.wait(rng.uniform(0.1, 1.0))
        else:
            w.wait(rng.uniform(0.5, 1.5 * console.watchdog))
    events = sorted(w.events, key=lambda e: e.time)
    return Script(tuple(events), round(max(w.t, seconds) + 3.0, 2))


def _ensure_mode(w: _Writer, console: Console, mode: int) -> None:
    if w.switches.get(console.mode, 0) != mode:
        w.set(console.mode, mode)
        w.wait(w.rng.uniform(0.05, 0.6))


def _record(w: _Writer, console: Console, task: str, story: _Story) -> None:
    """Manual mode, sometimes a reset first (a 3-s hold), then 1..4 frames, the spare input
    set before each (the pause it records) and now and then a bounce or a long press."""
    rng = w.rng
    _ensure_mode(w, console, 0)
    if story.frames and rng.random() < 0.35:
        w.press(console.button, rng.uniform(3.3, 4.5), rng.uniform(0.2, 0.8))
        story.frames = 0
    for _ in range(rng.randint(1, 4) if story.frames else rng.randint(2, 5)):
        console.teach(w, task)
        if rng.random() < 0.6:
            w.set(console.spare, rng.randint(0, 1))
        if rng.random() < 0.12:                        # the contact bounces first
            w.press(console.button, rng.uniform(0.005, console.bounce_max), rng.uniform(0.1, 0.4))
        hold = hold_time(rng, console.bounce_max) if rng.random() < 0.15 else rng.uniform(0.1, 0.4)
        w.press(console.button, hold, rng.uniform(0.2, 0.7))
        if hold >= 3.0:
            story.frames = 0
        elif hold >= 0.05:
            story.frames = min(story.frames + 1, console.capacity)


def _start(w: _Writer, console: Console) -> None:
    """Into automatic mode and SB1 pressed: a start (the spare input mostly on, as Task 3's
    start needs it; the step switch now and then)."""
    rng = w.rng
    if w.switches.get(console.mode, 0) == 1 and rng.random() < 0.7:
        w.set(console.mode, 0)                         # a run may still go on: leaving automatic stops it
        w.wait(rng.uniform(0.1, 0.5))
    if console.step and w.switches.get(console.mode, 0) == 0 and rng.random() < 0.4:
        w.set(console.step, int(rng.random() < 0.6))
    if rng.random() < 0.7:
        w.set(console.spare, int(rng.random() < 0.85))
    _ensure_mode(w, console, 1)
    w.press(console.button, rng.uniform(0.1, 0.35), 0.0)


def _moment(w: _Writer, console: Console) -> float:
    """How long into a run the next interrupt comes: anywhere in the next frames, or (one
    time in three) in the first scans of a phase as far as the generator can tell it (a
    frame's travel ends about every frame_s, a short pause is 0.5 s)."""
    rng = w.rng
    if rng.random() < 0.35:
        base = rng.choice((0.5, 1.0, 3.0)) + console.frame_s * rng.randint(0, 2)
        return base + rng.uniform(0.0, 0.08)
    return rng.expovariate(1 / (1.5 * console.frame_s))


def _run(w: _Writer, console: Console, task: str, story: _Story) -> None:
    """A start, then 1..3 interrupts at any moment of the run, and time for what follows."""
    rng = w.rng
    _start(w, console)
    stepping = bool(console.step) and w.switches.get(console.step or "", 0) == 1
    if stepping and rng.random() < 0.7:                # step mode: the presses that start the frames,
        for _ in range(rng.randint(2, 7)):             # some during a frame or its pause (ignored)
            w.wait(rng.uniform(0.2, console.frame_s + 3.5))
            if rng.random() < 0.15:
                w.flip(console.spare)
            w.press(console.button, rng.uniform(0.1, 0.3), 0.0)
    for _ in range(rng.randint(1, 3)):
        w.wait(_moment(w, console))
        a = rng.random()
        if stepping and a < 0.3:                       # step mode: the presses that start frames
            for _ in range(rng.randint(1, 4)):
                w.press(console.button, rng.uniform(0.1, 0.3), rng.uniform(0.2, 1.5 * console.frame_s + 3.5))
        elif a < 0.30:                                 # a stop, and often a second run after it
            w.press(console.button, rng.uniform(0.1, 0.3), 0.0)
            if rng.random() < 0.6:
                w.wait(rng.uniform(0.3, 3.0))
                if rng.random() < 0.3:
                    w.flip(console.spare)
                w.press(console.button, rng.uniform(0.1, 0.3), 0.0)
        elif a < 0.50:                                 # the spare input flipped: often a stop after it,
            w.flip(console.spare)                      # or flipped back a little later
            b = rng.random()
            if b < 0.6:
                w.wait(rng.uniform(0.1, 2.0 * console.frame_s))
                w.press(console.button, rng.uniform(0.1, 0.3), 0.0)
            elif b < 0.85:
                w.wait(rng.uniform(0.2, 3.0 * console.frame_s + 1.0))
                w.flip(console.spare)
        elif a < 0.64:                                 # leave automatic mode (mid-frame, mid-pause)
            w.set(console.mode, 0)
            if rng.random() < 0.4:
                console.teach(w, task)
            if rng.random() < 0.5:
                w.wait(rng.uniform(0.1, 2.0))
                w.set(console.mode, 1)
                w.wait(rng.uniform(0.1, 1.0))
                w.press(console.button, rng.uniform(0.1, 0.3), 0.0)
            else:
                return
        elif a < 0.76:                                 # a power cycle, and sometimes a press after it
            w.events.append(Event(round(w.t, 2), POWER, f"{round(rng.uniform(0.2, 1.5), 2):g}"))
            w.wait(rng.uniform(1.7, 3.0))
            if rng.random() < 0.5:
                w.press(console.button, rng.uniform(0.1, 0.3), 0.0)
        elif a < 0.86:                                 # a press of any length
            hold = hold_time(rng, console.bounce_max)
            w.press(console.button, hold, 0.0)
        else:                                          # the position switches moved in automatic mode
            console.teach(w, task)
    w.wait(rng.uniform(1.0, 3.0 * console.frame_s + 3.0))


def _long_run(w: _Writer, console: Console) -> None:
    """A playback longer than every watchdog, untouched."""
    _start(w, console)
    w.wait(w.rng.uniform(1.2, 2.0) * console.watchdog)


def _power_cycle(w: _Writer, console: Console) -> None:
    """The PLC switched off and on, in either mode, memory retained."""
    if w.rng.random() < 0.3:
        w.flip(console.mode)
        w.wait(w.rng.uniform(0.1, 1.0))
    w.events.append(Event(round(w.t, 2), POWER, f"{round(w.rng.uniform(0.2, 2.0), 2):g}"))
    w.wait(w.rng.uniform(2.0, 3.0))


def _fill_memory(w: _Writer, console: Console, story: _Story) -> None:
    """The frame memory filled and presses beyond it (the full-memory blink)."""
    rng = w.rng
    _ensure_mode(w, console, 0)
    for _ in range(console.capacity - story.frames):
        w.press(console.button, 0.12, 0.12)
    story.frames = console.capacity
    for _ in range(rng.randint(0, 3)):                 # refused presses, the spare input changed between
        if rng.random() < 0.5:
            w.flip(console.spare)
        w.press(console.button, rng.uniform(0.1, 0.3), rng.uniform(0.2, 2.5))
    w.wait(rng.uniform(0.5, 2.5))
    if rng.random() < 0.5:                             # and the 32 frames played
        _long_run(w, console)


def _switch_at(events: Sequence[Event], name: str, t: float) -> int:
    """The value console switch `name` has at `t` after `events` (in any order; power-up 0)."""
    sets = [e for e in events if e.name == name and not e.is_press and e.time <= t]
    return int(float(max(sets, key=lambda e: e.time).value)) if sets else 0


def aim(console: Console, rng: random.Random, task: str, script: Script, times: Sequence[float]) -> Script:
    """`script` with one or two actions added at the moments its model answer's stand changed
    (`times`: a frame started, a mechanism arrived, a link came to rest, HL1 changed), in that
    very scan, a scan or two before or after, within the half second before or the second
    after: a press, the spare input flipped
    (and often back), automatic mode left (and often entered again, with a press), a power
    cycle. Phase boundaries are where the order of a program's statements shows; a random
    script reaches them only by chance."""
    times = [t for t in times if START_S <= t < script.duration - 2.0]
    if not times:
        return script
    events = list(script.events)
    for _ in range(rng.randint(1, 2)):
        t = rng.choice(times) + rng.choice((0.0, 0.01, 0.02, -0.02, -rng.uniform(0.0, 0.5), rng.uniform(0.0, 0.3),
                                            rng.uniform(0.3, 1.2)))
        t = round(t, 2)
        a = rng.random()
        if a < 0.35:
            value = 1 - _switch_at(events, console.spare, t)
            events.append(Event(t, console.spare, str(value)))
            b = rng.random()
            if b < 0.35:                               # and back a little later
                events.append(Event(round(t + rng.uniform(0.3, 2.0), 2), console.spare, str(1 - value)))
            elif b < 0.8:                              # and a press after it
                events.append(Event(round(t + rng.uniform(0.2, 2.0), 2), console.button, "1",
                                    round(rng.uniform(0.1, 0.3), 2)))
        elif a < 0.6:
            events.append(Event(t, console.button, "1", round(rng.uniform(0.1, 0.3), 2)))
        elif a < 0.8:
            mode = _switch_at(events, console.mode, t)
            events.append(Event(t, console.mode, str(1 - mode)))
            if rng.random() < 0.5:
                back = round(t + rng.uniform(0.3, 2.0), 2)
                events.append(Event(back, console.mode, str(mode)))
                events.append(Event(round(back + rng.uniform(0.2, 0.8), 2), console.button, "1",
                                    round(rng.uniform(0.1, 0.3), 2)))
        else:
            events.append(Event(t, POWER, f"{round(rng.uniform(0.2, 1.5), 2):g}"))
    events.sort(key=lambda e: e.time)
    last = max(e.time + e.hold for e in events)
    return Script(tuple(events), round(max(script.duration, last + 3.0), 2))


__all__ = ["BLINKING", "BLINK_END_TOL", "Console", "Exploration", "Observed", "START_S", "aim", "blink_spans",
           "generate", "hold_time", "lamp_pattern", "lamp_timing", "show_lamp"]
