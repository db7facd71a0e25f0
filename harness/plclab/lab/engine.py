"""The virtual lab's engine: one stand's `Session` (the same PLC, plant and trace as
`plclab run`) advanced in virtual time paced by the wall clock, x1..x50, in a thread of its
own.

Everything that touches the session happens in that thread, between scans: the web server
posts commands (`call`) and gets a future back, and receives a state snapshot after each batch
of scans (`listen`). So the page is a view of the session, never a second simulator, and a
console change from any page is seen by the next scan.

Pacing: scans run when their virtual time is due on the wall clock times the speed; after each
batch a snapshot is published, so at x1 what the page shows is at most one scan behind the
plant. When the machine cannot keep up with the speed asked, the engine runs what it can and
reports the speed it reached instead of piling up a backlog.
"""
from __future__ import annotations

import collections
import concurrent.futures
import dataclasses
import math
import tempfile
import threading
import time
from pathlib import Path
from typing import Any, Callable, Optional, Sequence

from plclab.errors import CompileError, PlcLabError
from plclab.lab.panels import PANELS, Panel
from plclab.plants.base import PlantError
from plclab.scenario import Session
from plclab.stands.scripts import fault_params
from plclab.trace import Trace

SPEEDS = (1, 2, 5, 10, 20, 50)
MIN_BATCH_S = 0.01          # wall seconds between batches at x1 where a cycle is shorter (the CNC's 1 ms)
FAST_BATCH_S = 0.025        # wall seconds between batches faster than real time (40 snapshots/s; a page draws 25)
MAX_BEHIND_S = 0.25         # wall seconds of backlog after which the engine stops catching up
TRACE_KEEP_S = 30 * 60.0    # plant seconds the lab's trace keeps (a ring: older changes are dropped)
TRIM_EVERY_S = 60.0         # plant seconds between two trims of the ring
LOG_KEEP = 2000             # console actions and plant events kept (the newest)
FRAMES_EVERY_S = 0.1        # wall seconds between two reads of the recorded program's table
LAB_TICK_NS = 25_000_000    # the plant is stepped at least this often (40 page updates a second at x1)


class LabError(PlcLabError):
    """A command the lab refuses: one line for the page."""


