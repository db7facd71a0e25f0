"""Run the CNC motion blocks (the shipped ST, plc/POUs) in the soft PLC for the tests in tests/cnc.

Each helper compiles the block(s) once with a small test PROGRAM around them that runs a
whole frame inside one scan and records the visited points in arrays, so a property test
can check hundreds of frames quickly. (tests/conftest.py puts this directory on sys.path.)
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import Any

from st_helpers import load

from plclab.stands import pou_path

REPO = Path(__file__).resolve().parents[2]

MAX_POINTS = 20000


def pou(*stems: str) -> str:
    """The text of the POU files, in order: the reference version where the students get a
    stub (FB_CncEvalLinear: solutions/POUs)."""
    return "\n".join(pou_path(s, reference=True).read_text(encoding="utf-8") for s in stems)


class Runner:
    """A compiled test program: write its inputs, scan once, read its outputs."""

    def __init__(self, src: str):
        # a whole frame (or 10^5 DDA cycles) runs inside one scan: more than the default
        # watchdog allows on a slow CI machine
        self.sim = load(src, name="cnc_test.st", watchdog_s=120.0)

    def run(self, **inputs: Any) -> "Runner":
        for name, value in inputs.items():
            self.sim.plc.write(f"main.{name}", value)
        self.sim.plc.write("main.Go", True)
        self.sim.step(1)
        fault = self.sim.plc.fault
        assert fault is None, f"the test program faulted: {fault}"
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


@lru_cache(maxsize=None)
def dda(cycles: int = 400) -> Runner:
    """FB_CncDdaPulses fed per cycle from the arrays IncX/IncY; records every fine step."""
    steps = cycles * 8
    return Runner(pou("FB_CncDdaPulses") + f"""
PROGRAM main
VAR
    Dda : FB_CncDdaPulses;
    Go : BOOL; Cycles : DINT; N : INT := 4; Eps : LREAL := 0.01;
    IncX : ARRAY[1..{cycles}] OF LREAL;
    IncY : ARRAY[1..{cycles}] OF LREAL;
    SX : ARRAY[0..{steps}] OF INT;          (* per fine step: +1, -1 or 0 *)
    SY : ARRAY[0..{steps}] OF INT;
    CountX : ARRAY[1..{cycles}] OF DINT;    (* pulse counts after each cycle *)
    CountY : ARRAY[1..{cycles}] OF DINT;
    Overrun : BOOL;
    c : DINT; k : INT; f : DINT;
END_VAR
IF Go THEN
    Go := FALSE;
    Overrun := FALSE;
    Dda(Reset := TRUE, Cycle := FALSE, DX := 0.0, DY := 0.0, DZ := 0.0, N := N, Eps := Eps);
    Dda(Reset := FALSE);
    f := 0;
    FOR c := 1 TO Cycles DO
        FOR k := 1 TO N DO
            Dda(Cycle := k = 1, DX := IncX[c], DY := IncY[c], DZ := 0.0, N := N, Eps := Eps);
            Overrun := Overrun OR Dda.Overrun;
            SX[f] := 0; SY[f] := 0;
            IF Dda.StepX THEN IF Dda.DirX THEN SX[f] := -1; ELSE SX[f] := 1; END_IF; END_IF;
            IF Dda.StepY THEN IF Dda.DirY THEN SY[f] := -1; ELSE SY[f] := 1; END_IF; END_IF;
            f := f + 1;
        END_FOR;
        CountX[c] := Dda.PulsesX; CountY[c] := Dda.PulsesY;
    END_FOR;
END_IF;
END_PROGRAM
""")


@lru_cache(maxsize=None)
def dda_long() -> Runner:
    """10^5 interpolation cycles of a constant increment: the largest running error."""
    return Runner(pou("FB_CncDdaPulses") + """
PROGRAM main
VAR
    Dda : FB_CncDdaPulses;
    Go : BOOL; Cycles : DINT; N : INT := 4; D : LREAL;
    MaxError : LREAL; Err : LREAL; MaxGap : DINT; MinGap : DINT; Last : DINT; Fine : DINT;
    c : DINT; k : INT;
