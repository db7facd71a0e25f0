"""Exploration: the student's program and the task's model answer under the same random
operator scripts, each in its own PLC with its own plant; what the stands show is compared.

Scripted scenarios check what their authors thought of; a student's mistake often shows only
after a console history nobody scripted (a stop followed by a second run, a restart in the
middle of a pause). Here the stand's generator (plclab.stands.operators, declared in the
StandSpec) writes seeded random scripts; both programs play each one; the first moment the
stands differ beyond the stand's declared tolerances and freedoms (stands.exploration.Rules,
which the scripted rows honour too) is a divergence. It is then shrunk to a minimal script
(fewest actions, shortest holds, earliest times; 1-minimal: each step needed), written in the
input-CSV format next to the traces, and the row says what the operator did, what each stand
showed and the student's ST statement that last wrote the first differing output.

Deterministic and bounded: the seed is a hash of the submission's text (the same file gives
the same report, byte for byte; in grade-class the class's, class_seed) and the budget is a
number of scripts and of shrinking runs, never wall-clock time (`plclab bench` reports what one
script costs). A budget spent without a divergence is a pass of the row; the report says how
much was explored.

Cheap where it can be (issue 30): while searching, a play records only the probe's changes
(full traces only on the report's replay), the model answer's side of a script is played once
and reused (ModelPlays; across a class too), and the scripts may be played in several
processes (search, `jobs`) with the same result. The scripts are coverage-guided (issue 29):
those that take the model answer to states not seen before are kept and mutated (Coverage).

Only the comparison is the grader's; what an operator does, what a stand shows and how
closely two stands must agree are the stand's (plclab.stands.exploration).
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import pickle
import random
import re
import sys
import tempfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Optional, Sequence

from plclab.errors import PlcLabError
from plclab.runtime.retain import MemoryRetainStore
from plclab.runtime.tracing import pair_reader
from plclab.scenario import Session, compiled_once, unrecorded_sessions
from plclab.stands.operators import (BLINK_END_TOL, BLINK_HALF_MAX, BLINKING, START_S, Exploration, Observed,
                                     blink_spans)
from plclab.stands.scripts import FAULT, POWER, Event, Script, fault_params, read_script, without

from .localize import output_attr

SUSPECT_MARGIN = 0.1       # s: an action this close to where two drifted programs differ is ambiguous
MOVE_SUSPECT = 0.35        # s: an ambiguous action is moved this much later and the script played again
JITTER = 0.03             # s: how far actions are moved to tell a difference from a one-scan coincidence
SHRINK_RUNS = 200          # default budget of the shrinker, in script plays (both programs)
MINIMAL_RUNS = 120         # plays more to make the shrunk script 1-minimal (each step needed)


# --------------------------------------------------------------------------- playing a script

class _Probe:
    """Samples what the stand shows at every scan (a step hook after the plant's own) and keeps
    only the changes: signal -> [(t, value)], the first entry the power-up value."""

    def __init__(self, plant: Any, observe: Callable[[Any, Any], dict[str, Any]], clock: Callable[[], float],
                 inner: Optional[_InnerReader] = None, unchanged: Optional[Callable[[Any], Any]] = None):
        self.plant, self.observe, self.clock = plant, observe, clock
        # (Exploration.unchanged) where it gives what it gave at the last look, so would observe
        self.unchanged, self._seen = unchanged, None
        self.last: Optional[dict[str, Any]] = None
        self.changes: dict[str, list[tuple[float, Any]]] = {}
        # the program's inner state (the model answer's, for coverage): [(t, state)] at each change
        self.inner, self.states = inner, []
        self._inner_last: Any = None
        # the plant's binding in the closed loop (set by play): where it stood idle this scan,
        # the plant is as it was at the last scan and so is what it shows
        self.binding: Any = None

    def step(self, _dt: float) -> None:
        last = self.last
        binding = self.binding
        if last is None or binding is None or not binding.idle:
            if self.unchanged is not None:
                seen = self.unchanged(self.plant)
                if seen == self._seen and last is not None:
                    return self._inner_step()
                self._seen = seen
            now = round(self.clock(), 6)     # the session's time of the scan about to run
            v = self.observe(self.plant, last)
            if last is None:
                self.changes = {k: [(now, x)] for k, x in v.items()}
            elif v != last:                  # most scans change nothing: one C-level comparison
                for k, x in v.items():
                    if x != last[k]:
                        self.changes[k].append((now, x))
            self.last = v
        self._inner_step()

    def _inner_step(self) -> None:
        if self.inner is not None:
            state = self.inner()
            if state != self._inner_last:
                self.states.append((round(self.clock(), 6), state))
                self._inner_last = state

    def quiet_watch(self) -> Optional[list[tuple[Any, Any]]]:
        """What a quiet stretch of the closed loop (plclab.runtime.sim) must stop at so that
        this probe misses nothing: the inner state's variables; None where the probe looks at
        every scan (no plant binding to say it stood idle)."""
        if self.binding is None or self.last is None:
            return None
        return [] if self.inner is None else self.inner.pairs()


def actions(script: Script) -> list[tuple[float, int, str, str, str]]:
    """The script as timed actions (time, order, kind, name, value): set, press, release,
    power, fault."""
    out = []
    for n, e in enumerate(script.events):
        if e.name == POWER:
            out.append((e.time, n, "power", e.name, e.value))
        elif e.name == FAULT:
            out.append((e.time, n, "fault", e.name, e.value))
        elif e.is_press:
            out.append((e.time, n, "press", e.name, "1"))
            out.append((e.time + e.hold, n, "release", e.name, "0"))
        else:
            out.append((e.time, n, "set", e.name, e.value))
    return sorted(out, key=lambda a: (round(a[0], 6), a[1]))


class _InnerReader:
    """Reads the running program's variables `paths` (those it has; PLC restarts make new
    objects, so they are looked up again after one)."""

    def __init__(self, s: Session, paths: Sequence[str]):
        self.session, self.paths = s, paths
        self._plc: Any = None
        self._get: Callable[[], tuple] = tuple
        self._found: list[tuple[Any, Any]] = []

    def pairs(self) -> list[tuple[Any, Any]]:
        """(container, key) of each variable read, as PLC.resolve gives them."""
        s = self.session
        if self._plc is not s.plc:
            self._plc = s.plc
            self._found = [s.plc.resolve(p) for p in self.paths if s.has(p)]
            self._get = pair_reader(self._found, as_tuple=True)
        return self._found

    def __call__(self) -> tuple:
        if self._plc is not self.session.plc:
            self.pairs()
        return self._get()


def unrecorded(s: Session) -> None:
    """Search without recording (issue 30): while exploring, the comparison needs only what the
    probe keeps, so the session's simulation is replaced by one that samples no signal, and a
    plant that writes into the session's trace (the TUR-10's true positions) is detached. The
    report's traces come from a replay of the failing script with full recording. Called again
    after each PLC restart (which builds a recording simulation anew)."""
    from plclab.runtime.sim import Simulation
    if s.sim.recording:                                # (a session made in unrecorded_sessions is not)
        extra = [p for p in s.sim.plants[1:]]          # probes attached after the plant's binding
        s.sim = Simulation(s.plc, plants=[s.plant], record_located=False)
        s.sim.plants.extend(extra)
    if getattr(s.plant, "trace", None) is s.trace:
        s.plant.trace = None


def play(s: Session, script: Script, expl: Optional[Exploration] = None, until: Optional[float] = None,
         split: Optional[tuple[float, Callable[[], None]]] = None, record: bool = True,
         inner: Sequence[str] = ()) -> Optional[_Probe]:
    """Play `script` on session `s` up to `until` (default: its end), logging each action so the
    timeline shows it. With `expl`, a probe records what the stand shows; returns it.
    `split = (t, fn)`: fn() is called once when plant time t is reached (a line tracer starts).
    `record=False`: no trace is kept (exploration's search: only the probe's changes count).
    `inner`: ST paths of the program's state the probe keeps too (the model answer's coverage)."""
    probe = _Probe(s.plant, expl.observe, lambda: s.now, _InnerReader(s, inner) if inner else None,
                   expl.unchanged) if expl is not None else None

    def attach() -> None:
        if not record:
            unrecorded(s)
        if probe is not None and probe not in s.sim.plants:
            s.sim.plants.append(probe)
        if probe is not None:
            probe.binding = next((b for b in s.sim.plants if getattr(b, "plant", None) is s.plant), None)

    def run_to(t: float) -> None:
        nonlocal split
        if split is not None and split[0] <= t:
            at, fn = split
            split = None
            run_to(at)
            fn()
        dt = round(t - s.now, 9)
        if dt > 0:
            s.run(dt)

    attach()
    end = script.duration if until is None else until
    for t, _n, kind, name, value in actions(script):
        if t >= end:
            break
        run_to(t)
        if kind == "set":
            s.console.set(**{name: int(float(value))})
        elif kind == "press":
            s.console.hold(name)
        elif kind == "release":
            s.console.release(name)
        elif kind == "power":
            s.restart_plc(off_time=float(value))
            attach()
        else:
            fname, params = fault_params(value)
            s.inject(fname, **params)
    run_to(end)
    return probe


# --------------------------------------------------------------------------- comparison

@dataclass(frozen=True)
class Divergence:
    """The first moment the stands differ beyond the tolerances."""

    time: float
    signal: Observed
    model: Any                   # the model answer's value then
    student: Any                 # the student's
    kind: str                    # 'value' | 'missing' | 'extra' | 'late' | 'early'
    since: float                 # the last time this signal agreed (where the line search starts)
    drift: float                 # how far the student lagged the model answer just before
    lag: float = 0.0             # late / early: by how much
    model_since: float = 0.0     # since when each stand showed its value at `time` (its last
    student_since: float = 0.0   # change at or before it): what each stand did, in the message

    def text(self, tick: float) -> str:
        o = self.signal
        first = (f"at {self.time:.2f} s the model answer has {o.name} {o.show(self.model)}, "
                 f"your program {o.name} {o.show(self.student)}")
        if self.kind == "late":
            first += f" (it changes {self.lag:.2f} s later than the model answer's)"
        elif self.kind == "early":
            first += f" (it changes {self.lag:.2f} s earlier than the model answer's)"
        return first


def story(expl: Exploration, script: Script, d: Divergence) -> str:
    """What the operator did last, what the model answer's stand did and what the student's
    did, in the console's words and from the compared traces only (never a cause they do not
    show): 'after step 6 (1.59 s SB1 pressed 0.20 s) the model answer's stand showed lift down
    (L3) from 2.93 s; yours showed lift up (L2) from 0.85 s: it did not change after that
    step'."""
    o = d.signal
    steps = [(n, e) for n, e in enumerate(script.events, 1) if e.time <= d.time + 1e-9]
    words = []
    if steps:
        n, e = steps[-1]
        words.append(f"after step {n} ({e.time:.2f} s {expl.describe(e)})")
    else:
        words.append("before any console step")
    words.append(f"the model answer's stand showed {o.name} {o.show(d.model)} from {d.model_since:.2f} s")
    yours = f"yours showed {o.name} {o.show(d.student)} from {d.student_since:.2f} s"
    if steps and d.student_since < steps[-1][1].time and d.model_since >= steps[-1][1].time:
        yours += ": it did not change after that step"
    elif steps and d.model_since < steps[-1][1].time <= d.student_since:
        yours += ": the model answer's did not change after that step"
    return f"{words[0]} {words[1]}; {yours}"


