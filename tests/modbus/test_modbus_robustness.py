"""Hostile and heavy clients: the server answers or closes that one connection, keeps serving
everyone else, and never holds up the scan."""
from __future__ import annotations

import os
import socket
import struct
import threading
import time

import pytest

from modbus_support import TIMEOUT, FakeScan
from plclab.modbus.maps import OpenPlcMap
from plclab.modbus.rawclient import RawModbusClient, RawModbusError
from plclab.modbus.server import ModbusTcpServer, ServerError
from plclab.runtime.image import ProcessImage

READ_QW0 = struct.pack(">HHHBBHH", 9, 0, 6, 1, 3, 0, 1)       # a valid FC 3 frame


@pytest.fixture
def image():
    image = ProcessImage()
    image.set("QW", 0, 4242)
    return image


@pytest.fixture
def scan(image):
    with FakeScan(image) as scan:
        yield scan


@pytest.fixture
def server(image):
    with ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0, idle_timeout=1.0) as server:
        yield server


def connect(port: int) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


def recv_exact(sock: socket.socket, n: int) -> bytes:
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            return b""
        data += chunk
    return data


def recv_frame(sock: socket.socket) -> bytes:
    """One response frame, or b'' if the server closed the connection."""
    head = recv_exact(sock, 7)
    if not head:
        return b""
    body = recv_exact(sock, struct.unpack(">H", head[4:6])[0] - 1)
    return head + body if body else b""


def closed_by_server(sock: socket.socket) -> bool:
    try:
        while True:
            chunk = sock.recv(1024)
            if not chunk:
                return True
    except ConnectionResetError:
        return True


def still_serves(port: int) -> bool:
    with RawModbusClient("127.0.0.1", port, timeout=TIMEOUT) as client:
        return client.read_holding_registers(0, 1) == [4242]


def header(length: int, protocol: int = 0, tid: int = 1, unit: int = 1) -> bytes:
    return struct.pack(">HHHB", tid, protocol, length, unit)


@pytest.mark.parametrize("payload", [
    b"\x00\x01\x00",                                   # truncated header, then gone
    header(6) + b"\x03\x00",                           # truncated PDU, then gone
    os.urandom(300),                                   # noise
    READ_QW0 * 50,                                     # pipelined requests, not read
], ids=["short-header", "short-pdu", "noise", "unread-pipeline"])
def test_abrupt_disconnects(server, payload):
    sock = connect(server.port)
    sock.sendall(payload)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    sock.close()                                       # RST, not FIN
    assert still_serves(server.port)


@pytest.mark.parametrize("frame", [
    header(2000) + b"\x03" + bytes(300),               # length field above 254 (oversized)
    header(6, protocol=1) + b"\x03\x00\x00\x00\x01",   # not Modbus
    header(1) + b"",                                   # no function code
    header(0),
], ids=["oversized", "protocol-id", "length-1", "length-0"])
def test_untrustworthy_header_closes_only_that_connection(server, frame):
    with connect(server.port) as sock:
        sock.sendall(frame)
        assert closed_by_server(sock)
    assert still_serves(server.port)


def test_length_field_shorter_than_the_pdu(server):
    with connect(server.port) as sock:
        sock.sendall(header(4) + b"\x03\x00\x00\x00\x01")   # says 3 PDU bytes, sends 5
        reply = recv_frame(sock)
        assert reply[7:] == b"\x83\x03"                  # malformed PDU: exception 03
    assert still_serves(server.port)


def test_length_field_longer_than_the_pdu_times_out(server):
    with connect(server.port) as sock:
        sock.sendall(header(20) + b"\x03\x00\x00\x00\x01")  # waits for bytes that never come
        assert closed_by_server(sock)                       # after the 1 s idle timeout
    assert still_serves(server.port)


