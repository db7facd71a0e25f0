"""Run the CNC motion blocks of plc/POUs in the soft PLC for the tests in tests/cnc.

Each helper compiles the block(s) once with a small test PROGRAM around them that runs a
whole frame inside one scan and records the visited points in arrays, so a property test
can check hundreds of frames quickly. (The suite has no conftest.py and no package
__init__: test files put this directory on sys.path.)
"""
from __future__ import annotations

import sys
from functools import lru_cache
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests" / "runtime"))

from st_helpers import load  # noqa: E402

from plclab.stands import PLC_DIR  # noqa: E402

MAX_POINTS = 20000


def pou(*stems: str) -> str:
    """The text of shipped POU files, in order."""
    return "\n".join((PLC_DIR / "POUs" / f"{s}.st").read_text(encoding="utf-8") for s in stems)


class Runner:
    """A compiled test program: write its inputs, scan once, read its outputs."""

    def __init__(self, src: str):
        self.sim = load(src, name="cnc_test.st")

    def run(self, **inputs: Any) -> "Runner":
        for name, value in inputs.items():
            self.sim.plc.write(f"main.{name}", value)
        self.sim.plc.write("main.Go", True)
        self.sim.step(1)
        return self

    def __getitem__(self, name: str) -> Any:
        return self.sim.plc.read(f"main.{name}")

    def points(self, *names: str) -> list[tuple[Any, ...]]:
        """The recorded points 0..N (point 0: before the first iteration)."""
        n = self["N"]
        cols = [self.sim.plc.read(f"main.{name}")[: n + 1] for name in names]
        return list(zip(*cols))


@lru_cache(maxsize=None)
def eval_linear() -> Runner:
    return Runner(pou("FB_CncEvalLinear") + f"""
PROGRAM main
VAR
    Interp : FB_CncEvalLinear;
    DX : DINT; DY : DINT; DZ : DINT; Diagonal : BOOL; Go : BOOL;
    PX : ARRAY[0..{MAX_POINTS}] OF DINT;
    PY : ARRAY[0..{MAX_POINTS}] OF DINT;
    PZ : ARRAY[0..{MAX_POINTS}] OF DINT;
    N : DINT;
END_VAR
IF Go THEN
    Go := FALSE;
    Interp(Load := TRUE, DX := DX, DY := DY, DZ := DZ);
    N := 0;
    PX[0] := 0; PY[0] := 0; PZ[0] := 0;
    WHILE Interp.Busy AND N < {MAX_POINTS} DO
        Interp(Load := FALSE, Diagonal := Diagonal);
        N := N + 1;
        PX[N] := Interp.X; PY[N] := Interp.Y; PZ[N] := Interp.Z;
    END_WHILE;
END_IF;
END_PROGRAM
""")


@lru_cache(maxsize=None)
def eval_circular() -> Runner:
    return Runner(pou("FC_CncArcQuadrant", "FB_CncEvalCircular") + f"""
PROGRAM main
VAR
    Interp : FB_CncEvalCircular;
    I : DINT; J : DINT; XE : DINT; YE : DINT; Ccw : BOOL; Diagonal : BOOL; Go : BOOL;
    PX : ARRAY[0..{MAX_POINTS}] OF DINT;
    PY : ARRAY[0..{MAX_POINTS}] OF DINT;
    N : DINT;
    Error : BOOL;
END_VAR
IF Go THEN
    Go := FALSE;
    Interp(Load := TRUE, I := I, J := J, XE := XE, YE := YE, Ccw := Ccw);
    Error := Interp.Error;
    N := 0;
    PX[0] := I; PY[0] := J;
    WHILE Interp.Busy AND N < {MAX_POINTS} DO
        Interp(Load := FALSE, Diagonal := Diagonal);
        N := N + 1;
        PX[N] := Interp.X; PY[N] := Interp.Y;
    END_WHILE;
END_IF;
END_PROGRAM
""")
