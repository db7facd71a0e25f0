"""The `plclab` command: argument parsing only; the work is done by library functions.

Every error reaches the user as one line (or one line per ST diagnostic) and an exit code;
no traceback escapes.
"""
from __future__ import annotations

import argparse
import sys
from typing import Optional, Sequence

from plclab.errors import CompileError, PlcLabError


def _cmd_check(args: argparse.Namespace) -> int:
    from plclab.frontend import load_files

    load_files(args.files)
    print(f"ok: {len(args.files)} file(s) checked")
    return 0


def _seconds(text: str) -> float:
    """A duration on the command line: `10`, `2.5s`, `500ms`, `T#1m30s`."""
    from plclab.frontend.literals import LiteralError, parse_time

    t = text.strip()
    try:
        if t.upper().startswith(("T#", "TIME#")):
            return parse_time(t) / 1e9
        for suffix, scale in (("ms", 1e-3), ("s", 1.0), ("min", 60.0), ("m", 60.0), ("h", 3600.0)):
            if t.lower().endswith(suffix) and t[:-len(suffix)].replace(".", "", 1).isdigit():
                return float(t[:-len(suffix)]) * scale
        value = float(t)
    except (ValueError, LiteralError):
        raise argparse.ArgumentTypeError(f"not a duration: '{text}' (e.g. 10, 2.5s, 500ms, T#1m)") from None
    if value < 0 or value != value:
        raise argparse.ArgumentTypeError(f"not a duration: '{text}'")
    return value


def _cmd_sim(args: argparse.Namespace) -> int:
    from plclab.runtime.simcmd import run_sim

    result = run_sim(args.files, duration_s=args.duration, inputs=args.inputs, csv=args.csv, vcd=args.vcd,
                     plot=args.plot, watch=args.watch, tick_s=args.tick)
    print(result.summary)
    return 0 if result.fault is None else 1


def _cmd_bench(args: argparse.Namespace) -> int:
    from plclab.bench import run_bench

    run_bench(quick=args.quick)
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="plclab", description="IEC 61131-3 ST lab programs and soft-PLC harness")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    c = sub.add_parser("check", help="parse and type-check ST files (one compilation unit)")
    c.add_argument("files", nargs="+", metavar="FILE.st")
    c.set_defaults(func=_cmd_check)

    c = sub.add_parser("sim", help="run any ST program in virtual time with scripted inputs; write traces")
    c.add_argument("files", nargs="+", metavar="FILE.st")
    c.add_argument("--duration", type=_seconds, required=True, metavar="T", help="simulated time (e.g. 10s)")
    c.add_argument("--inputs", metavar="IN.csv", help="input script: rows time_s,name,value")
    c.add_argument("--csv", metavar="OUT.csv", help="write the trace as CSV (time_s,name,value)")
    c.add_argument("--vcd", metavar="OUT.vcd", help="write the trace as VCD (GTKWave)")
    c.add_argument("--plot", metavar="OUT.png", help="write a PNG plot of the trace")
    c.add_argument("--watch", action="append", default=[], metavar="NAME",
                   help="also trace an internal variable (instance.var), repeatable")
    c.add_argument("--tick", type=_seconds, metavar="T", help="base tick (default: GCD of task intervals)")
    c.set_defaults(func=_cmd_sim)

    c = sub.add_parser("bench", help="performance figures: front end, scan cost, virtual-time speed-up, Modbus")
    c.add_argument("--quick", action="store_true", help="shorter runs")
    c.set_defaults(func=_cmd_bench)
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except CompileError as e:
        for d in e.diagnostics:
            print(d, file=sys.stderr)
        return 1
    except PlcLabError as e:
        print(f"plclab: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("plclab: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