def _last_change(changes: list[tuple[float, Any]], t: float) -> tuple[float, Any]:
    """The change in effect at `t` (time, value): the last one at or before it."""
    last = changes[0]
    for c in changes:
        if c[0] > t + 1e-9:
            break
        last = c
    return last


def _value_at(changes: list[tuple[float, Any]], t: float) -> Any:
    return _last_change(changes, t)[1]


def _windows(script: Script, switch: str, value: int, settle: float) -> list[tuple[float, float]]:
    """The spans when console `switch` has had `value` for `settle` s (power-up: 0)."""
    spans, state, since = [], 0, 0.0
    for e in script.events:
        if e.name != switch or e.is_press:
            continue
        v = int(float(e.value))
        if v == state:
            continue
        if state == value:
            spans.append((since + settle, e.time))
        state, since = v, e.time
    if state == value:
        spans.append((since + settle, float("inf")))
    return [(a, b) for a, b in spans if b > a]


def _until_press(script: Script, switch: str, value: int, button: str, after: float = 0.0) -> list[tuple[float, float]]:
    """The spans from each change of console `switch` to `value` until `button`'s first press
    after it and `after` s more (or the switch's next change)."""
    spans: list[tuple[float, float]] = []
    state, start = 0, None
    for e in script.events:
        if e.name == button and e.is_press and start is not None:
            spans.append((start, e.time + after))
            start = None
        elif e.name == switch and not e.is_press:
            v = int(float(e.value))
            if v != state and start is not None:
                spans.append((start, e.time))
                start = None
            if v != state and v == value:
                start = e.time
            state = v
    if start is not None:
        spans.append((start, float("inf")))
    return [(a, b) for a, b in spans if b > a]


