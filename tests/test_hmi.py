"""The thermo stand's reference HMI (`plclab hmi thermo`): a Modbus TCP client doing the
textbook's SCADA tasks (show %MW3; show and set the heater power %MW2) against the Twido
register contract, explaining every refusal. The stand here is a Twido map on a process
image served on loopback; `test_scada.py` plays the same tasks against `plclab serve`."""
from __future__ import annotations

import re
import subprocess
import sys
import threading
import time

import pytest

from plclab.hmi import ThermoHmi, run_hmi
from plclab.modbus.maps import TwidoMap
from plclab.stands import twido_profile
from plclab.modbus.server import ModbusTcpServer
from plclab.runtime.image import ProcessImage

THERMO = twido_profile("thermo")

PLCLAB = [sys.executable, "-m", "plclab.cli"]
MANUAL, AUTO1 = 0, 1


def stand_image(mode: int = MANUAL) -> ProcessImage:
    image = ProcessImage()
    image.areas["MW"][0:7] = [mode, 0, 0, 41, 37, 0, 50]
    return image


@pytest.fixture
def image():
    return stand_image()


@pytest.fixture
def port(image):
    with ModbusTcpServer(TwidoMap(image, THERMO), "127.0.0.1", 0) as server:
        yield server.port


def mw(image: ProcessImage, n: int) -> int:
    """%MWn as a client reads it (a write waits in the queue for the PLC's next scan)."""
    return image.snapshot("MW", n, 1)[0]


def hmi_once(port: int, *sets: str) -> tuple[int, list[str]]:
    lines: list[str] = []
    rc = run_hmi("127.0.0.1", port, once=True, sets=sets, out=lines.append)
    return rc, lines


def test_points_sit_at_register_minus_start_address():
    hmi = ThermoHmi(channel=None, start=0)      # type: ignore[arg-type]
    assert hmi.points["temperature"].offset == 3 and hmi.points["heater"].offset == 2
    assert hmi.length == 7
    assert ThermoHmi(channel=None, start=1).points["heater"].offset == 1   # type: ignore[arg-type]


def test_task1_shows_the_heat_sink_temperature(port):
    rc, lines = hmi_once(port)
    assert rc == 0
    assert lines[-1] == "mode=manual fan=0 heater=0 temperature=41 C fan_speed=37/s setpoint=50 C"


def test_task2_sets_the_heater_power(port, image):
    rc, lines = hmi_once(port, "heater=1500")
    assert rc == 0 and "%MW2 (heater) := 1500" in lines
    assert mw(image, 2) == 1500
    assert "heater=1500" in lines[-1]


def test_mode_by_name_then_heater_in_one_go(image):
    image.areas["MW"][0] = AUTO1
    with ModbusTcpServer(TwidoMap(image, THERMO), "127.0.0.1", 0) as server:
        rc, lines = hmi_once(server.port, "mode=manual", "heater=2000")
    assert rc == 0 and (mw(image, 0), mw(image, 2)) == (MANUAL, 2000)


@pytest.mark.parametrize("sets, reason", [
    (("heater=2500",), "valid values are 0..2000"),
    (("setpoint=80",), "valid values are 25..70"),
    (("temperature=30",), "the register is read only"),
    (("mode=3",), "valid values are 0, 1, 2"),
])
def test_a_refused_write_shows_the_exception_and_the_rule(port, image, sets, reason):
    rc, lines = hmi_once(port, *sets)
    refusal = next(line for line in lines if line.startswith("!"))
    assert "exception 03 (illegal data value)" in refusal and refusal.endswith(reason)
    assert rc == 1
    assert [mw(image, n) for n in range(7)] == [MANUAL, 0, 0, 41, 37, 0, 50]     # nothing changed


def test_heater_in_automatic_mode_is_monitoring_only():
    image = stand_image(AUTO1)
    with ModbusTcpServer(TwidoMap(image, THERMO), "127.0.0.1", 0) as server:
        rc, lines = hmi_once(server.port, "heater=100")
    assert rc == 1 and lines[1].endswith("writable only while %MW0 = 0 (manual mode)")
    assert mw(image, 2) == 0


def test_unknown_points_and_values_are_one_line_each(port):
    rc, lines = hmi_once(port, "pressure=3", "heater=lots")
    assert rc == 1
    assert lines[1] == "! unknown point 'pressure'; one of mode, fan, heater, temperature, fan_speed, reserved, setpoint or %MWn"
    assert lines[2] == "! 'lots' is not a whole number"


