"""The robots' reference solutions as edits of the students' starting program.

A lab task asks the student to change the starting program (the textbook's appendix program
in ST), so its reference solution is that program with the task's changes: `solutions/
<stand>.toml` in a checkout lists them, POU by POU, as (old, new, count) text edits. Nothing
is copied: a starting block the task does not touch is the shipped file itself, and the
starting program's diff to a reference (`outline`) is exactly what a student has to write.
`full` applies the edits of the tasks it names, in order, then its own.

The file lives in the repository only (instructors, tests); an installed package has no
`solutions/`, and the stands refuse a reference variant there before reaching this module.
"""
from __future__ import annotations

import difflib
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from plclab.errors import PlcLabError


@dataclass(frozen=True)
class Edit:
    pou: str           # file stem of the POU it changes
    old: str
    new: str
    count: int = 1     # how often `old` occurs in that file when this edit is applied


@lru_cache(maxsize=None)
def _table(path: Path) -> dict:
    try:
        with path.open("rb") as f:
            return tomllib.load(f)
    except FileNotFoundError:
        raise PlcLabError(f"{path}: missing (the reference solutions' edits)") from None
    except tomllib.TOMLDecodeError as e:
        raise PlcLabError(f"{path}: {e}") from None


def variant_table(path: Path, variant: str) -> dict:
    """The `[variant]` table of a solutions file (doc, tasks, edit)."""
    table = _table(path)
    if variant not in table:
        raise PlcLabError(f"{path}: no [{variant}] section (has: {', '.join(table)})")
    return table[variant]


def edits(path: Path, variant: str) -> list[Edit]:
    """The edits that make `variant` from the starting program, in the order they apply."""
    section = variant_table(path, variant)
    out: list[Edit] = []
    for task in section.get("tasks", []):
        if task == variant:
            raise PlcLabError(f"{path}: [{variant}] names itself in tasks")
        out += edits(path, task)
    for n, e in enumerate(section.get("edit", []), 1):
        try:
            out.append(Edit(str(e["pou"]), str(e["old"]), str(e["new"]), int(e.get("count", 1))))
        except KeyError as missing:
            raise PlcLabError(f"{path}: [{variant}] edit {n}: no key {missing}") from None
    return out


def apply(path: Path, variant: str, texts: dict[str, str]) -> dict[str, str]:
    """`texts` (POU stem -> starting text) with `variant`'s edits made: an edit whose `old`
    does not occur exactly `count` times is one clear error, so a change of the starting
    program can never silently leave a reference half made."""
    out = dict(texts)
    for n, e in enumerate(edits(path, variant), 1):
        if e.pou not in out:
            raise PlcLabError(f"{path}: [{variant}] edit {n}: POU {e.pou} is not in the starting program")
        found = out[e.pou].count(e.old)
        if found != e.count:
            raise PlcLabError(f"{path}: [{variant}] edit {n} ({e.pou}): {e.old.strip()[:60]!r} occurs "
                              f"{found} times, not {e.count}")
        out[e.pou] = out[e.pou].replace(e.old, e.new)
    return out


def outline(start: dict[str, tuple[str, str]], answer: dict[str, str]) -> str:
    """The unified diff from the starting program (stem -> (shown path, text)) to a
    reference (stem -> text): what a student changes, file by file."""
    parts: list[str] = []
    for stem, (shown, text) in start.items():
        if answer[stem] != text:
            parts += difflib.unified_diff(text.splitlines(keepends=True), answer[stem].splitlines(keepends=True),
                                          f"a/{shown}", f"b/{shown}")
    return "".join(parts)