def _outside(windows: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """The complement of `windows` from 0 on."""
    out, at = [], 0.0
    for a, b in sorted(windows):
        if a > at:
            out.append((at, a))
        at = max(at, b)
    if at != float("inf"):
        out.append((at, float("inf")))
    return out


def _merged(changes: list, o: Observed) -> list:
    """`changes` without a change to a value the signal's tolerance takes for the one before (a
    window opening on a link at rest a few codes, or for a motion-only signal any distance, from
    where it stood)."""
    out = changes[:1]
    for t, v in changes[1:]:
        if not o.equal(out[-1][1], v):
            out.append((t, v))
    return out


def _in(spans: list[tuple[float, float]], t: float) -> bool:
    return any(a <= t < b for a, b in spans)


def _free_blinks(cm: list, cs: list, mode: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """The blinks of either lamp pattern that begin in `mode` (console spans), to their end and
    BLINK_END_TOL after (a blink begun there may go on after the mode changes)."""
    return [(a, b + BLINK_END_TOL) for a, b in blink_spans(cm) + blink_spans(cs) if _in(mode, a)]


def _free_after(script: Script, switch: str, conditions: tuple[tuple[str, int], ...],
                settle: float, after_drop: Optional[str] = None) -> list[tuple[float, float]]:
    """From each change of `switch` while every console switch of `conditions` has its value,
    until one of them next changes, and `settle` s after (Exploration.free_after). With
    `after_drop` (a button): only from a change of `switch` back to 1 after it dropped to 0
    since that button's last press, the conditions holding throughout (Task 3's enable dropped
    during a run and back before the last pause ends: read as a level then, or latched from
    its drop, the text allows both)."""
    spans: list[tuple[float, float]] = []
    level: dict[str, int] = {}
    start = None
    dropped = False
    for e in script.events:
        if after_drop is not None and e.name == after_drop and e.is_press:
            dropped = False
            continue
        if e.is_press or (e.name != switch and e.name not in dict(conditions)):
            continue
        v = int(float(e.value))
        if e.name == switch:
            changed = v != level.get(switch, 0)
            level[switch] = v
            held = all(level.get(n, 0) == want for n, want in conditions)
            if after_drop is not None:
                if changed and held and v == 0:
                    dropped = True
                if not (changed and held and v == 1 and dropped):
                    continue
            if changed and start is None and held:
                start = e.time
        else:
            if v != level.get(e.name, 0):
                dropped = False
                if start is not None:
                    spans.append((start, e.time + settle))
                    start = None
            level[e.name] = v
    if start is not None:
        spans.append((start, float("inf")))
    return spans


def _blink_to_end(shown: list, end: float, tick: float) -> list:
    """A lamp pattern whose last blink was still going when the script ended: the on/off state
    its last toggle left is where the script cut it, not a state the lamp settled in (which
    phase the two lamps stand in at END moves with END): the blink runs to the end."""
    if len(shown) >= 3 and shown[-2][1] == BLINKING and shown[-1][0] >= end - BLINK_HALF_MAX - 2 * tick:
        return shown[:-1]
    return shown


def _without(cm: list, cs: list, spans: list[tuple[float, float]]) -> tuple[list, list]:
    """Both change lists with what they show inside `spans` taken out: at the end of each span
    each keeps the value it shows then."""
    merged: list[tuple[float, float]] = []
    for a, b in sorted(spans):
        if merged and a <= merged[-1][1]:
            merged[-1] = (merged[-1][0], max(merged[-1][1], b))
        else:
            merged.append((a, b))
    if not merged:
        return cm, cs

    def cut(changes: list) -> list:
        out = changes[:1] + [c for c in changes[1:] if not any(a <= c[0] < b for a, b in merged)]
        out += [(b, _value_at(changes, b)) for _a, b in merged if b != float("inf")]
        out = out[:1] + sorted(out[1:], key=lambda c: c[0])
        dedup = out[:1]
        for t, v in out[1:]:
            if v != dedup[-1][1]:
                dedup.append((t, v))
        return dedup
    return cut(cm), cut(cs)


def compare(model: dict[str, list], student: dict[str, list], observed: Sequence[Observed], expl: Exploration,
            script: Script, end: float, task: str = "") -> Optional[Divergence]:
    """The first divergence of `student` from `model` (probe changes), or None.

    Each signal's changes are paired in order: a pair must carry the same value (the signal's
    own tolerance) and come at the same time within `timing_tol`, or within `timing_tol` of
    the lag the student had at the pair before (a program a scan late at every frame is late
    by a scan more each frame, plus `drift_rate` of the time since), and never more than
    `max_drift` late in all. A change one program makes and the other does not is a divergence
    unless it comes so near the end of the script that the other had no time to make it.

    The task's freedoms, declared by the stand, come first: a signal is compared as the
    operator sees it (`Observed.pattern`: a lamp on, off or blinking), a change into or out of
    a shown value may have a looser timing (`Observed.timing`), spans the task leaves to the
    program are taken out (`Exploration.free_after` of `task`, `Observed.free_blinks`), and a
    value may differ more the further apart in time the two stands are (`Observed.lag_band`)."""
    tol, cut = expl.timing_tol, end - expl.max_drift - expl.timing_tol
    found: list[Divergence] = []
    pairs: list[tuple[float, float, Observed, float]] = []      # (tm, ts, signal, since)
    shown: dict[str, tuple[list, list]] = {}
    free = [span for switch, conditions, *after_drop in expl.free_after(task) for span in
            _free_after(script, switch, conditions, expl.settle_s, *after_drop)]
    for o in observed:
        cm, cs = o.shown(model[o.name]), o.shown(student[o.name])
        if o.pattern is not None:                   # a blink cut by the script's end: not its last state
            cm, cs = _blink_to_end(cm, end, expl.tick_s), _blink_to_end(cs, end, expl.tick_s)
        spans = list(free)
        if o.free_blinks is not None:
            spans += _free_blinks(cm, cs, _windows(script, *o.free_blinks, 0.0))
        cm, cs = _without(cm, cs, spans)
        if o.only_when is not None or o.until_press is not None:
            # compared inside its windows only, each window from what both stands show as it
            # opens (never a value left over from before it)
            windows = _windows(script, *o.only_when) if o.only_when is not None else []
            if o.until_press is not None:
                windows += _until_press(script, *o.until_press)
            cm, cs = _without(cm, cs, _outside(windows))
            cm, cs = _merged(cm, o), _merged(cs, o)
        shown[o.name] = (cm, cs)
        since, moving_lag = 0.0, 0.0
        if not o.equal(cm[0][1], cs[0][1]):
            found.append(Divergence(0.0, o, cm[0][1], cs[0][1], "value", 0.0, 0.0))
            continue
        for k in range(1, max(len(cm), len(cs))):
            if k < len(cm) and k < len(cs):
                (tm, vm), (ts, vs) = cm[k], cs[k]
                lag = max(abs(ts - tm), abs(cs[k - 1][0] - cm[k - 1][0]) if k > 1 else 0.0)
                if o.rest is not None:
                    # the lag since both last stood still at the same place: a stop pressed in
                    # the same scan on both stands leaves the later starter that much travel
                    # short, and a link that cannot move (a stuck drive) keeps that difference
                    if o.rest(cm[k - 1][1]) and o.rest(cs[k - 1][1]) and o.equal(cm[k - 1][1], cs[k - 1][1]):
                        moving_lag = 0.0
                    moving_lag = max(moving_lag, abs(ts - tm))
                    lag = max(lag, moving_lag)
                if not o.equal(vm, vs, lag):
                    t = max(tm, ts)
                    found.append(Divergence(t, o, vm, vs, "value", since, ts - tm))
                    break
                loose = o.timing_tol(cm[k - 1][1], vm)
                if loose is None:
                    pairs.append((tm, ts, o, since))
                elif abs(ts - tm) > loose:                   # a freedom of the task, and beyond it
                    kind, t = ("late", tm) if ts > tm else ("early", ts)
                    found.append(Divergence(t, o, _value_at(cm, t), _value_at(cs, t), kind, since, 0.0,
                                            abs(ts - tm)))
                    break
                since = min(tm, ts)
            elif k < len(cm):
                tm, vm = cm[k]
                if tm <= min(cut, end - (o.timing_tol(cm[k - 1][1], vm) or 0.0)):
                    found.append(Divergence(tm, o, vm, _value_at(cs, tm), "missing", since, 0.0))
                break
            else:
                ts, vs = cs[k]
                if ts <= min(cut, end - (o.timing_tol(cs[k - 1][1], vs) or 0.0)):
                    found.append(Divergence(ts, o, _value_at(cm, ts), vs, "extra", since, 0.0))
                break
    prev, prev_t = 0.0, 0.0
    for tm, ts, o, since in sorted(pairs, key=lambda p: (p[0], p[1])):
        d = ts - tm
        if (abs(d) > tol and abs(d - prev) > tol + expl.drift_rate * (tm - prev_t)) or abs(d) > expl.max_drift:
            cm, cs = shown[o.name]
            if d > 0:
                found.append(Divergence(tm, o, _value_at(cm, tm), _value_at(cs, tm), "late", since, prev, d))
            else:
                found.append(Divergence(ts, o, _value_at(cm, ts), _value_at(cs, ts), "early", since, prev, -d))
            break
        prev, prev_t = d, tm
    if not found:
        return None
    first = min(found, key=lambda d: d.time)
    drift = 0.0
    for tm, ts, _o, _s in sorted(pairs, key=lambda p: (p[0], p[1])):
        if tm < first.time:
            drift = ts - tm
    o = first.signal                 # since when: from what each stand showed, not the windows compared
    cm, cs = o.shown(model[o.name]), o.shown(student[o.name])
    return Divergence(first.time, first.signal, first.model, first.student, first.kind, first.since, drift,
                      first.lag, _since(cm, first.time), _since(cs, first.time))


def _since(changes: list, t: float) -> float:
    """When the value shown at `t` began (its last change at or before `t`)."""
    return _last_change(changes, t)[0]


def suspects(script: Script, div: Divergence, model: dict, student: dict, observed: Sequence[Observed],
             tick: float, max_drift: float = 1.0) -> set[int]:
    """Actions so close to where the two programs' timing differs that which side of a
    transition they fall on decides the outcome (a correct program a scan later than the
    model answer must not fail for a press in that scan): their indexes in the script. The
    programs may be apart by as much as the stand lets them drift (`max_drift`)."""
    spans: list[tuple[float, float]] = []
    if abs(div.drift) >= tick / 2:
        spans.append((div.time - abs(div.drift) - SUSPECT_MARGIN, div.time + SUSPECT_MARGIN))
    for o in observed:
        for (tm, _vm), (ts, _vs) in zip(o.shown(model[o.name])[1:], o.shown(student[o.name])[1:]):
            if max(tm, ts) >= div.time:
                break
            if tick / 2 <= abs(ts - tm) <= max_drift:           # two programs a little apart in time
                spans.append((min(tm, ts) - SUSPECT_MARGIN, max(tm, ts) + SUSPECT_MARGIN))
    out = set()
    for n, e in enumerate(script.events):
        times = [e.time] + ([e.time + e.hold] if e.is_press else [])
        if any(a <= t <= b for t in times for a, b in spans):
            out.add(n)
    return out


# --------------------------------------------------------------------------- the two stands

@dataclass
class Program:
    """One side of the comparison: sources, the front end's result, a compiled-once cache."""

    sources: list[tuple[str, str]]
    checked: Any
    cache: list = field(default_factory=list)


@dataclass
class Outcome:
    divergence: Optional[Divergence]
    suspect: set[int]
    model: Optional[Session] = None
    student: Optional[Session] = None


@dataclass(frozen=True)
class ModelPlay:
    """The model answer's side of one script: what its stand showed (probe changes) and the
    states its program went through ([(t, state)], Exploration.state_paths)."""

    changes: dict[str, list[tuple[float, Any]]]
    states: list[tuple[float, tuple]]

    @property
    def phases(self) -> list[float]:
        """The moments the model answer's stand changed (where an aimed script acts)."""
        return sorted({t for ch in self.changes.values() for t, _v in ch[1:]})


class ModelPlays:
    """The model answer's plays, each script played once (issue 30): its play does not depend
    on the student, so the confirming, jitter and shrink replays of a grade, and in
    `grade-class` every student of the class (the same scripts: the class's seed), reuse it.
    Stored compactly (a zlib'd pickle per script), in memory and, with `folder`, on disk for
    the class's other grading processes (each file written whole, then renamed into place)."""

    def __init__(self, salt: str, folder: Optional[Path] = None):
        self.salt, self.folder = salt, folder
        self.memory: dict[str, bytes] = {}
        self.played = 0                     # plays of the model answer (misses)

    def key(self, script: Script) -> str:
        return hashlib.sha256(f"{self.salt}\0{script!r}".encode()).hexdigest()[:32]

    def get(self, script: Script) -> Optional[ModelPlay]:
        k = self.key(script)
        blob = self.memory.get(k)
        if blob is None and self.folder is not None:
            try:
                blob = (self.folder / f"{k}.play").read_bytes()
            except OSError:
                blob = None
            if blob is not None:
                self.memory[k] = blob
        if blob is None:
            return None
        changes, states = pickle.loads(zlib.decompress(blob))
        return ModelPlay(changes, states)

    def put(self, script: Script, play: ModelPlay) -> None:
        k = self.key(script)
        blob = zlib.compress(pickle.dumps((play.changes, play.states), protocol=pickle.HIGHEST_PROTOCOL), 6)
        self.memory[k] = blob
        if self.folder is not None:
            with contextlib.suppress(OSError):            # a cache: a failed write costs a replay only
                tmp = self.folder / f"{k}.{os.getpid()}.tmp"
                tmp.write_bytes(blob)
                os.replace(tmp, self.folder / f"{k}.play")


def _model_salt(stand_task: str, model: "Program") -> str:
    h = hashlib.sha256(stand_task.encode())
    for name, text in model.sources:
        h.update(f"\0{name}\0{text}".encode("utf-8", "replace"))
    return h.hexdigest()


class Explorer:
    """Plays scripts on the model answer and the student's program and compares them.

    While searching nothing is recorded but what the comparison needs (the probes' changes),
    and the model answer's side of each script is played once (`model_plays`); `record=True`
    plays as before issue 30 (both programs, full traces: what the tests compare against)."""

    def __init__(self, expl: Exploration, task: str, make_session: Callable, student: Program, model: Program,
                 model_plays: Optional[ModelPlays] = None, record: bool = False):
        self.expl, self.task, self.make_session = expl, task, make_session
        self.student, self.model = student, model
        self.observed = expl.compared(task)
        self.plays = 0
        self.phases: list[float] = []
        self.record = record
        self.model_plays = model_plays if model_plays is not None else ModelPlays(_model_salt(task, model))
        self._judged: dict[Script, Optional[Divergence]] = {}     # diverges(), by script
        self._unconfirmed: dict[Script, Optional[Divergence]] = {}   # the same, robustness not played

    def model_side(self, script: Script) -> ModelPlay:
        """The model answer's play of `script`: played once, then reused."""
        known = None if self.record else self.model_plays.get(script)
        if known is not None:
            return known
        _s, probe = self.run(self.model, "model", script, record=self.record, inner=self.expl.state_paths)
        assert probe is not None
        self.model_plays.played += 1
        out = ModelPlay(probe.changes, probe.states)
        if not self.record:
            self.model_plays.put(script, out)
        return out

    def session(self, p: Program, name: str) -> Session:
        retain = MemoryRetainStore()          # a fresh controller's memory, kept across its restarts
        with compiled_once(p.checked, share=p.cache):
            return self.make_session(p.sources, retain, p.checked)

    def run(self, p: Program, name: str, script: Script, until: Optional[float] = None,
            expl: bool = True, record: bool = True, inner: Sequence[str] = ()) -> tuple[Session, Optional[_Probe]]:
        with compiled_once(p.checked, share=p.cache):
            with unrecorded_sessions(not record):     # play() drops the recording at once
                s = self.session(p, name)
            probe = play(s, script, self.expl if expl else None, until, record=record, inner=inner)
        return s, probe

    def outcome(self, script: Script, keep: bool = False, record_phases: bool = False) -> Outcome:
        """Both programs on `script`: the divergence (None: alike) and the ambiguous actions.
        `record_phases`: keep the times the model answer's stand changed (`phases`: where the
        next script aims its actions). `keep`: both sessions, fully recorded, for the report."""
        self.plays += 1
        ms: Optional[Session] = None
        if keep:
            ms, mp = self.run(self.model, "model", script)
            assert mp is not None
            model = ModelPlay(mp.changes, [])
        else:
            model = self.model_side(script)
        ss, sp = self.run(self.student, "student", script, record=keep or self.record)
        assert sp is not None
        if record_phases:
            self.phases = model.phases
        div = compare(model.changes, sp.changes, self.observed, self.expl, script, script.duration, self.task)
        sus = suspects(script, div, model.changes, sp.changes, self.observed, self.expl.tick_s,
                       self.expl.max_drift) if div else set()
        return Outcome(div, sus, ms, ss if keep else None)

    def confirmed(self, script: Script, tries: int = 3) -> tuple[Script, Optional[Divergence], bool]:
        """A divergence not owed to an ambiguous action: such actions are moved a little later
        and the script played again (at most `tries` times; still ambiguous: no divergence, and
        the third value is True)."""
        for n in range(tries):
            out = self.outcome(script, record_phases=n == 0)
            if out.divergence is None:
                return script, None, False
            if not out.suspect:
                if not self.robust(script):
                    return script, None, True
                return script, out.divergence, False
            events = [Event(round(e.time + MOVE_SUSPECT, 3), e.name, e.value, e.hold) if n in out.suspect else e
                      for n, e in enumerate(script.events)]
            script = Script(tuple(sorted(events, key=lambda e: e.time)),
                            round(max(script.duration, max(e.time + e.hold for e in events) + 1.0), 3))
        return script, None, True

    def diverges(self, script: Script, confirm: bool = True) -> Optional[Divergence]:
        """The divergence of `script`, if no action is ambiguous and it does not hang on the scan
        the actions fall in (robust; `confirm=False`: that is not played, the shrinker confirms
        a whole pass's result at once). Each script is judged once: the shrinker comes back to
        a candidate it has tried (its last pass over single steps, when nothing else gained),
        and the answer cannot differ (virtual time), so it costs no play of its budget again."""
        if script in self._judged:
            return self._judged[script]
        if script not in self._unconfirmed:
            out = self.outcome(script)
            self._unconfirmed[script] = None if out.divergence is None or out.suspect else out.divergence
        seen = self._unconfirmed[script]
        if not confirm or seen is None:
            return seen
        found = seen if self.robust(script) else None
        self._judged[script] = found
        return found

    def robust(self, script: Script) -> bool:
        """The stands still differ with the actions a few scans off (every other one JITTER s
        earlier, the others later, and the other way round): a difference only one scan's
        coincidence shows (a stop press in the very scan a frame starts) decides nothing, as a
        hold at a threshold decides nothing."""
        return all(self.outcome(jittered(script, sign)).divergence is not None for sign in (1, -1))


def jittered(script: Script, sign: int) -> Script:
    """`script` with its actions JITTER s later and earlier in turn (`sign`: which come first)."""
    events = [Event(round(max(e.time + (JITTER if (n % 2 == 0) == (sign > 0) else -JITTER), 0.0), 3), e.name,
                    e.value, e.hold) for n, e in enumerate(script.events)]
    return Script(tuple(sorted(events, key=lambda e: e.time)), round(script.duration + JITTER, 3))


# --------------------------------------------------------------------------- shrinking

def _truncated(script: Script, div: Divergence, expl: Exploration) -> Script:
    end = round(div.time + expl.max_drift + expl.timing_tol + 0.3, 3)
    events = tuple(e for e in script.events if e.time <= div.time)
    return Script(events, min(script.duration, end))


SQUEEZE_GAPS = (0.3, 1.0, 3.5, 8.0)     # s: the caps tried on every wait between two actions at once


def squeezed(script: Script, cap: float) -> Script:
    """`script` with every wait between one action's end and the next action cut to `cap` s at
    most (and the first action's from START_S), the later actions moved with it."""
    events, shift, prev_end = [], 0.0, START_S
    for e in script.events:
        t = round(e.time - shift, 3)
        if t - prev_end > cap:
            cut = round(t - prev_end - cap, 3)
            shift, t = round(shift + cut, 3), round(t - cut, 3)
        events.append(Event(t, e.name, e.value, e.hold))
        prev_end = t + e.hold
    return Script(tuple(events), round(script.duration - shift, 3))


def started_later(script: Script, k: int) -> Optional[Script]:
    """`script` from its action `k` on, moved to begin at START_S (None: nothing to move)."""
    shift = round(script.events[k].time - START_S, 3)
    if shift <= 0:
        return None
    return Script(tuple(Event(round(e.time - shift, 3), e.name, e.value, e.hold) for e in script.events[k:]),
                  round(script.duration - shift, 3))


def shrink(ex: Explorer, script: Script, div: Divergence, budget: int = SHRINK_RUNS) -> tuple[Script, Divergence]:
    """A smaller script that still diverges: shortest first (every wait cut at once, the latest
    start), then fewest actions (chunks then single actions removed), shortest holds, earliest
    times (gaps halved). Each candidate is played on both programs; about `budget` plays
    (deterministic).

    A play costs what its script lasts, so the cuts that shorten the whole script come first:
    the candidates after them are cheaper. A removal (or a shorter hold, a later start) is
    taken on its one play; whether the pass's result is robust (Explorer.robust: its actions
    moved a few scans) is played once at the pass's end, and a pass whose result is not is
    undone. The moves of actions (cut waits, earlier times) and the last pass, for
    1-minimality, confirm each change as they take it. So the script returned is always
    robust. The confirmations may take a few plays past `budget`."""
    start = ex.plays
    best, best_div = _truncated(script, div, ex.expl), div

    def left() -> bool:
        return ex.plays - start < budget

    def accept(candidate: Optional[Script], confirm: bool = False) -> bool:
        nonlocal best, best_div
        if candidate is None or not left():
            return False
        d = ex.diverges(candidate, confirm=confirm)
        if d is None:
            return False
        best, best_div = _truncated(candidate, d, ex.expl), d
        return True

    def confirmed(since: tuple[Script, Divergence]) -> None:
        """The pass that began at `since` is kept if its result is robust, else undone."""
        nonlocal best, best_div
        if best is not since[0] and ex.diverges(best) is None:
            best, best_div = since

    if ex.diverges(best) is None:                    # truncation changed the outcome: keep the whole
        best = script
    # 0. shortest: every wait cut to a cap at once (the smallest that still shows it, confirmed
    #    as it is taken: a cap is a move of actions), then the latest start (the first actions
    #    dropped, the rest moved to the start; a binary search)
    for cap in SQUEEZE_GAPS:
        cand = squeezed(best, cap)
        if best.duration - cand.duration >= 0.5 and accept(cand, confirm=True):
            break
    since = (best, best_div)
    lo, hi = 0, len(best.events) - 1
    while lo < hi and left():
        k = (lo + hi + 1) // 2
        if accept(started_later(best, k)):
            lo, hi = 0, len(best.events) - 1
        else:
            hi = k - 1
    confirmed(since)
    # rounds of: fewer actions, shorter holds, earlier times, while one of them gains
    for _round in range(3):
        before = (len(best.events), best.duration, sum(e.hold for e in best.events))
        # 1. fewest actions: chunks of 16, 8, 4, 2 then single actions removed, from the end back
        since = (best, best_div)
        for size in ((16, 8, 4, 2, 1) if _round == 0 else (2, 1)):
            i = len(best.events) - size
            while i >= 0 and left():
                drop = set(range(i, min(i + size, len(best.events))))
                cand = Script(tuple(e for k, e in enumerate(best.events) if k not in drop), best.duration)
                accept(cand)
                i = min(i, len(best.events)) - size
            if size > 1 and not left():
                break
        confirmed(since)
        # 2. shortest holds
        since = (best, best_div)
        for i in range(len(best.events)):
            if not left() or i >= len(best.events):
                break
            e = best.events[i]
            if e.is_press:
                for hold in ((3.3,) if e.hold >= 3.3 else (0.2,) if e.hold > 0.2 else ()):
                    events = list(best.events)
                    events[i] = Event(e.time, e.name, e.value, hold)
                    if accept(Script(tuple(events), best.duration)):
                        break
        confirmed(since)
        # 3. earliest times: the gap before each action shrunk (the later ones move with it), the
        #    first action to START_S (the PLC has read its inputs once), every gap to 0.3 s, else
        #    to half. Moving actions closer is how a difference comes to hang on one scan's
        #    coincidence, so each move is confirmed robust as it is taken.
        for _ in range(2):
            for i in range(len(best.events)):
                if not left() or i >= len(best.events):
                    break
                prev = best.events[i - 1].time + best.events[i - 1].hold if i else START_S
                gap = best.events[i].time - prev
                for new_gap in ((0.0 if i == 0 else 0.3), round(gap / 2, 2)):
                    if gap - new_gap < 0.1:
                        continue
                    shift = round(gap - new_gap, 2)
                    events = list(best.events[:i]) + [Event(round(e.time - shift, 3), e.name, e.value, e.hold)
                                                       for e in best.events[i:]]
                    if accept(Script(tuple(events), round(best.duration - shift, 3)), confirm=True):
                        break
        if (len(best.events), best.duration, sum(e.hold for e in best.events)) == before or not left():
            break
    # 4. 1-minimal: no single action can be removed and the script still show the difference
    #    (shorter holds and earlier times may have made an action unneeded after its removal
    #    was tried); a budget of its own, so the report never shows a step that does not matter.
    #    Each removal is confirmed robust as it is taken.
    start, budget = ex.plays, MINIMAL_RUNS
    removed = True
    while removed and left():
        removed = False
        for i in reversed(range(len(best.events))):
            if not left():
                break
            if i < len(best.events) and accept(without(best, {i}), confirm=True):
                removed = True
    return best, best_div


# --------------------------------------------------------------------------- the student's line

def first_differing_output(model: Session, student: Session, div: Divergence) -> tuple[Optional[str], float]:
    """The first output driving the diverging signal that differs between the two programs,
    and the scan it first differs in (from `div.since` to the divergence)."""
    outputs = [o for o in div.signal.outputs if o in model.trace and o in student.trace]
    times = set()
    for o in outputs:
        for tr in (model.trace, student.trace):
            times.update(t / 1e9 for t, _v in tr.changes(o) if div.since - 1e-9 <= t / 1e9 <= div.time + 1e-9)
    for t in sorted(times):
        for o in outputs:
            if model.trace.value_at(o, t) != student.trace.value_at(o, t):
                return o, t
    return (outputs[0] if outputs else None), div.time


def last_writer(ex: Explorer, script: Script, output: str, t: float, since: float) -> Optional[tuple[str, int, str]]:
    """(file, line, statement) of the student's ST statement that last wrote `output` up to and
    in the scan at plant time `t` (looked for up to 5 s back): the script is
    played again, the scans from there under a line tracer; the generated Python's line map
    (`plclab check --emit-python`) names the ST line."""
    from plclab.runtime.native import python_only
    # the line tracer follows the generated Python: this replay runs the Python path
    with compiled_once(ex.student.checked, share=ex.student.cache), python_only():
        s = ex.session(ex.student, "line")
        target = output_attr(s, output)
        if target is None:
            return None
        owner, attr = target
        compiled = s.plc.compiled
        pattern = re.compile(rf"(?:^|[^\w.])G\.{re.escape(attr)}\s*=(?!=)")
        writers = {n for n, line in enumerate(compiled.source.splitlines(), 1) if pattern.search(line)}
        hits: list[int] = []
        changed: list[int] = []
        state: dict[str, Any] = {"line": None}

        def local(frame: Any, event: str, _arg: Any) -> Any:
            if event == "line":
                if state.get("plc") is not s.plc:                   # a PLC restart makes new objects
                    state["plc"], state["oa"] = s.plc, output_attr(s, output) or (owner, attr)
                o, a = state["oa"]
                now = getattr(o, a, None)
                if "value" in state and now != state["value"] and state["line"] is not None:
                    changed.append(state["line"])
                state["value"] = now
                state["line"] = frame.f_lineno
                if frame.f_lineno in writers:
                    hits.append(frame.f_lineno)
            return local

        def global_(frame: Any, event: str, _arg: Any) -> Any:
            return local if frame.f_code.co_filename == s.plc.compiled.filename else None

        old = sys.gettrace()
        start = round(max(t - 5.0, 0.0) / ex.expl.tick_s) * ex.expl.tick_s
        try:
            play(s, script, None, until=t + ex.expl.tick_s / 2, split=(start, lambda: sys.settrace(global_)))
        finally:
            sys.settrace(old)
        for n in reversed(hits or changed):
            info = compiled.where(n)
            if info is not None:
                return info.file, info.line, _st_line(ex.student.sources, info.file, info.line)
    return None


def _st_line(sources: Sequence[tuple[str, str]], file: str, line: int) -> str:
    for name, text in sources:
        if name == file:
            lines = text.splitlines()
            return lines[line - 1].strip() if 0 < line <= len(lines) else ""
    return ""


# --------------------------------------------------------------------------- a task's exploration

@dataclass
class Finding:
    """What exploration found: the shrunk script, the divergence, the student's line."""

    script: Script
    divergence: Divergence
    steps: list[str]
    first_difference: str
    line: Optional[tuple[str, int, str]]
    output: Optional[str]
    output_time: float
    model_output: Any = None
    student_output: Any = None
    candidates: list = field(default_factory=list)     # localize.Candidate, most likely first


@dataclass
class ExploreResult:
    """The result of exploring one task for one program."""

    episodes: int
    plant_seconds: float
    plays: int
    seed: int
    inconclusive: int = 0
    finding: Optional[Finding] = None
    model_plays: int = 0          # plays of the model answer while searching (the others were reused)


def _fast_tmp() -> Optional[str]:
    """A folder in memory (/dev/shm where there is one) for the model answer's plays the
    bench shares between its runs: thousands of scripts must not wait for a disk."""
    shm = Path("/dev/shm")
    return str(shm) if shm.is_dir() and os.access(shm, os.W_OK) else None


def seed_of(stand: str, task: str, sources: Sequence[tuple[str, str]]) -> int:
    """The seed: the submission's content (file texts, not names or paths), stand and task."""
    h = hashlib.sha256(f"{stand}\0{task}".encode())
    for _name, text in sources:
        h.update(b"\0")
        h.update(text.encode("utf-8", "replace"))
    return int.from_bytes(h.digest()[:8], "big")


# --------------------------------------------------------------------------- the scripts explored

ROUND_UNITS = 4        # units drawn from one state of the coverage (a unit: a script, then one aimed at it)
MUTATE_SHARE = 0.5     # of the units after the first round: a kept script mutated instead of a new one
BURST = (1, 6)         # a mutation's burst of button presses: how many, mostly
LONG_BURST = (8, 36)   # and one burst in LONG_SHARE: a frame memory filled and more, start/stop at every phase
LONG_SHARE = 0.3


@dataclass
class Coverage:
    """Coverage-guided exploration (issue 29): the model answer's states the scripts have
    reached (console mode x plant fault x the program's phase, frame, memory count and
    watchdog fault, Exploration.state_paths), and the corpus: the scripts that reached states
    not seen before, with the moments they first did (where their mutations act)."""

    seen: set = field(default_factory=set)
    corpus: list[tuple[Script, list[float]]] = field(default_factory=list)

    def add(self, script: Script, states: dict[tuple, float]) -> None:
        new = sorted(t for s, t in states.items() if s not in self.seen)
        self.seen.update(states)
        if new:
            self.corpus.append((script, new))


def states_of(ex: Explorer, script: Script) -> dict[tuple, float]:
    """The model answer's states `script` reaches, each with the first moment it does."""
    mode_switch = next((k for k, v in ex.expl.meaning.items() if v == ("manual", "automatic")), None)
    inner = ex.model_side(script).states
    points = sorted({t for t, _s in inner} | {e.time for e in script.events
                                              if e.name in (mode_switch, FAULT) and not e.is_press})
    out: dict[tuple, float] = {}
    mode, faulted, k, state = 0, False, 0, ()
    events = [e for e in script.events if e.name in (mode_switch, FAULT) and not e.is_press]
    j = 0
    for t in points:
        while j < len(events) and events[j].time <= t + 1e-9:
            if events[j].name == FAULT:
                faulted = True
            else:
                mode = int(float(events[j].value))
            j += 1
        while k < len(inner) and inner[k][0] <= t + 1e-9:
            state = inner[k][1]
            k += 1
        out.setdefault((mode, faulted) + tuple(state), t)
    return out


def _shifted(events: Sequence[Event], after: float, by: float) -> list[Event]:
    return [Event(round(e.time + by, 3), e.name, e.value, e.hold) if e.time >= after else e for e in events]


def mutate(ex: Explorer, rng: random.Random, cov: Coverage) -> Script:
    """A kept script changed where it first reached a new state (as coverage-guided fuzzers
    mutate their corpus): a burst of button presses there (the later steps moved after it;
    a full memory and a refused press, a restart and the presses after it), actions aimed at
    that moment (the stand's aim), a power cycle there, or its steps after that moment
    replaced by another kept script's (spliced)."""
    expl = ex.expl
    parent, times = rng.choice(cov.corpus)
    t = round(rng.choice(times) + rng.choice((0.0, 0.05, rng.uniform(0.1, 1.0))), 2)
    events = list(parent.events)
    duration = parent.duration
    op = rng.random()
    if op < 0.4:                                      # a burst of presses of the button
        button = expl.buttons[0]
        n = rng.randint(*(LONG_BURST if rng.random() < LONG_SHARE else BURST))
        at, added = t, []
        for _ in range(n):
            hold = round(rng.uniform(0.1, 0.3), 2)
            added.append(Event(round(at, 2), button, "1", hold))
            at += hold + rng.uniform(0.2, 0.6)
        span = round(at - t, 3)
        events = _shifted(events, t, span) + added
        duration = round(duration + span, 3)
    elif op < 0.7 and expl.aim is not None:           # the stand's aimed actions at that moment
        return expl.aim(rng, ex.task, parent, [t] * 3)
    elif op < 0.85:                                    # a power cycle there, then a press
        off = round(rng.uniform(0.2, 1.5), 2)
        span = round(off + rng.uniform(1.7, 3.0), 2)
        events = _shifted(events, t, span + 0.3) + [Event(t, POWER, f"{off:g}"),
                                                    Event(round(t + span, 2), expl.buttons[0], "1", 0.2)]
        duration = round(duration + span + 0.3, 3)
    else:                                             # spliced: another kept script's steps after t
        other, other_times = rng.choice(cov.corpus)
        t2 = rng.choice(other_times)
        tail = [Event(round(e.time - t2 + t + 0.1, 3), e.name, e.value, e.hold) for e in other.events
                if e.time >= t2]
        events = [e for e in events if e.time < t] + tail
        duration = round(max(t + 3.0, other.duration - t2 + t + 0.1), 3)
    events = _apart(sorted(events, key=lambda e: e.time))
    last = max((e.time + e.hold for e in events), default=0.0)
    return Script(tuple(events), round(max(duration, last + 3.0), 3))


def _apart(events: list[Event]) -> list[Event]:
    """`events` without a press that begins before the last press of its button is released
    and 0.1 s more (a spliced tail or a burst over a hold would shorten that hold to a length
    the generator never draws, maybe one a single scan decides)."""
    free: dict[str, float] = {}
    out = []
    for e in events:
        if e.is_press:
            if e.time < free.get(e.name, -1.0):
                continue
            free[e.name] = e.time + e.hold + 0.1
        out.append(e)
    return out


def _base(ex: Explorer, seed: Any, k: int, cov: Optional[Coverage]) -> Script:
    """Unit k's first script: a new random one, or (coverage-guided, after the first round,
    one unit in two) a kept script mutated."""
    if cov is not None and cov.corpus and k >= ROUND_UNITS:
        mrng = random.Random(f"{seed}:m{k}")
        if mrng.random() < MUTATE_SHARE:
            return mutate(ex, mrng, cov)
    return ex.expl.generate(random.Random(f"{seed}:{2 * k}"), ex.task, ex.expl.episode_s)


def _aimed(ex: Explorer, seed: Any, k: int, base: Script) -> Script:
    """Unit k's second script: the first again with actions aimed at the moments the model
    answer's stand changed in it (the stand's aim), else a new random one."""
    rng = random.Random(f"{seed}:{2 * k + 1}")
    phases = ex.model_side(base).phases
    if phases and ex.expl.aim is not None:
        return ex.expl.aim(rng, ex.task, base, list(phases))
    return ex.expl.generate(rng, ex.task, ex.expl.episode_s)


def script_stream(ex: Explorer, seed: Any, count: int, coverage: bool = True) -> Iterator[Script]:
    """`count` scripts for explorer `ex`, seeded by `seed`, in units of two: a random script
    (or, `coverage`-guided, a kept one mutated), then the same script with actions aimed at the
    moments the model answer's stand changed in it (the stand's aim: a press, a spare input
    flip, a mode change in the scan a frame starts or a link arrives, or a little after). The
    model answer's states each script reaches are merged into the coverage after every round
    of ROUND_UNITS units, so the stream depends on the seed and the model answer only: never
    on the student, nor on how many processes play it (`explore(jobs=)`)."""
    cov = Coverage() if coverage and ex.expl.state_paths else None
    n = 0
    while n < count:
        reached: list[tuple[Script, dict]] = []
        for k in range(n // 2, n // 2 + ROUND_UNITS):
            if n >= count:
                break
            base = _base(ex, seed, k, cov)
            for i in range(min(2, count - n)):
                script = base if i == 0 else _aimed(ex, seed, k, base)
                yield script
                n += 1
                if cov is not None:
                    reached.append((script, states_of(ex, script)))
        if cov is not None:
            for script, states in reached:
                cov.add(script, states)


# --------------------------------------------------------------------------- searching, on N processes

def _status(ex: Explorer, script: Script) -> tuple[str, Optional[tuple[Script, Divergence]]]:
    played, div, ambiguous = ex.confirmed(script)
    if div is not None:
        return "diverged", (played, div)
    return ("ambiguous" if ambiguous else "alike"), None


_WORKER: dict[str, Any] = {}      # the Explorer a search's worker processes inherit (fork)


def _worker_unit(job: tuple[Any, int, Script, int, bool, bool]) -> list[tuple[Script, str, dict]]:
    """In a worker process: unit k (its first script given, `n` scripts of it) played;
    (script, status, states reached) of each script, up to the first that diverges (`stop`)."""
    seed, k, base, n, coverage, stop = job
    ex: Explorer = _WORKER["ex"]
    out = []
    script = base
    for i in range(n):
        if i == 1:
            script = _aimed(ex, seed, k, base)
        status, _ = _status(ex, script)
        out.append((script, status, states_of(ex, script) if coverage else {}))
        if stop and status == "diverged":
            break
    return out


def search(ex: Explorer, seed: Any, count: int, jobs: int = 1, coverage: bool = True,
           stop: bool = True) -> Iterator[tuple[Script, str, Optional[tuple[Script, Divergence]]]]:
    """The scripts of the stream (script_stream) played on both programs, in the stream's
    order: (script, 'alike' | 'ambiguous' | 'diverged', (played, divergence) of a divergence),
    up to the first divergence (`stop`). `jobs` > 1: the units of each round are played in
    that many processes (forked: they inherit the compiled programs); what is yielded is the
    same as with one, and a divergence found there is confirmed again here."""
    if jobs <= 1 or not hasattr(os, "fork"):
        for script in script_stream(ex, seed, count, coverage):
            status, detail = _status(ex, script)
            yield script, status, detail
            if stop and status == "diverged":
                return
        return
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    coverage = coverage and bool(ex.expl.state_paths)
    cov = Coverage() if coverage else None
    _WORKER.clear()
    _WORKER["ex"] = ex
    pool = ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("fork"))
    try:
        n = 0
        while n < count:
            units = []
            for k in range(n // 2, n // 2 + ROUND_UNITS):
                if n >= count:
                    break
                size = min(2, count - n)
                units.append((seed, k, _base(ex, seed, k, cov), size, coverage, stop))
                n += size
            reached = []
            for results in pool.map(_worker_unit, units):
                for script, status, states in results:
                    detail = _status(ex, script)[1] if status == "diverged" else None
                    yield script, status, detail
                    if stop and status == "diverged":
                        return
                    reached.append((script, states))
            if cov is not None:
                for script, states in reached:
                    cov.add(script, states)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        _WORKER.clear()


def explore(expl: Exploration, stand: str, task: str, make_session: Callable, student: Program, model: Program,
            episodes: Optional[int] = None, shrink_runs: int = SHRINK_RUNS, seed: Optional[int] = None,
            jobs: int = 1, model_plays: Optional[Path] = None, coverage: bool = True,
            record: bool = False) -> ExploreResult:
    """Up to `episodes` seeded scripts (default: the stand's budget) on both programs, coverage-
    guided (`coverage`); the first confirmed divergence is shrunk and explained. `seed`: default
    the submission's (seed_of); `jobs`: processes playing the scripts (same result whatever the
    number); `model_plays`: a folder sharing the model answer's plays with other graders of the
    same scripts (grade-class); `record`: every play recorded in full and nothing reused, as
    before issue 30 (the same result, slower: for `plclab bench` and the tests)."""
    episodes = expl.episodes if episodes is None else episodes
    seed = seed_of(stand, task, student.sources) if seed is None else seed
    plays = ModelPlays(_model_salt(f"{stand}\0{task}", model), model_plays)
    ex = Explorer(expl, task, make_session, student, model, plays, record=record)
    result = ExploreResult(0, 0.0, 0, seed)
    for script, status, detail in search(ex, seed, episodes, jobs, coverage):
        result.episodes += 1
        result.plant_seconds += script.duration
        result.inconclusive += status == "ambiguous"          # still ambiguous after moving
        if detail is not None:
            played, div = detail
            small, sdiv = shrink(ex, played, div, shrink_runs)
            result.finding = explain(ex, small, sdiv, stand)
    result.plays = ex.plays
    result.model_plays = ex.model_plays.played
    return result


def explain(ex: Explorer, script: Script, div: Divergence, stand: Optional[str] = None) -> Finding:
    """The finding in the console's words: numbered steps, the first difference, the student's
    lines where the mistake most likely is (ranked against `stand`'s starting program) and the
    output's last writer."""
    out = ex.outcome(script, keep=True)
    if out.divergence is not None:
        div = out.divergence
    steps = [f"{n}. {e.time:.2f} s {ex.expl.describe(e)}" for n, e in enumerate(script.events, 1)]
    line, output, t_out, mv, sv, candidates = None, None, div.time, None, None, []
    if out.model is not None and out.student is not None:
        output, t_out = first_differing_output(out.model, out.student, div)
        if output is not None:
            mv = out.model.trace.value_at(output, t_out)
            sv = out.student.trace.value_at(output, t_out)
            found = student_lines(ex, script, output, t_out, stand)
            candidates = found.candidates if found is not None else []
            line = found.writer if found is not None and found.writer is not None else \
                last_writer(ex, script, output, t_out, div.since)
    return Finding(script, div, steps, div.text(ex.expl.tick_s), line, output, t_out, mv, sv, candidates)


def student_lines(ex: Explorer, script: Script, output: str, t: float, stand: Optional[str] = None) -> Any:
    """The student's statements where the mistake most likely is (plclab.grader.localize):
    `script` played again on the student's program (traced) and on the model answer, the
    dependence slice of `output` at plant time `t` ranked against `stand`'s starting program
    (a localize.Localized, None where nothing can be said)."""
    from plclab.runtime.native import python_only

    from .localize import candidates
    tick = ex.expl.tick_s
    with python_only():                     # the tracer follows the generated Python, restarts too
        with compiled_once(ex.model.checked, share=ex.model.cache):
            m = ex.session(ex.model, "slice-model")
        with compiled_once(ex.student.checked, share=ex.student.cache):
            s = ex.session(ex.student, "slice")

        def replay(sess: Session, begin: Callable[[], None]) -> None:
            p = ex.student if sess is s else ex.model
            with compiled_once(p.checked, share=p.cache):
                play(sess, script, None, until=t + tick / 2, split=(0.0, begin))

        return candidates(s, m, replay, output, t, ex.student.sources, stand)


# The requirement a divergence breaks, where one plainly matches (else it is E1's own): a
# mechanism not following its switch in manual mode before any automatic mode (Task 1's rows).
# A lamp or a playback difference has too many causes to name one requirement for it (a
# watchdog fault may be the symptom of a playback that should never have resumed): those stay
# E1's, with the history that shows them. Requirement ids are the grader's (plclab.grader.<stand>).
_MANUAL_ROWS = {("mp9c", "task1"): {"gripper": "T1.1", "rotation": "T1.2", "extension": "T1.3", "lift": "T1.4"}}


def _mode_at(script: Script, switch: str, t: float) -> tuple[int, bool]:
    """The mode switch's value at `t` and whether it was ever 1 before."""
    value, ever = 0, False
    for e in script.events:
        if e.time > t:
            break
        if e.name == switch and not e.is_press:
            value = int(float(e.value))
            ever = ever or value == 1
    return value, ever


def requirement_of(stand: str, task: str, f: Finding, expl: Exploration) -> Optional[str]:
    """The id of the requirement `f` breaks, where one plainly matches; None: E1's own."""
    mode_switch = next((k for k, v in expl.meaning.items() if v == ("manual", "automatic")), None)
    if mode_switch is None:
        return None
    mode, was_auto = _mode_at(f.script, mode_switch, f.divergence.time)
    name = f.divergence.signal.name
    if mode == 0 and not was_auto:
        return _MANUAL_ROWS.get((stand, task), {}).get(name)
    return None


__all__ = ["Coverage", "Divergence", "ExploreOptions", "ExploreResult", "Explorer", "Finding", "ModelPlays", "Program",
           "class_seed", "compare", "explain", "explore", "play", "script_stream", "search", "seed_of", "shrink"]


# --------------------------------------------------------------------------- the grade's row

EXPLORE_ID = "E1"


def model_answer(stand: str, task: str, reference: Optional[Sequence[str]]) -> tuple[Optional[Program], str]:
    """The task's model answer (a course's own `reference` files, else the checkout's
    solutions/) as a Program, or None and the one-line reason exploration cannot run."""
    from plclab.errors import CompileError
    from plclab.frontend import check_sources, read_sources
    from plclab.stands import get_stand, sources
    from plclab.stands.base import stand_spec
    expl = stand_spec(stand).explore
    if reference:
        try:
            srcs = read_sources(reference)
            return Program(srcs, check_sources(srcs)), ""
        except CompileError as e:
            return None, f"the reference does not compile: {e.diagnostics[0] if e.diagnostics else e}"
    variant = expl.references.get(task) if expl else None
    stand_ = get_stand(stand)
    if variant is None:
        return None, f"{stand} {task} has no model answer to explore against"
    if not stand_.available(variant):
        return None, ("no model answer here (the installed package carries none): run the grade in the "
                      "instructor's checkout of PLC Lab, or give the course's model answer with --reference FILE.st...")
    srcs = sources(stand_, variant)
    return Program(srcs, check_sources(srcs)), ""


def row_text(expl: Exploration, task: str) -> str:
    """E1's requirement, one sentence a student understands (the same in `--requirements`, the
    hand-out's tasks.md and the report)."""
    observed = expl.compared(task)
    names = ", ".join(o.name for o in observed)
    return (f"Whatever the operator does at the console, in any order and at any moment (switches, presses, "
            f"power cycles, plant faults), your stand shows what the model answer's stand shows ({names}), "
            f"each change within {expl.timing_tol:g} s, where the task leaves no freedom.")


def _int_or(v: Any) -> Any:
    return int(bool(v)) if isinstance(v, bool) else v


def row_words(expl: Exploration, f: Finding, sources: Sequence[tuple[str, str]]) -> tuple[str, str]:
    """E1's expected and observed texts for finding `f`: what the model answer's stand showed
    (with the tolerance and the task's freedom), what the student's showed, what the operator
    did and what each stand did then (`story`), the output that first differs where it does
    not contradict what the stands show (the statement that last wrote it is the row's
    `written`, plclab.grader.localize.written_text)."""
    d = f.divergence
    o = d.signal
    tol = f"timing +/- {expl.timing_tol:g} s" + (f", {o.tolerance}" if o.tolerance else "") + \
        (f"; {o.freedom}" if o.freedom else "")
    expected = f"{o.name} {o.show(d.model)} at {d.time:.2f} s, as the model answer's stand shows ({tol})"
    observed = f"{o.name} {o.show(d.student)}"
    if d.kind == "late":
        observed += f": the change comes {d.lag:.2f} s later than in the model answer"
    elif d.kind == "early":
        observed += f": the change comes {d.lag:.2f} s earlier than in the model answer"
    observed += f"; {story(expl, f.script, d)}"
    # the raw output only where it says the same as the stands: a lamp is compared as it is
    # seen (a blink's on/off at one instant says nothing), and an output differing before the
    # difference the stands show (inside a freedom) is no evidence of it
    consistent = o.pattern is None and d.since - 1e-9 <= f.output_time <= d.time + 1e-9
    if (f.output is not None and f.model_output is not None and f.model_output != f.student_output
            and consistent):
        observed += (f"; at {f.output_time:.2f} s {f.output} = {_int_or(f.student_output)} in your program, "
                     f"{_int_or(f.model_output)} in the model answer")
    return expected, observed


@dataclass(frozen=True)
class ExploreOptions:
    """How a grade explores, none of which changes its verdict or report but `seed`: `jobs`
    processes play the scripts (`plclab grade --jobs N`); `seed` replaces the submission's
    (grade-class: the class's, every student under the same scripts); `model_plays` is a folder
    where the model answer's plays of those scripts are shared by a class's grading processes."""

    jobs: int = 1
    seed: Optional[int] = None
    model_plays: Optional[str] = None


def class_seed(stand: str, task: str, folder: str) -> int:
    """The exploration seed of a class (grade-class): the stand, the task and the class folder's
    name, so every student of the class is explored under the same scripts (and the model
    answer's side of each is played once for the class), and a student's regrade in the same
    class gives the same report."""
    h = hashlib.sha256(f"{stand}\0{task}\0class\0{Path(folder).resolve().name}".encode())
    return int.from_bytes(h.digest()[:8], "big")


def exploration_rows(req: Any, sources: Sequence[tuple[str, str]], checked: Any,
                     reference: Optional[Sequence[str]] = None, episodes: Optional[int] = None,
                     out_dir: Optional[str] = None, options: Optional[ExploreOptions] = None
                     ) -> tuple[list[Any], list[str], dict[str, list[Path]]]:
    """The exploration row (E1) of a grade, the report's notes about it and the files written
    (the shrunk script and the student's traces under it, in `out_dir`). A difference that
    plainly breaks one of the task's requirements comes with that requirement's row too, after
    E1's (the engine puts it in place of the scenarios' row if they passed it)."""
    from plclab.stands.base import stand_spec
    from plclab.trace import write_csv, write_vcd

    from .localize import written_text
    from .report import Row
    expl = stand_spec(req.stand).explore
    if expl is None or episodes == 0:
        return [], [], {}
    model, why = model_answer(req.stand, req.task, reference)
    if model is None:
        return [], [f"exploration not run: {why}"], {}
    text = row_text(expl, req.task)
    student = Program(list(sources), checked)
    try:
        opts = options or ExploreOptions()
        result = explore(expl, req.stand, req.task, req.make_session, student, model, episodes, seed=opts.seed,
                         jobs=opts.jobs, model_plays=Path(opts.model_plays) if opts.model_plays else None)
    except Exception as e:                           # a bug of the grader: never the student's FAIL
        return [Row(EXPLORE_ID, text, False, "", f"not checked: the grader failed ({type(e).__name__}: {e}); "
                    "this is a bug of the grader, not of your program: please report it", None, "explore",
                    internal=True)], [], {}
    amount = (f"{result.episodes} random operator script{'s' if result.episodes != 1 else ''}, "
              f"{result.plant_seconds:.0f} s of plant time (seed {result.seed:016x})")
    f = result.finding
    if f is None:
        extra = f"; {result.inconclusive} ambiguous at one scan, not judged" if result.inconclusive else ""
        return [Row(EXPLORE_ID, text, True, scenario="explore")], \
            [f"exploration: {amount}: no difference from the model answer{extra}"], {}
    files: list[Path] = []
    script_name = f"{req.stand}-{req.task}-explore.csv"
    if out_dir is not None:
        base = Path(out_dir)
        base.mkdir(parents=True, exist_ok=True)
        (base / script_name).write_text(f.script.csv_text(), encoding="utf-8")
        files.append(base / script_name)
        with compiled_once(checked, share=student.cache):
            ex = Explorer(expl, req.task, req.make_session, student, model)
            s, _ = ex.run(student, "trace", f.script, expl=False)
        names = req.trace_names(s) if req.trace_names else None
        for suffix, write in ((".trace.csv", write_csv), (".trace.vcd", write_vcd)):
            path = base / f"{req.stand}-{req.task}-explore{suffix}"
            write(s.trace, path, names=names)
            files.append(path)
    expected, observed = row_words(expl, f, sources)
    d = f.divergence
    written = written_text(f.output, f.line, sources)
    lines = tuple(c.where(sources) for c in f.candidates)
    steps = tuple(f.steps) + (f"-> {f.first_difference}",)
    replay = (f"replay: plclab run {req.stand} --program {' '.join(n for n, _ in sources)} --inputs "
              f"{files[0] if files else script_name} --against {req.task}")
    rid = requirement_of(req.stand, req.task, f, expl)
    rows = [Row(EXPLORE_ID, text, False, expected, observed, d.time, "explore", steps=steps, lines=lines,
                written=written)]
    if rid is not None and any(r.id == rid for r in req.requirements):
        # named by the requirement it breaks: that row carries it where the scenarios passed it
        # (the engine decides), and E1 points there
        r = next(r for r in req.requirements if r.id == rid)
        rows.append(Row(rid, r.text, False, expected, observed, d.time, "explore", steps=steps, lines=lines,
                        written=written))
    notes = [f"exploration: {amount}: a difference in script {result.episodes}, shrunk to "
             f"{len(f.script.events)} console step{'s' if len(f.script.events) != 1 else ''}", replay]
    return rows, notes, {"explore": files}


def replay(spec: Any, s: Session, inputs: str, against: Optional[str], reference: Optional[Sequence[str]],
           student_sources: Optional[Sequence[tuple[str, str]]], checked: Any) -> Optional[str]:
    """`plclab run STAND --program FILE.st --inputs SCRIPT.csv [--against TASK]`: play the
    script on session `s` (its timeline and traces are the run's); with `against`, play it on
    the task's model answer too and return the first difference in the grade's words (None:
    alike)."""
    from plclab.grader.registry import requirement_set
    expl = spec.explore
    if expl is None:
        raise PlcLabError(f"run: {spec.name} has no operator scripts (--inputs is for the robots)")
    script = read_script(inputs, spec, s.labels)
    from plclab.plants.base import PlantError
    try:
        play(s, script)
    except PlantError as e:                              # a fault parameter the plant refuses
        raise PlcLabError(f"{inputs}: {e}") from None
    if against is None:
        return None
    req = requirement_set(spec.name, against)
    model, why = model_answer(spec.name, against, reference)
    if model is None:
        raise PlcLabError(f"run: --against {against}: {why}")
    srcs = list(student_sources) if student_sources is not None else s.sources
    student = Program(srcs, checked if checked is not None else s.checked)
    ex = Explorer(expl, against, req.make_session, student, model)
    out = ex.outcome(script)
    if out.divergence is None:
        return None
    return out.divergence.text(expl.tick_s)


# --------------------------------------------------------------------------- plclab bench

EXPLORE_GOAL_S = 20.0      # s of one core per task and program for the default budget


def bench_explore(stand: str, task: str, episodes: int = 4) -> Optional[dict]:
    """The CPU cost of exploration for a correct program (a copy of the model answer, graded
    against it): `episodes` scripts of the stand's stream played three ways on the same run,
    as before issue 30 (both programs recorded in full), searching without recording (one
    student's grade), and in a class (the model answer's side already played for the class:
    the student's side only); seconds per script, scripts per second, and what the stand's
    default budget costs (the goal: at most EXPLORE_GOAL_S). None where the model answers are
    not available (an installed package)."""
    import time

    from plclab.grader.registry import requirement_set
    from plclab.stands.base import stand_spec
    expl = stand_spec(stand).explore
    model, _why = model_answer(stand, task, None) if expl is not None else (None, "")
    if model is None or expl is None:
        return None
    req = requirement_set(stand, task)
    student = Program(list(model.sources), model.checked)
    per: dict[str, float] = {}
    result = None
    with tempfile.TemporaryDirectory(prefix="plclab-bench-", dir=_fast_tmp()) as shared:
        for how in ("recorded", "search", "class"):
            start = time.process_time()
            result = explore(expl, stand, task, req.make_session, student, model, episodes, seed=0,
                             record=how == "recorded", model_plays=Path(shared) if how != "recorded" else None)
            per[how] = (time.process_time() - start) / max(result.episodes, 1)
    assert result is not None
    return {"stand": stand, "task": task, "episodes": result.episodes, "plant_s": result.plant_seconds,
            "s_per_episode": per["search"], "episodes_per_s": 1 / per["search"] if per["search"] else 0.0,
            "s_per_episode_recorded": per["recorded"], "s_per_episode_class": per["class"],
            "budget": expl.episodes, "budget_s": per["search"] * expl.episodes,
            "budget_s_recorded": per["recorded"] * expl.episodes, "budget_s_class": per["class"] * expl.episodes,
            "goal_s": EXPLORE_GOAL_S}


def report_explore(report: Callable[[str], None], quick: bool = False) -> list[dict]:
    """`plclab bench`'s exploration lines, one per robot: a correct program's default-budget
    exploration as before issue 30, now, and in a class."""
    out = []
    for stand in ("mp9c", "tur10"):
        r = bench_explore(stand, "task3", 2 if quick else 4)
        if r is None:
            report(f"explore: {stand}: no model answer here (a checkout has them)")
            continue
        out.append(r)
        report(f"explore: {stand} {r['task']} ({r['plant_s'] / r['episodes']:.0f} s of plant time per script): "
               f"{r['episodes_per_s']:.2f} scripts/s; CPU per script {r['s_per_episode_recorded']:.2f} s recorded "
               f"(before), {r['s_per_episode']:.2f} s searching, {r['s_per_episode_class']:.2f} s in a class; "
               f"default budget {r['budget']} scripts = {r['budget_s']:.1f} s (before {r['budget_s_recorded']:.1f} s, "
               f"in a class {r['budget_s_class']:.1f} s; goal <= {r['goal_s']:g} s)")
    return out
