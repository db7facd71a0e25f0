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


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="plclab", description="IEC 61131-3 ST lab programs and soft-PLC harness")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    c = sub.add_parser("check", help="parse and type-check ST files (one compilation unit)")
    c.add_argument("files", nargs="+", metavar="FILE.st")
    c.set_defaults(func=_cmd_check)
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
