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

A script is a list of `Event`s. Its file form is the input-CSV format of traces (`time_s,name,
value`): a switch row sets it, a button's 1 and 0 rows are its press and release, `PLC` with
the seconds it stays off is a power cycle of the controller, `FAULT` with `name k=v ...`
injects a plant fault, and `END` marks how long the script runs. `plclab run STAND --program
FILE.st --inputs SCRIPT.csv` replays such a file.
"""
from __future__ import annotations

import csv
import io
import random
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Optional, Sequence

from plclab.errors import PlcLabError

POWER = "PLC"          # row name: the PLC is switched off for `value` seconds, then on again
FAULT = "FAULT"        # row name: a plant fault injected, value `name param=value ...`
END = "END"            # row name: the script ends here (its value is ignored)


@dataclass(frozen=True)
class Event:
    """One console action: a switch set (`hold` 0), a button held `hold` s, a power cycle
    (`name` PLC, `value` the off time in s) or a plant fault (`name` FAULT)."""

    time: float
    name: str
    value: str = "1"
    hold: float = 0.0

    @property
    def is_press(self) -> bool:
        return self.hold > 0


@dataclass(frozen=True)
class Script:
    events: tuple[Event, ...]
    duration: float

    def rows(self) -> list[tuple[float, str, str]]:
        """The script as (time_s, name, value) rows, sorted by time (input-CSV form)."""
        rows: list[tuple[float, str, str]] = []
        for e in self.events:
            if e.is_press:
                rows.append((e.time, e.name, "1"))
                rows.append((min(e.time + e.hold, self.duration), e.name, "0"))
            else:
                rows.append((e.time, e.name, e.value))
        rows.append((self.duration, END, "0"))
        rows = [(round(t, 3), n, v) for t, n, v in rows]
        return sorted(rows, key=lambda r: r[0])

    def csv_text(self) -> str:
        out = io.StringIO()
        w = csv.writer(out, lineterminator="\n")
        w.writerow(("time_s", "name", "value"))
        for t, n, v in self.rows():
            w.writerow((f"{t:.3f}", n, v))
        return out.getvalue()

    @property
    def plant_seconds(self) -> float:
        return self.duration


def script_from_rows(rows: Sequence[tuple[float, str, str]], buttons: Sequence[str],
                     where: str = "script") -> Script:
    """Rows (time_s, name, value) -> a Script: a button's 1 row opens a press its 0 row closes
    (a button still held at END is held to the end)."""
    events: list[Event] = []
    open_press: dict[str, float] = {}
    end = None
    for t, name, value in rows:
        if name == END:
            end = t
            break
        if name in buttons:
            if _bit(value, where, name):
                open_press.setdefault(name, t)
            elif name in open_press:
                start = open_press.pop(name)
                events.append(Event(start, name, "1", max(t - start, 1e-3)))
            continue
        events.append(Event(t, name, value.strip()))
    last = max((e.time + e.hold for e in events), default=0.0)
    duration = end if end is not None else last + 5.0
    for name, start in open_press.items():
        events.append(Event(start, name, "1", max(duration - start, 1e-3)))
    return Script(tuple(sorted(events, key=lambda e: e.time)), duration)


def _bit(value: str, where: str, name: str) -> int:
    v = value.strip()
    if v not in ("0", "1"):
        raise PlcLabError(f"{where}: {name} takes 0 or 1, not {v!r}")
    return int(v)


def fault_params(text: str) -> tuple[str, dict[str, Any]]:
    """`jammed mechanism=lift` -> ('jammed', {'mechanism': 'lift'}) (numbers as numbers)."""
    parts = text.split()
    if not parts:
        raise PlcLabError("FAULT row without a fault name")
    params: dict[str, Any] = {}
    for p in parts[1:]:
        if "=" not in p:
            raise PlcLabError(f"FAULT {parts[0]}: parameter {p!r} is not name=value")
        k, v = p.split("=", 1)
        try:
            params[k] = int(v)
        except ValueError:
            try:
                params[k] = float(v)
            except ValueError:
                params[k] = v
    return parts[0], params


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

    def equal(self, a: Any, b: Any) -> bool:
        return a == b if self.same is None else self.same(a, b)


@dataclass(frozen=True)
class Exploration:
    """What a stand declares for exploration (see the module docstring)."""

    generate: Callable[[random.Random, str, float], Script]
    observe: Callable[[Any, Any], dict[str, Any]]     # (plant, last values) -> observed and guard values
    compared: Callable[[str], tuple[Observed, ...]]   # task -> what is compared
    references: dict[str, str]                        # task -> the variant that is its model answer
    buttons: tuple[str, ...]                          # console inputs that are push buttons
    meaning: dict[str, tuple[str, str]]               # switch -> words for 0 and 1
    timing_tol: float = 0.06          # s: how much later or earlier a change may come
    max_drift: float = 1.0            # s: how far a program may lag the model answer in all
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


def hold_time(rng: random.Random) -> float:
    """An SB1 hold, as operators press: mostly taps and short presses, sometimes a contact
    bounce (under the 50 ms debounce), a long press (released before 3 s) or a 3-s hold. Holds
    within 0.15 s of a threshold (50 ms, 3 s) are not drawn: there one scan decides."""
    r = rng.random()
    if r < 0.12:
        return rng.uniform(0.005, 0.03)          # bounce
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
    faults: Callable[[random.Random], str]  # one fault as `name k=v ...`
    capacity: int = 32
    watchdog: float = 10.0


def generate(console: Console, rng: random.Random, task: str, seconds: float) -> Script:
    """A random operator script of about `seconds`: phrases (teach frames, play them back,
    reset, fill the memory, power cycle, a fault...) with actions at any moment inside them."""
    w = _Writer(rng, {console.mode: 0, console.spare: 0, console.button: 0})
    faulted = False
    while w.t < seconds:
        r = rng.random()
        manual = not w.switches.get(console.mode)
        if r < 0.28:                                   # teach 1..4 frames
            if not manual:
                w.set(console.mode, 0)
                w.wait(rng.uniform(0.1, 0.6))
            for _ in range(rng.randint(1, 4)):
                console.teach(w, task)
                if rng.random() < 0.5:
                    w.set(console.spare, rng.randint(0, 1))
                w.press(console.button, rng.uniform(0.1, 0.4), rng.uniform(0.2, 0.7))
        elif r < 0.36:                                 # a long playback: longer than the watchdog
            if manual:
                w.set(console.mode, 1)
                w.wait(rng.uniform(0.1, 0.5))
            w.press(console.button, rng.uniform(0.1, 0.35), 0.0)
            w.wait(rng.uniform(1.2, 2.0) * console.watchdog)
        elif r < 0.55:                                 # play back, with actions during it
            if console.step and rng.random() < 0.4:
                w.set(console.step, rng.randint(0, 1))
            if rng.random() < 0.8:
                w.set(console.spare, int(rng.random() < 0.75))
            if manual:
                w.set(console.mode, 1)
                w.wait(rng.uniform(0.1, 0.5))
            w.press(console.button, rng.uniform(0.1, 0.35), 0.0)
            end = w.t + rng.uniform(2.0, 3 * console.watchdog)
            while True:
                w.wait(rng.expovariate(1 / 3.0))
                if w.t >= end:
                    break
                a = rng.random()
                if a < 0.3:
                    w.flip(console.spare)
                elif a < 0.6:
                    w.press(console.button, hold_time(rng) if rng.random() < 0.3 else rng.uniform(0.1, 0.3), 0.0)
                elif a < 0.7 and console.step:
                    w.flip(console.step)
                elif a < 0.75:
                    console.teach(w, task)             # the position switches in automatic mode
                elif a < 0.85:
                    w.set(console.mode, 0)             # leave automatic mode (mid-frame, mid-pause)
                    break
                else:
                    w.events.append(Event(round(w.t, 2), POWER, f"{rng.uniform(0.2, 1.5):.2f}"))
                    w.wait(2.0)
        elif r < 0.63:                                 # a press of any length, in any mode
            w.press(console.button, hold_time(rng), rng.uniform(0.2, 1.0))
        elif r < 0.68 and manual:                      # a 3-s hold: reset
            w.press(console.button, rng.uniform(3.3, 4.5), rng.uniform(0.3, 1.0))
        elif r < 0.75:
            w.flip(console.spare)
        elif r < 0.80:
            w.flip(console.mode)
        elif r < 0.85:                                 # power cycle, memory retained
            w.events.append(Event(round(w.t, 2), POWER, f"{rng.uniform(0.2, 2.0):.2f}"))
            w.wait(rng.uniform(2.0, 3.0))
        elif r < 0.88 and manual:                      # fill the frame memory and go beyond
            for _ in range(console.capacity + rng.randint(0, 3)):
                w.press(console.button, 0.12, 0.12)
            w.wait(2.5)
        elif r < 0.91 and not faulted:
            faulted = True
            w.events.append(Event(round(w.t, 2), FAULT, console.faults(rng)))
            w.wait(0.5)
        elif r < 0.95 and console.step:
            w.flip(console.step)
        else:
            w.wait(rng.uniform(0.5, 1.5 * console.watchdog))
    events = sorted(w.events, key=lambda e: e.time)
    return Script(tuple(events), round(max(w.t, seconds) + 3.0, 2))


def without(script: Script, drop: set[int]) -> Script:
    return Script(tuple(e for i, e in enumerate(script.events) if i not in drop), script.duration)


def with_event(script: Script, i: int, e: Event) -> Script:
    events = list(script.events)
    events[i] = e
    return Script(tuple(sorted(events, key=lambda x: x.time)), script.duration)


__all__ = ["Console", "END", "Event", "Exploration", "FAULT", "Observed", "POWER", "Script", "fault_params",
           "generate", "hold_time", "replace", "script_from_rows", "with_event", "without"]
