"""Helpers shared by the Modbus tests: a fake scan thread and one client interface over two
independent client implementations (pymodbus's and plclab.modbus.rawclient)."""
from __future__ import annotations

import socket
import threading
import time
from typing import Callable

from pymodbus.client import ModbusTcpClient

from plclab.modbus.rawclient import RawModbusClient, RawModbusError
from plclab.runtime.image import ProcessImage

TIMEOUT = 10.0   # generous bound for anything that should take milliseconds


class FakeScan:
    """The scan thread's part of the image contract: apply queued writes at each tick."""

    def __init__(self, image: ProcessImage, period: float = 0.001,
                 program: Callable[[ProcessImage], None] | None = None):
        self.image = image
        self.period = period
        self.program = program
        self.ticks = 0
        self._cond = threading.Condition()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            self.image.apply_pending()
            if self.program is not None:
                self.program(self.image)
            with self._cond:
                self.ticks += 1
                self._cond.notify_all()
            time.sleep(self.period)

    def sync(self) -> None:
        """Return once every write queued before the call has been applied (two ticks)."""
        with self._cond:
            target = self.ticks + 2
            assert self._cond.wait_for(lambda: self.ticks >= target, TIMEOUT), "scan stalled"

    def __enter__(self) -> "FakeScan":
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(TIMEOUT)


class ExceptionReply(Exception):
    def __init__(self, code: int):
        self.code = code
        super().__init__(f"exception {code}")


class PymodbusAdapter:
    """pymodbus's client behind the same calls as the raw client; exceptions -> ExceptionReply."""

    name = "pymodbus"

    def __init__(self, port: int, unit: int = 1):
        self.client = ModbusTcpClient("127.0.0.1", port=port, timeout=TIMEOUT, retries=0)
        assert self.client.connect()
        self.unit = unit

    def _ok(self, result):
        if result.isError():
            raise ExceptionReply(result.exception_code)
        return result

    def close(self) -> None:
        self.client.close()

    def read_coils(self, start: int, count: int) -> list[int]:
        bits = self._ok(self.client.read_coils(start, count=count, device_id=self.unit)).bits
        return [int(b) for b in bits[:count]]

    def read_discrete_inputs(self, start: int, count: int) -> list[int]:
        bits = self._ok(self.client.read_discrete_inputs(start, count=count, device_id=self.unit)).bits
        return [int(b) for b in bits[:count]]

    def read_holding_registers(self, start: int, count: int) -> list[int]:
        return list(self._ok(self.client.read_holding_registers(start, count=count, device_id=self.unit)).registers)

    def read_input_registers(self, start: int, count: int) -> list[int]:
        return list(self._ok(self.client.read_input_registers(start, count=count, device_id=self.unit)).registers)

    def write_coil(self, address: int, value: bool) -> None:
        self._ok(self.client.write_coil(address, bool(value), device_id=self.unit))

    def write_register(self, address: int, value: int) -> None:
        self._ok(self.client.write_register(address, value, device_id=self.unit))

    def write_coils(self, start: int, values: list[int]) -> None:
        self._ok(self.client.write_coils(start, [bool(v) for v in values], device_id=self.unit))

    def write_registers(self, start: int, values: list[int]) -> None:
        self._ok(self.client.write_registers(start, values, device_id=self.unit))

    def readwrite_registers(self, read_start: int, read_count: int, write_start: int,
                            values: list[int]) -> list[int]:
        return list(self._ok(self.client.readwrite_registers(
            read_address=read_start, read_count=read_count, write_address=write_start,
            values=values, device_id=self.unit)).registers)


class RawAdapter:
    """plclab.modbus.rawclient (raw sockets + struct), exceptions -> ExceptionReply."""

    name = "raw"

    def __init__(self, port: int, unit: int = 1):
        self.client = RawModbusClient("127.0.0.1", port, unit=unit, timeout=TIMEOUT)

    def close(self) -> None:
        self.client.close()

    def __getattr__(self, name: str):
        method = getattr(self.client, name)

        def call(*args, **kwargs):
            try:
                return method(*args, **kwargs)
            except RawModbusError as exc:
                raise ExceptionReply(exc.code) from None
        return call


CLIENTS = {"pymodbus": PymodbusAdapter, "raw": RawAdapter}


def exception_code(fn: Callable[[], object]) -> int | None:
    """The exception code `fn` got, or None if it succeeded."""
    try:
        fn()
    except ExceptionReply as exc:
        return exc.code
    return None


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

    # OpenPLC's main loop around them (webserver/core/main.cpp): updateBuffersIn(), the
    # program, updateBuffersOut(); a PLC of this project plays the program.
    def update_buffers_in(self, image: ProcessImage) -> None:
        image.areas["IX"][0:400] = self.read_dig_inp()
        image.areas["IW"][0:50] = self.read_ana_inp()

    def update_buffers_out(self, image: ProcessImage) -> None:
        self.write_dig_out(image.areas["QX"][0:400])
        self.write_ana_out(image.areas["QW"][0:50])
