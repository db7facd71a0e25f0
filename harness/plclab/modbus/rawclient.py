"""A minimal blocking Modbus TCP client on raw sockets + struct.

Why it exists next to pymodbus's client: it is a second, independent encoding of the protocol
(it shares no code with the server's codec), it can send deliberately broken frames for the
robustness tests, and it is cheap enough to measure the server rather than the client in
`plclab bench`.
"""
from __future__ import annotations

import socket
import struct

_HEADER = struct.Struct(">HHHB")


class RawModbusError(Exception):
    """The server answered with an exception response."""

    def __init__(self, function: int, code: int):
        self.function = function
        self.code = code
        super().__init__(f"function {function}: exception {code:02d}")


class RawModbusClient:
    """One TCP connection; `request()` is the primitive, the rest are typed helpers."""

    def __init__(self, host: str, port: int, *, unit: int = 1, timeout: float = 5.0):
        self.unit = unit
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._tid = 0

    def close(self) -> None:
        self.sock.close()

    def __enter__(self) -> "RawModbusClient":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- frames -------------------------------------------------------------------------
    def send_raw(self, data: bytes) -> None:
        self.sock.sendall(data)

    def recv_exact(self, n: int) -> bytes:
        buf = b""
        while len(buf) < n:
            chunk = self.sock.recv(n - len(buf))
            if not chunk:
                raise ConnectionError(f"closed after {len(buf)} of {n} bytes")
            buf += chunk
        return buf

    def recv_frame(self) -> tuple[int, int, bytes]:
        """(transaction id, unit id, PDU) of the next response."""
        tid, pid, length, unit = _HEADER.unpack(self.recv_exact(7))
        if pid != 0 or length < 2:
            raise ConnectionError(f"bad response header pid={pid} length={length}")
        return tid, unit, self.recv_exact(length - 1)

    def request(self, pdu: bytes, *, unit: int | None = None) -> bytes:
        """Send one PDU, return the response PDU (exception responses raise RawModbusError)."""
        self._tid = (self._tid + 1) & 0xFFFF
        unit = self.unit if unit is None else unit
        self.send_raw(_HEADER.pack(self._tid, 0, len(pdu) + 1, unit) + pdu)
        tid, runit, response = self.recv_frame()
        if tid != self._tid or runit != unit:
            raise ConnectionError(f"response tid/unit {tid}/{runit}, sent {self._tid}/{unit}")
        if response[0] == pdu[0] | 0x80:
            raise RawModbusError(pdu[0], response[1])
        if response[0] != pdu[0]:
            raise ConnectionError(f"response function {response[0]} to request {pdu[0]}")
        return response

    # -- typed helpers ------------------------------------------------------------------
    def _read_bits(self, function: int, start: int, count: int) -> list[int]:
        resp = self.request(struct.pack(">BHH", function, start, count))
        data = resp[2:2 + resp[1]]
        return [(data[i // 8] >> (i % 8)) & 1 for i in range(count)]

    def _read_words(self, function: int, start: int, count: int) -> list[int]:
        resp = self.request(struct.pack(">BHH", function, start, count))
        return list(struct.unpack(f">{resp[1] // 2}H", resp[2:2 + resp[1]]))

    def read_coils(self, start: int, count: int) -> list[int]:
        return self._read_bits(1, start, count)

    def read_discrete_inputs(self, start: int, count: int) -> list[int]:
        return self._read_bits(2, start, count)

    def read_holding_registers(self, start: int, count: int) -> list[int]:
        return self._read_words(3, start, count)

    def read_input_registers(self, start: int, count: int) -> list[int]:
        return self._read_words(4, start, count)

    def write_coil(self, address: int, value: bool) -> None:
        self.request(struct.pack(">BHH", 5, address, 0xFF00 if value else 0))

    def write_register(self, address: int, value: int) -> None:
        self.request(struct.pack(">BHH", 6, address, value))

    def write_coils(self, start: int, values: list[int]) -> None:
        data = bytearray((len(values) + 7) // 8)
        for i, v in enumerate(values):
            if v:
                data[i // 8] |= 1 << (i % 8)
        self.request(struct.pack(">BHHB", 15, start, len(values), len(data)) + bytes(data))

    def write_registers(self, start: int, values: list[int]) -> None:
        data = struct.pack(f">{len(values)}H", *values)
        self.request(struct.pack(">BHHB", 16, start, len(values), len(data)) + data)

    def readwrite_registers(self, read_start: int, read_count: int, write_start: int,
                            values: list[int]) -> list[int]:
        data = struct.pack(f">{len(values)}H", *values)
        resp = self.request(struct.pack(">BHHHHB", 23, read_start, read_count, write_start,
                                        len(values), len(data)) + data)
        return list(struct.unpack(f">{resp[1] // 2}H", resp[2:2 + resp[1]]))
