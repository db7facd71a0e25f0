"""Twido map with the thermo stand's register table (docs/thermo.md), through both clients."""
from __future__ import annotations

import pytest

from modbus_support import CLIENTS, FakeScan, exception_code
from plclab.modbus.maps import TwidoMap
from plclab.stands import twido_profile
from plclab.modbus.server import ModbusTcpServer
from plclab.runtime.image import ProcessImage

THERMO = twido_profile("thermo")

MANUAL, AUTO1, AUTO2 = 0, 1, 2


@pytest.fixture
def image():
    image = ProcessImage()
    image.areas["MW"][0:7] = [MANUAL, 0, 0, 22, 0, 0, 40]
    return image


@pytest.fixture
def scan(image):
    with FakeScan(image) as scan:
        yield scan


@pytest.fixture
def server(image):
    with ModbusTcpServer(TwidoMap(image, THERMO), "127.0.0.1", 0) as server:
        yield server


@pytest.fixture(params=sorted(CLIENTS))
def client(request, server):
    client = CLIENTS[request.param](server.port)
    yield client
    client.close()


def test_holding_register_n_is_mwn(image, client):
    image.set("MW", 3, 47)
    assert client.read_holding_registers(0, 7) == [MANUAL, 0, 0, 47, 0, 0, 40]
    # The textbook's ClearSCADA point: heater power at offset 2 from start address 0.
    image.set("MW", 2, 1500)
    assert client.read_holding_registers(2, 1) == [1500]


def test_writes_in_manual_mode(image, scan, client):
    client.write_register(2, 2000)                    # FC 6: heater, the textbook's Task 2
    client.write_registers(0, [MANUAL, 1000, 10])     # FC 16
    assert client.readwrite_registers(6, 1, 6, [70]) == [70]   # FC 23
    scan.sync()
    assert image.snapshot("MW", 0, 7) == [MANUAL, 1000, 10, 22, 0, 0, 70]


@pytest.mark.parametrize("call", [
    lambda c: c.read_coils(0, 1),
    lambda c: c.read_discrete_inputs(0, 1),
    lambda c: c.read_input_registers(0, 1),
    lambda c: c.write_coil(0, True),
    lambda c: c.write_coils(0, [1, 0]),
], ids=["fc1", "fc2", "fc4", "fc5", "fc15"])
def test_functions_without_twido_registers_are_exception_01(client, call):
    assert exception_code(lambda: call(client)) == 1


@pytest.mark.parametrize("call, code", [
    (lambda c: c.read_holding_registers(7, 1), 2),          # no %MW7 in the table
    (lambda c: c.read_holding_registers(5, 3), 2),          # span runs past %MW6
    (lambda c: c.write_register(100, 1), 2),
    (lambda c: c.write_registers(6, [50, 1]), 2),
    (lambda c: c.write_register(3, 30), 3),                 # read only
    (lambda c: c.write_register(0, 3), 3),                  # mode 0, 1, 2 only
    (lambda c: c.write_register(1, 1001), 3),               # fan 0..1000
    (lambda c: c.write_register(2, 0xFFFF), 3),             # -1 as INT
    (lambda c: c.write_register(6, 24), 3),                 # setpoint 25..70
    (lambda c: c.write_register(6, 71), 3),
    (lambda c: c.write_registers(0, [AUTO1, 100]), 3),      # fan in automatic mode (after write)
    (lambda c: c.readwrite_registers(0, 7, 1, [500, 3000]), 3),
    (lambda c: c.readwrite_registers(0, 8, 6, [50]), 2),
], ids=["read-mw7", "read-span", "fc6-addr", "fc16-addr", "read-only", "mode", "fan", "heater-neg",
        "sp-low", "sp-high", "auto-fan", "fc23-value", "fc23-read-addr"])
def test_refused_requests_change_nothing(image, scan, client, call, code):
    before = image.snapshot("MW", 0, 8)
    assert exception_code(lambda: call(client)) == code
    scan.sync()
    assert image.snapshot("MW", 0, 8) == before


def test_fan_and_heater_are_writable_only_in_manual_mode(image, scan, client):
    client.write_register(0, AUTO2)
    scan.sync()
    assert exception_code(lambda: client.write_register(1, 500)) == 3
    assert exception_code(lambda: client.write_register(2, 500)) == 3
    client.write_register(6, 45)                      # the setpoint stays writable
    # One request that returns to manual and sets the heater is judged on its result.
    client.write_registers(0, [MANUAL, 300, 700])
    scan.sync()
    assert image.snapshot("MW", 0, 7) == [MANUAL, 300, 700, 22, 0, 0, 45]


def test_multi_register_write_is_all_or_nothing(image, scan, client):
    # registers 0..2 valid, 3 is read only: nothing of the request may land
    assert exception_code(lambda: client.write_registers(0, [MANUAL, 100, 200, 22])) == 3
    # the last value out of range refuses the valid ones before it
    assert exception_code(lambda: client.write_registers(0, [MANUAL, 100, 2001])) == 3
    scan.sync()
    assert image.snapshot("MW", 0, 7) == [MANUAL, 0, 0, 22, 0, 0, 40]
