"""The textbook's two SCADA exercises (section 5.3.2 and "Study of the methods of creating the
project in the ClearSCADA"), played over Modbus TCP against `plclab serve thermo` as a real
process, the way a SCADA client configured from the textbook would:

- a Modbus channel over TCP/IP to the stand's address and port;
- a scanner polling holding registers from a start address ("Data address") for a number of
  registers ("Data length");
- points at offset = Modbus address of the controller variable - start address (Twido map:
  %MWn is address n): Task 1 reads the heat-sink temperature %MW3, Task 2 displays and
  controls the heater power %MW2 with the control limits 0..2000.

Both of the project's independent client encodings are used: pymodbus's client and
plclab.modbus.rawclient. Real time: the heater at full power warms the radiator by 0.1 C/s,
so %MW3 shows a whole degree more within about 5 s.
"""
from __future__ import annotations

import re
import signal
import subprocess
import sys
import time

import pytest
from pymodbus.client import ModbusTcpClient

from plclab.modbus.rawclient import RawModbusClient, RawModbusError

PLCLAB = [sys.executable, "-m", "plclab.cli"]
TIMEOUT = 10.0                 # s, one Modbus request
RISE_WITHIN = 20.0             # s of wall time for %MW3 to show the heater's effect
ILLEGAL_DATA_VALUE = 3

MODE, FAN, HEATER, TEMPERATURE, SETPOINT = 0, 1, 2, 3, 6      # %MWn = holding register n
MANUAL, AUTO2 = 0, 2


class Refused(Exception):
    def __init__(self, code: int):
        self.code = code
        super().__init__(f"exception {code:02d}")


class PymodbusChannel:
    """A Modbus TCP channel through pymodbus's client."""

    name = "pymodbus"

    def __init__(self, port: int):
        self.client = ModbusTcpClient("127.0.0.1", port=port, timeout=TIMEOUT, retries=0)
        assert self.client.connect(), f"no connection to 127.0.0.1:{port}"

    def _ok(self, result):
        if result.isError():
            raise Refused(result.exception_code)
        return result

    def read_holding(self, start: int, count: int) -> list[int]:
        return list(self._ok(self.client.read_holding_registers(start, count=count, device_id=1)).registers)

    def write_register(self, address: int, value: int) -> None:
        self._ok(self.client.write_register(address, value, device_id=1))

    def close(self) -> None:
        self.client.close()


class RawChannel:
    """A Modbus TCP channel through plclab.modbus.rawclient (raw sockets + struct)."""

    name = "raw"

    def __init__(self, port: int):
        self.client = RawModbusClient("127.0.0.1", port, timeout=TIMEOUT)

    def read_holding(self, start: int, count: int) -> list[int]:
        return self.client.read_holding_registers(start, count)

    def write_register(self, address: int, value: int) -> None:
        try:
            self.client.write_register(address, value)
        except RawModbusError as e:
            raise Refused(e.code) from None

    def close(self) -> None:
        self.client.close()


CHANNELS = {"pymodbus": PymodbusChannel, "raw": RawChannel}


class Scanner:
    """The textbook's Modbus scanner: polls holding registers [start, start + length)."""

    def __init__(self, channel, start: int = 0, length: int = 7):
        self.channel, self.start, self.length = channel, start, length
        self.values: list[int] = []

    def poll(self) -> None:
        self.values = self.channel.read_holding(self.start, self.length)


def scan_applies(scanner: Scanner, register: int, value: int, within: float = 1.0) -> None:
    """Poll until the register shows `value`: a write is applied by the PLC's next scan
    (100 ms), as it would be seen by SCADA's next poll."""
    deadline = time.monotonic() + within
    while True:
        scanner.poll()
        if scanner.values[register - scanner.start] == value or time.monotonic() > deadline:
            break
        time.sleep(0.05)
    assert scanner.values[register - scanner.start] == value, \
        f"%MW{register} = {scanner.values[register - scanner.start]}, expected {value} after {within:g} s"


class AnalogPoint:
    """A ClearSCADA analog point on a scanner: offset = register - start address, no scaling;
    optional control with minimum / maximum (the point's "Control" tab)."""

    def __init__(self, scanner: Scanner, register: int, minimum: int | None = None, maximum: int | None = None):
        self.scanner = scanner
        self.offset = register - scanner.start
        assert 0 <= self.offset < scanner.length, "the point is outside the scanner's data"
        self.minimum, self.maximum = minimum, maximum

    @property
    def value(self) -> int:
        return self.scanner.values[self.offset]

    def control(self, value: int) -> None:
        """What the point's Control method sends: one register write at the point's address."""
        self.scanner.channel.write_register(self.scanner.start + self.offset, value)


