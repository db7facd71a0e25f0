"""PSM I/O: the plant-side server against a byte-for-byte mimic of OpenPLC's psm.cpp client,
this project's PsmClient, the shared plant loop and the generated OpenPLC PSM script."""
from __future__ import annotations

import socket
import sys
import threading
import types

import pytest

from modbus_support import TIMEOUT
from plclab.errors import PlcLabError
from plclab.modbus.psm import (ERROR_LIMIT, PsmClient, PsmError, PsmServer, drive_plant,
                               parse_location, psm_script)
from plclab.modbus.rawclient import RawModbusClient, RawModbusError
from plclab.runtime.image import ProcessImage


class OpenPlcPsm:
    """webserver/core/hardware_layers/psm.cpp, request arrays copied from it: tid 1, unit 0,
    one send and ONE read(1024) per request, checks on the bytes it checks."""

    def __init__(self, port: int):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT)

    def _send_read(self, request: bytes) -> bytes:
        self.sock.send(request)
        return self.sock.recv(1024)                      # psm.cpp: read(psm, buffer, 1024)

    def read_dig_inp(self) -> list[int]:
        request = bytes([0, 1, 0, 0, 0, 6, 0, 2, 0, 0, 0x01, 0x90])
        buffer = self._send_read(request)
        assert len(buffer) == 59 and buffer[8] >= 50     # whole response in the one read
        return [(buffer[i] >> j) & 1 for i in range(9, 59) for j in range(8)]

    def read_ana_inp(self) -> list[int]:
        request = bytearray([0, 1, 0, 0, 0, 6, 0, 4, 0, 0, 0, 25])
        words = []
        for start in (0, 25):
            request[9] = start                           # "request the next 25 items"
            buffer = self._send_read(bytes(request))
            assert len(buffer) == 59 and buffer[8] >= 50
            words += [buffer[k + 1] | buffer[k] << 8 for k in range(9, 59, 2)]
        return words

    def write_dig_out(self, bits: list[int]) -> None:
        request = bytearray([0, 1, 0, 0, 0, 57, 0, 15, 0, 0, 0x01, 0x90, 50] + [0] * 50)
        for a, bit in enumerate(bits):
            if bit:
                request[13 + a // 8] |= 1 << (a % 8)
        buffer = self._send_read(bytes(request))
        assert len(buffer) == 12 and (buffer[10], buffer[11]) == (0x01, 0x90)

    def write_ana_out(self, words: list[int]) -> None:
        request = bytearray([0, 1, 0, 0, 0, 57, 0, 16, 0, 0, 0, 25, 50] + [0] * 50)
        for start in (0, 25):
            request[9] = start
            k = 13
            for w in words[start:start + 25]:
                request[k], request[k + 1] = w >> 8, w & 0xFF
                k += 2
            buffer = self._send_read(bytes(request))
            assert len(buffer) == 12 and buffer[11] >= 25

    def stop_psm(self) -> None:
        self.sock.send(bytes([0, 1, 0, 0, 0, 6, 0, 6, 0, 50, 0, 127]))   # reply not read

    def close(self) -> None:
        self.sock.close()


@pytest.fixture
def plant_image():
    return ProcessImage()


@pytest.fixture
def psm_server(plant_image):
    server = PsmServer(plant_image, "127.0.0.1", 0).start()
    yield server
    server.stop()


def test_openplc_psm_client_scan_exchange_and_stop(plant_image, psm_server):
    plant_image.set_bit("IX", 0, 0, True)
    plant_image.set_bit("IX", 3, 2, True)               # %IX3.2 = discrete input 26
    plant_image.set_bit("IX", 49, 7, True)
    for i in range(50):
        plant_image.set("IW", i, 1000 + i)
    openplc = OpenPlcPsm(psm_server.port)
    for _scan in range(3):                               # updateBuffersIn, program, updateBuffersOut
        bits = openplc.read_dig_inp()
        assert [i for i, b in enumerate(bits) if b] == [0, 26, 399]
        assert openplc.read_ana_inp() == [1000 + i for i in range(50)]
        out_bits = [0] * 400
        out_bits[8] = out_bits[399] = 1                  # %QX1.0, %QX49.7
        openplc.write_dig_out(out_bits)
        openplc.write_ana_out([2 * i + _scan for i in range(50)])
        # the plant side has no scan: PLC writes are in the image at once
        assert plant_image.get_bit("QX", 1, 0) and plant_image.get_bit("QX", 49, 7)
        assert plant_image.snapshot("QX", 0, 400).count(1) == 2
        assert plant_image.snapshot("QW", 0, 50) == [2 * i + _scan for i in range(50)]
    assert not psm_server.should_quit()
    openplc.stop_psm()                                   # finalizeHardware()
    assert psm_server.wait(TIMEOUT)
    assert psm_server.should_quit()
    openplc.close()


def test_register_50_only_stops_on_127_and_is_outside_qw(plant_image, psm_server):
    with PsmClient("127.0.0.1", psm_server.port, timeout=TIMEOUT) as client:
        with RawModbusClient("127.0.0.1", psm_server.port, unit=0) as raw:
            raw.write_register(50, 5)
            assert raw.read_holding_registers(49, 2) == [0, 5]
            assert not psm_server.should_quit()
            with pytest.raises(RawModbusError) as exc:
                raw.read_holding_registers(50, 2)        # nothing past register 50
            assert exc.value.code == 2
            assert plant_image.get("QW", 50) == 0
        client.request_stop()
        assert psm_server.wait(TIMEOUT)


def test_psm_client_moves_the_plc_image(plant_image, psm_server):
    plc = ProcessImage()
    plc.set_bit("QX", 0, 3, True)
    plc.set("QW", 0, 500)
    plc.set("QW", 49, 65535)
    plant_image.set_bit("IX", 1, 1, True)
    plant_image.set("IW", 0, 220)
    plant_image.set("IW", 30, 7)
    with PsmClient("127.0.0.1", psm_server.port, timeout=TIMEOUT) as client:
        client.read_inputs(plc)
        client.write_outputs(plc)
    assert plc.get_bit("IX", 1, 1) and plc.snapshot("IX", 0, 400).count(1) == 1
    assert (plc.get("IW", 0), plc.get("IW", 30)) == (220, 7)
    assert plant_image.get_bit("QX", 0, 3)
    assert (plant_image.get("QW", 0), plant_image.get("QW", 49)) == (500, 65535)


def test_psm_client_errors_are_one_line_and_disable_after_the_limit(plant_image):
    server = PsmServer(plant_image, "127.0.0.1", 0).start()
    port = server.port
    client = PsmClient("127.0.0.1", port, timeout=TIMEOUT).connect()
    server.stop()
    plc = ProcessImage()
    for _ in range(ERROR_LIMIT):
        with pytest.raises(PsmError, match=r"^psm: [^\n]+$"):
            client.read_inputs(plc)                      # then each retry reconnects
    assert client.disabled
    with pytest.raises(PsmError, match="disabled"):
        client.write_outputs(plc)
    with pytest.raises(PsmError, match=rf"^psm: 127\.0\.0\.1:{port}: cannot connect: "):
        PsmClient("127.0.0.1", port, timeout=TIMEOUT).connect()


class EchoPlant:
    """A stand-in plant: the input %IX0.0 follows %QX0.0, %IW0 = %QW0 + 1."""

    period = 0.001
    outputs = ["QX0.0", "QW0"]

    def __init__(self) -> None:
        self.steps = 0

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, int]:
        self.steps += 1
        return {"IX0.0": outputs["QX0.0"], "%IW0": outputs["QW0"] + 1}