END_VAR
IF Go THEN
    Go := FALSE;
    MaxError := 0.0; MaxGap := 0; MinGap := 1000000; Last := -1; Fine := 0;
    Dda(Reset := TRUE, Cycle := FALSE, N := N, Eps := 0.01);
    Dda(Reset := FALSE);
    FOR c := 1 TO Cycles DO
        FOR k := 1 TO N DO
            Dda(Cycle := k = 1, DX := D, DY := -D / 3.0, DZ := 0.0, N := N, Eps := 0.01);
            IF Dda.StepX THEN
                IF Last >= 0 THEN
                    MaxGap := MAX(MaxGap, Fine - Last);
                    MinGap := MIN(MinGap, Fine - Last);
                END_IF;
                Last := Fine;
            END_IF;
            Fine := Fine + 1;
        END_FOR;
        (* the travel commanded so far (c cycles of D) against the pulses issued *)
        Err := ABS(DINT_TO_LREAL(c) * (D / 0.01) - DINT_TO_LREAL(Dda.PulsesX));
        MaxError := MAX(MaxError, Err);
        Err := ABS(DINT_TO_LREAL(c) * (-D / 3.0 / 0.01) - DINT_TO_LREAL(Dda.PulsesY));
        MaxError := MAX(MaxError, Err);
    END_FOR;
END_IF;
END_PROGRAM
""")


@lru_cache(maxsize=None)
def integ_linear() -> Runner:
    return Runner(pou("FB_CncIntegLinear") + f"""
PROGRAM main
VAR
    Interp : FB_CncIntegLinear;
    DX : LREAL; DY : LREAL; DZ : LREAL; VMax : LREAL; A : LREAL; Go : BOOL;
    PX : ARRAY[0..{MAX_POINTS}] OF LREAL;
    PY : ARRAY[0..{MAX_POINTS}] OF LREAL;
    PZ : ARRAY[0..{MAX_POINTS}] OF LREAL;
    PV : ARRAY[0..{MAX_POINTS}] OF LREAL;
    N : DINT;
END_VAR
IF Go THEN
    Go := FALSE;
    Interp(Load := TRUE, DX := DX, DY := DY, DZ := DZ, VMax := VMax, A := A);
    N := 0;
    PX[0] := 0.0; PY[0] := 0.0; PZ[0] := 0.0; PV[0] := 0.0;
    WHILE Interp.Busy AND N < {MAX_POINTS} DO
        Interp(Load := FALSE);
        N := N + 1;
        PX[N] := Interp.X; PY[N] := Interp.Y; PZ[N] := Interp.Z; PV[N] := Interp.V;
    END_WHILE;
END_IF;
END_PROGRAM
""")


@lru_cache(maxsize=None)
def integ_circular() -> Runner:
    return Runner(pou("FC_CncAngle", "FB_CncIntegCircular") + f"""
PROGRAM main
VAR
    Interp : FB_CncIntegCircular;
    I : LREAL; J : LREAL; XE : LREAL; YE : LREAL; Ccw : BOOL; VMax : LREAL; A : LREAL; Go : BOOL;
    PX : ARRAY[0..{MAX_POINTS}] OF LREAL;
    PY : ARRAY[0..{MAX_POINTS}] OF LREAL;
    PPhi : ARRAY[0..{MAX_POINTS}] OF LREAL;
    PBound : ARRAY[0..{MAX_POINTS}] OF LREAL;
    N : DINT;
    Error : BOOL;
END_VAR
IF Go THEN
    Go := FALSE;
    Interp(Load := TRUE, I := I, J := J, XE := XE, YE := YE, Ccw := Ccw, VMax := VMax, A := A);
    Error := Interp.Error;
    N := 0;
    PX[0] := I; PY[0] := J; PPhi[0] := 0.0; PBound[0] := 0.0;
    WHILE Interp.Busy AND N < {MAX_POINTS} DO
        Interp(Load := FALSE);
        N := N + 1;
        PX[N] := Interp.X; PY[N] := Interp.Y; PPhi[N] := Interp.Phi; PBound[N] := Interp.ErrorBound;
    END_WHILE;
END_IF;
END_PROGRAM
""")
