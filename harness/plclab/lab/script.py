"""Input scripts replayed in the lab (issue #21 item 3): an operator script in the input-CSV
format of traces (`time_s,name,value`, read by plclab.trace.csvio.read_rows, the one reader),
as the grader's exploration writes them next to its traces and `plclab run --inputs` replays
them.

A row names a console control by its label (`SA1`, `SB1`, `I0.7`), its plant name (`I07`) or
the address it is wired to (`%IX1.6`): a switch row sets it (0 / 1), a push button's 1 and
0 rows are its press and release, a setting (the CNC's RP1) takes its value. `PLC` with the
seconds it stays off is a power cycle of the controller, `FAULT` with `name k=v ...` injects
a plant fault, `END` ends the script. Every row is checked before anything runs: a bad one is
`FILE:LINE: error: ...`.
"""
from __future__ import annotations

import io
from dataclasses import dataclass
from typing import Any

from plclab.errors import PlcLabError
from plclab.lab.panels import Panel
from plclab.trace.csvio import TraceFormatError, decode_text, read_rows

MAX_SCRIPT_BYTES = 256 * 1024       # an operator script of a few minutes is a few kB
POWER, FAULT, END = "PLC", "FAULT", "END"


@dataclass(frozen=True)
class Step:
    """One row of a script, resolved: `kind` 'switch' | 'button' | 'knob' | 'power' | 'fault' | 'end'."""

    time: float
    line: int
    kind: str
    target: str          # the console label (switch, button, knob), the fault's name
    value: Any           # 0 / 1, the knob's value, the off time, the fault's parameters
    text: str            # the row as the console log shows it: 'SB1 = 1'


class _Named(io.StringIO):
    def __init__(self, text: str, name: str):
        super().__init__(text, newline="")
        self.name = name


def parse_script(data: bytes, name: str, panel: Panel, labels: dict[str, str]) -> list[Step]:
    """The steps of script `data` (file `name`) on the stand of `panel`, every row checked."""
    if len(data) > MAX_SCRIPT_BYTES:
        raise PlcLabError(f"{name}: larger than {MAX_SCRIPT_BYTES // 1024} KiB: not an input script")
    rows = read_rows(_Named(decode_text(data, name), name))
    by_name: dict[str, Any] = {}
    for c in panel.controls:
        for key in (c.label, c.input, labels.get(c.signal, "")):
            if key:
                by_name.setdefault(_norm(key), c)
    knobs = {_norm(k.label): k for k in panel.knobs}
    steps: list[Step] = []
    for r in rows:
        def fail(message: str) -> TraceFormatError:
            return TraceFormatError(name, r.line, message)
        t, text = r.time_ns / 1e9, r.text.strip()
        word = r.name.strip()
        if word.upper() == END:
            steps.append(Step(t, r.line, "end", END, None, "END"))
            break
        if word.upper() == POWER:
            try:
                off = float(text)
            except ValueError:
                off = -1.0
            if not 0 <= off <= 600:
                raise fail(f"PLC takes the seconds the PLC stays off (0..600), not {text!r}")
            steps.append(Step(t, r.line, "power", POWER, off, f"PLC off {off:g} s"))
            continue
        if word.upper() == FAULT:
            parts = text.split()
            faults = {f.name: f for f in panel.faults}
            if not parts or parts[0] not in faults:
                raise fail(f"FAULT takes 'name param=value ...' with a fault of this stand "
                           f"({', '.join(faults) or 'none'}), not {text!r}")
            params = {}
            for p in parts[1:]:
                key, eq, value = p.partition("=")
                if not eq or key not in {fp.name for fp in faults[parts[0]].params}:
                    raise fail(f"FAULT {parts[0]}: {p!r} is not one of its parameters as name=value")
                params[key] = value
            steps.append(Step(t, r.line, "fault", parts[0], params, f"FAULT {text}"))
            continue
        knob = knobs.get(_norm(word))
        if knob is not None:
            try:
                value = int(text)
            except ValueError:
                raise fail(f"{knob.label} takes a whole number {knob.lo}..{knob.hi}, not {text!r}") from None
            if not knob.lo <= value <= knob.hi:
                raise fail(f"{knob.label}: {value} is outside {knob.lo}..{knob.hi} {knob.unit}")
            steps.append(Step(t, r.line, "knob", knob.label, value, f"{knob.label} = {value}"))
            continue
        control = by_name.get(_norm(word))
        if control is None:
            raise fail(f"{word!r} is no console input of {panel.stand} (one of "
                       f"{', '.join(c.label for c in panel.controls)}, or their addresses; PLC, FAULT, END)")
        if text not in ("0", "1"):
            raise fail(f"{control.label} takes 0 or 1, not {text!r}")
        steps.append(Step(t, r.line, control.kind, control.label, int(text), f"{control.label} = {text}"))
    if not steps:
        raise PlcLabError(f"{name}: no rows: an input script has rows time_s,name,value")
    return steps


def _norm(name: str) -> str:
    return name.strip().upper().replace("%", "")
