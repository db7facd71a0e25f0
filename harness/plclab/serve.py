"""`plclab serve`: the soft PLC in real time with its plant and Modbus face, until stopped.

The pieces are the library's own: a PLC (runtime.plc) scanned on the wall clock
(runtime.realtime), the plant model stepped in-process before each scan or reached over
OpenPLC's PSM protocol, a Modbus TCP server face on the process image and, with an
in-process plant, the stand's console face (plclab.modbus.console; with io = psm the plant
process serves it). Stopping (Ctrl-C, SIGTERM) ends the scan loop, closes the servers and
flushes retained variables.
"""
from __future__ import annotations

import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable, Optional, Sequence, TextIO

from plclab.config import ModbusConfig, StandConfig
from plclab.errors import PlcLabError
from plclab.frontend import check_sources
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.runtime.realtime import RealTimeRunner
from plclab.runtime.retain import RetainStore


FIRST_SCAN_WAIT_S = 5.0
"""How long start() waits for the first scan before opening the faces anyway (a first scan
that has not come by then is a fault the faces report)."""

FACE_MAX_REQUESTS_PER_S = 5000
"""Admission control of the Modbus face: the scan first. Python runs one thread at a time, and
a face answering 35,000 requests/s took the interpreter (and a core) from the 10 ms scan, which
lost ticks; capped, the face's share stays small and a flood of requests waits (clients see
latency, the scan keeps its period). 5000/s is far beyond a SCADA client's polling (OpenPLC on
a Raspberry Pi answers a few thousand)."""


@dataclass
class ServeOptions:
    sources: Sequence[tuple[str, str]]   # (file name, ST text) of the program: one compilation unit
    stand: StandConfig
    modbus: ModbusConfig
    plant: Any = None                # in-process plant model, or None (io = psm or no plant)
    register_map: str = "openplc"    # "openplc" | "twido"
    twido_profile: Any = None
    console: Optional[tuple[str, int]] = None   # the console face's address (in-process plant)


class Service:
    """A running soft PLC: start(), then stop() from any thread (or a signal)."""

    def __init__(self, opts: ServeOptions, report: Callable[[str], None] = print):
        self.opts = opts
        self.report = report
        st = opts.stand
        checked = check_sources(opts.sources)
        store = RetainStore(st.retain_file, report=report)
        self.plc = PLC(compile_unit(checked), tick_ns=st.tick_ms * 1_000_000 if st.tick_ms else None,
                       watchdog_s=st.watchdog_ms / 1000 if st.watchdog_ms else 1e9, retain=store,
                       retain_period_ns=st.retain_period_ms * 1_000_000,
                       retain_fault=st.retain_save_error == "fault")
        self.psm = None
        self.plant_host = None
        plants = []
        if st.io == "psm":
            from plclab.modbus.psm import PsmClient
            self.psm = PsmClient(st.psm.host, st.psm.port).connect()
        elif opts.plant is not None:
            from plclab.plants.host import PlantHost

            self.plant_host = PlantHost(opts.plant, report=lambda line: print(line, file=sys.stderr, flush=True),
                                        traceback=bool(os.environ.get("PLCLAB_DEBUG")))
            plants.append(self.plant_host)
        self.runner = RealTimeRunner(self.plc, plants, on_scan=self._after_scan if self.psm else None)
        self.runner.on_error = report     # a stopped scan loop is a FAULT, said once
        if self.psm is not None:
            self.runner.before_scan = self._before_scan   # type: ignore[attr-defined]
        self.server = None
        if opts.modbus.enabled:
            self.server = self._make_server()
        self.console = None
        self._stopped = threading.Event()

    def _make_server(self):
        from plclab.modbus.maps import OpenPlcMap, TwidoMap
        from plclab.modbus.server import ModbusTcpServer

        m = self.opts.modbus
        if self.opts.register_map == "twido":
            rmap = TwidoMap(self.plc.image, self.opts.twido_profile)
        else:
            rmap = OpenPlcMap(self.plc.image)
        return ModbusTcpServer(rmap, m.bind, m.port, unit_ids=m.unit_ids, idle_timeout=m.idle_timeout_s,
                               max_clients=m.max_clients, first_request_timeout=m.first_request_timeout_s,
                               health=self.problem, max_requests_per_s=FACE_MAX_REQUESTS_PER_S)

    def problem(self) -> Optional[str]:
        """Why the PLC is not scanning (its fault), or None while it runs: the Modbus face
        answers exception 04 while there is one, so no client reads stale values."""
        if self.plc.state == "RUN":
            return None
        return str(self.plc.fault) if self.plc.fault is not None else f"PLC {self.plc.state}"

    def _before_scan(self, plc: PLC) -> None:
        self.psm.read_inputs(plc.image)

    def _after_scan(self, plc: PLC) -> None:
        self.psm.write_outputs(plc.image)

    def start(self) -> None:
        """The scan first, then the faces: a client's first request is answered from the
        outputs of a scan, never from the power-up zeros of an image no scan has written (a
        recorded session replays as it was answered)."""
        self.runner.start()
        self.runner.first_scan.wait(FIRST_SCAN_WAIT_S)
        if self.server is not None:
            self.server.start()
        if self.plant_host is not None and self.opts.console is not None:
            from plclab.modbus.console import start_console_face
            self.console = start_console_face(self.plant_host, self.opts.console,
                                              lambda line: print(line, file=sys.stderr, flush=True))

    def status(self) -> str:
        s = self.runner.stats
        clients = self.server.active_clients if self.server is not None else 0
        state = self.plc.state if self.plc.fault is None else f"FAULT: {self.plc.fault}"
        store = self.plc.retain_store
        if store is not None and store.save_error is not None:
            state += "  RETAIN NOT SAVED"
        missed = f" ({s.skipped_ticks} ticks missed, {s.max_lateness_s * 1000:.1f} ms latest)" if s.overruns else ""
        return (f"t={self.plc.now_ns / 1e9:9.2f} s  scans={s.ticks}  overruns={s.overruns}{missed}  "
                f"clients={clients}  {state}")

    def stop(self) -> None:
        if self._stopped.is_set():
            return
        self._stopped.set()
        self.runner.stop()            # also stops the PLC, which flushes retain
        if self.server is not None:
            self.server.stop()
        if self.console is not None:
            self.console.stop()
        if self.psm is not None:
            self.psm.close()

    def wait(self, duration: Optional[float] = None, status: Optional[TextIO] = None) -> None:
        """Block until stop() (or `duration` seconds), refreshing a status line on a terminal."""
        end = None if duration is None else time.monotonic() + duration
        tty = status is not None and status.isatty()
        while not self._stopped.is_set():
            if end is not None and time.monotonic() >= end:
                break
            self._stopped.wait(0.5)
            if tty:
                status.write("\r" + self.status() + "   ")
                status.flush()
        if tty:
            status.write("\n")


