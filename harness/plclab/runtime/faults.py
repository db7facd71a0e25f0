"""Runtime faults of the soft PLC: what stops a program and how it is reported."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

REPORT_THIS = ("this is a bug of plclab, not of your program: please report it with your ST "
               "files and the command you ran")


class PlcFault(Exception):
    """Raised by compiled code (or the runtime) when the program cannot go on.

    kind: 'division_by_zero' | 'division_overflow' | 'index_out_of_range' | 'watchdog' | ...
    Every kind is a fault of the running program (OpenPLC would stop or crash there too);
    any other exception out of a scan is the harness's own bug (FaultRecord.internal).
    """

    def __init__(self, kind: str, message: str):
        super().__init__(message)
        self.kind = kind
        self.message = message


@dataclass(frozen=True)
class FaultRecord:
    """A fault as the user sees it: what, where (POU, file, line) and when (PLC time).

    `internal` marks an error of the harness itself (a TypeError in generated or library
    code...): the PLC stops all the same, but the record says so and asks for a report, and
    the grader does not charge it to the student. `detail` keeps the Python traceback of
    such an error for that report."""

    kind: str
    message: str
    pou: Optional[str]
    file: Optional[str]
    line: Optional[int]
    time_ns: int
    internal: bool = False
    detail: str = field(default="", compare=False, repr=False)
    place: str = ""          # in a plc.xml's LD / FBD: the POU, rung and element, instead of the line

    def __str__(self) -> str:
        where = ""
        if self.place:
            where = f"{self.file}: {self.place}: "
        elif self.file is not None:
            where = f"{self.file}:{self.line}: "
        pou = f" in {self.pou}" if self.pou else ""
        if self.internal:
            return (f"{where}PLC STOPPED by an internal error of plclab{pou} at t={self.time_ns / 1e9:g} s: "
                    f"{self.message}; {REPORT_THIS}")
        return f"{where}PLC FAULT ({self.kind}){pou} at t={self.time_ns / 1e9:g} s: {self.message}"
