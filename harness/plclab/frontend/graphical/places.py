"""Where a piece of ST made from a plc.xml came from: the POU, rung / network and element.

Every chunk of generated text is recorded with its `Place`; a `GeneratedSource` is the ST
text (a `str`, read by everything that reads ST) that can answer "what did the student draw
here?" for a line and column. Diagnostics, faults and grade rows use it instead of naming a
line of text the student never wrote.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

from plclab.errors import CompileError, Diagnostic

@dataclass(frozen=True)
class Place:
    """A spot on the drawing (or in a text body) that a piece of generated ST came from."""

    pou: str
    lang: str = ""                 # 'LD', 'FBD', 'ST', '' (declarations, configuration)
    section: int = 0               # rung (LD) / network (FBD) number from the top, 1-based
    element: str = ""              # 'coil L9', 'contact SB1', 'block TON0 (TON)'
    local_id: Optional[int] = None
    detail: str = ""               # 'declarations', 'body line 4', ...

    def __str__(self) -> str:
        head = f"{self.pou} ({self.lang})" if self.lang else self.pou
        parts = [head]
        if self.section:
            parts.append(f"{'rung' if self.lang == 'LD' else 'network'} {self.section}")
        if self.element:
            parts.append(self.element + (f" (localId {self.local_id})" if self.local_id is not None else ""))
        if self.detail:
            parts.append(self.detail)
        return ", ".join(parts)


class GeneratedSource(str):
    """ST text made from a TC6 project, which knows where each piece of it came from.

    It is a `str` (everything that reads ST reads it as is); `place(line, col)` answers "what
    did the student draw or write here?" for a 1-based line and column of the text."""

    spans: dict[int, list[tuple[int, int, Place]]]
    generated: str   # the file name diagnostics use
    xml: bytes = b""  # the plc.xml it was made from (source_from_xml; the lab draws its ladder)

    def __new__(cls, text: str, spans: dict[int, list[tuple[int, int, Place]]], name: str) -> "GeneratedSource":
        obj = super().__new__(cls, text)
        obj.spans = spans
        obj.generated = name
        return obj

    def place(self, line: int, col: int = 1) -> Optional[Place]:
        row = self.spans.get(line)
        if not row:
            return None
        for c0, c1, p in row:
            if c0 <= col < c1:
                return p
        left = [s for s in row if s[0] <= col]
        return (left[-1] if left else row[0])[2]


def locate(source: Any, line: int, col: int = 1) -> Optional[Place]:
    """The drawing location of (line, col) of a source text read from a plc.xml, or None for
    plain ST (or a spot with no origin). The grader names a statement with this."""
    return source.place(line, col) if isinstance(source, GeneratedSource) else None


def drawing_location(sources: Any, file: str, line: int, col: int = 1) -> Optional[str]:
    """Where (file, line[, col]) of the program's ST is on the student's drawing, as the text a
    report puts in place of the line: `FB_Task1 (LD), rung 3, coil L9 (localId 27)` (for an
    ST body kept in a plc.xml: `FB_X (ST), line 4 of its body`). None for a plain ST file,
    which names its own lines. `sources`: the (name, text) pairs `read_sources` gave."""
    for name, text in sources:
        if name == file:
            place = locate(text, line, col)
            return str(place) if place is not None else None
    return None


class TextBuilder:
    """Accumulates (text, place) chunks and knows each chunk's line and columns."""

    def __init__(self) -> None:
        self.parts: list[str] = []
        self.spans: dict[int, list[tuple[int, int, Place]]] = {}
        self.line = 1
        self.col = 1

    def add(self, text: str, place: Optional[Place] = None) -> None:
        self.parts.append(text)
        lines = text.split("\n")
        for i, piece in enumerate(lines):
            if i:
                self.line += 1
                self.col = 1
            if piece and place is not None:
                self.spans.setdefault(self.line, []).append((self.col, self.col + len(piece), place))
            self.col += len(piece)

    def text(self) -> str:
        return "".join(self.parts)


def generation_error(name: str, place: Place, message: str) -> CompileError:
    return CompileError([Diagnostic(name, 1, 1, message, where=str(place))])
