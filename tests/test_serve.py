"""`plclab serve` as a user runs it: a real process, a real Modbus client, SIGTERM to stop."""
from __future__ import annotations

import re
import signal
import subprocess
import sys
import time
from pathlib import Path

from plclab.modbus.rawclient import RawModbusClient

PLCLAB = [sys.executable, "-m", "plclab.cli"]

PROGRAM = """
PROGRAM main
VAR x AT %IX0.0 : BOOL; q AT %QX0.0 : BOOL; n AT %QW0 : INT; setpoint AT %MW0 : INT; echo AT %QW1 : INT; END_VAR
VAR RETAIN runs : INT; END_VAR
n := n + 1;
echo := setpoint * 2;
IF n = 1 THEN runs := runs + 1; END_IF;
q := runs > 1;
END_PROGRAM
CONFIGURATION Config0 RESOURCE Res0 ON PLC
TASK t (INTERVAL := T#10ms, PRIORITY := 0);
PROGRAM inst WITH t : main;
END_RESOURCE END_CONFIGURATION
"""


def start(tmp_path: Path) -> tuple[subprocess.Popen, int]:
    conf = tmp_path / "openplc.conf"
    conf.write_text(f"[mp9c]\nretain_file = {tmp_path / 'retain.json'}\nio = inprocess\n")
    prog = tmp_path / "prog.st"
    prog.write_text(PROGRAM)
    proc = subprocess.Popen(PLCLAB + ["serve", "mp9c", "--program", str(prog), "--config", str(conf),
                                      "--port", "0", "--console", "127.0.0.1:0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=tmp_path)
    line = proc.stdout.readline()
    m = re.search(r"modbus on 127\.0\.0\.1:(\d+)", line)
    assert m, f"no listening line: {line!r} {proc.stderr.read() if proc.poll() is not None else ''}"
    return proc, int(m.group(1))


def wait_for(condition, timeout: float = 20.0, period: float = 0.02):
    """Poll `condition` until it is true or `timeout` seconds have passed; its last value. A
    slow machine gets the time it needs, a server that does not do it still fails."""
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value or time.monotonic() >= deadline:
            return value
        time.sleep(period)


def stop(proc: subprocess.Popen) -> tuple[int, str]:
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=10)
    return proc.returncode, out


def test_serve_scans_in_real_time_answers_modbus_and_stops_cleanly_on_sigterm(tmp_path):
    proc, port = start(tmp_path)
    try:
        with RawModbusClient("127.0.0.1", port) as c:
            first = c.read_holding_registers(0, 1)[0]
            # the scan runs while clients read: the scan counter n (%QW0) moves on
            assert wait_for(lambda: c.read_holding_registers(0, 1)[0] > first)
            c.write_register(1024, 21)                  # %MW0 (OpenPLC map: holding 1024 = %MW0)
            assert wait_for(lambda: c.read_holding_registers(1, 1)[0] == 42)   # the program saw the write
    finally:
        rc, out = stop(proc)
    assert rc == 0
    assert "stopped:" in out and "overruns=" in out


def test_retained_variable_is_flushed_on_sigterm_and_restored(tmp_path):
    proc, port = start(tmp_path)
    with RawModbusClient("127.0.0.1", port) as c:
        assert wait_for(lambda: c.read_holding_registers(0, 1)[0] > 0)    # it has scanned
    stop(proc)
    assert (tmp_path / "retain.json").exists()
    proc, port = start(tmp_path)
    try:
        with RawModbusClient("127.0.0.1", port) as c:
            assert wait_for(lambda: c.read_coils(0, 1)[0] == 1)   # runs = 2: the first run was retained
    finally:
        stop(proc)


def test_serve_errors_are_one_line(tmp_path):
    conf = tmp_path / "bad.conf"
    conf.write_text("[mp9c]\nvariant = task4\n")
    r = subprocess.run(PLCLAB + ["serve", "mp9c", "--config", str(conf)], capture_output=True, text=True,
                       timeout=30)
    assert r.returncode == 1
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "[mp9c]" in lines[0] and "variant" in lines[0] and "task4" in lines[0]
