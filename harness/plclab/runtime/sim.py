"""Virtual time: the PLC (and optionally a plant model) advanced in lockstep, with a trace.

Timing convention (docs/timing.md, OpenPLC's scan loop): the first scan runs at t = 0; an input
event at time t is seen by the first scan at or after t; a change a scan produces is stamped
with that scan's time. Each tick the plants step first (from the outputs of the previous
scan, over one tick), then scripted inputs apply, then the PLC scans. Plants are plain
objects (plclab.runtime.plantio) that know nothing of ST.
"""
from __future__ import annotations

import bisect
import contextlib
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator, Optional

from plclab.errors import PlcLabError
from plclab.iec import types as T
from plclab.iec.address import parse_address
from plclab.runtime.image import image_slot
from plclab.runtime.plantio import Plant, PlantBinding
from plclab.runtime.gencode import define
from plclab.runtime.plc import PLC, image_bits
from plclab.trace import Recorder, Trace


@dataclass(frozen=True)
class InputEvent:
    time_ns: int
    name: str
    value: Any


def _kind(ty: T.Type) -> tuple[str, Optional[int]]:
    b = T.base_of(ty)
    if b is T.BOOL:
        return "bool", None
    if isinstance(b, T.ElementaryType):
        if b.is_real:
            return "real", None
        if b.kind in ("sint", "uint", "bits"):
            return "int", b.bits
        return "int", 64
    if isinstance(b, T.EnumType) or isinstance(b, T.StringType):
        return "str", None
    return "str", None


