"""Traces: signal changes over virtual time, their CSV/VCD/PNG forms and a golden-file diff.

    trace = Trace()
    trace.declare("%QX0.1", "bool", False)
    trace.change(1_230_000_000, "%QX0.1", True)
    write_csv(trace, "run.csv"); write_vcd(trace, "run.vcd"); plot_trace(trace, "run.png")
    assert diff(read_csv("golden.csv"), trace, tolerance_ns=scan_ns) is None
"""
from .csvio import TraceFormatError, csv_text, parse_csv, read_csv, write_csv
from .diff import Difference, diff
from .recorder import Recorder
from .times import format_seconds, ns_to_s, parse_seconds, s_to_ns
from .trace import KINDS, NotFound, SignalInfo, State, Trace, UnknownSignal
from .vcdio import vcd_names, write_vcd


def plot_trace(*args, **kwargs):
    """plclab.trace.plot.plot_trace, imported when a plot is asked for: matplotlib costs about
    0.3 s to import, a third of a `plclab run` that plots nothing."""
    from .plot import plot_trace as plot

    return plot(*args, **kwargs)

__all__ = [
    "KINDS", "Difference", "NotFound", "Recorder", "SignalInfo", "State", "Trace",
    "TraceFormatError", "UnknownSignal", "csv_text", "diff", "format_seconds", "ns_to_s",
    "parse_csv", "parse_seconds", "plot_trace", "read_csv", "s_to_ns", "vcd_names", "write_csv",
    "write_vcd",
]