def test_drive_plant_against_psm_server_until_stop(plant_image, psm_server):
    plant = EchoPlant()
    done: list[int] = []
    loop = threading.Thread(target=lambda: done.append(drive_plant(plant, psm_server)))
    loop.start()
    plc = ProcessImage()
    plc.set_bit("QX", 0, 0, True)
    plc.set("QW", 0, 41)
    with PsmClient("127.0.0.1", psm_server.port, timeout=TIMEOUT) as client:
        client.write_outputs(plc)
        for _ in range(int(TIMEOUT / 0.01)):
            client.read_inputs(plc)
            if plc.get_bit("IX", 0, 0) and plc.get("IW", 0) == 42:
                break
            threading.Event().wait(0.01)
        assert plc.get_bit("IX", 0, 0) and plc.get("IW", 0) == 42
        client.request_stop()
    loop.join(TIMEOUT)
    assert done and done[0] == plant.steps > 0


def test_parse_location():
    assert parse_location("%IX3.2") == ("IX", 26)
    assert parse_location("qw49") == ("QW", 49)
    for bad in ("IX50.0", "IX1.8", "QW50", "IW1.1", "MW0", "QX3"):
        with pytest.raises(ValueError):
            parse_location(bad)


def test_psm_script_runs_the_plant_in_openplc_main_py_form(monkeypatch, tmp_path):
    text = psm_script("thermo", harness_dir=tmp_path)
    code = compile(text, "main.py", "exec")
    calls: list[str] = []
    state = {"QX0.0": 1, "QW0": 9}
    fake_psm = types.ModuleType("psm")
    fake_psm.start = lambda: calls.append("start")
    fake_psm.stop = lambda: calls.append("stop")
    fake_psm.get_var = lambda loc: state[loc]
    fake_psm.set_var = lambda loc, value: state.__setitem__(loc, value)
    fake_psm.should_quit = lambda: calls.count("step") >= 3
    plant = EchoPlant()
    plant.period = 0.0

    def step(outputs, dt):
        calls.append("step")
        return EchoPlant.step(plant, outputs, dt)
    plant.step = step
    plants = types.ModuleType("plclab.plants")
    plants.psm_plant = lambda stand: plant if stand == "thermo" else None
    monkeypatch.setitem(sys.modules, "psm", fake_psm)
    monkeypatch.setitem(sys.modules, "plclab.plants", plants)
    monkeypatch.setitem(sys.modules, "plclab.plants.thermo", types.ModuleType("plclab.plants.thermo"))
    monkeypatch.setattr(sys, "path", list(sys.path))
    exec(code, {"__name__": "__main__"})
    assert calls == ["start", "step", "step", "step", "stop"]
    assert state["IX0.0"] == 1 and state["%IW0"] == 10
    assert str(tmp_path) in sys.path
    with pytest.raises(PlcLabError, match="unknown stand 'kuka'"):
        psm_script("kuka")
