"""Runtime faults of the soft PLC: what stops a program and how it is reported."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional


class PlcFault(Exception):
    """Raised by compiled code (or the runtime) when the program cannot go on.

    kind: 'division_by_zero' | 'index_out_of_range' | 'watchdog' | 'overflow' | 'internal'
    """

    def __init__(self, kind: str, message: str):
        super().__init__(message)
        self.kind = kind
        self.message = message


@dataclass(frozen=True)
class FaultRecord:
    """A fault as the user sees it: what, where (POU, file, line) and when (PLC time)."""

    kind: str
    message: str
    pou: Optional[str]
    file: Optional[str]
    line: Optional[int]
    time_ns: int

    def __str__(self) -> str:
        where = ""
        if self.file is not None:
            where = f"{self.file}:{self.line}: "
        pou = f" in {self.pou}" if self.pou else ""
        return f"{where}PLC FAULT ({self.kind}){pou} at t={self.time_ns / 1e9:g} s: {self.message}"
