"""The soft PLC: program instances, tasks, the scan cycle, located I/O, faults and retain.

One tick (the base tick is the GCD of the task intervals):
  1. apply writes queued by Modbus faces, copy the input image into located variables
  2. run the PROGRAM instances whose task is due, in RESOURCE declaration order
  3. copy located outputs / memory into the image
This is OpenPLC's scan cycle; the clock that timers read advances by one base tick per scan
(virtual time) or follows the wall clock (real time, see plclab.runtime.realtime).
"""
from __future__ import annotations

import functools
import math
import re
import struct
import time
import traceback
from dataclasses import dataclass
from typing import Any, Callable, Optional

from plclab.errors import PlcLabError
from plclab.frontend import ast as A
from plclab.frontend.checked import CheckedUnit
from plclab.iec import types as T
from plclab.iec.address import SIZE_BITS, Address
from plclab.runtime import native as _native
from plclab.runtime.compiler import CompiledProgram, compile_unit, located_attr
from plclab.runtime.faults import FaultRecord, PlcFault
from plclab.runtime.gencode import define
from plclab.runtime.image import AREAS, ProcessImage, image_slot
from plclab.runtime.stdfb import ScanClock

DEFAULT_TICK_NS = 20_000_000          # OpenPLC's default scan time when no task gives one
DEFAULT_WATCHDOG_S = 2.0              # wall-clock limit of one scan
LOOP_CHECK_EVERY = 4096

RUN, FAULT, STOP = "RUN", "FAULT", "STOP"


@dataclass
class LocatedBinding:
    """One located variable: where it lives in the program and in the process image."""

    address: str          # '%IX1.6'
    area: str             # 'IX' | 'QX' | 'IW' | 'QW' | 'MW' | 'MD' | 'ML'
    index: int            # element index in the area (8 * byte + bit for bits)
    owner: Any            # object holding the variable
    attr: str             # attribute name on the owner
    ty: T.Type
    name: str             # qualified variable name ('' for anonymous AT declarations)
    to_raw: Callable[[Any], int]
    from_raw: Callable[[int], Any]

    @property
    def is_input(self) -> bool:
        return self.area[0] == "I"


def _converters(ty: T.Type, bits: int) -> tuple[Callable[[Any], int], Callable[[int], Any]]:
    b = T.base_of(ty)
    mask = (1 << bits) - 1
    if b is T.BOOL:
        return (lambda v: 1 if v else 0), (lambda r: bool(r))
    if b is T.REAL:
        return (lambda v: struct.unpack("<I", struct.pack("<f", v))[0]), \
               (lambda r: struct.unpack("<f", struct.pack("<I", r & mask))[0])
    if b is T.LREAL:
        return (lambda v: struct.unpack("<Q", struct.pack("<d", v))[0]), \
               (lambda r: struct.unpack("<d", struct.pack("<Q", r & mask))[0])
    wrap = T.wrapper_for(b) or (lambda v: v)
    return (lambda v: int(v) & mask), (lambda r: wrap(r & mask))



_PROGRAM_FAULTS: dict[type, str] = {
    ZeroDivisionError: "division_by_zero", RecursionError: "stack_overflow",
    IndexError: "index_out_of_range", OverflowError: "overflow",
    MemoryError: "out_of_memory",     # past the process limit of a program run (plclab.limits)
}
"""Python errors a program's own arithmetic or nesting raises, as the fault kind it is (the
compiled code raises PlcFault for the faults it checks itself)."""


class ProgramInstance:
    """A PROGRAM instance bound to its task."""

    def __init__(self, name: str, obj: Any, task: Optional[str], interval_ns: Optional[int], decl: Any):
        self.name, self.obj, self.task, self.interval_ns, self.decl = name, obj, task, interval_ns, decl


def _snapshot(retained: list[tuple[str, Any, str, T.Type]]) -> dict[str, Any]:
    """The retain snapshot (path -> JSON value) of the variables `retained` (PLC.retained)."""
    from plclab.runtime.retain import to_json_value
    return {path: to_json_value(getattr(owner, attr)) for path, owner, attr, _t in retained}


