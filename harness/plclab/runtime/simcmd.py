"""`plclab sim`: any program in virtual time, inputs from a CSV script, traces out.

This is the generic "CI checks I/O traces" entry point for programs that are not a stand.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence

from plclab.errors import PlcLabError
from plclab.fileio import check_output
from plclab.frontend import load_files
from plclab.runtime.faults import FaultRecord
from plclab.runtime.plc import PLC
from plclab.runtime.compiler import compile_unit
from plclab.runtime.sim import InputEvent, Simulation
from plclab.trace import Trace, plot_trace, read_csv, write_csv, write_vcd


@dataclass
class SimResult:
    trace: Trace
    fault: Optional[FaultRecord]
    summary: str
    sim: Simulation


def read_input_script(path: str) -> list[InputEvent]:
    """Rows `time_s,name,value` -> events; a bad row is one `FILE:LINE: error:` line."""
    try:
        script = read_csv(path, require_initial=False)
    except FileNotFoundError:
        raise PlcLabError(f"{path}: no such file") from None
    except OSError as e:
        raise PlcLabError(f"{path}: cannot read: {e.strerror}") from None
    events = []
    for name in script.signals():
        for i, (t, v) in enumerate(script.changes(name)):
            events.append(InputEvent(t, name, v))
    events.sort(key=lambda e: e.time_ns)
    return events


def run_sim(files: Sequence[str], duration_s: float, inputs: Optional[str] = None, csv: Optional[str] = None,
            vcd: Optional[str] = None, plot: Optional[str] = None, watch: Sequence[str] = (),
            tick_s: Optional[float] = None) -> SimResult:
    for out in (csv, vcd, plot):
        if out:
            check_output(out)                # a bad output path is refused before the run
    checked = load_files(files)
    plc = PLC(compile_unit(checked), tick_ns=round(tick_s * 1e9) if tick_s else None)
    events = read_input_script(inputs) if inputs else []
    extra = [e.name for e in events if e.name.startswith("%")]
    sim = Simulation(plc, watch=watch, extra_addresses=extra)
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
