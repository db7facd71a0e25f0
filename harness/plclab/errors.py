"""Diagnostics: every problem a user sees is one line, made here at the edge.

Errors travel as values (`Diagnostic`) or typed exceptions (`PlcLabError` and subclasses);
the CLI prints them and sets the exit code. Nothing below the CLI prints.
"""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True, order=True)
class Diagnostic:
    """One error in ST source: printed as `file:line:col: error: message` (1-based line/col).

    In ST made from a drawing (a plc.xml's LD / FBD body) `where` names the spot on the
    drawing instead (`FB_Task1 (LD), rung 3, coil L9 (localId 27)`), and the line is
    `file: where: message`: the generated text's line and column mean nothing to the student."""

    file: str
    line: int
    col: int
    message: str
    where: str = field(default="", compare=False)

    def __str__(self) -> str:
        if self.where:
            return f"{self.file}: {self.where}: {self.message}"
        return f"{self.file}:{self.line}:{self.col}: error: {self.message}"


class PlcLabError(Exception):
    """An error a user caused and can fix; its str() is the one line shown to them."""


class CompileError(PlcLabError):
    """ST that does not pass the front end; carries every diagnostic found."""

    def __init__(self, diagnostics: list[Diagnostic]):
        self.diagnostics = sorted(set(diagnostics))
        super().__init__("\n".join(str(d) for d in self.diagnostics))


class ConfigError(PlcLabError):
    """A bad openplc.conf: the message names section, key, value and what is allowed."""


def quoted(value: object, limit: int = 40) -> str:
    """A value as a one-line message quotes it (repr of text), cut to `limit` characters: a
    5,000-digit number or a binary line must not become a 5,000-character error."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."
