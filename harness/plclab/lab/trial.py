"""The lab's trial load of an uploaded program, in a process of its own (plclab.lab.engine
check_program): the sources as JSON [[name, text], ...] on stdin; the process holds itself to
the memory limit of a program run (plclab.limits), checks, compiles and instantiates the
program once (no retain, no scan) and prints `ok`; `check` when the check finds errors (the
lab names them, on the drawing for a plc.xml); or `checked (WHY)` / `loaded (WHY)` when the
check or the load cannot be done (a MemoryError past the limit, a RecursionError)."""
from __future__ import annotations

import json
import sys


def main() -> int:
    data = sys.stdin.read()
    from plclab.errors import CompileError
    from plclab.frontend import check_sources
    from plclab.frontend.parser import load_parser
    from plclab.lab.engine import _why
    from plclab.limits import limit_memory
    from plclab.runtime.compiler import compile_unit
    from plclab.runtime.plc import PLC
    load_parser()
    limit_memory()                        # imports and the parser's tables first: the allowance is the program's
    stage = "checked"
    try:
        sources = [(str(n), str(t)) for n, t in json.loads(data)]
        try:
            checked = check_sources(sources)
        except CompileError:
            print("check", flush=True)
            return 0
        if checked.config is None:
            print("check", flush=True)
            return 0
        stage = "loaded"
        PLC(compile_unit(checked)).stop()
    except (Exception, RecursionError, MemoryError) as e:     # noqa: BLE001 - a student's file
        try:
            print(f"{stage} ({_why(e)})", flush=True)
        except MemoryError:
            return 3
        return 1
    print("ok", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