def _snapshot_of(retained: list[tuple[str, Any, str, T.Type]], memory: Any, fingerprint: tuple,
                 _state: Any) -> dict[str, Any]:
    """The retain snapshot of the moment `memory` (a native.RetainMemory of the variables
    `retained`, of one cold start of a PLC) gave `fingerprint`: they are made to hold it for
    the snapshot, then what they held is put back (that PLC may still be running). `_state`
    is what owns their C memory (PLC._native_keep): held here, that memory outlives a restart
    of the PLC (which makes new memory) and the PLC itself, for as long as the store keeps
    this snapshot to be made."""
    now = memory()
    memory.put_back(fingerprint)
    try:
        return _snapshot(retained)
    finally:
        memory.put_back(now)


class PLC:
    """A loaded program, ready to scan. Time is in nanoseconds of PLC time."""

    def __init__(self, compiled: CompiledProgram, image: Optional[ProcessImage] = None,
                 tick_ns: Optional[int] = None, watchdog_s: float = DEFAULT_WATCHDOG_S,
                 retain: Any = None, retain_period_ns: int = 1_000_000_000, retain_fault: bool = False,
                 native: Optional[bool] = None):
        self.compiled = compiled
        # the native scan path (plclab.runtime.native): None where it cannot run this program
        self.native = _native.for_plc(compiled, native)
        self.checked: CheckedUnit = compiled.checked
        if self.checked.scope_count > 1:
            raise PlcLabError("these files hold the globals of several stands (GVL files): "
                              "give the files of one program")
        self.image = image if image is not None else ProcessImage()
        self.watchdog_s = watchdog_s
        self.retain_store = retain
        self.retain_period_ns = retain_period_ns
        self.retain_fault = retain_fault    # a failed retain save: FAULT (True) or reported, scan on
        self._last_persist_ns = 0
        self.state = STOP
        self.fault: Optional[FaultRecord] = None
        self.scan_clock = ScanClock()       # __CURRENT_TIME, which the standard timers read
        self.ticks = 0
        self._loop_count = 0
        self._scan_started = 0.0
        self._has_loops = "_rt.loop_check()" in compiled.source
        ns = compiled.namespace
        ns["_rt"] = self
        self.G = ns["G"]
        self._tick_override = tick_ns
        self._cold_start()

    def _cold_start(self) -> None:
        """Variables to their initial values, retained ones restored, outputs published."""
        self._setup_instances()
        self._retained: Optional[list[tuple[str, Any, str, T.Type]]] = None   # of these instances
        self._retain_sig: Optional[str] = None
        self._retain_fp: Optional[Callable[[], Optional[tuple]]] = None
        self._flushed_fp: Optional[tuple] = None      # what the last flush into an exclusive store held
        self.tick_ns = self._tick_override or self._base_tick()
        self._schedule = self._make_schedule()
        self.bindings = self._bind_located()
        self._inputs = [b for b in self.bindings if b.is_input]
        self._outputs = [b for b in self.bindings if not b.is_input]
        self._compile_io()
        if self.retain_store is not None:
            self.restore_retain()
        self.write_outputs()      # located outputs / memory hold their initial values from the start
        self.fault = None
        self.state = RUN

    # ------------------------------------------------------------------ construction
    def _setup_instances(self) -> None:
        ns = self.compiled.namespace
        ns["_init_globals"]()
        self.instances: list[ProgramInstance] = []
        config = self.checked.config
        if config is not None:
            for res in config.resources:
                for p in res.programs:
                    if p.pou is None:
                        continue
                    cls = ns[self.compiled.program_classes[p.pou.key]]
                    interval = p.task_decl.interval_ns if p.task_decl is not None else None
                    self.instances.append(ProgramInstance(p.name, cls(), p.task, interval, p))
        else:
            # No CONFIGURATION (e.g. `plclab sim` on a lone PROGRAM): every PROGRAM runs each tick.
            for pou in self.checked.unit.pous:
                if pou.kind == "PROGRAM" and pou.key in self.compiled.program_classes:
                    cls = ns[self.compiled.program_classes[pou.key]]
                    self.instances.append(ProgramInstance(pou.name, cls(), None, None, None))
        if self.native is not None:
            # the same initial values, now in C memory; instances and G become its mirrors
            self.G = self.native.attach(self)
        self.instance_by_name = {i.name.upper(): i for i in self.instances}

    def _base_tick(self) -> int:
        intervals = [i.interval_ns for i in self.instances if i.interval_ns]
        if not intervals:
            return DEFAULT_TICK_NS
        return math.gcd(*intervals)

    def _make_schedule(self) -> list[tuple[int, Callable[[], None]]]:
        """(period in ticks, callable) in declaration order; period 1 = every tick."""
        sched = []
        for inst in self.instances:
            period = 1
            if inst.interval_ns:
                period = max(1, inst.interval_ns // self.tick_ns)
            sched.append((period, inst.obj._run if self.native is None else None))
        self._periods = tuple(period for period, _run in sched)
        if self.native is not None:
            sched = self.native.schedule(self, sched)     # one C call runs them all
        return sched

    def _bind_located(self) -> list[LocatedBinding]:
        out = []
        for key, d in self.checked.globals.items():
            if d.location is not None and d.ty is not None:
                attr = key if not key.startswith("%") else located_attr(d)
                out.append(self._binding(d, self.G, attr, d.name))
        for inst in self.instances:
            pou = self.compiled.checked.pous.get(type(inst.obj)._ST_NAME.upper())
            for d in pou.decls if pou else []:
                if d.location is not None and d.ty is not None:
                    attr = d.key if d.name else located_attr(d)
                    out.append(self._binding(d, inst.obj, attr, f"{inst.name}.{d.name}" if d.name else ""))
        return out

    def _binding(self, d: A.VarDecl, owner: Any, attr: str, name: str) -> LocatedBinding:
        loc = d.location      # checked by the front end: an OpenPLC area, in range
        a = Address(loc.area, loc.size, loc.parts[0], loc.parts[1] if loc.size == "X" else None)
        to_raw, from_raw = _converters(d.ty, a.bits)
        return LocatedBinding(str(a), a.area, a.index, owner, attr, d.ty, name, to_raw, from_raw)

    @property
    def now_ns(self) -> int:
        """PLC time in ns, as the standard timers read it (constant during one scan)."""
        return self.scan_clock.now

    @now_ns.setter
    def now_ns(self, value: int) -> None:
        self.scan_clock.now = value

    # ------------------------------------------------------------------ hooks used by compiled code
    def loop_check(self) -> None:
        """Called on every loop iteration: a scan that runs too long is a watchdog fault."""
        self._loop_count += 1
        if self._loop_count % LOOP_CHECK_EVERY == 0 and \
                time.perf_counter() - self._scan_started > self.watchdog_s:
            raise PlcFault("watchdog", f"scan exceeded the watchdog limit of {self.watchdog_s:g} s "
                                       f"(endless loop?)")

    @staticmethod
    def init_fb(inst: Any, values: dict) -> Any:
        for k, v in values.items():
            setattr(inst, k, T.copy_value(v))
        return inst

    # ------------------------------------------------------------------ the scan
    def read_inputs(self) -> None:
        """Queued Modbus writes in, then the input image into the located variables (and the
        output / memory image too when a client wrote to it)."""
        external = self.image.apply_pending()
        self._copy_in(external)

    def write_outputs(self) -> None:
        self.image.publish(self._copy_out)

    def _compile_io(self) -> None:
        """Generate the image <-> variable copies of this program's located variables: one
        straight-line function each way instead of a loop of conversions every scan."""
        ns: dict[str, Any] = {}
        lines_in = ["def _copy_in(external):"]
        lines_out = ["def _copy_out(areas):"]

        owners: dict[int, str] = {}

        def access(b: LocatedBinding, i: int) -> str:
            name = owners.setdefault(id(b.owner), f"o{len(owners)}")
            ns[name] = b.owner
            return f"{name}.{b.attr}"

        def cell(b: LocatedBinding) -> str:
            ns[f"a_{b.area}"] = self.image.areas[b.area]     # the area lists are never replaced
            return f"a_{b.area}[{b.index}]"

        def from_raw(b: LocatedBinding, raw: str, i: int) -> str:
            t = T.base_of(b.ty)
            if t is T.BOOL:
                return f"{raw} != 0"
            if isinstance(t, T.ElementaryType) and t.kind in ("sint", "uint", "bits"):
                mask = (1 << t.bits) - 1
                if t.kind == "sint":
                    return f"(({raw} + {1 << (t.bits - 1)}) & {mask}) - {1 << (t.bits - 1)}"
                return f"{raw} & {mask}"
            ns[f"f{i}"] = b.from_raw
            return f"f{i}({raw})"

        def to_raw(b: LocatedBinding, value: str, i: int) -> str:
            t = T.base_of(b.ty)
            if t is T.BOOL:
                return f"1 if {value} else 0"
            if isinstance(t, T.ElementaryType) and t.kind in ("sint", "uint", "bits"):
                return f"{value} & {(1 << SIZE_BITS[b.area[1]]) - 1}"
            ns[f"t{i}"] = b.to_raw
            return f"t{i}({value})"

        for i, b in enumerate(self._inputs):
            lines_in.append(f"    {access(b, i)} = {from_raw(b, cell(b), i)}")
        lines_in.append("    if external:")
        for j, b in enumerate(self._outputs, start=len(self._inputs)):
            lines_in.append(f"        {access(b, j)} = {from_raw(b, cell(b), j)}")
            lines_out.append(f"    {cell(b)} = {to_raw(b, access(b, j), j)}")
        lines_in.append("        pass")
        lines_out.append("    pass")
        define("\n".join(lines_in + lines_out) + "\n", "<plc-io>", ns)
        self._copy_in, self._copy_out = ns["_copy_in"], ns["_copy_out"]
        self._quiet_run = None
        if self.native is not None:
            self._copy_in, self._copy_out = self.native.io(self, self._copy_in, self._copy_out)
            self._quiet_run = self.native.quiet(self)

    def runs_a_task_now(self) -> bool:
        """Whether a scan at the current tick runs any task (one of period k runs at every k-th
        tick): where a program is entered at all."""
        tick = self.ticks
        return any(period == 1 or tick % period == 0 for period in self._periods)

    def scan(self) -> bool:
        """Run one tick at the current PLC time; returns False if the PLC is (now) faulted."""
        if self.state != RUN:
            return False
        self.read_inputs()
        tick = self.ticks
        if self._has_loops:       # only a loop can run past the watchdog limit
            self._scan_started = time.perf_counter()
            self._loop_count = 0
        try:
            for period, run in self._schedule:
                if period == 1 or tick % period == 0:
                    run()
        except Exception as exc:         # a program fault, or the harness's own bug (see _enter_fault)
            self._enter_fault(exc)
            return False
        self.write_outputs()
        if self.retain_store is not None and self.now_ns - self._last_persist_ns >= self.retain_period_ns:
            self._last_persist_ns = self.now_ns
            if not self.persist_retain() and self.retain_fault:
                self.enter_fault("retain", f"cannot save the retained variables: {self.retain_store.save_error}")
                return False
        return True

    def run_quiet(self, n: int, watch: Any = None) -> int:
        """Up to `n` ticks of `scan(); advance()` in one native call, for a closed loop whose
        plant stands idle (nothing but this PLC's outputs could change what it does): every
        scan takes the inputs the image holds now, and the run stops after the first scan
        that changes an output or a variable of `watch` (plclab.runtime.native.Watch) or
        faults. Returns how many ticks were run; the PLC is then where as many `scan();
        advance()` would have left it (the image's outputs, time, fault). 0 where no such run
        can be the same: the Python path, a PLC not running, a Modbus write waiting, the I/O
        stages replaced (the lab's forces), or a retain save due at the first scan."""
        run = self._quiet_run
        if (run is None or n < 1 or self.state != RUN or self.image._pending
                or "read_inputs" in self.__dict__ or "write_outputs" in self.__dict__
                or self.now_ns != self.ticks * self.tick_ns):
            return 0
        if self.retain_store is not None:      # the scan that saves runs on the usual path
            n = min(n, -(-(self._last_persist_ns + self.retain_period_ns - self.now_ns) // self.tick_ns))
            if n < 1:
                return 0
        k, rc = run(n, watch)
        self.ticks += k - 1                     # at the last scan run
        self.now_ns = self.ticks * self.tick_ns
        if rc:                                  # it faulted, as scan() would
            self._enter_fault(_native._fault(rc, self._native_state, self.native.cprog.sites, self))
        else:
            self.write_outputs()
        self.advance()
        return k

    def advance(self) -> None:
        """Move PLC time to the next tick (virtual time)."""
        self.ticks += 1
        self.now_ns = self.ticks * self.tick_ns

    # ------------------------------------------------------------------ faults
    def _enter_fault(self, exc: BaseException) -> None:
        """Stop in FAULT. A PlcFault, or one of the Python errors a program's own arithmetic
        or nesting can raise, is the program's fault; anything else (a TypeError in generated
        or library code...) is an internal error of the harness, recorded as such."""
        kind = exc.kind if isinstance(exc, PlcFault) else _PROGRAM_FAULTS.get(type(exc))
        internal = kind is None
        if internal:
            kind = "internal"
            message = f"{type(exc).__name__}: {exc}"
        else:
            message = getattr(exc, "message", None) or str(exc) or type(exc).__name__
        where = self._locate(exc)
        drawing = self.checked.drawings.get(where.file) if where else None
        place = drawing.place(where.line) if drawing is not None else None
        self.fault = FaultRecord(kind, message, where.pou if where else None,
                                 where.file if where else None, where.line if where else None, self.now_ns,
                                 internal=internal,
                                 detail="".join(traceback.format_exception(exc)) if internal else "",
                                 place=str(place) if place is not None else "")
        self.state = FAULT
        self._safe_outputs()

    def enter_fault(self, kind: str, message: str) -> None:
        """FAULT for a reason outside the program (a retain save, the I/O layer, the scan
        loop): outputs safe, no POU or line to name."""
        self.fault = FaultRecord(kind, message, None, None, None, self.now_ns)
        self.state = FAULT
        self._safe_outputs()

    def _locate(self, exc: BaseException):
        found = getattr(exc, "st_where", None)      # a fault of the native scan path
        tb = exc.__traceback__
        while tb is not None:
            if tb.tb_frame.f_code.co_filename == self.compiled.filename:
                info = self.compiled.where(tb.tb_lineno)
                if info is not None:
                    found = info
            tb = tb.tb_next
        return found

    def _safe_outputs(self) -> None:
        """FAULT: every output to FALSE / 0, as an OpenPLC runtime stopping does."""
        def clear(areas: dict) -> None:
            for area in ("QX", "QW"):
                a = areas[area]
                for i in range(len(a)):
                    a[i] = 0
        self.image.publish(clear)

    def restart(self) -> None:
        """Cold restart after a fault or stop: variables re-initialised, retain restored."""
        self._cold_start()

    def stop(self) -> None:
        if self.retain_store is not None and self.state == RUN:
            self.persist_retain()
        self.state = STOP

    # ------------------------------------------------------------------ retain
    def retained(self) -> list[tuple[str, Any, str, T.Type]]:
        """(path, owner, attribute, type) of every retained variable (worked out once per
        cold start: the instances are fixed until the next)."""
        if self._retained is None:
            self._retained = self._find_retained()
        return self._retained

    def _find_retained(self) -> list[tuple[str, Any, str, T.Type]]:
        out = []
        for key in self.compiled.retained_globals:
            d = self.checked.globals[key]
            out.append((key, self.G, key, d.ty))
        for inst in self.instances:
            pou = self.checked.pous.get(type(inst.obj)._ST_NAME.upper())
            if pou is None:
                continue
            for d in pou.decls:
                if d.retain and d.name and d.section in ("VAR", "VAR_INPUT", "VAR_OUTPUT"):
                    out.append((f"{inst.name.upper()}.{d.key}", inst.obj, d.key, d.ty))
        return out

    def retain_snapshot(self) -> dict[str, Any]:
        return _snapshot(self.retained())

    def retain_signature(self) -> str:
        from plclab.runtime.retain import signature
        if self._retain_sig is None:
            self._retain_sig = signature((path, ty) for path, _o, _a, ty in self.retained())
        return self._retain_sig

    def persist_retain(self) -> bool:
        """Save the retained variables; False if the save failed (the store reported it once
        and retries at the next flush: a full disk never stops the scan).

        A store that only this PLC writes (`exclusive`: a grading's memory) is not written
        again with what it already holds: the native path tells that by the retained
        variables' C memory (a few bytes compared, where building the snapshot reads every
        value, each second of plant time of every play of a grading). Such a store keeps that
        memory, and the snapshot is made of it only when a restart loads it (most plays end
        without one)."""
        store = self.retain_store
        if store is None or not self.retained():
            return True
        fp = None
        if getattr(store, "exclusive", False):
            if self._retain_fp is None:
                self._retain_fp = _native.retain_fingerprint(self) if self.native is not None else (lambda: None)
            fp = self._retain_fp()
            if fp is not None and fp == self._flushed_fp:
                return True
        if fp is not None:
            ok = store.flush_later(self.retain_signature(),
                                   functools.partial(_snapshot_of, self.retained(), self._retain_fp, fp,
                                                     self._native_keep))
        else:
            ok = store.flush(self.retain_signature(), self.retain_snapshot())
        self._flushed_fp = fp if ok else None
        return ok

    def restore_retain(self) -> None:
        """Retained variables from the file, all or none: one value that is not of its
        variable's type sets the whole file aside."""
        from plclab.runtime.retain import RetainError, fb_values_from_json, from_json_value
        items = self.retained()
        if not items:
            return
        data = self.retain_store.load(self.retain_signature())
        if data is None:
            return
        restored: list[tuple[Any, str, Any]] = []
        for path, owner, attr, ty in items:
            if path not in data:
                continue
            try:
                if isinstance(ty, T.FBType):
                    inst = getattr(owner, attr)
                    pou = self.checked.pous.get(str(getattr(type(inst), "_ST_NAME", "")).upper())
                    types = {d.key: d.ty for d in pou.decls if d.ty is not None} if pou is not None else None
                    restored += [(inst, k, v) for k, v in fb_values_from_json(data[path], inst, types)]
                else:
                    restored.append((owner, attr, from_json_value(data[path], ty)))
            except RetainError as e:
                self.retain_store.reject(f"{path}{'.' + e.field if e.field else ''}: {e}")
                return
        for owner, attr, value in restored:
            setattr(owner, attr, value)

    # ------------------------------------------------------------------ access by name
    def resolve(self, name: str) -> tuple[Any, Any]:
        """(container, key) of a located address, a global, or a path such as
        `Main.Robot.Sequencer.Ptr` or `Positions[2]` / `Main.Cp.Frames[3].Data[1]`: the value
        is `container[key]` for an array element, else `getattr(container, key)`."""
        return self.resolve_typed(name)[:2]

    def resolve_typed(self, name: str) -> tuple[Any, Any, T.Type]:
        """`resolve`, plus the variable's type."""
        up = name.strip().upper()
        if up.startswith("%"):
            for b in self.bindings:
                if b.address == up:
                    return b.owner, b.attr, b.ty
            raise PlcLabError(f"no variable is located at {name}")
        steps = re.findall(r"\.?\s*([A-Z_][A-Z0-9_]*)|\[([^\]]*)\]", up)
        if not steps or not steps[0][0] or "".join(
                (("." if i and n else "") + n) if n else f"[{ix}]" for i, (n, ix) in enumerate(steps)
        ).replace(" ", "") != up.replace(" ", ""):
            raise PlcLabError(f"malformed variable name '{name}'")
        unknown = PlcLabError(f"unknown variable '{name}'")
        first = steps[0][0]
        if first in self.instance_by_name and len(steps) > 1:
            inst = self.instance_by_name[first]
            container, key, ty = inst.obj, None, T.FBType(inst.name, inst.decl.pou if inst.decl else
                                                         self.checked.pous[type(inst.obj)._ST_NAME.upper()])
            steps = steps[1:]
        elif first in self.checked.globals and hasattr(self.G, first):
            container, key, ty = self.G, first, self.checked.globals[first].ty
            steps = steps[1:]
        else:
            for inst in self.instances:
                if first in getattr(type(inst.obj), "__slots__", ()):
                    pou = self.checked.pous[type(inst.obj)._ST_NAME.upper()]
                    container, key, ty = inst.obj, first, pou.symbols[first].ty
                    steps = steps[1:]
                    break
            else:
                raise unknown
        for field, index in steps:
            value = container if key is None else _get(container, key)
            if field:
                sub = _member_type(ty, field)
                if sub is None or not hasattr(value, field):
                    raise unknown
                container, key, ty = value, field, sub
            else:
                arr = T.base_of(ty)
                if not isinstance(arr, T.ArrayType):
                    raise unknown
                try:
                    idx = [int(x) for x in index.split(",")]
                except ValueError:
                    raise PlcLabError(f"'{name}': array indexes must be integers") from None
                if len(idx) != len(arr.dims) or any(not lo <= i <= hi for i, (lo, hi) in zip(idx, arr.dims)):
                    raise PlcLabError(f"'{name}': index outside {arr.name}")
                flat = 0
                for i, (lo, hi) in zip(idx, arr.dims):
                    flat = flat * (hi - lo + 1) + (i - lo)
                container, key, ty = value, flat, arr.elem
        if key is None:
            raise unknown
        return container, key, ty

    def read(self, name: str) -> Any:
        container, key = self.resolve(name)
        return _get(container, key)

    def write(self, name: str, value: Any) -> None:
        """Set a variable (for inputs prefer the image: the next scan samples it)."""
        up = name.strip().upper()
        if up.startswith("%"):
            for b in self.bindings:
                if b.address == up:
                    self.image.areas[b.area][b.index] = b.to_raw(value)
                    if not b.is_input:
                        setattr(b.owner, b.attr, b.from_raw(b.to_raw(value)))
                    return
            self.write_address(up, value)
            return
        container, key, ty = self.resolve_typed(name)
        normalise = T.wrapper_for(ty)
        # stored as C stores it (INT 40000 is -25536): a variable always holds a value of its
        # type, which the compiled code relies on (plclab.runtime.ranges)
        _set(container, key, normalise(value) if normalise is not None else value)

    def write_address(self, address: str, value: Any) -> None:
        """Write a raw value into the image at an address no variable is located at."""
        area, index = image_slot(address)
        self.image.areas[area][index] = int(value) & ((1 << image_bits(area)) - 1)


def _get(container: Any, key: Any) -> Any:
    return container[key] if isinstance(container, list) else getattr(container, key)


def _set(container: Any, key: Any, value: Any) -> None:
    if isinstance(container, list):
        container[key] = value
    else:
        setattr(container, key, value)


def _member_type(ty: T.Type, name: str) -> Optional[T.Type]:
    """The type of field / FB variable `name` of a value of type `ty`."""
    b = T.base_of(ty)
    if isinstance(b, T.StructType):
        f = b.fields.get(name)
        return f[0] if f else None
    if isinstance(b, T.FBType):
        pou = b.pou
        if isinstance(pou, A.PouDecl):
            d = (pou.symbols or {}).get(name)
            return d.ty if d is not None else None
        for n, tn in getattr(pou, "inputs", ()) + getattr(pou, "outputs", ()):
            if n == name:
                return T.ELEMENTARY[tn]
    return None


def image_bits(area: str) -> int:
    return AREAS[area][1]


def load_plc(checked: CheckedUnit, **kwargs: Any) -> PLC:
    return PLC(compile_unit(checked), **kwargs)