class Lab:
    """One stand, its program and its plant, run for the browser page(s)."""

    def __init__(self, stand: str, sources: Optional[Sequence[tuple[str, str]]] = None,
                 variant: Optional[str] = None, program_files: Sequence[str] = (), speed: float = 1.0,
                 work_dir: Optional[Path] = None):
        from plclab.stands import stand_module

        self.stand = stand
        self.module = stand_module(stand)
        self.panel: Panel = PANELS[stand]
        variant = variant or self.module.STAND.starting_variant    # as the real stand: Appendix 1 loaded
        self.variant = variant
        self.program_files = list(program_files)      # where --program came from (reload re-reads them)
        self.uploaded: Optional[list[tuple[str, str]]] = None   # the last program a page loaded
        self._tmp = None
        if work_dir is None:
            self._tmp = tempfile.TemporaryDirectory(prefix=f"plclab-lab-{stand}-")
            work_dir = Path(self._tmp.name)
        self.work_dir = Path(work_dir)
        self.retain_path = self.work_dir / f"{stand}.retain.json"
        from plclab.stands import sources as variant_sources
        srcs = list(sources) if sources is not None else variant_sources(self.module.STAND, variant)
        self.program_name = ", ".join(Path(n).name for n, _t in srcs if not n.startswith("<")) \
            if sources is not None else f"{variant} (shipped)"
        self.shipped = sources is None                # the shipped variant runs (no program loaded)
        self.session: Session = self._new_session(list(sources) if sources is not None else None)
        from plclab.lab.variables import Forces
        self.forces = Forces()                         # the watch and force table's forces
        self.forces.attach(self.session.plc)
        self.watched: list[str] = []                   # the watch table's variables
        from plclab.lab.monitor import Monitor
        self.monitor = Monitor()                       # online monitoring: one POU instance's values
        self._listing: tuple[Any, list] = (None, [])
        self.speed = self._check_speed(speed)
        self.paused = False
        self.actual_speed = 0.0
        self.held: set[str] = set()                   # push buttons held now (console inputs)
        self.console_levels: dict[str, int] = {}       # label -> what the operator set (the page shows it)
        self.loads = 0                                 # programs loaded so far (a page re-reads the source)
        self.trend_names: list[str] = list(self.panel.trends)
        self.extras = Trace()                        # trended variables the session does not record
        self._extra_unknown: dict[str, str] = {}
        self._trend_sent: dict[str, int] = {}
        self._events_sent = 0
        self._actions_sent = 0
        self._listeners: list[Callable[[dict], None]] = []
        self.viewers = 0                             # pages connected (no page: no snapshot to make)
        self._commands: "collections.deque[tuple[Callable[[], Any], concurrent.futures.Future, bool]]" = \
            collections.deque()
        self._console_since_scan = False             # a console change waits for the PLC to see it
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self.seq = 0
        self.scans_run = 0
        self._pace = (0.0, 1.0, 0.0)                 # (wall, speed, virtual): where the pacing stands

    def _new_session(self, program: Optional[list[tuple[str, str]]], checked: Any = None) -> Session:
        """The stand at power-up running `program` (None: the shipped variant)."""
        s = self.module.session(self.variant, program=program, checked=checked,
                                retain_path=self.retain_path, watch_internals=False)
        # the stand's observables (TUR-10's Target1..5, ...) are read by name where the program
        # has them, for the drawing and the trends; not recorded (the trace stays the I/O's)
        from plclab.stands.base import stand_spec
        s.observables = stand_spec(self.stand).observables_for(self.variant if program is None else None)
        self.session = s
        self._refine_tick()
        return s

    # ------------------------------------------------------------------ input scripts
    script: Any = None             # (name, steps, index of the next step) while a script replays
    epoch = 0                      # stand resets so far: a page clears its trends and logs on a new one

    def start_script(self, steps: list, name: str) -> None:
        """Replay an input script (plclab.lab.script): the stand is reset (a fresh plant at
        power-up, the PLC cold with no retained values, the trace started again at t = 0) and
        each step is applied before the first scan at or after its plant time."""
        old = self.session
        old.plc.stop()
        self.retain_path.unlink(missing_ok=True)
        s = self._new_session(None if self.shipped else list(old.sources), None if self.shipped else old.checked)
        for path in self.forces.attach(s.plc):
            s.log(f"force released: {path} (not in the program)")
        self.held.clear()
        self.console_levels.clear()
        self.extras = Trace()
        self._extra_unknown.clear()
        self._trend_sent, self._events_sent, self._actions_sent = {}, 0, 0
        self._trimmed_at = 0.0
        self.start_refused, self._start_watch = None, None
        self.epoch += 1
        self.script = (name, list(steps), 0)
        s.log(f"input script {name}: {len(steps)} step(s), the stand reset")
        self._apply_due()
        s.run(s.tick)                             # the first scan (t = 0), as at start
        self.scans_run += 1
        self._rebase = True

    def stop_script(self) -> None:
        if self.script is not None:
            name, steps, i = self.script
            self.session.log(f"input script {name} stopped at step {i} of {len(steps)}")
            self.script = None

    def _next_step_time(self) -> Optional[float]:
        if self.script is None:
            return None
        _name, steps, i = self.script
        return steps[i].time if i < len(steps) else None

    def _apply_due(self) -> None:
        """Apply the script's steps due before the next scan (plant time s.now)."""
        s = self.session
        while self.script is not None:
            name, steps, i = self.script
            if i >= len(steps):
                s.log(f"input script {name}: done")
                self.script = None
                return
            step = steps[i]
            if step.time > s.now + 1e-9:
                return
            self.script = (name, steps, i + 1)
            self._apply_step(step, i + 1, len(steps))

    def _apply_step(self, step: Any, n: int, total: int) -> None:
        s = self.session
        s.log(f"script step {n}/{total} (line {step.line}, t={step.time:g} s): {step.text}")
        try:
            if step.kind == "switch":
                self.set_control(step.target, step.value)
            elif step.kind == "button":
                control = self._control(step.target)
                if step.value:
                    s.console.hold(control.input)
                else:
                    s.console.release(control.input)
                self.console_levels[step.target] = step.value
            elif step.kind == "knob":
                self.set_knob(step.target, step.value)
            elif step.kind == "power":
                s.restart_plc(off_time=step.value)
                self.forces.attach(s.plc)
            elif step.kind == "fault":
                _name, params = fault_params(step.value)
                self.inject(step.target, {k: str(v) for k, v in params.items()})
            elif step.kind == "end":
                s.log(f"input script {self.script[0] if self.script else ''}: END reached")
                self.script = None
        except (LabError, PlcLabError) as e:
            s.log(f"script step {n} refused: {e}")

    # ------------------------------------------------------------------ life cycle
    def start(self) -> "Lab":
        self.session.run(self.session.tick)          # the first scan (t = 0): power-up outputs
        self._thread = threading.Thread(target=self._loop, name=f"lab-{self.stand}", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(5)
        self.session.plc.stop()                      # retain flushed
        if self._tmp is not None:
            self._tmp.cleanup()

    def listen(self, fn: Callable[[dict], None]) -> None:
        """`fn(snapshot)` after every batch of scans (called in the engine's thread)."""
        self._listeners.append(fn)

    # ------------------------------------------------------------------ commands
    def call(self, fn: Callable[[], Any], console: bool = False) -> concurrent.futures.Future:
        """Run `fn()` in the engine's thread between scans; its result (or exception) in the
        future. Console changes (`console=True`) are applied one per scan while running, so a
        press and its release are both seen by the PLC however quickly they come."""
        fut: concurrent.futures.Future = concurrent.futures.Future()
        self._commands.append((fn, fut, console))
        self._wake.set()
        return fut

    def _drain(self) -> None:
        """Run the commands waiting; a console change waits until a scan has seen the one
        before it (while running: paused, they all apply at once)."""
        while self._commands:
            fn, fut, console = self._commands[0]
            if console and self._console_since_scan and not self.paused:
                return
            self._commands.popleft()
            if fut.set_running_or_notify_cancel():
                try:
                    fut.set_result(fn())
                except BaseException as e:   # noqa: BLE001 - the caller gets it through the future
                    fut.set_exception(e)
            self._console_since_scan |= console

    def _refine_tick(self) -> None:
        """Step the plant at least every LAB_TICK_NS (thermo's task runs every 100 ms): the
        page then gets >= 20 new plant states a second. The program's tasks keep their
        periods (the tick divides every TASK interval), as in `plclab run --tick`."""
        s = self.session
        natural = s.plc.tick_ns
        if natural <= LAB_TICK_NS or s.plc.ticks:
            return
        s.tick_ns = math.gcd(natural, LAB_TICK_NS)
        logged = len(s.actions)
        s.restart_plc()                       # not a scan run yet: the same cold start, finer steps
        del s.actions[logged:]

    def ops(self) -> tuple[str, ...]:
        """The commands this stand's page has (the SCADA registers are thermo's only, the
        knobs and part programs the CNC's)."""
        ops = ("set", "press", "release", "speed", "pause", "run", "scan", "restart", "inject", "clear", "trends",
               "tree", "watch", "force", "unforce", "source", "monitor", "unscript")
        if self.stand == "thermo":
            ops += ("register",)
        if self.panel.knobs:
            ops += ("knob",)
        if self.panel.part is not None:
            ops += ("part", "contour")
        return ops

    def set_knob(self, label: str, value: int) -> None:
        try:
            knob = self.panel.knob(label)
        except KeyError:
            raise LabError(f"{self.stand} has no setting '{str(label)[:40]}' "
                           f"(one of {', '.join(k.label for k in self.panel.knobs)})") from None
        if not knob.lo <= value <= knob.hi:
            raise LabError(f"{label}: {value} is outside {knob.lo}..{knob.hi} {knob.unit}")
        plc = self.session.plc
        try:
            knob.apply(self.session, value)
        except PlantError as e:
            raise LabError(str(e)) from None
        if self.session.plc is not plc:         # the knob downloaded the program again (FINE_MS)
            for path in self.forces.attach(self.session.plc):   # forces on what it still has stay
                self.session.log(f"force released: {path} (not in the program loaded)")
        self.console_levels[label] = value

    def load_part(self, text: str, name: str, method: str) -> str:
        """A CNC part program into the PLC's frame table (plclab.lab.cncview)."""
        from plclab.nc.gcode import GcodeError
        try:
            return self.panel.part.load(self.session, text, name, method)
        except (GcodeError, ValueError) as e:
            raise LabError(str(e)) from None

    def contour(self) -> dict:
        from plclab.lab.cncview import cnc_contour
        return cnc_contour(self.session)

    # the commands themselves (each runs in the engine's thread through `call`)
    def set_control(self, label: str, value: int) -> None:
        control = self._control(label)
        if control.kind != "switch":          # a push button set on would stay pressed for ever
            raise LabError(f"{label} is a push button: it is pressed and released, not set")
        self.session.plant.set_switch(control.input, int(bool(value)))
        self.console_levels[label] = int(bool(value))
        self.session.log(f"{label}={int(bool(value))}")

    def press(self, label: str, down: bool) -> None:
        control = self._control(label)
        if control.kind != "button":
            raise LabError(f"{label} is a switch: it is set on or off, not pressed")
        if down:
            self.session.console.hold(control.input)
            if not control.latching:          # a latched button is no hold of the student's time
                self.held.add(control.input)
        else:
            self.session.console.release(control.input)
            self.held.discard(control.input)
        self._watch_start(control.input, down)
        self.console_levels[label] = int(down)
        self._rebase = True            # the pace changes while a button is held (see `pace`)

    # ------------------------------------------------------------------ a start press refused
    start_refused: Optional[str] = None    # why the last start press started nothing (the page shows it)
    _start_watch: Any = None               # (output change counts at the press, deadline or None)

    def _watch_start(self, name: str, down: bool) -> None:
        """A press of the stand's start button in automatic mode is watched: when none of the
        outputs a start changes has changed `within` s of its release, the lab says so and
        what the program reads of the console then (the StandSpec's StartPress: I/O only)."""
        from plclab.stands.base import stand_spec
        start = stand_spec(self.stand).start
        if start is None or name != start.button:
            return
        s = self.session
        if down:
            self.start_refused = None
            switch, level = start.mode
            if int(bool(s.value(switch))) != level or self._playing(start):
                self._start_watch = None           # manual mode (a press records a frame), or a stop press
                return
            self._start_watch = ({o: s.trace.change_count(o) for o in start.outputs if o in s.trace}, None)
        elif self._start_watch is not None:
            self._start_watch = (self._start_watch[0], s.now + start.within)

    def _playing(self, start: Any) -> bool:
        """Whether playback is under way (a press then stops it): the program says so where
        the stand's observables name it (Running, InFrame); a program without them, when one
        of the outputs a start moves changed in the last seconds (a frame, or its pause)."""
        s = self.session
        told = []
        for name in ("Running", "InFrame"):
            if name in s.observables:
                try:
                    told.append(bool(s.value(name)))
                except Exception:     # noqa: BLE001 - a student's program need not have it
                    pass
        if told:
            return any(told)
        recent = round((s.now - start.within - 1.0) * 1e9)
        for o in start.outputs:
            if o in s.trace:
                changes = s.trace.changes(o)
                if len(changes) > 1 and changes[-1][0] >= recent:
                    return True
        return False

    def _check_start(self) -> None:
        counts, deadline = self._start_watch
        s = self.session
        if any(s.trace.change_count(o) != n for o, n in counts.items()):
            self._start_watch = None               # an output changed: playback started (or stopped)
            return
        if deadline is None or s.now < deadline:
            return
        self._start_watch = None
        from plclab.stands.base import stand_spec
        start = stand_spec(self.stand).start
        assert start is not None
        label = {c.input: c.label for c in self.panel.controls}
        read = []
        for name, off, on in start.reads:
            try:
                level = int(bool(s.value(name)))
            except PlcLabError:
                continue
            read.append(f"{label.get(name, name)} {'on' if level else 'off'}"
                        + (f" ({on if level else off})" if (off, on) != ("off", "on") else ""))
        frames, ask = "", " Is one of them off that the program needs on?"
        try:
            count = int(s.value("FrameCount"))
            frames = f"; {count} frame(s) recorded" if count else "; no frame recorded"
            ask = ask if count else " Record frames first (manual mode)."
        except Exception:        # noqa: BLE001 - a program without the shipped frame memory
            pass
        first, last = start.outputs[0], start.outputs[-1]
        text = (f"{label.get(start.button, start.button)} pressed in automatic mode: the program started "
                f"nothing ({first}..{last} unchanged {start.within:g} s after the release). "
                f"It reads {', '.join(read)}{frames}.{ask}")
        self.start_refused = text
        s.log(text)

    def pace(self) -> float:
        """The speed the plant runs at now: x1 while a push button is held, whatever the
        speed asked, so a hold lasts as long in the plant as the student holds it (a click
        records a frame at x50 too, and only 3 s of the student's own time reset)."""
        return 1.0 if self.held else self.speed

    def _control(self, label: str):
        try:
            return self.panel.control(label)
        except KeyError:
            raise LabError(f"{self.stand} has no console control '{label}' "
                           f"(one of {', '.join(c.label for c in self.panel.controls)})") from None

    def set_speed(self, speed: float) -> None:
        self.speed = self._check_speed(speed)
        self._rebase = True

    def set_paused(self, paused: bool) -> None:
        self.paused = bool(paused)
        self._rebase = True

    def single_scan(self) -> None:
        if not self.paused:
            raise LabError("single scan: pause first")
        self._run_scans(1)

    def restart_plc(self) -> None:
        """Power-cycle the controller: retained variables kept, the plant stays; forces stay
        (as a programming tool keeps them through a restart)."""
        self.session.restart_plc()
        self.forces.attach(self.session.plc)
        self._rebase = True

    # the watch and force table (plclab.lab.variables)
    def variable_tree(self) -> list[dict]:
        from plclab.lab.variables import variable_tree
        return variable_tree(self.session.plc)

    def set_watch(self, paths: Sequence[str]) -> list[str]:
        from plclab.lab.variables import MAX_WATCH, elementary
        clean: list[str] = []
        for p in paths:
            p = str(p).strip()
            if p and p not in clean:
                clean.append(p)
        if len(clean) > MAX_WATCH:
            raise LabError(f"at most {MAX_WATCH} watched variables ({len(clean)} asked)")
        for p in clean:
            elementary(self.session.plc, p)
        self.watched = clean
        return clean

    def listing(self) -> list[dict]:
        """The program's POUs for online monitoring (plclab.lab.monitor), once per program."""
        from plclab.lab.monitor import listing
        s = self.session
        if self._listing[0] is not s.checked:
            self._listing = (s.checked, listing(s.plc, s.sources))
        return self._listing[1]

    def select_monitor(self, pou: str, instance: Optional[str]) -> None:
        for p in self.listing():
            if p["name"].upper() == str(pou).upper():
                self.monitor.select(self.session.plc, p, instance if instance else None)
                self._monitor_at = 0.0
                self._power = None
                if "ladder" in p:                  # an LD POU: its power flow, from the same instance
                    from plclab.lab.ladder import PowerFlow, pou_elements
                    elements = pou_elements(self.session.sources, p["name"])
                    if elements is not None:
                        self._power = (PowerFlow, elements, self.monitor.instance or next(iter(p["instances"]), None))
                return
        raise LabError(f"the program has no POU '{str(pou)[:80]}'")

    _monitor_at = 0.0
    _power: Any = None

    def _power_flow(self) -> Optional[dict]:
        """The shown LD POU's power on every element output (plclab.lab.ladder), or None."""
        if self._power is None:
            return None
        from plclab.lab.ladder import time_aware
        flow, elements, instance = self._power
        return flow(elements, instance, time_aware(self.session.plc)).state()

    def _monitor_values(self, full: bool) -> Any:
        now = time.monotonic()
        if not full and now - self._monitor_at < FRAMES_EVERY_S:
            return _SAME
        self._monitor_at = now
        return self.monitor.values(self.session.plc, full)

    def force(self, path: str, value: Any) -> None:
        shown = self.forces.force(path, value)
        self.session.log(f"FORCE {path} := {_force_text(shown)}")
        if path not in self.watched:
            self.watched = [*self.watched, path][-32:]

    def unforce(self, path: Optional[str]) -> None:
        for p in self.forces.release(path):
            self.session.log(f"force released: {p}")

    def _watch_values(self) -> list[list]:
        from plclab.lab.variables import show
        out = []
        plc = self.session.plc
        for p in self.watched:
            try:
                value = show(plc.read(p))
            except PlcLabError:
                value = None
            out.append([p, value, p in self.forces.values])
        return out

    def _forced_labels(self) -> list[str]:
        """The console controls and lamps a force holds (forced by label, address or path)."""
        if not self.forces.values:
            return []
        plc = self.session.plc
        targets = set()
        for p in self.forces.values:
            try:
                c, k = plc.resolve(p)
                targets.add((id(c), k))
            except PlcLabError:
                pass
        out = []
        for label, signal in [(c.label, c.signal) for c in self.panel.controls] + \
                             [(lamp.label, lamp.label) for lamp in self.panel.lamps]:
            for name in (signal, self.session.labels.get(signal, "")):
                try:
                    c, k = plc.resolve(name)
                except PlcLabError:
                    continue
                if (id(c), k) in targets:
                    out.append(label)
                    break
        return out

    def load_program(self, sources: Sequence[tuple[str, str]], checked: Any, name: str, upload: bool = False) -> None:
        """Download `sources` (already through `prepare_program`). Should the load still fail,
        the previous program is loaded again (cold, retained variables kept) and the error
        is one line: the lab always has a program running."""
        s = self.session
        old_sources, old_checked = s.sources, s.checked
        old_tick = s.tick_ns
        try:
            s.tick_ns = None                  # the new program's own tick first (then refined)
            s.load_program(sources, checked)
            self._refine_tick()
        except (Exception, RecursionError, MemoryError) as e:     # noqa: BLE001 - any failure: back
            s.tick_ns = old_tick
            s.load_program(old_sources, old_checked)
            self.forces.attach(s.plc)
            self._rebase = True
            raise LabError(f"the program could not be loaded ({_why(e)}); the PLC runs the previous "
                           f"program again (restarted)") from None
        for path in self.forces.attach(s.plc):          # forces on what the new program has stay
            s.log(f"force released: {path} (not in the program loaded)")
        self.watched = [p for p in self.watched if _has(s.plc, p)]
        self.shipped = False
        self.monitor.pou = None                        # the page picks a POU of the new program
        self._power = None
        self.program_name = name
        self.loads += 1
        if upload:                         # Reload loads it again (the browser's files are not on disk)
            self.uploaded = list(sources)
        self._extra_unknown.clear()
        self._rebase = True

    def inject(self, fault: str, params: dict[str, str]) -> None:
        spec = {f.name: f for f in self.panel.faults}.get(fault)
        if spec is None:
            raise LabError(f"{self.stand} has no fault '{fault}' (one of {', '.join(f.name for f in self.panel.faults)})")
        values: dict[str, Any] = {}
        for p in spec.params:
            text = str(params.get(p.name, p.default)).strip()
            if text == "":
                continue
            if p.choices:
                if text not in p.choices:
                    raise LabError(f"{fault}: {p.name} must be one of {', '.join(p.choices)}, not '{text}'")
                values[p.name] = int(text) if text.isdigit() else text
            else:
                try:
                    number = float(text)
                except ValueError:
                    raise LabError(f"{fault}: {p.name} must be a number, not '{text}'") from None
                if not math.isfinite(number):
                    raise LabError(f"{fault}: {p.name} must be a finite number, not '{text}'")
                values[p.name] = int(number) if number.is_integer() and p.name in ("value", "axis") else number
        try:
            self.session.inject(fault, **values)
        except PlantError as e:
            raise LabError(str(e)) from None

    def clear_faults(self) -> None:
        self.session.clear_faults()

    def set_trends(self, names: Sequence[str]) -> list[str]:
        """Choose the trended signals; an unknown name is refused (one line), the rest kept."""
        clean = []
        for n in names:
            n = str(n).strip()
            if n and n not in clean:
                clean.append(n)
        if len(clean) > 16:
            raise LabError(f"at most 16 trended signals ({len(clean)} asked)")
        for n in clean:
            if n not in self.session.trace and n not in self.session.labels:
                try:
                    self._read_extra(n)
                except LabError:
                    raise
        self.trend_names = clean
        self._trend_sent = {}
        return clean

    def _read_extra(self, name: str) -> Any:
        try:
            value = self.session.value(name)
        except Exception:        # noqa: BLE001 - any lookup failure is an unknown name for the user
            raise LabError(f"'{name}' is neither a located address (%IX0.1), a label of the stand nor a "
                           f"variable of the program (e.g. Main.Cp.Count)") from None
        if isinstance(value, (list, tuple, dict)) or not isinstance(value, (bool, int, float, str)):
            raise LabError(f"'{name}' is not an elementary variable: trend one of its elements or fields")
        return value

    # ------------------------------------------------------------------ the loop
    _rebase = True

    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                self._run_paced()
            except MemoryError:       # past the lab's memory limit outside a scan (a scan's is a PLC fault)
                self.paused = True
                self.session.log("the lab paused: out of memory (the memory limit of a program run, "
                                 "docs/reliability.md); load a smaller program or restart the lab")
                self._stop.wait(0.5)
            except Exception as e:    # noqa: BLE001 - a bug of ours: the clock stops, the pages say why
                import logging
                logging.getLogger("plclab.lab").exception("lab engine")
                self.paused = True
                self.session.log(f"the lab paused: internal error ({type(e).__name__}: {e}); please report it")
                self._stop.wait(0.5)

    def _run_paced(self) -> None:
        s = self.session
        base_wall = base_virt = 0.0
        rate_wall, rate_virt = time.monotonic(), s.now
        while not self._stop.is_set():
            self._drain()
            if self.session is not s:      # an input script's reset swapped the session: pace the new one
                s = self.session
                rate_wall, rate_virt = time.monotonic(), s.now
                self._rebase = True
            if self._rebase:
                self._rebase = False
                base_wall, base_virt = time.monotonic(), s.now - s.tick
            speed = self.pace()
            self._pace = (base_wall, speed, base_virt)
            if self.paused:
                self.actual_speed = 0.0
                self._publish()
                self._wake.wait(0.2)
                self._wake.clear()
                continue
            tick = s.tick
            now = time.monotonic()
            target = base_virt + (now - base_wall) * speed
            due = math.floor((target - s.now) / tick + 1e-9) + 1     # scans at or before `target`
            if due <= 0:
                wait = (s.now - target) / speed
                self._wake.wait(max(0.0, min(wait, 0.2)))
                self._wake.clear()
                continue
            if (due - 1) * tick / speed > MAX_BEHIND_S:   # cannot keep up: run a slice, rebase
                due = max(1, int(MAX_BEHIND_S * speed / tick))
                self._rebase = True
            self._run_scans(1 if self._commands else due)     # a command waits: one scan, then it
            if now - rate_wall >= 1.0:
                self.actual_speed = (s.now - rate_virt) / (now - rate_wall)
                rate_wall, rate_virt = now, s.now
            self._publish()
            # sleep until the next scan is due (at x1: wake on time, so the page is at most one
            # scan behind); faster than real time, batches at least FAST_BATCH_S apart: each
            # snapshot carries every trend point and event since the one before, and more of
            # them than a page draws would only cost the lab and the browsers
            wake = base_wall + (s.now - base_virt) / speed
            if speed > 1:
                wake = max(wake, now + FAST_BATCH_S)
            elif tick < MIN_BATCH_S:                    # the CNC's 1-ms cycle: batches of 10 ms
                wake = max(wake, now + MIN_BATCH_S)
            pause = wake - time.monotonic()
            if pause > 0 and not self._commands:
                self._wake.wait(pause)
                self._wake.clear()

    def advance(self, seconds: float) -> None:
        """Run `seconds` of plant time now (whole scans), as the loop does (tests, paused use)."""
        self._run_scans(max(1, math.ceil(round(seconds / self.session.tick, 6))))

    def _run_scans(self, n: int) -> None:
        """n scans; a replayed script's steps applied each before its scan."""
        if self.script is None:
            self._scan_block(n)
            return
        s = self.session
        while n > 0:
            self._apply_due()
            t = self._next_step_time()
            k = n if t is None else max(1, min(n, math.ceil(round((t - s.now) / s.tick, 6))))
            self._scan_block(k)
            n -= k
        self._apply_due()

    def _scan_block(self, n: int) -> None:
        s = self.session
        self._console_since_scan = False
        extras = [name for name in self.trend_names
                  if name not in s.trace and name not in s.labels and name not in self._extra_unknown]
        if not extras:
            s.run(n * s.tick)
        else:
            for _ in range(n):                 # trended variables the trace lacks: sampled every scan
                s.run(s.tick)
                self._sample_extras(extras)
        self.scans_run += n
        if self._start_watch is not None:
            self._check_start()
        if s.now - self._trimmed_at >= TRIM_EVERY_S:
            self._trim()

    _trimmed_at = 0.0

    def _trim(self) -> None:
        """Keep the last TRACE_KEEP_S of plant time in the traces and the last LOG_KEEP
        actions and events: a lab left running at x50 for a day stays the size of that
        window (the downloads say which window they hold)."""
        s = self.session
        self._trimmed_at = s.now
        cut_ns = round((s.now - TRACE_KEEP_S) * 1e9)
        if cut_ns > 0:
            s.trace.drop_before(cut_ns)
            self.extras.drop_before(cut_ns)
            sim_cut = cut_ns - (round(s.now * 1e9) - s.plc.now_ns)    # the PLC's own clock (restarts)
            if sim_cut > 0:
                s.sim.trace.drop_before(sim_cut)
        for items, sent in ((s.actions, "_actions_sent"), (s.plant.events, "_events_sent")):
            extra = len(items) - LOG_KEEP
            if extra > 0:
                del items[:extra]
                setattr(self, sent, max(0, getattr(self, sent) - extra))

    def trace_window(self) -> tuple[float, float]:
        """The plant times (from, to) the lab's trace holds now."""
        return self.session.trace.start_ns / 1e9, max(0.0, self.session.now - self.session.tick)

    def _sample_extras(self, names: list[str]) -> None:
        t_ns = round((self.session.now - self.session.tick) * 1e9)
        for name in names:
            try:
                value = self._read_extra(name)
            except LabError as e:
                self._extra_unknown[name] = str(e)
                continue
            if isinstance(value, bool):
                kind = "bool"
            elif isinstance(value, int):
                kind = "int"
            elif isinstance(value, float):
                kind = "real"
            else:
                kind = "str"
            if name not in self.extras:
                self.extras.declare(name, kind, value, t_ns, width=64 if kind == "int" else None)
            else:
                self.extras.change(t_ns, name, value)

    # ------------------------------------------------------------------ snapshots
    def _publish(self) -> None:
        if not self._listeners or not self.viewers:
            return
        snap = self.snapshot()
        for fn in list(self._listeners):
            fn(snap)

    def snapshot(self, full: bool = False) -> dict[str, Any]:
        """The state a page shows. `full` (a page connecting) carries the whole history of
        events and the last minute of every trend instead of only what is new."""
        s = self.session
        plc = s.plc
        self.seq += 1
        fault = plc.fault
        if fault is not None:            # on the header's clock (the PLC's restarts at every load)
            fault = dataclasses.replace(fault, time_ns=fault.time_ns + round(s.now * 1e9) - plc.now_ns)
        forced_labels = self._forced_labels()
        snap: dict[str, Any] = {
            "type": "state", "seq": self.seq, "t": round(s.now - s.tick, 6), "tick": s.tick,
            "speed": self.speed, "paused": self.paused, "actual_speed": round(self.actual_speed, 2),
            "held": sorted(self.held), "pace": self.pace(), "start_refused": self.start_refused,
            "held_labels": [c.label for c in self.panel.controls if c.input in self.held],   # as the console prints them
            "program": self.program_name, "loads": self.loads, "epoch": self.epoch,
            "script": self._script_state(),
            "trace_from": round(s.trace.start_ns / 1e9, 3), "trace_keep": TRACE_KEEP_S,
            "paced": self.paced_now(),          # where the plant should be now: t + the lag
            "wall": time.monotonic(),           # when (CLOCK_MONOTONIC, the same in every process here)
            "plc": {"state": plc.state, "fault": str(fault) if fault else None,
                    "pou": fault.pou if fault else None, "file": fault.file if fault else None,
                    "line": fault.line if fault else None},
            "io": self._io(forced_labels),
            "mimic": self.panel.mimic(s),
        }
        # what is new since the last snapshot; a full one (a page connecting) has it all, and
        # what follows it starts from it (with pages open the counts are current anyway)
        events = s.plant.events
        start = 0 if full else self._events_sent
        snap["events"] = [{"t": round(e.time, 3), "kind": e.kind, "detail": e.detail} for e in events[start:]]
        self._events_sent = len(events)
        start = 0 if full else self._actions_sent
        snap["actions"] = [{"t": round(a.time, 3), "text": a.text} for a in s.actions[start:]][-200:]
        self._actions_sent = len(s.actions)
        snap["trends"] = self._trend_changes(full)
        snap["trend_errors"] = {n: self._extra_unknown[n] for n in self.trend_names if n in self._extra_unknown}
        if self.stand == "thermo":
            snap["registers"] = self.registers()
        snap["watch"] = self._watch_values()
        snap["forced"] = {p: _force_text(v) for p, v in self.forces.values.items()}
        snap["forced_labels"] = forced_labels
        values = self._monitor_values(full)
        if values is not _SAME and values is not None:
            snap["monitor"] = {"pou": self.monitor.pou, "instance": self.monitor.instance, "values": values}
            power = self._power_flow()
            if power is not None:
                snap["monitor"]["power"] = power
        frames = self._frames(full)
        if frames is not _SAME:
            snap["frames"] = frames
        return snap

    def _script_state(self) -> Optional[dict]:
        if self.script is None:
            return None
        name, steps, i = self.script
        nxt = steps[i] if i < len(steps) else None
        return {"name": name, "done": i, "steps": len(steps),
                "next": f"t={nxt.time:g} s: {nxt.text}" if nxt is not None else None}

    _frames_at = 0.0
    _frames_sent: Any = None

    def _frames(self, full: bool) -> Any:
        """The recorded program's table (panels), when it changed (read at most every
        FRAMES_EVERY_S of wall time: a page highlights the frame being executed)."""
        now = time.monotonic()
        if not full and now - self._frames_at < FRAMES_EVERY_S:
            return _SAME
        self._frames_at = now
        table = self.panel.frames(self.session)
        if not full and table == self._frames_sent:
            return _SAME
        self._frames_sent = table
        return table

    def paced_now(self) -> float:
        """The plant time the wall clock says it is now (the last scan's time when paused):
        what the page's state lags behind. A page compares it with `t` (`plclab bench`)."""
        if self.paused:
            return round(self.session.now - self.session.tick, 6)
        wall, speed, virt = self._pace
        return virt + (time.monotonic() - wall) * speed

    def _io(self, forced: Sequence[str] = ()) -> dict[str, int]:
        s = self.session
        io = {}
        closed = getattr(s.plant, "NORMALLY_CLOSED", frozenset())
        for c in self.panel.controls:        # the console as the operator set it (seen while paused too)
            if c.kind == "button":           # a button's level: pressed (1) or not, whatever its contact
                io[c.label] = self.console_levels.setdefault(c.label, 0)
            else:
                io[c.label] = self.console_levels.setdefault(c.label, int(bool(s.value(c.signal))))
            if c.label in forced:            # forced: what the PLC reads, not where the control is
                try:
                    level = int(bool(s.plc.read(c.signal)))
                except PlcLabError:
                    continue
                # a button is pressed when its contact reads closed (a normally closed one: open)
                io[c.label] = level ^ int(c.kind == "button" and c.input in closed)
        for k in self.panel.knobs:
            io[k.label] = self.console_levels.setdefault(k.label, k.initial)
        for lamp in self.panel.lamps:
            io[lamp.label] = int(bool(s.value(lamp.label)))
        return io

    def _trend_changes(self, full: bool) -> dict[str, list]:
        s = self.session
        out: dict[str, list] = {}
        horizon_ns = round((s.now - self.panel.trend_window) * 1e9)
        for name in self.trend_names:
            trace = s.trace if name in s.trace else self.extras if name in self.extras else None
            if trace is None:
                continue
            count = trace.change_count(name)
            if full:
                changes = trace.changes(name)
                recent = [c for c in changes if c[0] >= horizon_ns]
                earlier = [c for c in changes if c[0] < horizon_ns]
                points = (earlier[-1:] + recent)
            else:
                start = max(0, self._trend_sent.get(name, 0) - 1)
                points = trace.changes_from(name, start)
            self._trend_sent[name] = count
            out[name] = [[t / 1e9, _plain(v)] for t, v in points]
        return out

    # ------------------------------------------------------------------ thermo registers
    def registers(self) -> list[dict[str, Any]]:
        from plclab.stands import twido_profile
        THERMO = twido_profile("thermo")
        image = self.session.plc.image
        raw = image.snapshot("MW", 0, max(r.address for r in THERMO.registers) + 1)
        from plclab.modbus.profiles import THERMO_MODES
        return [{"address": r.address, "name": r.name, "access": r.access.value,
                 "choices": [[k, v] for k, v in sorted(THERMO_MODES.items())] if r.name == "mode" else None,
                 "valid": str(r.valid) if r.valid is not None else "",
                 "rule": f"writable only when {r.writable_when}" if r.writable_when else "",
                 "description": r.description, "value": r.as_value(raw[r.address])} for r in THERMO.registers]

    def twido_map(self, external: bool = False):
        """The Twido face's register map on whichever PLC runs now (a restart or a program
        load makes a new process image; the map follows it). `external`: the map an
        external SCADA client writes through, each write (done or refused) in the lab's log."""
        from plclab.modbus.maps import TwidoMap
        from plclab.modbus.protocol import ModbusException
        from plclab.stands import twido_profile
        THERMO = twido_profile("thermo")

        lab = self

        class LoggedTwidoMap(TwidoMap):
            def write(self, table, start, values):
                what = ", ".join(f"%MW{start + i}={v}" for i, v in enumerate(values))
                try:
                    super().write(table, start, values)
                except ModbusException as e:
                    from plclab.hmi import EXCEPTION_NAMES
                    code = int(e.code)
                    text = (f"SCADA client: {what} refused: exception {code:02d} "
                            f"({EXCEPTION_NAMES.get(code, 'unknown')}): {e.reason}")
                    lab.call(lambda: lab.session.log(text))
                    raise
                lab.call(lambda: lab.session.log(f"SCADA client: {what} written"))
        return (LoggedTwidoMap if external else TwidoMap)(_CurrentImage(self), THERMO)

    def write_register(self, address: int, value: int) -> None:
        from plclab.modbus.protocol import ModbusException, Table
        try:
            self.twido_map().write(Table.HOLDING_REGISTERS, int(address), (int(value) & 0xFFFF,))
        except ModbusException as e:
            from plclab.hmi import EXCEPTION_NAMES
            code = int(e.code)
            raise LabError(f"%MW{address} = {value} refused: exception {code:02d} "
                           f"({EXCEPTION_NAMES.get(code, 'unknown')}): {e.reason}") from None
        self.session.log(f"SCADA %MW{address}={value}")

    # ------------------------------------------------------------------ downloads
    def trace_for_download(self) -> Trace:
        """The session's trace plus the trended variables it does not record."""
        s = self.session
        if not self.extras.signals():
            return s.trace
        out = Trace()
        for src in (s.trace, self.extras):
            for name in src.signals():
                info = src.info(name)
                changes = src.changes(name)
                out.declare(name, info.kind, changes[0][1], changes[0][0], width=info.width)
                for t, v in changes[1:]:
                    out.change(t, name, v)
        out.advance(s.trace.end_ns)
        return out

    @staticmethod
    def _check_speed(speed: float) -> float:
        try:
            speed = float(speed)
        except (TypeError, ValueError):
            raise LabError(f"speed must be a number (x0.1 .. x50), not '{str(speed)[:40]}'") from None
        if not 0.1 <= speed <= 50 or not math.isfinite(speed):
            raise LabError(f"speed x{speed:g}: from x0.1 to x50 (x1: real time)")
        return speed


_SAME = object()             # "as in the last snapshot" (not sent)


def _force_text(value: Any) -> str:
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    return str(value)


def _has(plc: Any, path: str) -> bool:
    try:
        plc.resolve(path)
    except PlcLabError:
        return False
    return True


class _CurrentImage:
    """The process image of the PLC the lab runs now (ImageLike for the Modbus maps)."""

    def __init__(self, lab: Lab):
        self._lab = lab

    def snapshot(self, area: str, start: int, count: int) -> list[int]:
        return self._lab.session.plc.image.snapshot(area, start, count)

    def queue_write(self, area: str, start: int, values: list[int]) -> None:
        self._lab.session.plc.image.queue_write(area, start, values)


def _plain(value: Any) -> Any:
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _why(e: BaseException) -> str:
    if isinstance(e, RecursionError):
        return "it nests too deeply: RecursionError"
    if isinstance(e, MemoryError):
        return "it needs more memory than the lab has: MemoryError"
    return f"{type(e).__name__}: {str(e)[:200]}"


def read_upload(files: Sequence[tuple[str, Any]]) -> tuple[list[tuple[str, str]], list[str]]:
    """A page's upload as the program's sources: ST files as they are, an OpenPLC Editor
    project (`.xml`, bytes) turned into its ST as every command reads it (its ST files'
    blocks may be boxes in its drawing); or the diagnostics, which name the POU, rung and
    element of a drawing. Held to the memory limit of a program run (plclab.limits)."""
    from plclab.frontend import is_project_file
    from plclab.limits import memory_limited
    from plclab.frontend.plcxml import source_from_xml       # imported before the limit (lxml maps a lot)
    st_texts = [(n, t) for n, t in files if not is_project_file(n)]
    out: list[tuple[str, str]] = []
    errors: list[str] = []
    for name, data in files:
        if not is_project_file(name):
            out.append((name, data))
            continue
        try:
            with memory_limited():
                out.append((name, source_from_xml(name, data, st_texts)))
        except CompileError as e:
            errors.extend(str(d) for d in e.diagnostics)
        except PlcLabError as e:
            text = str(e)
            errors.append(text if text.startswith(name) else f"{name}: {text}")
        except (Exception, RecursionError, MemoryError) as e:     # noqa: BLE001 - a student's file
            errors.append(f"{name}: project: the project cannot be read ({_why(e)})")
    return out, errors


TRIAL_TIMEOUT_S = 120.0     # wall seconds a trial load may take (a lab program: well under a second)



def check_program(sources: Sequence[tuple[str, str]], trial: bool = False):
    """The front end's verdict on an uploaded program: (checked, []) or (None, diagnostics).
    With `trial`, the program is also compiled and instantiated once (no retain, no scan)
    in a child process held to the memory limit of a program run (plclab.limits: a process
    limit, as grade-class gives each student), so what fails there fails before the PLC
    stops and no upload grows the lab's own process past it. Whatever goes wrong (even a
    RecursionError or a MemoryError) is one line, never an exception."""
    where = f"{sources[-1][0]}:1:1: error: " if sources else "<upload>:1:1: error: "
    if trial:                           # first: what the check and the load take is then known to fit
        why = _trial_load(sources)
        if why is not None:
            return None, [f"{where}the program cannot be {why}"]
    return _check_program(sources, where)


def _check_program(sources: Sequence[tuple[str, str]], where: str):
    from plclab.frontend import check_sources
    try:
        checked = check_sources(sources)
    except CompileError as e:
        return None, [str(d) for d in e.diagnostics]
    except (Exception, RecursionError, MemoryError) as e:       # noqa: BLE001 - a student's file
        return None, [f"{where}the program cannot be checked ({_why(e)})"]
    if checked.config is None:
        return None, [f"{sources[-1][0]}:1:1: error: no CONFIGURATION: load the complete program (the bundle "
                      f"from `plclab build`, with its CONFIGURATION Config0 and TASKs)"]
    return checked, []


def _trial_load(sources: Sequence[tuple[str, str]]) -> Optional[str]:
    """Check, compile and instantiate `sources` in a child process under the memory limit
    (plclab.lab.trial); None when it loads (or fails the check: the caller's check names the
    diagnostics on the drawing), else 'loaded (why not)' / 'checked (why not)'."""
    import json
    import os
    import subprocess
    import sys

    import plclab
    env = dict(os.environ)
    root = str(Path(plclab.__file__).resolve().parents[1])
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    data = json.dumps([[str(n), str(t)] for n, t in sources])
    try:
        done = subprocess.run([sys.executable, "-m", "plclab.lab.trial"], input=data, capture_output=True,
                              text=True, env=env, timeout=TRIAL_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return f"loading it took more than {TRIAL_TIMEOUT_S:g} s"
    except OSError as e:
        return f"the trial load could not start: {e.strerror or e}"
    lines = done.stdout.strip().splitlines()
    if done.returncode == 0 and lines and lines[-1] in ("ok", "check"):
        return None                     # loads, or the check's diagnostics (this process names them)
    if lines and lines[-1].startswith(("checked (", "loaded (")):
        return lines[-1]
    if done.returncode < 0 or "MemoryError" in done.stderr:
        return "loaded (it needs more memory than the lab has: MemoryError)"
    return f"loaded (the trial load stopped, exit {done.returncode})"
