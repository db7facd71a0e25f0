"""One plant shared by the PLC link and the console face: stepped in lockstep, never fatal.

Why a host around the plant model:
- Lockstep. Inside OpenPLC the plant runs behind the PSM link; OpenPLC's PSM client polls it
  once per scan (inputs read, program, outputs written). `exchange()` is called at each poll
  and steps the plant once with the outputs of the last scan, over the real time elapsed
  since the previous poll, so a sensor the PLC selects in one scan is read in the next one
  whatever the scan time (TUR-10's sensor bus depends on it).
- Two threads reach the plant: the PLC link steps it, the console face sets its switches and
  reads its lamps and readouts. One lock keeps each of these whole.
- A plant that raises must not take the PLC down (OpenPLC dies of SIGPIPE if its PSM server
  goes away). The first exception freezes the plant: the PLC keeps getting the last inputs,
  the console face shows the plant fault lamp, and the error is reported once.

Standard library only (it runs inside OpenPLC's Python too).
"""
from __future__ import annotations

import sys
import threading
import time
import traceback as _traceback
from typing import Any, Callable

MAX_STEP_S = 0.5      # a PLC that stalled longer is not made up for in one plant step


def _to_stderr(text: str) -> None:
    sys.stderr.write(text + "\n")
    sys.stderr.flush()


class PlantHost:
    """A plant model (plclab.plants.base contract) with a lock, a clock and fault containment.

    It is itself a plant (outputs, period, step), so the in-process runtime steps it like the
    model; the PSM server calls `exchange()` instead, which takes dt from `clock`.
    `report` gets the one report of a plant fault: its traceback when `traceback` is set (the
    OpenPLC log is the only place to see it), else one line.
    """

    def __init__(self, plant: Any, *, clock: Callable[[], float] = time.monotonic,
                 report: Callable[[str], None] = _to_stderr, traceback: bool = False):
        self.plant = plant
        self.face = plant.FACE
        # push buttons whose contact opens when pressed (an emergency stop): the console face
        # shows what the operator did (1 = pressed), the plant gives the PLC the contact's level
        self.normally_closed = frozenset(getattr(plant, "NORMALLY_CLOSED", ()))
        self.outputs = list(plant.outputs)
        self.period = plant.period
        self.clock = clock
        self.report = report
        self.traceback = traceback
        self.fault: str | None = None         # what the plant raised, once it has
        self.steps = 0
        self._lock = threading.Lock()
        self._last_poll: float | None = None
        self._outputs: dict[str, int] = {}
        self._inputs: dict[str, int] = {}
        self._readouts: list[int] = [0] * len(self.face.readouts)
        try:                                  # a face may be read before the PLC connects
            self._readouts = list(plant.readouts())
        except Exception as exc:  # noqa: BLE001
            self._freeze(exc)

    # -- the PLC side ---------------------------------------------------------------------
    def exchange(self, outputs: dict[str, int]) -> dict[str, int]:
        """One PLC scan's I/O exchange: step over the time since the last one (0 the first
        time, at most MAX_STEP_S) with these outputs; the inputs for the next scan."""
        with self._lock:
            now = self.clock()
            dt = 0.0 if self._last_poll is None else min(max(now - self._last_poll, 0.0), MAX_STEP_S)
            self._last_poll = now
            return self._step(outputs, dt)

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, int]:
        """The plant contract, for a caller that keeps time itself (the in-process runtime)."""
        with self._lock:
            return self._step(outputs, dt)

    def _step(self, outputs: dict[str, int], dt: float) -> dict[str, int]:
        self._outputs = dict(outputs)
        if self.fault is None:
            try:
                self._inputs = dict(self.plant.step(outputs, dt))
                self._readouts = list(self.plant.readouts())
                self.steps += 1
            except Exception as exc:  # noqa: BLE001 - any plant bug: freeze, report, go on
                self._freeze(exc)
        return dict(self._inputs)

    def _freeze(self, exc: BaseException) -> None:
        self.fault = f"{type(exc).__name__}: {exc}"
        head = f"plant: the {type(self.plant).__name__} model raised {self.fault}; its inputs are frozen"
        if self.traceback:
            self.report(head + "\n" + "".join(_traceback.format_exception(type(exc), exc, exc.__traceback__)).rstrip())
        else:
            self.report(head + " (PLCLAB_DEBUG=1 shows the traceback)")

    # -- the console side -----------------------------------------------------------------
    def set_switch(self, name: str, value: int) -> None:
        """Set a console switch; seen by the PLC from the next exchange."""
        with self._lock:
            if self.fault is None:
                try:
                    self.plant.set_switch(name, 1 if value else 0)
                except Exception as exc:  # noqa: BLE001 - the face only sends FACE names
                    self._freeze(exc)

    def load_tape(self, method: int, frames: list[tuple[int, ...]]) -> None:
        """Put a part program on the plant's tape reader (FACE.tape); a bad tape raises the
        plant's PlantError (a ValueError), a failed plant a ValueError too: nothing is loaded.
        The readouts are taken afresh: from the moment it is loaded, the `tape` readout counts
        this tape's stored frames (0), never the last tape's until the PLC's next exchange, so
        a reader of the face cannot take the last tape's count for this one's."""
        with self._lock:
            if self.fault is not None:
                raise ValueError(f"the plant has failed ({self.fault})")
            self.plant.load_tape(method, frames)
            try:
                self._readouts = list(self.plant.readouts())
            except Exception as exc:  # noqa: BLE001 - as in a step: freeze, report, go on
                self._freeze(exc)

    def lamps(self) -> list[int]:
        """The FACE lamps (PLC outputs of the last exchange), then the plant fault lamp."""
        with self._lock:
            lamps = [1 if self._outputs.get(loc, 0) else 0 for _label, loc in self.face.lamps]
            return lamps + [0 if self.fault is None else 1]

    def readouts(self) -> list[int]:
        """The FACE readouts as of the last step (frozen with the plant)."""
        with self._lock:
            return list(self._readouts)
