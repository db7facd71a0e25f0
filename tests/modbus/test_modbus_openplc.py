"""OpenPLC register map over Modbus TCP: every function code, through pymodbus's client and
through the independent raw-socket client."""
from __future__ import annotations

import struct

import pytest

from modbus_support import CLIENTS, FakeScan, exception_code
from plclab.modbus.maps import OpenPlcMap
from plclab.modbus.rawclient import RawModbusClient, RawModbusError
from plclab.modbus.server import ModbusTcpServer
from plclab.runtime.image import ProcessImage


@pytest.fixture
def image():
    return ProcessImage()


@pytest.fixture
def scan(image):
    with FakeScan(image) as scan:
        yield scan


@pytest.fixture
def server(image):
    with ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0) as server:
        yield server


@pytest.fixture(params=sorted(CLIENTS))
def client(request, server):
    client = CLIENTS[request.param](server.port)
    yield client
    client.close()


def test_reads_map_each_table_to_its_area(image, client):
    image.set_bit("QX", 0, 1, True)
    image.set_bit("QX", 99, 7, True)
    image.set_bit("IX", 3, 2, True)          # %IX3.2 is discrete input 26
    image.set("IW", 5, 0xBEEF)
    image.set("QW", 1023, 11)
    image.set("MW", 0, 22)
    image.set("MD", 1, 0x12345678)
    image.set("ML", 0, 0x1122334455667788)

    assert client.read_coils(0, 3) == [0, 1, 0]
    assert client.read_coils(792, 8) == [0] * 7 + [1]
    assert client.read_discrete_inputs(24, 4) == [0, 0, 1, 0]
    assert client.read_input_registers(4, 2) == [0, 0xBEEF]
    assert client.read_holding_registers(1023, 2) == [11, 22]          # %QW1023, %MW0
    # %MD1 is holding 2050-2051, high word first (OpenPLC modbus.cpp order)
    assert client.read_holding_registers(2049, 4) == [0, 0x1234, 0x5678, 0]
    assert client.read_holding_registers(4096, 4) == [0x1122, 0x3344, 0x5566, 0x7788]
    assert client.read_holding_registers(4097, 2) == [0x3344, 0x5566]


def test_writes_reach_the_image_on_the_next_tick(image, scan, client):
    client.write_coil(10, True)
    client.write_coils(16, [1, 0, 1, 1, 0, 0, 0, 0, 1])
    client.write_register(3, 0xFFFF)
    client.write_registers(1023, [7, 8])                 # %QW1023 and %MW0 in one request
    client.write_registers(2050, [0xDEAD])               # high word of %MD1 only
    client.write_registers(4100, [1, 2, 3, 4])           # all of %ML1
    scan.sync()
    assert image.get("QX", 10) == 1
    assert image.snapshot("QX", 16, 9) == [1, 0, 1, 1, 0, 0, 0, 0, 1]
    assert image.get("QW", 3) == 0xFFFF
    assert (image.get("QW", 1023), image.get("MW", 0)) == (7, 8)
    assert image.get("MD", 1) == 0xDEAD0000
    assert image.get("ML", 1) == 0x0001000200030004

    client.write_registers(2051, [0xBEEF])               # low word merges with the high one
    scan.sync()
    assert image.get("MD", 1) == 0xDEADBEEF
    client.write_coil(10, False)
    scan.sync()
    assert client.read_coils(10, 1) == [0]

    # FC 23: the write is done first and the read sees it, before the scan applies it.
    assert client.readwrite_registers(1024, 3, 1025, [55, 66]) == [8, 55, 66]
    scan.sync()
    assert image.snapshot("MW", 0, 3) == [8, 55, 66]


def test_unlocated_address_inside_an_area_reads_zero_and_accepts_writes(image, scan, client):
    assert client.read_holding_registers(1500, 2) == [0, 0]
    client.write_register(1500, 1234)
    scan.sync()
    assert client.read_holding_registers(1500, 2) == [1234, 0]
    assert client.read_input_registers(1023, 1) == [0]


@pytest.mark.parametrize("call", [
    lambda c: c.read_coils(800, 1),
    lambda c: c.read_coils(795, 10),
    lambda c: c.read_discrete_inputs(800, 1),
    lambda c: c.read_input_registers(1023, 2),
    lambda c: c.read_holding_registers(8190, 4),
    lambda c: c.write_coil(800, True),
    lambda c: c.write_coils(799, [1, 1]),
    lambda c: c.write_register(8192, 1),
    lambda c: c.write_registers(8190, [1, 2, 3]),
    lambda c: c.readwrite_registers(9000, 1, 0, [5]),    # bad read address: write not done
], ids=["coils", "coils-span", "inputs", "input-regs", "holding", "fc5", "fc15", "fc6",
        "fc16", "fc23"])
def test_outside_every_area_is_exception_02_and_changes_nothing(image, scan, client, call):
    before = {area: list(values) for area, values in image.areas.items()}
    assert exception_code(lambda: call(client)) == 2
    scan.sync()
    assert image.areas == before


def _raw_pdu(port: int, pdu: bytes) -> int | None:
    with RawModbusClient("127.0.0.1", port) as raw:
        try:
            raw.request(pdu)
        except RawModbusError as exc:
            return exc.code
    return None


@pytest.mark.parametrize("pdu, code", [
    (struct.pack(">BHH", 1, 0, 0), 3),                    # quantity 0
    (struct.pack(">BHH", 2, 0, 2001), 3),                 # above 2000 bits
    (struct.pack(">BHH", 3, 0, 126), 3),                  # above 125 registers
    (struct.pack(">BHH", 4, 0, 0), 3),
    (struct.pack(">BHH", 5, 0, 0x1234), 3),               # coil value neither FF00 nor 0000
    (struct.pack(">BHHB", 15, 0, 1969, 247) + bytes(247), 3),
    (struct.pack(">BHHB", 16, 0, 124, 248) + bytes(248)[:240], 3),   # too many, and short
    (struct.pack(">BHHB", 16, 0, 2, 3) + bytes(3), 3),    # byte count disagrees with quantity
    (struct.pack(">BHHHHB", 23, 0, 126, 0, 1, 2) + bytes(2), 3),
    (struct.pack(">BHHHHB", 23, 0, 1, 0, 122, 244) + bytes(244)[:230], 3),
    (struct.pack(">BHH", 3, 0xFFFF, 2), 2),               # past 65535
    (bytes([7]), 1),                                      # read exception status: not served
    (bytes([0x41]), 1),                                   # OpenPLC's debugger functions: not served
    (bytes([0x2B, 0x0E, 1, 0]), 1),
], ids=["fc1-q0", "fc2-2001", "fc3-126", "fc4-q0", "fc5-value", "fc15-1969", "fc16-124",
        "fc16-bytecount", "fc23-read126", "fc23-write122", "span", "fc7", "fc65", "fc43"])
def test_bad_quantities_values_and_functions(image, scan, server, pdu, code):
    before = {area: list(values) for area, values in image.areas.items()}
    assert _raw_pdu(server.port, pdu) == code
    scan.sync()
    assert image.areas == before
