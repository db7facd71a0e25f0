"""Client slots of a Modbus face (issue 15): idle clients cannot lock the others out, a
connection that never asks for anything is closed soon, and a faulted PLC answers 04."""
from __future__ import annotations

import socket
import time

import pytest

from modbus_support import TIMEOUT
from plclab.modbus.maps import OpenPlcMap
from plclab.modbus.rawclient import RawModbusClient, RawModbusError
from plclab.runtime.image import ProcessImage


from plclab.modbus.server import ModbusTcpServer


@pytest.fixture
def image():
    image = ProcessImage()
    image.set("QW", 0, 4242)
    return image


def closed_by_server(sock: socket.socket) -> bool:
    sock.settimeout(TIMEOUT)
    try:
        while True:
            if not sock.recv(1024):
                return True
    except ConnectionResetError:
        return True
    except TimeoutError:
        return False


def test_a_full_face_closes_the_longest_idle_connection_to_admit_a_new_one(image):
    with ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0, max_clients=3) as server:
        idle = socket.create_connection(("127.0.0.1", server.port), timeout=TIMEOUT)
        busy = [RawModbusClient("127.0.0.1", server.port, timeout=TIMEOUT) for _ in range(2)]
        for c in busy:
            assert c.read_holding_registers(0, 1) == [4242]     # active after `idle` connected
        with RawModbusClient("127.0.0.1", server.port, timeout=TIMEOUT) as newcomer:
            assert newcomer.read_holding_registers(0, 1) == [4242]
        assert closed_by_server(idle)
        for c in busy:
            assert c.read_holding_registers(0, 1) == [4242]     # the active ones kept their slots
            c.close()
        idle.close()
        assert server.stats["evicted"] == 1 and server.stats["refused"] == 0


def test_one_hundred_idle_connections_do_not_lock_a_client_out(image):
    with ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0, max_clients=100) as server:
        hogs = [socket.create_connection(("127.0.0.1", server.port), timeout=TIMEOUT) for _ in range(100)]
        deadline = time.monotonic() + TIMEOUT          # bounded: until the server has accepted them all
        while server.active_clients < 100 and time.monotonic() < deadline:
            time.sleep(0.01)
        newcomers = []
        try:
            for _ in range(5):                                   # each one finds the face full
                newcomers.append(RawModbusClient("127.0.0.1", server.port, timeout=TIMEOUT))
                assert newcomers[-1].read_holding_registers(0, 1) == [4242]
            for c in newcomers:
                assert c.read_holding_registers(0, 1) == [4242]  # the newcomers were not evicted
            assert all(closed_by_server(h) for h in hogs[:5])    # the five idle the longest were
            assert server.stats["evicted"] == 5 and server.stats["refused"] == 0
        finally:
            for c in newcomers + hogs:
                c.close()


def test_without_eviction_a_full_face_closes_the_new_connection(image):
    with ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0, max_clients=1, evict_when_full=False) as server:
        with RawModbusClient("127.0.0.1", server.port, timeout=TIMEOUT) as first:
            assert first.read_holding_registers(0, 1) == [4242]
            with socket.create_connection(("127.0.0.1", server.port), timeout=TIMEOUT) as second:
                assert closed_by_server(second)
            assert first.read_holding_registers(0, 1) == [4242]
        assert server.stats["refused"] == 1 and server.stats["evicted"] == 0


def test_a_connection_that_never_sends_a_request_gets_the_short_timeout(image):
    with ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0, idle_timeout=600,
                         first_request_timeout=0.2) as server:
        with RawModbusClient("127.0.0.1", server.port, timeout=TIMEOUT) as talker:
            assert talker.read_holding_registers(0, 1) == [4242]
            with socket.create_connection(("127.0.0.1", server.port), timeout=TIMEOUT) as silent:
                assert closed_by_server(silent)             # closed long before the 600 s idle timeout
            assert talker.read_holding_registers(0, 1) == [4242]   # a client that asked keeps its slot


def test_a_faulted_plc_answers_every_request_with_exception_04(image):
    problem: list[str] = []
    with ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0,
                         health=lambda: problem[0] if problem else None) as server:
        with RawModbusClient("127.0.0.1", server.port, timeout=TIMEOUT) as client:
            assert client.read_holding_registers(0, 1) == [4242]
            problem.append("PLC FAULT (internal): the scan loop stopped")
            for call in (lambda: client.read_holding_registers(0, 1), lambda: client.write_register(0, 1),
                         lambda: client.read_coils(0, 8)):
                with pytest.raises(RawModbusError) as e:
                    call()
                assert e.value.code == 4
            assert image.areas["QW"][0] == 4242                  # nothing written while faulted
            problem.clear()
            assert client.read_holding_registers(0, 1) == [4242]
        assert server.stats["faulted"] == 3
