"""PSM I/O: the plant-side server against a byte-for-byte mimic of OpenPLC's psm.cpp client
and this project's PsmClient (the plant stepped in lockstep: test_psm_lockstep.py; the
generated OpenPLC PSM script: test_psm_script.py)."""
from __future__ import annotations

import pytest

from modbus_support import TIMEOUT, OpenPlcPsm
from plclab.modbus.psm import ERROR_LIMIT, PsmClient, PsmError, PsmServer, parse_location
from plclab.modbus.rawclient import RawModbusClient, RawModbusError
from plclab.runtime.image import ProcessImage


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


def test_parse_location():
    assert parse_location("%IX3.2") == ("IX", 26)
    assert parse_location("qw49") == ("QW", 49)
    for bad in ("IX50.0", "IX1.8", "QW50", "IW1.1", "MW0", "QX3"):
        with pytest.raises(ValueError):
            parse_location(bad)
