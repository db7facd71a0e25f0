"""`plclab sim`: any program in virtual time, inputs from a CSV script, traces out.

This is the generic "CI checks I/O traces" entry point for programs that are not a stand.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional, Sequence

from plclab.errors import PlcLabError, quoted
from plclab.fileio import check_output
from plclab.frontend import load_files
from plclab.frontend.literals import LiteralError, parse_time
from plclab.iec import types as T
from plclab.runtime.faults import FaultRecord
from plclab.runtime.image import image_slot
from plclab.runtime.plc import PLC
from plclab.runtime.compiler import compile_unit
from plclab.runtime.sim import InputEvent, Simulation
from plclab.trace import Trace, TraceFormatError, plot_trace, write_csv, write_vcd
from plclab.trace.csvio import read_rows


@dataclass
class SimResult:
    trace: Trace
    fault: Optional[FaultRecord]
    summary: str
    sim: Simulation


def read_input_script(path: str, plc: PLC) -> list[InputEvent]:
    """Rows `time_s,name,value` -> events. Each value is read as the type of what it sets (the
    variable, or the variable located at the address): text for a REAL, 40000 for an INT, a
    20-digit number anywhere is refused, never wrapped. A bad row is one `FILE:LINE: error:` line."""
    try:
        rows = read_rows(path)
    except FileNotFoundError:
        raise PlcLabError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise PlcLabError(f"{path}: is a directory, not an input script") from None
    except OSError as e:
        raise PlcLabError(f"{path}: cannot read: {e.strerror or e}") from None
    types: dict[str, Any] = {}
    events = []
    for row in rows:
        try:
            if row.name not in types:
                types[row.name] = input_type(plc, row.name)
            value = typed_value(row.text, types[row.name], row.name)
        except PlcLabError as e:
            raise TraceFormatError(path, row.line, str(e)) from None
        events.append(InputEvent(row.time_ns, row.name, value))
    return events


def input_type(plc: PLC, name: str) -> Any:
    """The type a scripted value for `name` must have: the variable's, or the type of the
    variable located at an address. An address no variable of the program is located at is
    refused: the program never reads it, so a row setting it is a typo (`%IW7` for `%IW1`)
    that would otherwise go unnoticed."""
    if name.strip().startswith("%"):
        area, index = image_slot(name)
        for b in plc.bindings:
            if b.area == area and b.index == index:
                return b.ty
        raise PlcLabError(f"{name.strip()} is not used by the program ({_declared(plc, area)})")
    ty = plc.resolve_typed(name)[2]
    if not isinstance(T.base_of(ty), (T.ElementaryType, T.StringType, T.EnumType)):
        raise PlcLabError(f"{name} is not an elementary variable; set one of its elements or fields")
    return ty


def _declared(plc: PLC, area: str, shown: int = 8) -> str:
    """What the program locates in image area `area`, for the message of an unused address."""
    addresses = sorted({b.address for b in plc.bindings if b.area == area},
                       key=lambda a: image_slot(a))
    if not addresses:
        return f"it declares no %{area} address"
    more = f" and {len(addresses) - shown} more" if len(addresses) > shown else ""
    return f"it declares {', '.join(addresses[:shown])}{more}"


_INT_TEXT = re.compile(r"[+-]?\d{1,40}")


def typed_value(text: str, ty: Any, name: str) -> Any:
    """`text` as a value of `ty`, or PlcLabError saying why not (never a wrapped value)."""
    t = text.strip()
    shown = quoted(t)
    b = T.base_of(ty)
    if b is T.BOOL:
        if t.lower() in ("0", "1", "true", "false"):
            return t.lower() in ("1", "true")
        raise PlcLabError(f"bad value {shown} for BOOL {name}: expected 0 or 1")
    if isinstance(b, T.ElementaryType) and b.kind in ("sint", "uint", "bits"):
        return _integer(t, shown, b.min, b.max, f"{b.name} {name}")
    if isinstance(b, T.ElementaryType) and b.is_real:
        try:
            value = float(t)
        except ValueError:
            raise PlcLabError(f"bad value {shown} for {b.name} {name}: not a number") from None
        if b is T.REAL and math.isfinite(value) and abs(value) > T.REAL_MAX:
            raise PlcLabError(f"value {shown} is out of range for REAL {name} (at most 3.4e38 in magnitude)")
        return value
    if isinstance(b, T.ElementaryType) and b.kind in ("time", "date", "tod", "dt"):
        if t.upper().startswith(("T#", "TIME#")) and b.kind == "time":
            try:
                return parse_time(t)
            except (LiteralError, ValueError):
                raise PlcLabError(f"bad value {shown} for TIME {name}") from None
        return _integer(t, shown, -(1 << 63), (1 << 63) - 1, f"{b.name} {name} (nanoseconds, or T#...)")
    if isinstance(b, T.EnumType):
        member = t.split("#")[-1].upper()
        if member in b.values:
            return member
        raise PlcLabError(f"bad value {shown} for {b.name} {name}: one of {', '.join(b.values)}")
    if isinstance(b, T.StringType):
        return text
    raise PlcLabError(f"{name} cannot be set from an input script")


def _integer(t: str, shown: str, low: int, high: int, what: str) -> int:
    if not _INT_TEXT.fullmatch(t):
        if re.fullmatch(r"[+-]?\d+", t):
            raise PlcLabError(f"value {shown} is out of range for {what} ({low}..{high})")
        raise PlcLabError(f"bad value {shown} for {what}: expected an integer")
    value = int(t)
    if not low <= value <= high:
        raise PlcLabError(f"value {t} is out of range for {what} ({low}..{high})")
    return value


def run_sim(files: Sequence[str], duration_s: float, inputs: Optional[str] = None, csv: Optional[str] = None,
            vcd: Optional[str] = None, plot: Optional[str] = None, watch: Sequence[str] = (),
            tick_s: Optional[float] = None) -> SimResult:
    for out in (csv, vcd, plot):
        if out:
            check_output(out)                # a bad output path is refused before the run
    checked = load_files(files)
    plc = PLC(compile_unit(checked), tick_ns=round(tick_s * 1e9) if tick_s else None)
    events = read_input_script(inputs, plc) if inputs else []
    for name in watch:                       # a watched name the program lacks: say which option
        try:
            plc.resolve(name)
        except PlcLabError as e:
            raise PlcLabError(f"--watch {name}: {e}") from None
    sim = Simulation(plc, watch=watch)
    try:
        sim.schedule(events)
    except PlcLabError as e:
        raise PlcLabError(f"{inputs}: {e}") from None
    sim.run(duration_s)
    trace = sim.trace
    for path, writer in ((csv, write_csv), (vcd, write_vcd)):
        if path:
            writer(trace, path)
    if plot:
        plot_trace(trace, plot, title=", ".join(Path(f).name for f in files))
    changes = sum(len(trace.changes(n)) - 1 for n in trace.signals())
    summary = (f"simulated {duration_s:g} s in {plc.ticks} scans of {plc.tick_ns / 1e6:g} ms: "
               f"{len(trace.signals())} signals, {changes} changes")
    if plc.fault is not None:
        summary += f"\n{plc.fault}"
    return SimResult(trace, plc.fault, summary, sim)