class Simulation:
    """Drives one PLC (and plants) in virtual time and records a trace."""

    def __init__(self, plc: PLC, plants: Iterable[Plant] = (), watch: Iterable[str] = (),
                 record_located: bool = True, extra_addresses: Iterable[str] = ()):
        self.plc = plc
        self.plants = [PlantBinding(p, plc.image) for p in plants]
        self.trace = Trace()
        self._events: list[InputEvent] = []
        self._event_times: list[int] = []
        self._next_event = 0
        self._watch: Any = None         # ((PLC, ids of the hooks' lists), native.Watch) of quiet runs
        self._names: list[str] = []
        self._sources: list[tuple[Any, Any, str]] = []   # (container, key, 'attr' | 'item' | 'bit')
        seen = set()
        if record_located:
            for b in sorted(plc.bindings, key=lambda b: (b.area[0] != "I", b.area, b.index)):
                if b.address in seen:
                    continue
                seen.add(b.address)
                self._add_signal(b.address, b.ty, b.owner, b.attr, "attr")
        for addr in extra_addresses:
            area, index = image_slot(addr)
            norm = str(parse_address(addr))           # the canonical spelling: %I0.1 is %IX0.1
            if norm in seen:
                continue
            seen.add(norm)
            ty = T.BOOL if area[1] == "X" else {"W": T.WORD, "D": T.DWORD, "L": T.LWORD}[area[1]]
            self._add_signal(norm, ty, plc.image.areas[area], index, "bit" if area[1] == "X" else "item")
        for name in watch:
            owner, key = plc.resolve(name)
            how = "item" if isinstance(owner, list) else "attr"
            ty = self._type_of(name, owner[key] if how == "item" else getattr(owner, key))
            self._add_signal(name, ty, owner, key, how)
        self._sample = self._compile_sampler()
        self.recorder = Recorder(self.trace, names=self._names)

    @property
    def recording(self) -> bool:
        """Whether this simulation samples any signal into its trace."""
        return bool(self._names)

    def _compile_sampler(self) -> Callable[[], list]:
        """One generated function reading every recorded signal (once per scan, on the hot path)."""
        ns: dict[str, Any] = {}
        parts = []
        for i, (container, key, how) in enumerate(self._sources):
            ns[f"c{i}"] = container
            parts.append(f"c{i}.{key}" if how == "attr" else f"c{i}[{key}] != 0" if how == "bit" else f"c{i}[{key}]")
        values = f"({', '.join(parts)},)" if parts else "()"
        define(f"def _sample():\n    return {values}\n", "<sim-sample>", ns)
        return ns["_sample"]

    def _type_of(self, name: str, value: Any) -> T.Type:
        if isinstance(value, bool):
            return T.BOOL
        if isinstance(value, int):
            return T.LINT
        if isinstance(value, float):
            return T.LREAL
        if isinstance(value, str):
            return T.STRING
        raise PlcLabError(f"'{name}' is not an elementary variable; watch one of its elements or fields")

    def _add_signal(self, name: str, ty: T.Type, container: Any, key: Any, how: str) -> None:
        kind, width = _kind(ty)
        value = getattr(container, key) if how == "attr" else container[key]
        self.trace.declare(name, kind, bool(value) if how == "bit" else value, 0, width=width)
        self._names.append(name)
        self._sources.append((container, key, how))

    # ------------------------------------------------------------------ inputs
    def schedule(self, events: Iterable[InputEvent]) -> None:
        """Add scripted input events (applied before the first scan at or after their time)."""
        for ev in events:
            self._resolve_target(ev.name)   # fail now, with the name, not in the middle of a run
            i = bisect.bisect_right(self._event_times, ev.time_ns)
            self._event_times.insert(i, ev.time_ns)
            self._events.insert(i, ev)

    def _resolve_target(self, name: str) -> None:
        if name.strip().startswith("%"):
            image_slot(name)
        else:
            self.plc.resolve(name)

    def set(self, name: str, value: Any) -> None:
        """Set an input address or a variable now (seen by the next scan)."""
        plc = self.plc
        if name.strip().startswith("%"):
            area, index = image_slot(name)
            for b in plc.bindings:
                if b.area == area and b.index == index:
                    plc.image.areas[area][index] = b.to_raw(_coerce(value, b.ty))
                    return
            plc.image.areas[area][index] = int(value) & ((1 << image_bits(area)) - 1)
        else:
            current = plc.read(name)
            plc.write(name, _coerce_like(value, current))

    # ------------------------------------------------------------------ time
    @property
    def now_ns(self) -> int:
        return self.plc.now_ns

    @property
    def now(self) -> float:
        return self.plc.now_ns / 1e9

    @property
    def tick(self) -> float:
        return self.plc.tick_ns / 1e9

    # `plclab bench`'s cost split: while a dict is set here (Simulation.profiling), every
    # simulation steps through step_profiled and adds its costs to it
    _profile: Optional[dict[str, float]] = None
    _clock_cost = 0.0              # seconds one reading of the CPU clock costs (calibrated)

    @classmethod
    @contextlib.contextmanager
    def profiling(cls, costs: dict[str, float]) -> Iterator[dict[str, float]]:
        """Inside the block, every simulation (also one a PLC restart makes) adds the CPU time
        of each part of its closed loop to `costs` (see step_profiled). Not thread-safe: a
        benchmark's."""
        from time import process_time as clock
        n = 20000
        t0 = clock()
        for _ in range(n):
            clock()
        cls._clock_cost = (clock() - t0) / n
        cls._profile = costs
        try:
            yield costs
        finally:
            cls._profile = None

    def step(self, ticks: int = 1) -> None:
        """Run `ticks` scans: plant, scripted inputs, scan, record, advance."""
        if self._profile is not None:
            return self.step_profiled(ticks, self._profile)
        plc = self.plc
        dt = plc.tick_ns
        dt_s = dt / 1e9
        events, times = self._events, self._event_times
        sample = self._sample
        # nothing sampled (a search's play): the trace's end is set below all the same
        record = self.recorder.record if self._names else None
        steps = [plant.step for plant in self.plants]
        scan, advance = plc.scan, plc.advance
        quiet = self._quiet_plan() if record is None and ticks > 1 else None
        i = 0
        while i < ticks:
            now = plc.now_ns
            step_dt = dt_s if plc.ticks else 0.0    # at t = 0 with dt = 0: the plant's power-up state
            for step in steps:
                step(step_dt)
            if self._next_event < len(events):
                while self._next_event < len(events) and times[self._next_event] <= now:
                    ev = events[self._next_event]
                    self.set(ev.name, ev.value)
                    self._next_event += 1
            if quiet is not None and i + 1 < ticks and all(b.idle for b in quiet[0]):
                k = self._run_quiet(quiet, ticks - i, step_dt)
                if k:
                    i += k
                    continue
            scan()
            if record is not None:
                record(now, sample())
            advance()
            i += 1
        self.trace.advance(plc.now_ns - dt if plc.ticks else 0)

    def _quiet_plan(self) -> Optional[tuple[list[PlantBinding], list[Any]]]:
        """(plant bindings, hooks) where this closed loop may run quiet stretches in one native
        call (PLC.run_quiet): every plant has the `idle` shortcut and every hook says what it
        must see change (`quiet_watch`, a grader's probe); None otherwise."""
        bindings = [b for b in self.plants if isinstance(b, PlantBinding)]
        hooks = [h for h in self.plants if not isinstance(h, PlantBinding)]
        if self.plc.native is None or not bindings or not all(b.can_idle for b in bindings) \
                or any(not hasattr(h, "quiet_watch") for h in hooks):
            return None
        return bindings, hooks

    def _run_quiet(self, quiet: tuple[list[PlantBinding], list[Any]], n: int, step_dt: float) -> int:
        """This tick's scan and as many of the next ticks as stay quiet, in one native call,
        where every plant stood idle this tick: until an output or a watched variable changes,
        the plants stay idle (the idle shortcut holds for the same outputs: only their time
        moves, tick by tick as stepping them would) and no hook has anything new to see. Not
        past the tick of the next scripted input. Returns the ticks run (0: none, the caller
        scans as usual)."""
        bindings, hooks = quiet
        plc = self.plc
        if self._next_event < len(self._events):
            n = min(n, -(-(self._event_times[self._next_event] - plc.now_ns) // plc.tick_ns))
        wanted = []
        for h in hooks:
            got = h.quiet_watch()
            if got is None:
                return 0
            if got:
                wanted.append(got)
        watch = None
        if wanted:       # the same lists for the same PLC (until a restart): the same watch
            key = (plc, [id(w) for w in wanted])
            if self._watch is None or self._watch[0] != key:
                from plclab.runtime.native import Watch
                self._watch = (key, Watch.of(plc, [p for w in wanted for p in w]))
            watch = self._watch[1]
            if watch is None:
                return 0
        k = plc.run_quiet(n, watch)
        for b in bindings:                      # the plants' steps of the ticks after this one
            b.repeat_idle(k - 1, step_dt)
        return k

    def step_profiled(self, ticks: int, costs: dict[str, float]) -> None:
        """`step(ticks)` with the CPU time of each part of the closed loop added to `costs`
        (seconds under 'plant', 'exchange', 'observation', 'scan', 'record'; 'scans' counts
        the scans): what `plclab bench` splits a scan's cost into. A hook among the plants that
        is not a plant binding (a grader's probe) is observation. Same order and results as
        `step`. CPU time, so that other load on a shared machine does not count; each timed
        interval less one reading of the clock (calibrated by `profiling`)."""
        from time import process_time as clock
        plc = self.plc
        dt = plc.tick_ns
        dt_s = dt / 1e9
        events, times = self._events, self._event_times
        sample = self._sample
        record = self.recorder.record
        plant_s = exchange_s = observe_s = scan_s = record_s = 0.0
        n_plant = n_observe = 0
        for _ in range(ticks):
            now = plc.now_ns
            step_dt = dt_s if plc.ticks else 0.0
            for binding in self.plants:
                if not isinstance(binding, PlantBinding):      # a hook (a grader's probe)
                    t0 = clock()
                    binding.step(step_dt)
                    observe_s += clock() - t0
                    n_observe += 1
                    continue
                t0 = clock()
                if binding.step_idle(step_dt):    # unchanged and at rest: the plant's own shortcut
                    plant_s += clock() - t0
                    n_plant += 1
                    continue
                t0 = clock()
                read, step, write = binding.exchange
                outputs = read()
                t1 = clock()
                inputs = step(outputs, step_dt)
                t2 = clock()
                write(inputs)
                t3 = clock()
                plant_s += t2 - t1
                exchange_s += (t1 - t0) + (t3 - t2)
                n_plant += 1
            while self._next_event < len(events) and times[self._next_event] <= now:
                ev = events[self._next_event]
                self.set(ev.name, ev.value)
                self._next_event += 1
            t0 = clock()
            plc.scan()
            t1 = clock()
            record(now, sample())
            plc.advance()
            t2 = clock()
            scan_s += t1 - t0
            record_s += t2 - t1
        self.trace.advance(plc.now_ns - dt if plc.ticks else 0)
        c = self._clock_cost
        for key, value in (("plant", plant_s - n_plant * c), ("exchange", exchange_s - 2 * n_plant * c),
                           ("observation", observe_s - n_observe * c), ("scan", scan_s - ticks * c),
                           ("record", record_s - ticks * c), ("scans", ticks)):
            costs[key] = costs.get(key, 0.0) + value

    def run(self, seconds: float) -> None:
        """Advance by `seconds` of plant time (rounded up to whole ticks)."""
        ticks = -(-round(seconds * 1e9) // self.plc.tick_ns)
        self.step(ticks)

    def run_until(self, predicate: Callable[["Simulation"], bool], timeout: float) -> bool:
        """Scan until `predicate(sim)` holds (checked after each scan) or `timeout` s pass."""
        end = self.plc.now_ns + round(timeout * 1e9)
        while self.plc.now_ns <= end:
            self.step(1)
            if predicate(self):
                return True
        return False


def _coerce(value: Any, ty: T.Type) -> Any:
    b = T.base_of(ty)
    if b is T.BOOL:
        return bool(int(value)) if not isinstance(value, bool) else value
    if isinstance(b, T.ElementaryType) and b.is_real:
        return float(value)
    if isinstance(b, T.ElementaryType):
        return int(value)
    return value


def _coerce_like(value: Any, current: Any) -> Any:
    if isinstance(current, bool):
        return bool(int(value)) if not isinstance(value, bool) else value
    if isinstance(current, int):
        return int(value)
    if isinstance(current, float):
        return float(value)
    return value

