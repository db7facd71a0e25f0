"""The G-code front end: a part program (ISO 6983 subset, textbook 4.1.3) -> frames.

Supported: G00 G01 G02 G03 (arcs by I/J or R), G17, G20/G21, G90/G91, F, X/Y/Z, N (block
numbers), comments in parentheses or after ';', '%' lines; S, M, T and O words are ignored
with a note. Anything else is one `file:line:col: error: ...` line and nothing runs.
Tool-radius correction (G40/G41/G42 with D) is recognised and refused: it is not built yet.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from plclab.errors import PlcLabError

SUPPORTED = "G00 G01 G02 G03 (I/J or R) G17 G20 G21 G90 G91 F X Y Z N; S M T O ignored"
ARC_TOLERANCE_MM = 0.01          # the end of an arc may miss its circle by this much
RAPID_MM_MIN = 600.0             # G00: the stand's largest feed (one step per fine cycle)
WORD = re.compile(r"\s*([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")


@dataclass(frozen=True)
class Frame:
    """One block of motion, absolute mm: `kind` 0 G00, 1 G01, 2 G02, 3 G03; (i, j) the arc's
    centre relative to the start; `feed` mm/min; `line` the source line."""

    kind: int
    start: tuple[float, float, float]
    end: tuple[float, float, float]
    i: float = 0.0
    j: float = 0.0
    feed: float = 0.0
    line: int = 0

    @property
    def is_arc(self) -> bool:
        return self.kind in (2, 3)

    @property
    def centre(self) -> tuple[float, float]:
        return self.start[0] + self.i, self.start[1] + self.j


@dataclass
class Program:
    frames: list[Frame] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


class GcodeError(PlcLabError):
    """A bad part program: `file:line:col: error: ...`."""


def parse_file(path: str | Path) -> Program:
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise PlcLabError(f"{p}: cannot read the part program ({e})") from None
    return parse(text, str(p))


def parse(text: str, filename: str = "<part>") -> Program:
    prog = Program()
    pos = [0.0, 0.0, 0.0]
    motion, absolute, scale, feed = 0, True, 1.0, 0.0
    ignored: set[str] = set()
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = _strip_comments(raw, filename, lineno)
        if not line.strip() or line.strip() == "%":
            continue
        words: dict[str, tuple[float, int]] = {}
        gcodes: list[tuple[int, int]] = []
        col = 0
        while col < len(line):
            if line[col].isspace():
                col += 1
                continue
            m = WORD.match(line, col)
            if not m:
                raise GcodeError(f"{filename}:{lineno}:{col + 1}: error: cannot read '{line[col:].split()[0]}' "
                                 f"(supported: {SUPPORTED})")
            letter, value = m.group(1).upper(), float(m.group(2))
            wcol = col + len(m.group(0)) - len(m.group(0).lstrip()) + 1
            col = m.end()
            if letter == "G":
                gcodes.append((round(value), wcol))
            elif letter in "XYZIJRF":
                if letter in words:
                    raise GcodeError(f"{filename}:{lineno}:{wcol}: error: '{letter}' twice in one block")
                words[letter] = (value, wcol)
            elif letter in "SMTO":
                ignored.add(letter)
            elif letter == "N":
                pass
            elif letter == "D":
                words[letter] = (value, wcol)
            else:
                raise GcodeError(f"{filename}:{lineno}:{wcol}: error: unknown word '{m.group(0).strip()}' "
                                 f"(supported: {SUPPORTED})")
        for g, gcol in gcodes:
            if g in (0, 1, 2, 3):
                motion = g
            elif g == 90:
                absolute = True
            elif g == 91:
                absolute = False
            elif g == 20:
                scale = 25.4
            elif g == 21:
                scale = 1.0
            elif g == 17:
                pass
            elif g in (40, 41, 42):
                raise GcodeError(f"{filename}:{lineno}:{gcol}: error: G{g}: tool-radius correction is not "
                                 f"supported by this version (supported: {SUPPORTED})")
            else:
                raise GcodeError(f"{filename}:{lineno}:{gcol}: error: unknown word 'G{g:02d}' "
                                 f"(supported: {SUPPORTED})")
        if "D" in words:
            raise GcodeError(f"{filename}:{lineno}:{words['D'][1]}: error: D (tool radius) is not supported "
                             f"by this version (supported: {SUPPORTED})")
        if "F" in words:
            feed = words["F"][0] * scale
            if feed <= 0:
                raise GcodeError(f"{filename}:{lineno}:{words['F'][1]}: error: feed F must be > 0")
        if not any(a in words for a in "XYZ"):
            if any(a in words for a in "IJR"):
                c = min(words[a][1] for a in "IJR" if a in words)
                raise GcodeError(f"{filename}:{lineno}:{c}: error: an arc needs its end point (X/Y)")
            continue
        end = list(pos)
        for k, axis in enumerate("XYZ"):
            if axis in words:
                v = words[axis][0] * scale
                end[k] = v if absolute else pos[k] + v
        start = tuple(pos)
        first_col = min(c for _v, c in words.values())
        if motion in (1, 2, 3) and feed <= 0:
            raise GcodeError(f"{filename}:{lineno}:{first_col}: error: no feed: program F > 0 before G0{motion}")
        if motion in (0, 1):
            prog.frames.append(Frame(motion, start, tuple(end), feed=RAPID_MM_MIN if motion == 0 else feed,
                                     line=lineno))
        else:
            i, j = _centre(words, start, end, motion, scale, filename, lineno, first_col)
            prog.frames.append(Frame(motion, start, tuple(end), i, j, feed, lineno))
        pos = end
    for letter in sorted(ignored):
        prog.notes.append(f"{filename}: note: {letter} words ignored (the stand has no spindle, coolant or tool changer)")
    return prog


def _strip_comments(line: str, filename: str, lineno: int) -> str:
    out, depth = [], 0
    for ch in line:
        if ch == ";" and depth == 0:
            break
        if ch == "(":
            depth += 1
        elif ch == ")":
            if depth == 0:
                raise GcodeError(f"{filename}:{lineno}:{len(''.join(out)) + 1}: error: ')' without '('")
            depth -= 1
        elif depth == 0:
            out.append(ch)
            continue
        out.append(" ")
    if depth:
        raise GcodeError(f"{filename}:{lineno}:{line.index('(') + 1}: error: comment not closed")
    return "".join(out)


def _centre(words, start, end, motion, scale, filename, lineno, col) -> tuple[float, float]:
    """The arc's centre relative to its start, from I/J or R; checked against the end."""
    sx, sy, ex, ey = start[0], start[1], end[0], end[1]
    if "R" in words:
        r = words["R"][0] * scale
        dx, dy = ex - sx, ey - sy
        d = math.hypot(dx, dy)
        if d == 0 or abs(r) < d / 2 - 1e-9:
            raise GcodeError(f"{filename}:{lineno}:{words['R'][1]}: error: R{abs(r):g} cannot join the start and "
                             f"the end point ({d:.4f} mm apart)")
        h = math.sqrt(max(0.0, r * r - d * d / 4))
        # G02 with R > 0: the centre to the right of the chord; R < 0 takes the long way round
        side = -1.0 if motion == 2 else 1.0
        if r < 0:
            side = -side
        mx, my = sx + dx / 2, sy + dy / 2
        cx, cy = mx - side * h * dy / d, my + side * h * dx / d
        return cx - sx, cy - sy
    if "I" not in words and "J" not in words:
        raise GcodeError(f"{filename}:{lineno}:{col}: error: G0{motion} needs I/J or R")
    i = words["I"][0] * scale if "I" in words else 0.0
    j = words["J"][0] * scale if "J" in words else 0.0
    r0, r1 = math.hypot(i, j), math.hypot(ex - sx - i, ey - sy - j)
    if r0 == 0:
        raise GcodeError(f"{filename}:{lineno}:{col}: error: the arc's centre is its start point")
    if abs(r1 - r0) > ARC_TOLERANCE_MM:
        raise GcodeError(f"{filename}:{lineno}:{col}: error: the end point is not on the arc's circle "
                         f"(radius {r0:.4f} mm at the start, {r1:.4f} mm at the end; tolerance {ARC_TOLERANCE_MM} mm)")
    return i, j
