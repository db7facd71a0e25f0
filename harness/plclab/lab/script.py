"""Input scripts replayed in the lab (issue #21 item 3): an operator script in the input-CSV
format of traces (`time_s,name,value`), as the grader's exploration writes them next to its
traces and `plclab run --inputs` replays them. The rows are read and checked by the one
reader of operator scripts (plclab.stands.scripts.read_steps); the lab only says which names
its page knows.

A row names a console control by its label (`SA1`, `SB1`, `I0.7`), its plant name (`I07`) or
the address it is wired to (`%IX1.6`): a switch row sets it (0 / 1), a push button's 1 and
0 rows are its press and release, a setting (the CNC's RP1) takes its value. `PLC` with the
seconds it stays off is a power cycle of the controller, `FAULT` with `name k=v ...` injects
a plant fault, `END` ends the script. Every row is checked before anything runs: a bad one is
`FILE:LINE: error: ...`.
"""
from __future__ import annotations

from plclab.lab.panels import Panel
from plclab.stands.scripts import MAX_SCRIPT_BYTES, Step, Vocabulary, read_steps

__all__ = ["MAX_SCRIPT_BYTES", "Step", "parse_script", "vocabulary"]


def vocabulary(panel: Panel, labels: dict[str, str]) -> Vocabulary:
    """The names the page's controls answer to (label, plant name, address), its settings and
    its faults; a step's target is the control's label."""
    controls: dict[str, tuple[str, str]] = {}
    for c in panel.controls:
        for key in (c.label, c.input, labels.get(c.signal, "")):
            if key:
                controls.setdefault(Vocabulary.norm(key), (c.kind, c.label))
    knobs = {Vocabulary.norm(k.label): (k.label, k.lo, k.hi, k.unit) for k in panel.knobs}
    faults = {f.name: tuple(p.name for p in f.params) for f in panel.faults}
    return Vocabulary(panel.stand, controls, tuple(c.label for c in panel.controls), faults, knobs)


def parse_script(data: bytes, name: str, panel: Panel, labels: dict[str, str]) -> list[Step]:
    """The steps of script `data` (file `name`) on the stand of `panel`, every row checked."""
    return read_steps(data, name, vocabulary(panel, labels))