@pytest.fixture(scope="module")
def stand(tmp_path_factory):
    """`plclab serve thermo` on a free port, with its own openplc.conf (retain in a temp dir)."""
    tmp = tmp_path_factory.mktemp("scada")
    conf = tmp / "openplc.conf"
    conf.write_text(f"[thermo]\nretain_file = {tmp / 'thermo.retain'}\n")
    proc = subprocess.Popen(PLCLAB + ["serve", "thermo", "--config", str(conf), "--port", "0",
                                      "--console", "127.0.0.1:0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp)
    line = proc.stdout.readline()
    m = re.search(r"modbus on 127\.0\.0\.1:(\d+)", line)
    if not m:
        proc.kill()
        pytest.fail(f"no listening line: {line!r} {proc.communicate(timeout=10)[1]}")
    yield int(m.group(1))
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=10)
    assert proc.returncode == 0, err
    assert "stopped:" in out and "FAULT" not in out


@pytest.fixture(params=sorted(CHANNELS))
def channel(request, stand):
    ch = CHANNELS[request.param](stand)
    yield ch
    ch.close()


def test_task1_reads_and_displays_the_heat_sink_temperature(channel):
    scanner = Scanner(channel, start=0, length=7)
    temperature = AnalogPoint(scanner, TEMPERATURE)
    assert temperature.offset == 3
    scanner.poll()
    assert 20 <= temperature.value <= 80, f"%MW3 = {temperature.value} C"
    # the same point through a scanner starting elsewhere: offset = 3 - 1 = 2
    other = Scanner(channel, start=1, length=6)
    point = AnalogPoint(other, TEMPERATURE)
    other.poll()
    assert point.offset == 2 and abs(point.value - temperature.value) <= 1


def test_task2_controls_the_heater_power_and_sees_the_temperature_respond(stand):
    operator, monitor = PymodbusChannel(stand), RawChannel(stand)
    try:
        scanner = Scanner(operator, start=0, length=7)
        mode, heater = AnalogPoint(scanner, MODE), AnalogPoint(scanner, HEATER, 0, 2000)
        temperature = AnalogPoint(Scanner(monitor, 0, 7), TEMPERATURE)
        assert heater.offset == 2                                  # the textbook's example
        mode.control(MANUAL)
        scan_applies(scanner, MODE, MANUAL)
        heater.control(0)
        scan_applies(scanner, HEATER, 0)
        temperature.scanner.poll()
        start = temperature.value
        heater.control(2000)                                       # maximum heating
        scan_applies(scanner, HEATER, 2000)
        with pytest.raises(Refused) as refused:                    # beyond the control limits
            heater.control(2500)
        assert refused.value.code == ILLEGAL_DATA_VALUE
        time.sleep(0.3)
        scanner.poll()
        assert heater.value == 2000                                # nothing changed
        deadline = time.monotonic() + RISE_WITHIN
        while time.monotonic() < deadline:
            temperature.scanner.poll()
            if temperature.value >= start + 1:
                break
            time.sleep(0.2)
        assert temperature.value >= start + 1, \
            f"%MW3 stayed at {temperature.value} C for {RISE_WITHIN:g} s with the heater at 2000"
        heater.control(0)
        scan_applies(scanner, HEATER, 0)
    finally:
        operator.close()
        monitor.close()


def test_task2_heater_power_is_monitoring_only_in_automatic_mode(channel):
    """In automatic-2 the heater is the disturbance (1000 with the switch off): %MW2 reports it
    and refuses writes, as does every register outside its contract."""
    scanner = Scanner(channel, 0, 7)
    mode, heater, setpoint = AnalogPoint(scanner, MODE), AnalogPoint(scanner, HEATER), AnalogPoint(scanner, SETPOINT)
    mode.control(AUTO2)
    try:
        scan_applies(scanner, MODE, AUTO2)
        scan_applies(scanner, HEATER, 1000)   # automatic-2 with the switch off: heater 1000
        for value in (0, 2000):
            with pytest.raises(Refused) as refused:
                heater.control(value)
            assert refused.value.code == ILLEGAL_DATA_VALUE
        with pytest.raises(Refused):
            setpoint.control(80)              # outside 25..70
        with pytest.raises(Refused):
            AnalogPoint(scanner, TEMPERATURE).control(30)      # read only
        with pytest.raises(Refused):
            mode.control(3)
        time.sleep(0.3)
        scanner.poll()
        assert scanner.values[MODE] == AUTO2 and scanner.values[SETPOINT] == 40 and heater.value == 1000
    finally:
        mode.control(MANUAL)
        scan_applies(scanner, MODE, MANUAL)