def test_connection_survives_exceptions_and_pipelining(server):
    with connect(server.port) as sock:
        sock.sendall(header(2, tid=5) + b"\x63")           # unknown function 0x63
        assert recv_frame(sock) == header(3, tid=5) + b"\xe3\x01"
        sock.sendall(header(6, tid=6) + struct.pack(">BHH", 3, 0, 0))   # quantity 0
        assert recv_frame(sock) == header(3, tid=6) + b"\x83\x03"
        sock.sendall(READ_QW0 * 3)                          # three requests, one segment
        for _ in range(3):
            assert recv_frame(sock) == header(5, tid=9) + b"\x03\x02" + struct.pack(">H", 4242)


def test_silent_client_neither_blocks_others_nor_stays_forever(server, scan):
    with connect(server.port) as silent:
        ticks = scan.ticks
        assert still_serves(server.port)
        assert closed_by_server(silent)                     # idle timeout (1 s)
        scan.sync()
        assert scan.ticks > ticks


def test_client_that_never_reads_its_replies_blocks_nobody(server, scan):
    with connect(server.port) as hog:
        hog.sendall(READ_QW0 * 8000)                        # ~90 kB of replies, never read
        ticks = scan.ticks
        for _ in range(20):
            assert still_serves(server.port)
        scan.sync()
        assert scan.ticks > ticks


def test_unit_id_filter_and_client_limit(image):
    with ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0, unit_ids=[1], max_clients=2,
                         evict_when_full=False) as server:
        a = RawModbusClient("127.0.0.1", server.port, unit=1, timeout=TIMEOUT)
        b = RawModbusClient("127.0.0.1", server.port, unit=2, timeout=0.3)
        with pytest.raises(TimeoutError):
            b.read_holding_registers(0, 1)                  # other unit ids: dropped
        with connect(server.port) as third:
            assert closed_by_server(third)                  # over max_clients
        assert a.read_holding_registers(0, 1) == [4242]
        # the server thread counts b's frame when it reads it: on a loaded machine that may
        # be after b's client gave up, so wait for the count (bounded) before closing b
        deadline = time.monotonic() + TIMEOUT
        while server.stats["ignored"] < 1 and time.monotonic() < deadline:
            time.sleep(0.01)
        b.close()
        a.close()
        assert server.stats["ignored"] == 1 and server.stats["refused"] == 1


def test_port_in_use_is_a_one_line_error(server, image):
    with pytest.raises(ServerError, match=r"^modbus: cannot listen on 127\.0\.0\.1:\d+: .+$"):
        ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", server.port).start()


def test_stop_closes_connected_clients(image):
    server = ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0).start()
    client = RawModbusClient("127.0.0.1", server.port, timeout=TIMEOUT)
    assert client.read_holding_registers(0, 1) == [4242]
    server.stop()
    assert server.wait(TIMEOUT) and not server.running
    with pytest.raises((ConnectionError, OSError)):
        client.read_holding_registers(0, 1)
    client.close()


@pytest.fixture
def patient_server(image):
    """The face as `plclab serve` runs it (idle connections closed after a minute): 50 busy
    client threads on a loaded 2-core machine can leave one of them a second between two
    requests, which the 1 s idle timeout above would rightly close."""
    with ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0) as server:
        yield server


def test_load_50_clients_x_200_requests(image, scan, patient_server):
    """Every request answered correctly; the scan keeps ticking throughout."""
    server = patient_server
    clients, requests = 50, 200
    image.areas["MW"][0:10] = list(range(100, 110))
    failures: list[str] = []
    ticks_before = scan.ticks

    def worker(i: int) -> None:
        try:
            with RawModbusClient("127.0.0.1", server.port, timeout=TIMEOUT) as client:
                for k in range(requests):
                    if k % 2:
                        client.write_register(i, k)
                    elif client.read_holding_registers(1024, 10) != list(range(100, 110)):
                        failures.append(f"client {i}: wrong values")
        except (OSError, ConnectionError, RawModbusError) as exc:
            failures.append(f"client {i}: {exc}")

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60.0)
    assert not any(t.is_alive() for t in threads), "clients still waiting after 60 s"
    assert failures == []
    scan.sync()
    assert image.snapshot("QW", 0, clients) == [requests - 1] * clients
    assert server.stats["requests"] >= clients * requests
    assert scan.ticks > ticks_before
