"""`plclab lab STAND`: the virtual lab in the browser (docs/lab.md).

The stand runs as in `plclab run` (a `Session`: PLC, plant, trace) in real time or faster
(`engine`); a local aiohttp server (`server`) pushes its state to a plain HTML/SVG/JS page
shipped in `static/`, which is a view of that session and the console that operates it.
`panels` says what each stand's page shows.
"""
from __future__ import annotations

from typing import Optional, Sequence

from plclab.lab.engine import Lab, LabError
from plclab.lab.server import LabServer, LabThread, serve_lab

__all__ = ["Lab", "LabError", "LabServer", "LabThread", "open_lab", "serve_lab"]


def open_lab(stand: str, program: Optional[Sequence[str]] = None, variant: Optional[str] = None, bind: str = "127.0.0.1",
             port: int = 8080, speed: float = 1.0, modbus_port: Optional[int] = 5020) -> LabServer:
    """A lab server for `stand` running the ST files `program` (else the shipped `variant`),
    not yet listening. A program that fails the check is refused here, with its diagnostics.
    Without a variant: the student's starting program (the real stand has Appendix 1 loaded)."""
    from plclab.frontend import read_sources
    from plclab.lab.engine import check_program
    from plclab.stands import get_stand

    variant = variant or get_stand(stand).starting_variant
    get_stand(stand).variant(variant)
    sources = None
    if program:
        from plclab.stands.base import stand_spec
        combine = stand_spec(stand).program_sources   # the CNC: a file with FB_CncEvalLinear alone runs
        sources = combine(program) if combine else read_sources(program)   # unreadable: CompileError lines
        _checked, errors = check_program(sources)
        if errors:
            raise LabError("the program does not pass the check:\n" + "\n".join(errors))
    lab = Lab(stand, sources=sources, variant=variant, program_files=list(program or ()), speed=speed)
    return LabServer(lab, bind=bind, port=port, modbus_port=modbus_port if stand == "thermo" else None)
