"""The G-code front end: a part program (ISO 6983 subset, textbook 4.1.3) -> frames.

Supported: G00 G01 G02 G03 (arcs by I/J or R), G17, G20/G21, G40/G41/G42 with D (the
tool-radius table), G90/G91, F, X/Y/Z, N (block numbers), M02/M30 (program end), comments in
parentheses or after ';', '%' lines; S, T, O and the other M words are ignored with a note.
Anything else is one `file:line:col: error: ...` line and nothing runs.

Read strictly, with the modal groups a CNC user knows (LinuxCNC's G-code overview): a code
the stand does not know is refused by its exact name (`G91.1` is not `G91`); two codes of one
modal group in a block are an error (`G00 G01`); a word that means nothing for its block is an
error (R or I/J on G00/G01, I/J with R); comments do not nest; the program ends at M02/M30
(blocks after it are not run, with a warning, as LinuxCNC ignores them); arcs are in the XY
plane (a G02/G03 moving Z, a helix, is refused); an arc's end may miss its circle by one step
of the drives (`--step`), the frames' own rounding.

The frames keep the programmed contour; the tool-radius correction itself is made by the PLC
when it prepares the frames (FB_CncToolRadius, textbook 4.2.2.1). This front end refuses what
that preparation cannot build: the correction switched on in an arc, a corrected segment
shorter than the tool radius, an inner arc not larger than the tool, a corner where the
contour reverses, an arc whose joint with a corrected neighbour is not tangent (the textbook
builds arcs' equidistants for conjugate contours only).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

from plclab import fileio
from plclab.errors import PlcLabError

SUPPORTED = ("G00 G01 G02 G03 (I/J or R) G17 G20 G21 G40 G41 G42 D G90 G91 F X Y Z N M02 M30; "
             "S T O and other M words ignored")
TANGENT_RAD = 1e-3               # arcs' joints with corrected neighbours must be this tangent
DEFAULT_STEP_MM = 0.01           # the drives' step when none is given (plclab cnc --step)
# The modal groups of the codes the stand knows (LinuxCNC's numbering): two of one group in a
# block are an error.
MODAL_GROUPS = {0: 1, 1: 1, 2: 1, 3: 1, 17: 2, 90: 3, 91: 3, 20: 6, 21: 6, 40: 7, 41: 7, 42: 7}
M_GROUPS = {0: 4, 1: 4, 2: 4, 30: 4, 60: 4, 3: 7, 4: 7, 5: 7, 7: 8, 8: 8, 9: 8}   # M words (ignored but 2, 30)
GROUP_NAMES = {("G", 1): "motion", ("G", 2): "plane selection", ("G", 3): "distance mode", ("G", 6): "units",
               ("G", 7): "cutter radius compensation", ("M", 4): "stopping", ("M", 7): "spindle",
               ("M", 8): "coolant"}
PROGRAM_END = (2, 30)            # M02, M30: the program ends at this block
RAPID_MM_MIN = 600.0             # G00: the stand's largest feed (one step per fine cycle)
WORD = re.compile(r"\s*([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")


@dataclass(frozen=True)
class Frame:
    """One block of motion, absolute mm: `kind` 0 G00, 1 G01, 2 G02, 3 G03; (i, j) the arc's
    centre relative to the start; `feed` mm/min; `line` the source line; `comp` and
    `tool_radius` the tool-radius correction in effect (applied by the PLC, FB_CncToolRadius)."""

    kind: int
    start: tuple[float, float, float]
    end: tuple[float, float, float]
    i: float = 0.0
    j: float = 0.0
    feed: float = 0.0
    line: int = 0
    comp: int = 0              # tool-radius correction: 0 G40, 1 G41, 2 G42
    tool_radius: float = 0.0   # mm, from the D table

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


MAX_PART_BYTES = 8 * 1024 * 1024     # a part program is text of a few thousand blocks


class GcodeError(PlcLabError):
    """A bad part program: `file:line:col: error: ...`."""


def parse_file(path: str | Path, tools: Optional[dict[int, float]] = None,
               step_mm: float = DEFAULT_STEP_MM) -> Program:
    p = Path(path)
    try:                 # a regular file of reasonable size, checked before reading
        text = fileio.read_input(p, MAX_PART_BYTES).decode("utf-8")
    except fileio.InputError as e:
        raise PlcLabError(f"{p}: cannot read the part program ({e})") from None
    except UnicodeDecodeError as e:
        raise PlcLabError(f"{p}: cannot read the part program (not UTF-8 text: {e.reason})") from None
    return parse(text, str(p), tools, step_mm)


def _code(letter: str, text: str) -> str:
    """A G or M word for a message: a whole number as the stand lists it (G1 -> G01), a
    decimal one exactly as written (G91.1, G1.5: it is not the whole one)."""
    value = float(text)
    return f"{letter}{int(value):02d}" if value == int(value) else f"{letter}{text.lstrip('+')}"


def parse(text: str, filename: str = "<part>", tools: Optional[dict[int, float]] = None,
          step_mm: float = DEFAULT_STEP_MM) -> Program:
    """The frames of a part program; `tools` is the D table (number -> tool radius, mm);
    `step_mm` the drives' step (an arc's end may miss its circle by one step)."""
    tools = dict(tools or {})
    prog = Program()
    pos = [0.0, 0.0, 0.0]
    motion, absolute, scale, feed = 0, True, 1.0, 0.0
    comp, radius = 0, 0.0
    ignored: set[str] = set()
    ended = 0                          # the line of M02/M30: the program ends there
    for lineno, raw in enumerate(text.splitlines(), start=1):
        if ended:                      # not read any more (LinuxCNC ignores it): said once if not empty
            try:
                rest = _strip_comments(raw, filename, lineno).strip()
            except GcodeError:
                rest = raw.strip()
            if rest and rest != "%":
                prog.notes.append(f"{filename}:{lineno}: warning: blocks after the program end (line {ended}) "
                                  f"are not run")
                break
            continue
        line = _strip_comments(raw, filename, lineno)
        if not line.strip() or line.strip() == "%":
            continue
        words: dict[str, tuple[float, int]] = {}
        gcodes: list[tuple[int, int]] = []
        groups: dict[tuple[str, int], str] = {}         # (G or M, modal group) -> code in this block
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
            if letter in "GM":
                code = _code(letter, m.group(2))
                known = value == int(value) and (int(value) in MODAL_GROUPS if letter == "G" else True)
                if not known:
                    raise GcodeError(f"{filename}:{lineno}:{wcol}: error: {code} is not supported by the stand "
                                     f"(supported: {SUPPORTED})")
                number = (MODAL_GROUPS if letter == "G" else M_GROUPS).get(int(value))
                if number is not None:
                    group = (letter, number)
                    if group in groups:
                        raise GcodeError(f"{filename}:{lineno}:{wcol}: error: {groups[group]} and {code} in one "
                                         f"block: both of modal group {number} ({GROUP_NAMES[group]}), one "
                                         f"of each group per block")
                    groups[group] = code
                if letter == "G":
                    gcodes.append((int(value), wcol))
                elif int(value) in PROGRAM_END:
                    ended = lineno
                else:
                    ignored.add(letter)
            elif letter in "XYZIJRF":
                if letter in words:
                    raise GcodeError(f"{filename}:{lineno}:{wcol}: error: '{letter}' twice in one block")
                words[letter] = (value, wcol)
            elif letter in "STO":
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
            elif g in (40, 41, 42):
                comp = g - 40
                comp_col = gcol
        if "D" in words:
            d, dcol = words["D"]
            if d == 0:
                radius = 0.0
            elif d != int(d) or int(d) not in tools:
                known = ", ".join(f"D{k}" for k in sorted(tools)) or "none given (plclab cnc --tool D1=R)"
                raise GcodeError(f"{filename}:{lineno}:{dcol}: error: D{d:g} is not in the tool table ({known})")
            else:
                radius = float(tools[int(d)])
        if comp and radius <= 0 and any(g in (41, 42) for g, _c in gcodes):
            raise GcodeError(f"{filename}:{lineno}:{comp_col}: error: G{40 + comp} needs a tool radius: D")
        if "F" in words:
            feed = words["F"][0] * scale
            if feed <= 0:
                raise GcodeError(f"{filename}:{lineno}:{words['F'][1]}: error: feed F must be > 0")
        _check_meaning(words, motion, filename, lineno)
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
        r = radius if comp else 0.0
        if motion in (0, 1):
            frame = Frame(motion, start, tuple(end), feed=RAPID_MM_MIN if motion == 0 else feed, line=lineno,
                          comp=comp, tool_radius=r)
        else:
            if "Z" in words and abs(end[2] - start[2]) > 1e-9:
                raise GcodeError(f"{filename}:{lineno}:{words['Z'][1]}: error: G0{motion} with Z: a helix is not "
                                 f"supported by the stand (arcs are in the XY plane, G17; move Z in a G00/G01 "
                                 f"block)")
            i, j = _centre(words, start, end, motion, scale, filename, lineno, first_col, step_mm)
            frame = Frame(motion, start, tuple(end), i, j, feed, lineno, comp, r)
        _check_correction(prog.frames[-1] if prog.frames else None, frame, filename,
                          min(c for letter, (_v, c) in words.items() if letter in "XYZ"))
        prog.frames.append(frame)
        pos = end
    for letter in sorted(ignored):
        prog.notes.append(f"{filename}: note: {letter} words ignored (the stand has no spindle, coolant or tool changer)")
    return prog


def _check_meaning(words: dict[str, tuple[float, int]], motion: int, filename: str, lineno: int) -> None:
    """A word that means nothing for its block is an error, not silently dropped (LinuxCNC):
    I/J/R belong to arcs, and an arc takes either its centre (I/J) or its radius (R)."""
    if motion in (0, 1):
        for letter in "IJR":
            if letter in words:
                what = "an arc's radius" if letter == "R" else "an arc's centre"
                raise GcodeError(f"{filename}:{lineno}:{words[letter][1]}: error: {letter} ({what}) means nothing "
                                 f"for G0{motion}: arcs only (G02/G03)")
    elif "R" in words and ("I" in words or "J" in words):
        c = words["I" if "I" in words else "J"][1]
        raise GcodeError(f"{filename}:{lineno}:{c}: error: G0{motion} with both R and I/J: give the radius (R) "
                         f"or the centre (I/J), not both")


def tangent(f: Frame, at_end: bool) -> tuple[float, float]:
    """The direction of motion of frame `f` at its start or end (XY)."""
    if not f.is_arc:
        return f.end[0] - f.start[0], f.end[1] - f.start[1]
    cx, cy = f.centre
    px, py = (f.end if at_end else f.start)[:2]
    return (-(py - cy), px - cx) if f.kind == 3 else (py - cy, -(px - cx))


def _check_correction(prev: Optional[Frame], f: Frame, filename: str, col: int) -> None:
    """Refuse what the PLC's tool-radius preparation cannot build (see the module doc)."""
    where = f"{filename}:{f.line}:{col}: error:"
    if not f.comp:
        return
    if f.is_arc and (prev is None or prev.comp != f.comp):
        raise GcodeError(f"{where} G{40 + f.comp} must be switched on in a straight block (G00/G01), not in an arc")
    if not f.is_arc:
        length = math.dist(f.start[:2], f.end[:2])
        if length < f.tool_radius:
            raise GcodeError(f"{where} the correction cannot be built: a segment of {length:.3f} mm is shorter "
                             f"than the tool radius {f.tool_radius:g} mm")
    else:
        r = math.hypot(f.i, f.j)
        inside = (f.comp == 1) == (f.kind == 3)
        if inside and r <= f.tool_radius:
            raise GcodeError(f"{where} the correction cannot be built: an inner arc of radius {r:g} mm "
                             f"is not larger than the tool radius {f.tool_radius:g} mm")
    if prev is not None and prev.comp == f.comp:
        d1, d2 = tangent(prev, True), tangent(f, False)
        n1, n2 = math.hypot(*d1), math.hypot(*d2)
        if n1 == 0 or n2 == 0:
            return
        cross = (d1[0] * d2[1] - d1[1] * d2[0]) / (n1 * n2)
        dot = (d1[0] * d2[0] + d1[1] * d2[1]) / (n1 * n2)
        if dot < 0 and abs(cross) < TANGENT_RAD:
            raise GcodeError(f"{where} the correction cannot be built: the contour reverses at this block")
        if (prev.is_arc or f.is_arc) and abs(math.atan2(cross, dot)) > TANGENT_RAD:
            raise GcodeError(f"{where} the correction cannot be built: the joint with an arc is not tangent "
                             f"(corrected arcs need conjugate contours, textbook 4.2.2.1)")


