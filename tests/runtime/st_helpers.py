"""Small helpers shared by tests/runtime/test_semantics_*.py: compile ST, run it in virtual time.

Imported by its plain name: tests/conftest.py puts this directory on sys.path.
"""
from __future__ import annotations

from typing import Any, Iterable, Optional

from plclab.frontend import check_sources
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.runtime.sim import Simulation

OPTIMIZE = True
"""Whether load() compiles with the compiler's fast paths; the `compile_mode` fixture
(tests/runtime/conftest.py) runs each semantics test once each way."""
NATIVE = False
"""Whether load() runs the program on the native path (where cgen covers it), else Python."""

MS = 1_000_000          # ns per ms
S = 1_000_000_000       # ns per s


def load(src: str, *, tick_ms: Optional[int] = None, watch: Iterable[str] = (),
         name: str = "t.st", **plc_kwargs: Any) -> Simulation:
    """Check + compile `src`, build a PLC (base tick `tick_ms` if given) and a Simulation."""
    cu = check_sources([(name, src)])
    if tick_ms is not None:
        plc_kwargs["tick_ns"] = tick_ms * MS
    plc_kwargs.setdefault("native", NATIVE)
    plc = PLC(compile_unit(cu, optimize=OPTIMIZE), **plc_kwargs)
    return Simulation(plc, watch=list(watch))


def program(decls: str, body: str, extra: str = "", **kw: Any) -> Simulation:
    """A lone `PROGRAM main` (no CONFIGURATION: it runs every tick) plus `extra` POUs/types."""
    src = f"{extra}\nPROGRAM main\n{decls}\n{body}\nEND_PROGRAM\n"
    return load(src, **kw)


def once(decls: str, body: str, extra: str = "", **kw: Any) -> Simulation:
    """`program(...)` scanned exactly once (at t = 0)."""
    sim = program(decls, body, extra, **kw)
    sim.step(1)
    return sim


def val(sim: Simulation, name: str) -> Any:
    """Read `main.<name>` (`name` may be `fb.out`); an address or `main.x` is read as is."""
    if name.startswith("%") or name.upper().startswith("MAIN."):
        return sim.plc.read(name)
    return sim.plc.read(f"main.{name}")


def scan_until(sim: Simulation, name: str, value: Any, max_ticks: int = 10_000) -> int:
    """Step one tick at a time until `val(sim, name) == value`; return the time in ns of the
    scan that produced it (the scan's own time, per the trace timing convention)."""
    for _ in range(max_ticks):
        t = sim.plc.now_ns
        sim.step(1)
        if val(sim, name) == value:
            return t
    raise AssertionError(f"{name} never became {value!r} within {max_ticks} ticks")
