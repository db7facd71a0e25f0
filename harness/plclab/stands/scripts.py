"""Operator scripts and their file form: what an operator at a robot's console did, in order.

A script is a list of `Event`s: a switch set, a button held for some time, a PLC power cycle
(`PLC`, the seconds it stays off: the retained memory is kept), a plant fault (`FAULT`,
`name param=value ...`). Its file form is the input-CSV format of traces (`time_s,name,value`):
a switch row sets it, a button's 1 and 0 rows are its press and release, `END` marks how long
the script runs. The grader's exploration writes such files next to its traces; `plclab run
STAND --program FILE.st --inputs SCRIPT.csv` and the browser lab replay them, both through
the one reader here (`read_steps`: every row checked, `FILE:LINE: error: ...`), each saying
only which names its console knows (a `Vocabulary`).
"""
from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence

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


MAX_OFF_S = 600.0      # s: the longest power cycle a script row may ask for
MAX_SCRIPT_BYTES = 256 * 1024       # an operator script of a few minutes is a few kB


@dataclass(frozen=True)
class Step:
    """One row of a script file, checked and resolved: `kind` 'switch' | 'button' | 'knob' |
    'power' | 'fault' | 'end'; `target` the name the caller acts on (a console input, a knob,
    a fault); `value` 0 / 1, the knob's value, the off time or the fault's `name k=v` text."""

    time: float
    line: int
    kind: str
    target: str
    value: Any
    text: str            # the row as a console log shows it: 'SB1 = 1'


@dataclass(frozen=True)
class Vocabulary:
    """What the rows of a script may name on one stand: console contacts under any of their
    names (label, plant name, address: compared without case, '%' and '.', so I0.7, I07 and
    %IX0.7 alike), settings with their ranges, and the plant's faults with their parameters."""

    stand: str
    controls: dict[str, tuple[str, str]]               # name -> (kind 'switch'|'button', target)
    listed: tuple[str, ...]                            # the names an error lists
    faults: dict[str, tuple[str, ...]] = field(default_factory=dict)   # fault -> its parameters
    knobs: dict[str, tuple[str, int, int, str]] = field(default_factory=dict)  # name -> (label, lo, hi, unit)

    @staticmethod
    def norm(name: str) -> str:
        return name.strip().upper().replace("%", "").replace(".", "")

    def control(self, name: str) -> Optional[tuple[str, str]]:
        return self.controls.get(self.norm(name))

    def knob(self, name: str) -> Optional[tuple[str, int, int, str]]:
        return self.knobs.get(self.norm(name))


def power_off_time(text: str) -> float:
    """A PLC row's value: the seconds the PLC stays off (0..MAX_OFF_S)."""
    try:
        off = float(text)
    except ValueError:
        off = -1.0
    if not 0 <= off <= MAX_OFF_S:
        raise PlcLabError(f"{POWER} takes the seconds the PLC stays off (0..{MAX_OFF_S:g}), not {text!r}")
    return off


def checked_fault(text: str, faults: dict[str, tuple[str, ...]]) -> tuple[str, dict[str, Any]]:
    """A FAULT row's value `name k=v ...`, its name one of the stand's faults and every
    parameter one of that fault's (the values are the plant's to judge when it is injected)."""
    if not text.split():
        raise PlcLabError(f"FAULT takes 'name param=value ...' with a fault of this stand "
                          f"({', '.join(faults) or 'none'}), not {text!r}")
    name, params = fault_params(text)
    if name not in faults:
        raise PlcLabError(f"unknown fault {name!r} (one of {', '.join(faults) or 'none'}): FAULT takes "
                          "'name param=value ...'")
    for k in params:
        if k not in faults[name]:
            raise PlcLabError(f"fault {name} has no parameter {k!r} (it has: {', '.join(faults[name]) or 'none'})")
    return name, params


def parse_rows(rows: Sequence[Any], where: str, vocab: Vocabulary) -> list[Step]:
    """The steps of a script's rows (plclab.trace.csvio rows: time_ns, line, name, text), every
    row checked: a bad one is `WHERE:LINE: error: ...`, before anything runs."""
    from plclab.trace.csvio import TraceFormatError
    steps: list[Step] = []
    for r in rows:
        t, text, word = r.time_ns / 1e9, r.text.strip(), r.name.strip()
        try:
            steps.append(_step(t, r.line, word, text, vocab))
        except PlcLabError as e:
            raise TraceFormatError(where, r.line, str(e)) from None
        if steps[-1].kind == "end":
            break
    if not steps:
        raise PlcLabError(f"{where}: no rows: an input script has rows time_s,name,value")
    return steps