def _strip_comments(line: str, filename: str, lineno: int) -> str:
    """The line with its comments blanked out (columns kept). Comments do not nest (LinuxCNC,
    ISO 6983): a '(' inside a comment is an error, not a deeper level."""
    out, opened = [], -1                 # opened: the column of the open comment's '('
    for col, ch in enumerate(line):
        if opened < 0 and ch == ";":
            break
        if ch == "(":
            if opened >= 0:
                raise GcodeError(f"{filename}:{lineno}:{col + 1}: error: '(' inside a comment (opened at column "
                                 f"{opened + 1}): comments do not nest")
            opened = col
        elif ch == ")":
            if opened < 0:
                raise GcodeError(f"{filename}:{lineno}:{col + 1}: error: ')' without '('")
            opened = -1
        elif opened < 0:
            out.append(ch)
            continue
        out.append(" ")
    if opened >= 0:
        raise GcodeError(f"{filename}:{lineno}:{opened + 1}: error: comment not closed")
    return "".join(out)


def _centre(words, start, end, motion, scale, filename, lineno, col, step_mm) -> tuple[float, float]:
    """The arc's centre relative to its start, from I/J or R; checked against the end: the end
    may miss the circle by one step of the drives (the frames are rounded to steps anyway)."""
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
    if abs(r1 - r0) > step_mm + 1e-9:
        raise GcodeError(f"{filename}:{lineno}:{col}: error: the end point is not on the arc's circle "
                         f"(radius {r0:.4f} mm at the start, {r1:.4f} mm at the end; tolerance one step, "
                         f"{step_mm:g} mm)")
    return i, j
