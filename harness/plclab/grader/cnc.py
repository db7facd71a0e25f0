"""CNC requirement set: Task 4 of the CNC lab (docs/cnc.md), the students' own
FB_CncEvalLinear, the linear interpolator of the evaluation-function method (textbook
4.2.1.1, eq. 1-5).

The student hands in the whole program they were given (`plclab handout cnc`) with the body
of FB_CncEvalLinear written. The grader loads one straight frame at a time into the frame
table (as the harness loads every part program, GVL_CNC), presses SB1 and watches the table
it owns: where the drives took it after each fine cycle of 1 ms, which steps the STEP lines
commanded, and HL1 (program running), which goes dark when the frame is done. The segments
cover every quadrant, both axes alone and the diagonal; the feed asks for one iteration per
fine cycle, so each fine cycle is one iteration of the student's block.

Every failing row names the segment (its increments DX, DY in steps), what was expected with
its tolerance, and what the table did.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Optional

from plclab.nc.gcode import Frame
from plclab.nc.toolpath import segment_distance
from plclab.scenario import Session
from plclab.stands import cnc

from .registry import Checks, Requirement, RequirementSet, Scenario, register

H_MM = 0.01                      # the drives' step h
FEED = 600.0                     # mm/min: 1000 steps/s, one iteration per fine cycle (eq. 5)
FINE = cnc.FINE_CYCLE_S
PATH_BOUND = 1.0                 # steps: every visited point within h of the line (plain method)
SEGMENTS = ((37, 11), (-13, 29), (-41, -17), (9, -33),     # one in each quadrant, shallow and steep
            (0, 25), (-20, 0), (15, 15), (-24, 24), (28, -5))  # along an axis, the diagonals
SLACK = 0.2                      # s a frame may run beyond its |DX| + |DY| iterations

E1 = Requirement("E1", "Every frame ends exactly at its end point (no step more or less, tolerance 0), "
                       f"on {len(SEGMENTS)} segments in all four quadrants, along the axes and diagonal; "
                       "the frame is done (HL1 dark) within its |DX| + |DY| iterations "
                       f"+ {SLACK:g} s.", "segments")
E2 = Requirement("E2", f"Every visited point lies within {PATH_BOUND:g} step h of the frame's line "
                       "(eq. 1-3: the evaluation function keeps the path within one step).", "segments")
E3 = Requirement("E3", "Every step goes toward the end point: the direction bits follow the signs of the "
                       "increments in every quadrant (abstract coordinates).", "segments")
E4 = Requirement("E4", "The plain method makes one unit step per iteration (X or Y, never both in one "
                       f"fine cycle of {FINE * 1000:g} ms) and the drives miss no step (their step-rate "
                       "limit).", "segments")
REQUIREMENTS = (E1, E2, E3, E4)


def make_session(sources: list[tuple[str, str]], retain_path: Optional[Path], checked: Any = None) -> Session:
    """The student's program on a fresh CNC stand (drives of 0.01 mm)."""
    return cnc.SPEC.session(program=sources, retain_path=retain_path, checked=checked, step_mm=H_MM)


