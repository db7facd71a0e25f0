"""Real time: scan on the wall clock, drift-compensated, overruns counted.

The deadline of tick k is `start + k * tick` (not "last scan + tick"), so a late scan does
not shift every later one; a scan that starts more than one tick late is an overrun, and the
missed ticks are skipped (counted), as a PLC's cyclic task would. PLC time (what the timers
read) is the wall-clock time since start, like OpenPLC's __CURRENT_TIME.

No exception ends the loop silently: anything raised by a plant, an I/O layer (the PSM
connection) or the runtime puts the PLC in FAULT (outputs safe, `plc.fault` says what), is
reported once through `on_error`, and ends the loop; the status line and the Modbus face
(which answers exception 04 while the PLC is not in RUN) show it. A dead scan never hides
behind a face that still says RUN.
"""
from __future__ import annotations

import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Optional

from plclab.errors import PlcLabError
from plclab.runtime.plantio import PlantBinding
from plclab.runtime.plc import PLC


@dataclass
class RealTimeStats:
    ticks: int = 0
    overruns: int = 0
    skipped_ticks: int = 0
    max_lateness_s: float = 0.0
    lateness: list[float] = field(default_factory=list)   # per-scan start lateness (bounded)

    def jitter_s(self) -> tuple[float, float]:
        """(p50, p99) of the scan start lateness, seconds."""
        if not self.lateness:
            return 0.0, 0.0
        xs = sorted(self.lateness)
        return xs[len(xs) // 2], xs[min(len(xs) - 1, int(len(xs) * 0.99))]


class RealTimeRunner:
    """Runs a PLC (and plants) on the wall clock in a background thread."""

    MAX_SAMPLES = 100_000

    def __init__(self, plc: PLC, plants: Iterable[Any] = (), on_scan: Optional[Callable[[PLC], None]] = None,
                 clock: Callable[[], float] = time.monotonic, sleep: Callable[[float], None] = time.sleep):
        self.plc = plc
        self.plants = [PlantBinding(p, plc.image) for p in plants]
        self.on_scan = on_scan
        self.before_scan: Optional[Callable[[PLC], None]] = None
        self.on_error: Optional[Callable[[str], None]] = None
        self.error: Optional[str] = None        # why the loop stopped by itself, if it did
        self.stats = RealTimeStats()
        self.scanned_ns: Optional[int] = None   # PLC time of the last scan whose outputs are in the image
        self.first_scan = threading.Event()     # set once a scan has run (or the loop has ended)
        self._clock, self._sleep = clock, sleep
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None

    def start(self) -> None:
        self._claim_the_interpreter()
        self._thread = threading.Thread(target=self._loop, name="plc-scan", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
        self._release_the_interpreter()
        self.plc.stop()

    def _claim_the_interpreter(self) -> None:
        """The scan first: Python hands its interpreter lock to a waiting thread only every
        switch interval (5 ms by default), and a scan waits for it each time it wakes, takes
        the image lock or returns from I/O. With a Modbus face busy answering (another thread
        that always wants the lock), a 10 ms task then lost whole ticks. A switch interval of
        1/40 of the tick (0.25 ms for 10 ms) bounds each wait far below the period; restored
        by stop()."""
        self._old_switch = sys.getswitchinterval()
        wanted = max(self.plc.tick_ns / 1e9 / 40, 0.0001)
        if wanted < self._old_switch:
            sys.setswitchinterval(wanted)

    def _release_the_interpreter(self) -> None:
        old = getattr(self, "_old_switch", None)
        if old is not None:
            sys.setswitchinterval(old)
            self._old_switch = None

    def run_for(self, seconds: float) -> None:
        """Run in the calling thread for `seconds` of wall time (tests, benchmarks)."""
        self._claim_the_interpreter()
        try:
            self._loop(until=self._clock() + seconds)
        finally:
            self._release_the_interpreter()

    def _loop(self, until: Optional[float] = None) -> None:
        try:
            self._scan_loop(until)
        except Exception as exc:   # noqa: BLE001 - whatever it is, the PLC must show it
            self._fail(exc)
        finally:
            self.first_scan.set()  # nobody waits for a scan that will never come

    def _fail(self, exc: Exception) -> None:
        """The loop cannot go on: FAULT (outputs safe), reported once, then the loop ends."""
        if isinstance(exc, (OSError, PlcLabError)):
            kind, note = "io", ""
        else:
            kind, note = "internal", " (a plclab bug: please report it)"
        text = str(exc) if isinstance(exc, PlcLabError) else f"{type(exc).__name__}: {exc}"
        self.error = f"the scan loop stopped: {text}{note}"
        try:
            self.plc.enter_fault(kind, self.error)
        except Exception:          # noqa: BLE001 - the report below must still go out
            pass
        if self.on_error is not None:
            self.on_error(str(self.plc.fault) if self.plc.fault is not None else self.error)

    def _scan_loop(self, until: Optional[float]) -> None:
        plc = self.plc
        tick_s = plc.tick_ns / 1e9
        start = self._clock()
        k = 0
        last_scan_ns = 0
        stats = self.stats
        while not self._stop.is_set():
            deadline = start + k * tick_s
            now = self._clock()
            if until is not None and deadline > until:
                break
            if now < deadline:
                self._sleep(deadline - now)
                now = self._clock()
            late = now - deadline
            if late > tick_s:
                missed = int(late // tick_s)
                stats.overruns += 1
                stats.skipped_ticks += missed
                k += missed
            stats.max_lateness_s = max(stats.max_lateness_s, late)
            if len(stats.lateness) < self.MAX_SAMPLES:
                stats.lateness.append(late)
            now_ns = int((now - start) * 1e9)
            for plant in self.plants:
                plant.step((now_ns - last_scan_ns) / 1e9)
            last_scan_ns = now_ns
            plc.now_ns = now_ns
            plc.ticks = k
            if self.before_scan is not None:
                self.before_scan(plc)
            plc.scan()
            self.scanned_ns = now_ns
            if self.on_scan is not None:
                self.on_scan(plc)
            stats.ticks += 1
            k += 1
            if not self.first_scan.is_set():
                self.first_scan.set()
