"""`plclab serve` never runs a dead scan behind a live face (issue 15): a retain save that
fails is reported once while the PLC scans on (or, if configured, is a FAULT), any exception
of the real-time loop is a FAULT, and the status line and the Modbus face (exception 04) show it."""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import pytest

from plclab import config
from plclab.cli import main
from plclab.modbus.rawclient import RawModbusClient, RawModbusError
from plclab.frontend import check_sources
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.runtime.realtime import RealTimeRunner
from plclab.serve import ServeOptions, Service

TIMEOUT = 10.0
PROGRAM = """
PROGRAM main
VAR n AT %QW0 : INT; lamp AT %QX0.0 : BOOL; END_VAR
VAR RETAIN runs : DINT; END_VAR
n := n + 1; runs := runs + 1; lamp := TRUE;
END_PROGRAM
CONFIGURATION Config0 RESOURCE Res0 ON PLC
TASK t (INTERVAL := T#10ms, PRIORITY := 0);
PROGRAM inst WITH t : main;
END_RESOURCE END_CONFIGURATION
"""


def service(tmp_path: Path, stand_text: str, plant=None) -> tuple[Service, list[str]]:
    conf = tmp_path / "openplc.conf"
    conf.write_text(f"[modbus]\nport = 5020\n[mp9c]\nretain_period_ms = 10\n{stand_text}")
    cfg = config.load(conf)
    modbus = dataclasses.replace(cfg.modbus, port=0)
    reports: list[str] = []
    svc = Service(ServeOptions([("prog.st", PROGRAM)], cfg.stand("mp9c"), modbus, plant), report=reports.append)
    return svc, reports


def wait_for(predicate, what: str) -> None:
    deadline = time.monotonic() + TIMEOUT
    while not predicate():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.01)


@pytest.fixture
def blocked(tmp_path: Path) -> str:
    (tmp_path / "state").write_text("a file where a directory should be")
    return "state/retain.json"


def test_a_failing_retain_save_is_reported_once_and_the_plc_keeps_scanning(tmp_path, blocked):
    svc, reports = service(tmp_path, f"retain_file = {blocked}\n")
    svc.start()
    try:
        wait_for(lambda: svc.plc.retain_store.failed_saves >= 3, "three failed saves")
        ticks = svc.runner.stats.ticks
        wait_for(lambda: svc.runner.stats.ticks > ticks + 5, "more scans")
        assert svc.plc.state == "RUN" and "RUN" in svc.status() and "RETAIN NOT SAVED" in svc.status()
        assert [r for r in reports if "retain" in r] == reports and len(reports) == 1
        with RawModbusClient("127.0.0.1", svc.server.port, timeout=TIMEOUT) as c:
            first = c.read_holding_registers(0, 1)[0]
            wait_for(lambda: c.read_holding_registers(0, 1)[0] != first, "a live value over Modbus")
    finally:
        svc.stop()


def test_a_failing_retain_save_configured_as_fault_is_visible_on_the_face(tmp_path, blocked):
    svc, reports = service(tmp_path, f"retain_file = {blocked}\nretain_save_error = fault\n")
    svc.start()
    try:
        wait_for(lambda: svc.plc.state == "FAULT", "the FAULT")
        assert "FAULT" in svc.status() and "cannot save the retained variables" in svc.status()
        with RawModbusClient("127.0.0.1", svc.server.port, timeout=TIMEOUT) as c:
            with pytest.raises(RawModbusError) as e:
                c.read_holding_registers(0, 1)
            assert e.value.code == 4
    finally:
        svc.stop()


def test_an_exception_in_the_real_time_loop_is_a_visible_fault(tmp_path):
    svc, reports = service(tmp_path, f"retain_file = {tmp_path / 'r.json'}\n")
    calls = []

    def io_layer(plc) -> None:                         # the PSM link, say, dropping on its third use
        calls.append(1)
        if len(calls) == 3:
            raise ConnectionResetError(104, "Connection reset by peer")
    svc.runner.before_scan = io_layer
    svc.start()
    try:
        wait_for(lambda: svc.plc.state == "FAULT", "the FAULT")
        svc.runner._thread.join(TIMEOUT)
        assert not svc.runner._thread.is_alive()               # the loop ended, said so
        assert len(reports) == 1 and "PLC FAULT (io)" in reports[0]
        assert "scan loop stopped: ConnectionResetError" in reports[0]
        assert "FAULT" in svc.status()
        assert svc.plc.image.areas["QX"][0] == 0               # outputs safe
        with RawModbusClient("127.0.0.1", svc.server.port, timeout=TIMEOUT) as c:
            with pytest.raises(RawModbusError) as e:
                c.read_coils(0, 1)
            assert e.value.code == 4
    finally:
        svc.stop()


class ExplodingPlant:
    """A plant model with a bug: its third step raises."""

    outputs = ("%QX0.0",)

    def __init__(self):
        self.steps = 0

    def step(self, outputs: dict, dt: float) -> dict:
        self.steps += 1
        if self.steps == 3:
            raise KeyError("valve")
        return {}


def test_a_bug_in_the_loop_is_a_fault_that_asks_to_be_reported():
    plc = PLC(compile_unit(check_sources([("prog.st", PROGRAM)])))
    clock = iter(i * 0.01 for i in range(10_000))
    runner = RealTimeRunner(plc, [ExplodingPlant()], clock=lambda: next(clock), sleep=lambda s: None)
    reports: list[str] = []
    runner.on_error = reports.append
    runner.run_for(1.0)
    assert plc.state == "FAULT" and plc.fault.kind == "internal"
    assert len(reports) == 1 and "KeyError: 'valve'" in reports[0] and "please report it" in reports[0]
    assert runner.stats.ticks == 2                             # it stopped at the third step


@pytest.mark.parametrize("where, expected", [
    ("dir", "is a directory"),
    ("state/retain.json", "is a file, not a directory"),
])
def test_a_retain_file_that_can_never_be_written_is_refused_up_front(tmp_path, capsys, blocked, where, expected):
    (tmp_path / "dir").mkdir()
    conf = tmp_path / "openplc.conf"
    conf.write_text(f"[mp9c]\nretain_file = {where}\n")
    st = tmp_path / "prog.st"
    st.write_text(PROGRAM)
    assert main(["serve", "mp9c", "--config", str(conf), "--program", str(st), "--port", "0",
                 "--duration", "0"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "openplc.conf: [mp9c] retain_file:" in err[0] and expected in err[0]
    assert (tmp_path / "dir").is_dir() and (tmp_path / "state").is_file()