def test_interactive_commands_and_a_status_line_on_every_change(port, image):
    lines: list[str] = []
    script = iter(["help", "heater 700", "show", "%MW6 45", "quit", "heater 9"])   # nothing after quit
    rc = run_hmi("127.0.0.1", port, period=0.05, commands=script, out=lines.append)
    text = "\n".join(lines)
    assert rc == 0
    assert "commands (one per line)" in text
    statuses = [line for line in lines if line.startswith("t=")]
    assert "heater=0 " in statuses[0] and "heater=700 " in statuses[1]
    assert statuses[-1].endswith("setpoint=45 C")
    assert re.search(r"%MW2\s+heater\s+700\s+heater control", text)
    assert (mw(image, 2), mw(image, 6)) == (700, 45)


def test_lost_communication_is_said_once_and_restored(image):
    server = ModbusTcpServer(TwidoMap(image, THERMO), "127.0.0.1", 0).start()
    port = server.port
    lines: list[str] = []

    def wait_for(fragment: str, timeout: float = 10.0) -> None:
        deadline = time.monotonic() + timeout
        while not any(fragment in line for line in lines):
            assert time.monotonic() < deadline, f"no line with {fragment!r} in {lines}"
            time.sleep(0.02)

    def operator():
        nonlocal server
        wait_for("t=")
        server.stop()
        wait_for("retrying")
        time.sleep(0.3)                       # several periods without the stand
        server = ModbusTcpServer(TwidoMap(image, THERMO), "127.0.0.1", port).start()
        wait_for("communication restored")
        yield "heater 321"
        yield "quit"

    done: list[int] = []
    t = threading.Thread(target=lambda: done.append(run_hmi("127.0.0.1", port, period=0.05,
                                                                commands=operator(), out=lines.append)))
    t.start()
    t.join(30)
    server.stop()
    assert done == [0], lines
    assert sum("retrying" in line for line in lines) == 1
    assert "%MW2 (heater) := 321" in lines


def test_command_line_once_with_a_refusal(port):
    proc = subprocess.run(PLCLAB + ["hmi", "thermo", f"127.0.0.1:{port}", "--once", "--set", "heater=2500"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1
    assert "exception 03" in proc.stdout and "temperature=41 C" in proc.stdout
    assert proc.stderr == ""


def test_command_line_without_a_stand_is_one_line():
    with ModbusTcpServer(TwidoMap(ProcessImage(), THERMO), "127.0.0.1", 0) as server:
        port = server.port
    proc = subprocess.run(PLCLAB + ["hmi", "thermo", f"127.0.0.1:{port}", "--once"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1
    assert proc.stderr.strip() == f"plclab: error: cannot reach the stand at 127.0.0.1:{port} " \
                                  f"(is `plclab serve thermo` running?)"
    bad = subprocess.run(PLCLAB + ["hmi", "thermo", "localhost:http"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "expected HOST:PORT" in bad.stderr
    busy = subprocess.run(PLCLAB + ["hmi", "thermo", "--period", "0"], capture_output=True, text=True, timeout=60)
    assert busy.returncode == 1 and busy.stderr.count("\n") == 1 and "--period 0 s" in busy.stderr


def test_serve_with_the_hmi_in_its_terminal(tmp_path):
    """`plclab serve thermo --hmi`: the stand and its HMI in one terminal; the operator's
    commands reach the running program, and `quit` stops the service cleanly."""
    conf = tmp_path / "openplc.conf"
    conf.write_text(f"[thermo]\nretain_file = {tmp_path / 'thermo.retain'}\n")
    proc = subprocess.Popen(PLCLAB + ["serve", "thermo", "--config", str(conf), "--port", "0", "--hmi",
                                      "--console", "127.0.0.1:0"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=tmp_path)
    try:
        assert "modbus on 127.0.0.1:" in proc.stdout.readline()
        assert proc.stdout.readline().startswith("thermo HMI: Modbus TCP 127.0.0.1:")
        assert "mode=manual" in proc.stdout.readline()
        proc.stdin.write("mode auto1\n")
        proc.stdin.flush()
        deadline = time.monotonic() + 20
        seen = []
        heater = 0
        while time.monotonic() < deadline and heater == 0:
            line = proc.stdout.readline()       # automatic-1 at 40 C from 22 C: the PI starts heating,
            seen.append(line)                   # and %MW2 reports the command it outputs
            m = re.search(r"mode=auto-1 .*heater=(\d+)", line)
            heater = int(m.group(1)) if m else 0
        assert heater > 0, seen
        out, err = proc.communicate("quit\n", timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert "stopped:" in out and err == ""


def test_serve_hmi_is_refused_for_a_stand_without_one():
    proc = subprocess.run(PLCLAB + ["serve", "mp9c", "--port", "0", "--hmi"], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 1 and proc.stdout == ""
    assert proc.stderr.strip().splitlines() == [
        "plclab: error: mp9c has no HMI here (the reference HMI needs the Twido map of the thermo stand "
        "and its Modbus face)"]