def _segment(s: Session, c: Checks, dx: int, dy: int, hl1: tuple[Any, Any]) -> None:
    """Run one frame of increments (dx, dy) steps from where the table is; check E1-E4."""
    axes = s.plant.axes
    start = (axes["X"].steps, axes["Y"].steps)
    end = (start[0] + dx, start[1] + dy)
    name = f"segment DX {dx:+d}, DY {dy:+d} steps from ({start[0]}, {start[1]})"
    frame = Frame(kind=1, start=(start[0] * H_MM, start[1] * H_MM, 0.0),
                  end=(end[0] * H_MM, end[1] * H_MM, 0.0), i=0.0, j=0.0, feed=FEED, line=1)
    missed_before = sum(s.plant.missed().values())
    cnc.load_frames(s, [frame], "evalfn")
    s.console.set(SB1=1)                          # pressed for two fine cycles
    t0 = s.now
    budget = (abs(dx) + abs(dy)) * FINE + SLACK
    owner, key = hl1
    points = [start]                              # the table after each fine cycle
    lit = False
    while s.now - t0 < budget:
        s.sim.step(1)
        if len(points) == 2:
            s.console.set(SB1=0)
        points.append((axes["X"].steps, axes["Y"].steps))
        on = bool(getattr(owner, key))
        lit = lit or on
        if lit and not on:
            break
    s._copy_trace()
    done = lit and not bool(getattr(owner, key))
    reached = points[-1]
    with c.requirement(E1) as rid:
        if c.check(rid, done, f"{name}: the frame done (HL1 dark) within {budget:.3f} s",
                   "HL1 still lit: the block never ends the frame (Busy stays TRUE)" if lit
                   else "HL1 never lit: the program did not start the frame", s.now):
            c.check(rid, reached == end, f"{name}: the table at ({end[0]}, {end[1]}) exactly (tolerance 0)",
                    f"at ({reached[0]}, {reached[1]}): {reached[0] - end[0]:+d}, {reached[1] - end[1]:+d} steps off",
                    s.now)
    with c.requirement(E2) as rid:
        worst = max(points, key=lambda q: segment_distance((*start, 0), (*end, 0), (*q, 0)))
        error = segment_distance((*start, 0), (*end, 0), (*worst, 0))
        c.check(rid, error <= PATH_BOUND + 1e-9,
                f"{name}: every point within {PATH_BOUND:g} step of the line (tolerance 0)",
                f"({worst[0]}, {worst[1]}) is {error:.2f} steps from it", s.now)
    moves = [(b[0] - a[0], b[1] - a[1]) for a, b in zip(points, points[1:])]
    with c.requirement(E3) as rid:
        for k, (mx, my) in enumerate(moves):
            wrong = [axis for axis, m, d in (("X", mx, dx), ("Y", my, dy)) if m and (d == 0 or (m > 0) != (d > 0))]
            if wrong:
                c.fail(rid, f"{name}: steps in X {'+' if dx > 0 else '-' if dx else 'none'}, "
                            f"Y {'+' if dy > 0 else '-' if dy else 'none'} only",
                       f"a step in {wrong[0]} {'+' if (mx if wrong[0] == 'X' else my) > 0 else '-'} "
                       f"(iteration {k + 1})", t0 + (k + 1) * FINE)
                break
    with c.requirement(E4) as rid:
        for k, (mx, my) in enumerate(moves):
            if mx and my:
                c.fail(rid, f"{name}: one unit step per iteration (X or Y)",
                       f"X and Y stepped in the same fine cycle (iteration {k + 1})", t0 + (k + 1) * FINE)
                break
        missed = sum(s.plant.missed().values()) - missed_before
        c.check(rid, missed == 0, f"{name}: no step missed by the drives (at most 1 per "
                                  f"{FINE * 1000:g} ms per axis)", f"{missed} steps missed", s.now)


def sc_segments(s: Session, c: Checks) -> None:
    """The segments one after another from where the last one ended; a frame that never ends
    is stopped with SB3 (emergency stop) before the next one is loaded."""
    hl1 = s.plc.resolve(cnc.SPEC.labels()["HL1"])
    for dx, dy in SEGMENTS:
        _segment(s, c, dx, dy, hl1)
        if bool(getattr(*hl1)):
            s.console.hold("SB3")                 # stop the runaway frame, then go on
            s.run(0.01)
            s.console.release("SB3")
            s.run(0.01)


register(RequirementSet(stand="cnc", task="task4",
                        title="CNC stand, Task 4: the evaluation-function linear interpolator (FB_CncEvalLinear)",
                        requirements=REQUIREMENTS, scenarios=(Scenario("segments", sc_segments),),
                        make_session=make_session))