def serve_forever(opts: ServeOptions, duration: Optional[float] = None, hmi: bool = False) -> int:
    """The CLI's `serve`: start, print where it listens, run until Ctrl-C / SIGTERM. With
    `hmi`, the stand's reference HMI (plclab.hmi) runs in this terminal on the Modbus face,
    and quitting it stops the service."""
    if hmi and (not opts.modbus.enabled or opts.register_map != "twido"):
        raise PlcLabError(f"{opts.stand.name} has no HMI here (the reference HMI needs the Twido map of the "
                          f"thermo stand and its Modbus face)")
    service = Service(opts)

    def on_signal(signum, frame):   # noqa: ARG001 - signal handler signature
        service._stopped.set()
    # handlers first: a stop asked for as soon as the listening line is out is a clean stop
    old = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        service.start()
    except BaseException:           # nothing to stop: the start's own error, handlers as they were
        _restore(old)
        raise
    try:
        where = f"modbus on {opts.modbus.bind}:{service.server.port}" if service.server else "modbus disabled"
        if service.console is not None:
            where += f", console face on {service.console.host}:{service.console.port}"
        print(f"serving {opts.stand.name} ({opts.sources[0][0]}{' ...' if len(opts.sources) > 1 else ''}): "
              f"tick {service.plc.tick_ns / 1e6:g} ms, {where}; Ctrl-C stops", flush=True)
        if hmi:
            _start_hmi(service, opts)
        service.wait(duration, None if hmi else sys.stderr)    # the HMI's lines are the status
    finally:
        service._stopped.clear()
        service.stop()
        _restore(old)
    print(f"stopped: {service.status()}", flush=True)
    return 0 if service.plc.fault is None else 1


def _restore(handlers: dict) -> None:
    for sig, handler in handlers.items():
        signal.signal(sig, handler)


def _start_hmi(service: Service, opts: ServeOptions) -> None:
    from plclab.hmi import run_hmi

    def hmi() -> None:
        try:
            run_hmi(opts.modbus.client_host, service.server.port, commands=sys.stdin,
                    out=lambda line: print(line, flush=True))
        except PlcLabError as e:
            print(f"plclab: error: {e}", file=sys.stderr, flush=True)
        service._stopped.set()
    threading.Thread(target=hmi, name="hmi", daemon=True).start()