def _step(t: float, line: int, word: str, text: str, vocab: Vocabulary) -> Step:
    if word.upper() == END:
        return Step(t, line, "end", END, None, "END")
    if word.upper() == POWER:
        off = power_off_time(text)
        return Step(t, line, "power", POWER, off, f"PLC off {off:g} s")
    if word.upper() == FAULT:
        checked_fault(text, vocab.faults)
        return Step(t, line, "fault", text.split()[0], text, f"FAULT {text}")
    knob = vocab.knob(word)
    if knob is not None:
        label, lo, hi, unit = knob
        try:
            value = int(text)
        except ValueError:
            raise PlcLabError(f"{label} takes a whole number {lo}..{hi}, not {text!r}") from None
        if not lo <= value <= hi:
            raise PlcLabError(f"{label}: {value} is outside {lo}..{hi} {unit}")
        return Step(t, line, "knob", label, value, f"{label} = {value}")
    control = vocab.control(word)
    if control is None:
        raise PlcLabError(f"{word!r} is no console input of {vocab.stand} (one of {', '.join(vocab.listed)}, "
                          f"or their addresses; {POWER}, {FAULT}, {END})")
    kind, target = control
    if text not in ("0", "1"):
        raise PlcLabError(f"{target} takes 0 or 1, not {text!r}")
    return Step(t, line, kind, target, int(text), f"{target} = {text}")


def read_steps(data: bytes, where: str, vocab: Vocabulary) -> list[Step]:
    """A script file's bytes -> its checked steps (at most MAX_SCRIPT_BYTES)."""
    from plclab.trace.csvio import decode_text, read_rows
    if len(data) > MAX_SCRIPT_BYTES:
        raise PlcLabError(f"{where}: larger than {MAX_SCRIPT_BYTES // 1024} KiB: not an input script")
    return parse_rows(read_rows(_Named(decode_text(data, where), where)), where, vocab)


class _Named(io.StringIO):
    def __init__(self, text: str, name: str):
        super().__init__(text, newline="")
        self.name = name


def script_of(steps: Sequence[Step]) -> Script:
    """Checked steps -> a Script: a button's 1 row opens a press its 0 row closes (a button
    still held at END is held to the end); without an END row the script runs 5 s past its
    last action."""
    events: list[Event] = []
    open_press: dict[str, float] = {}
    end = None
    for st in steps:
        if st.kind == "end":
            end = st.time
            break
        if st.kind == "button":
            if st.value:
                open_press.setdefault(st.target, st.time)
            elif st.target in open_press:
                start = open_press.pop(st.target)
                events.append(Event(start, st.target, "1", max(round(st.time - start, 6), 1e-3)))
        elif st.kind == "power":
            events.append(Event(st.time, POWER, f"{st.value:g}"))
        elif st.kind == "fault":
            events.append(Event(st.time, FAULT, st.value))
        else:
            events.append(Event(st.time, st.target, str(st.value)))
    last = max((e.time + e.hold for e in events), default=0.0)
    duration = end if end is not None else last + 5.0
    for name, start in open_press.items():
        events.append(Event(start, name, "1", max(round(duration - start, 6), 1e-3)))
    return Script(tuple(sorted(events, key=lambda e: e.time)), duration)


def stand_vocabulary(spec: Any, labels: Optional[dict[str, str]] = None) -> Vocabulary:
    """The names a script may use on a robot (StandSpec `spec`): its console inputs (buttons
    the exploration declares) and their addresses (`labels`: signal -> address), its faults."""
    buttons = set(spec.explore.buttons) if spec.explore is not None else set()
    controls: dict[str, tuple[str, str]] = {}
    for name in spec.console:
        entry = ("button" if name in buttons else "switch", name)
        for key in (name, (labels or {}).get(name, "")):
            if key:
                controls.setdefault(Vocabulary.norm(key), entry)
    faults = {f.name: tuple(p.name for p in f.params) for f in spec.faults}
    return Vocabulary(spec.name, controls, tuple(spec.console), faults)


def read_script(path: str, spec: Any, labels: Optional[dict[str, str]] = None) -> Script:
    """An operator script file for robot `spec` (plclab run --inputs), every row checked."""
    from plclab.fileio import InputError, read_input
    try:
        data = read_input(path, limit=MAX_SCRIPT_BYTES)
    except InputError as e:
        raise PlcLabError(f"{path}: {e}") from None
    return script_of(read_steps(data, path, stand_vocabulary(spec, labels)))


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


def without(script: Script, drop: set[int]) -> Script:
    return Script(tuple(e for i, e in enumerate(script.events) if i not in drop), script.duration)


def with_event(script: Script, i: int, e: Event) -> Script:
    events = list(script.events)
    events[i] = e
    return Script(tuple(sorted(events, key=lambda x: x.time)), script.duration)


__all__ = ["END", "Event", "FAULT", "MAX_OFF_S", "MAX_SCRIPT_BYTES", "POWER", "Script", "Step", "Vocabulary",
           "checked_fault", "fault_params", "parse_rows", "power_off_time", "read_script", "read_steps",
           "script_of", "stand_vocabulary", "with_event", "without"]
