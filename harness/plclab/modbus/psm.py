"""OpenPLC's PSM (Python SubModule) I/O protocol: the plant side (server) and the PLC side (client).

OpenPLC's PSM hardware layer (webserver/core/hardware_layers/psm.cpp) is a Modbus TCP client
that polls 127.0.0.1:2605 every scan, with hand-made frames:
  in:  FC 2  start 0  qty 400  -> %IX0.0..%IX49.7 (address = 8*byte + bit)
       FC 4  start 0  qty 25, then start 25 qty 25 -> %IW0..%IW49
  out: FC 15 start 0  qty 400 (50 data bytes) <- %QX0.0..%QX49.7
       FC 16 start 0  qty 25, then start 25 qty 25 <- %QW0..%QW49
  stop (on PLC stop): FC 6 register 50 = 127, reply not read.
Every frame has transaction id 1 and unit id 0, and each response must arrive in one read()
of up to 1024 bytes. OpenPLC packs %QW without gaps (an unlocated %QW shifts the later
ones), so stands must use contiguous %QW from %QW0. After 10 errors it disables PSM until
the runtime restarts.

The plant side is `PsmServer`: it serves a ProcessImage with that layout and offers the same
get_var / set_var / should_quit calls as OpenPLC's `core/psm/psm.py`, so one plant loop
(`drive_plant`) runs against either. The plant side has no scan thread, so writes from the
PLC land in the image at once, under its lock (like the datastore writes of OpenPLC's psm.py).

The PLC side is `PsmClient`, sending the same frames as psm.cpp for this project's real-time
runtime, but reading each response whole and checking it.

`psm_script(stand)` is the text of an OpenPLC `core/psm/main.py` that runs a stand's plant.
"""
from __future__ import annotations

import re
import socket
import struct
import time
from pathlib import Path
from typing import Callable, Protocol

from plclab.errors import PlcLabError

from .maps import RegisterMap
from .protocol import (MBAP, MBAP_SIZE, ExceptionCode, ModbusException, Table, pack_bits,
                       unpack_bits)
from .server import DEFAULT_HOST, ModbusTcpServer

PSM_PORT = 2605
PSM_BITS = 400            # %IX0.0..%IX49.7 and %QX0.0..%QX49.7
PSM_WORDS = 50            # %IW0..%IW49 and %QW0..%QW49
PSM_BLOCK = 25            # OpenPLC moves words in two blocks of 25
STOP_REGISTER = 50
STOP_VALUE = 127          # OpenPLC's KILL_SIGNAL
ERROR_LIMIT = 10          # psm.cpp's ERROR_LIMIT
STANDS = ("mp9c", "tur10", "thermo")


class PsmError(PlcLabError):
    """The PSM link failed (connect, timeout, malformed or exception response)."""


class PsmImage(Protocol):
    """What the PSM faces need of a ProcessImage."""

    def snapshot(self, area: str, start: int, count: int) -> list[int]: ...

    def publish(self, fn: Callable[[dict[str, list[int]]], None]) -> None: ...


# --------------------------------------------------------------------------- locations

_LOCATION = re.compile(r"^%?(IX|QX|IW|QW)(\d+)(?:\.(\d+))?$", re.IGNORECASE)


def parse_location(location: str) -> tuple[str, int]:
    """'IX1.2' or '%IX1.2' -> ('IX', 10); 'QW3' -> ('QW', 3), within the PSM layout."""
    m = _LOCATION.match(location.strip())
    if not m:
        raise ValueError(f"not a PSM location: {location!r} (IXb.i, QXb.i, IWn, QWn)")
    area, number, bit = m.group(1).upper(), int(m.group(2)), m.group(3)
    if area in ("IX", "QX"):
        if bit is None or int(bit) > 7:
            raise ValueError(f"bit location needs byte.bit with bit 0..7: {location!r}")
        index, size = 8 * number + int(bit), PSM_BITS
    else:
        if bit is not None:
            raise ValueError(f"word location has no bit: {location!r}")
        index, size = number, PSM_WORDS
    if index >= size:
        raise ValueError(f"{location!r} is outside the PSM layout")
    return area, index


# --------------------------------------------------------------------------- plant side

class PsmMap(RegisterMap):
    """OpenPLC's PSM layout over a process image; holding register 50 is the stop request."""

    def __init__(self, image: PsmImage, on_stop: Callable[[], None] = lambda: None):
        self.image = image
        self.on_stop = on_stop
        self.stop_register = 0

    def read(self, table: Table, start: int, count: int) -> list[int]:
        area, size = {Table.DISCRETE_INPUTS: ("IX", PSM_BITS), Table.COILS: ("QX", PSM_BITS),
                      Table.INPUT_REGISTERS: ("IW", PSM_WORDS),
                      Table.HOLDING_REGISTERS: ("QW", PSM_WORDS + 1)}[table]
        self._check(table, start, count, size)
        if table is Table.HOLDING_REGISTERS and start + count > STOP_REGISTER:
            words = self.image.snapshot("QW", start, STOP_REGISTER - start) if start < STOP_REGISTER else []
            return words + [self.stop_register]
        return self.image.snapshot(area, start, count)

    def write(self, table: Table, start: int, values: tuple[int, ...]) -> None:
        if table is Table.COILS:
            self._check(table, start, len(values), PSM_BITS)
            self._store("QX", start, [1 if v else 0 for v in values])
            return
        if table is not Table.HOLDING_REGISTERS:
            raise ModbusException(ExceptionCode.ILLEGAL_FUNCTION, f"writing {table.value}")
        self._check(table, start, len(values), PSM_WORDS + 1)
        words = list(values[:max(0, STOP_REGISTER - start)])
        if words:
            self._store("QW", start, words)
        if start + len(values) > STOP_REGISTER:
            self.stop_register = values[STOP_REGISTER - start]
            if self.stop_register == STOP_VALUE:
                self.on_stop()

    def _store(self, area: str, start: int, values: list[int]) -> None:
        def put(areas: dict[str, list[int]]) -> None:
            areas[area][start:start + len(values)] = values
        self.image.publish(put)

    @staticmethod
    def _check(table: Table, start: int, count: int, size: int) -> None:
        if start + count > size:
            raise ModbusException(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                                  f"PSM {table.value} {start}..{start + count - 1} outside 0..{size - 1}")


class PsmServer(ModbusTcpServer):
    """The plant side of PSM: OpenPLC's PSM layout on 127.0.0.1:2605, serving `image`.

    No idle timeout by default: OpenPLC's client connects once and never reconnects, and a
    stopped PLC leaves its connection idle. Writing 127 to holding register 50 stops the
    server (after the reply is sent); `should_quit()` then turns True.
    """

    def __init__(self, image: PsmImage, host: str = DEFAULT_HOST, port: int = PSM_PORT, *,
                 idle_timeout: float | None = None, max_clients: int = 16):
        self.image = image
        self.psm_map = PsmMap(image, on_stop=self._on_stop)
        self._quit = False
        super().__init__(self.psm_map, host, port, idle_timeout=idle_timeout,
                         max_clients=max_clients, name="psm")

    def _on_stop(self) -> None:
        self._quit = True
        self.request_stop()

    # OpenPLC core/psm/psm.py API, so a plant loop runs unchanged against either.
    def should_quit(self) -> bool:
        return self._quit or self._stopped.is_set()

    def get_var(self, location: str) -> int:
        area, index = parse_location(location)
        return self.image.snapshot(area, index, 1)[0]

    def set_var(self, location: str, value: int | bool) -> None:
        area, index = parse_location(location)
        word = (1 if value else 0) if area.endswith("X") else int(value) & 0xFFFF

        def put(areas: dict[str, list[int]]) -> None:
            areas[area][index] = word
        self.image.publish(put)


class PsmPlant(Protocol):
    """What `plclab.plants.psm_plant(stand)` returns (implemented with the plant models).

    `outputs`: the PSM locations the plant reads each step (e.g. "QX0.0", "QW1");
    `step(outputs, dt)`: advance the model by dt seconds given those values, return the
    locations to set (e.g. {"IX0.0": 1, "IW0": 220}); `period`: seconds between steps.
    """

    period: float
    outputs: list[str]

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, int]: ...


class PsmIo(Protocol):
    """OpenPLC's `psm` module, or a PsmServer."""

    def get_var(self, location: str) -> int: ...

    def set_var(self, location: str, value: int) -> None: ...

    def should_quit(self) -> bool: ...


def drive_plant(plant: PsmPlant, io: PsmIo, *, clock: Callable[[], float] = time.monotonic,
                sleep: Callable[[float], None] = time.sleep) -> int:
    """Step `plant` in real time against `io` until io.should_quit(); returns steps done.

    The same loop as the one psm_script() writes into OpenPLC's main.py.
    """
    steps = 0
    last = clock()
    while not io.should_quit():
        now = clock()
        outputs = {loc: int(io.get_var(loc)) for loc in plant.outputs}
        for loc, value in plant.step(outputs, now - last).items():
            io.set_var(loc, value)
        last = now
        steps += 1
        sleep(plant.period)
    return steps


# --------------------------------------------------------------------------- PLC side

_REQ_FC2 = MBAP.pack(1, 0, 6, 0) + struct.pack(">BHH", 2, 0, PSM_BITS)


def _req_fc4(start: int) -> bytes:
    return MBAP.pack(1, 0, 6, 0) + struct.pack(">BHH", 4, start, PSM_BLOCK)


def _req_fc15(bits: list[int]) -> bytes:
    data = pack_bits(bits)
    return MBAP.pack(1, 0, 7 + len(data), 0) + struct.pack(">BHHB", 15, 0, PSM_BITS, len(data)) + data


def _req_fc16(start: int, words: list[int]) -> bytes:
    data = struct.pack(f">{len(words)}H", *words)
    return (MBAP.pack(1, 0, 7 + len(data), 0)
            + struct.pack(">BHHB", 16, start, len(words), len(data)) + data)


_REQ_STOP = MBAP.pack(1, 0, 6, 0) + struct.pack(">BHH", 6, STOP_REGISTER, STOP_VALUE)


class PsmClient:
    """The PLC side of PSM: exchanges a ProcessImage with a PSM server the way psm.cpp does.

    Call `read_inputs(image)` before a scan and `write_outputs(image)` after it (OpenPLC's
    updateBuffersIn / updateBuffersOut). Failures raise PsmError; after ERROR_LIMIT of them
    the link is disabled (every call raises at once), as in OpenPLC. All 50 %QW are sent in
    order, which equals OpenPLC's gap-free packing when a program uses %QW0.. contiguously.
    """

    def __init__(self, host: str = DEFAULT_HOST, port: int = PSM_PORT, timeout: float = 1.0):
        self.host = host
        self.port = port
        self.timeout = timeout
        self.error_count = 0
        self._sock: socket.socket | None = None

    @property
    def disabled(self) -> bool:
        return self.error_count >= ERROR_LIMIT

    def connect(self) -> "PsmClient":
        try:
            self._sock = socket.create_connection((self.host, self.port), timeout=self.timeout)
        except OSError as exc:
            raise self._fail(f"cannot connect: {exc.strerror or exc}") from None
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return self

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def __enter__(self) -> "PsmClient":
        return self.connect() if self._sock is None else self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def read_inputs(self, image: PsmImage) -> None:
        """%IX0.0..%IX49.7 and %IW0..%IW49 from the plant into the image (one publish)."""
        body = self._exchange(_REQ_FC2, 2)
        if len(body) != 1 + PSM_BITS // 8 or body[0] != PSM_BITS // 8:
            raise self._fail("reading digital inputs: bad byte count")
        bits = unpack_bits(body[1:], PSM_BITS)
        words: list[int] = []
        for start in (0, PSM_BLOCK):
            body = self._exchange(_req_fc4(start), 4)
            if len(body) != 1 + 2 * PSM_BLOCK or body[0] != 2 * PSM_BLOCK:
                raise self._fail("reading analog inputs: bad byte count")
            words.extend(struct.unpack(f">{PSM_BLOCK}H", body[1:]))

        def put(areas: dict[str, list[int]]) -> None:
            areas["IX"][0:PSM_BITS] = bits
            areas["IW"][0:PSM_WORDS] = words
        image.publish(put)

    def write_outputs(self, image: PsmImage) -> None:
        """%QX0.0..%QX49.7 and %QW0..%QW49 from the image to the plant."""
        bits = image.snapshot("QX", 0, PSM_BITS)
        words = [w & 0xFFFF for w in image.snapshot("QW", 0, PSM_WORDS)]
        body = self._exchange(_req_fc15(bits), 15)
        if body != struct.pack(">HH", 0, PSM_BITS):
            raise self._fail("writing digital outputs: bad echo")
        for start in (0, PSM_BLOCK):
            body = self._exchange(_req_fc16(start, words[start:start + PSM_BLOCK]), 16)
            if body != struct.pack(">HH", start, PSM_BLOCK):
                raise self._fail("writing analog outputs: bad echo")

    def request_stop(self) -> None:
        """Tell the plant to quit (holding register 50 = 127); like OpenPLC, no reply is read."""
        if self._sock is None:
            self.connect()
        assert self._sock is not None
        try:
            self._sock.sendall(_REQ_STOP)
        except OSError as exc:
            raise PsmError(f"psm: stop request failed: {exc.strerror or exc}") from None

    # -- framing --------------------------------------------------------------------------
    def _fail(self, what: str) -> PsmError:
        """Count one error (connects included) and make its one-line message."""
        self.error_count += 1
        self.close()    # the stream may be out of step: start the next exchange afresh
        suffix = "; PSM disabled" if self.disabled else ""
        return PsmError(f"psm: {self.host}:{self.port}: {what}{suffix}")

    def _exchange(self, request: bytes, function: int) -> bytes:
        if self.disabled:
            raise PsmError(f"psm: disabled after {ERROR_LIMIT} errors")
        if self._sock is None:
            self.connect()
        assert self._sock is not None
        try:
            self._sock.sendall(request)
            header = self._recv(MBAP_SIZE)
            transaction, protocol, length, _unit = MBAP.unpack(header)
            if protocol != 0 or not 2 <= length <= 254:
                raise self._fail(f"bad response header {header.hex()}")
            pdu = self._recv(length - 1)
        except TimeoutError:
            raise self._fail(f"no response to function {function} within {self.timeout} s") from None
        except OSError as exc:
            raise self._fail(f"function {function}: {exc.strerror or exc}") from None
        if transaction != 1:
            raise self._fail(f"response transaction id {transaction}, expected 1")
        if pdu[0] == function | 0x80:
            code = pdu[1] if len(pdu) > 1 else 0
            raise self._fail(f"function {function} answered exception {code:02d}")
        if pdu[0] != function:
            raise self._fail(f"response function {pdu[0]}, expected {function}")
        return pdu[1:]

    def _recv(self, n: int) -> bytes:
        assert self._sock is not None
        buf = bytearray()
        while len(buf) < n:
            chunk = self._sock.recv(n - len(buf))
            if not chunk:
                raise ConnectionResetError("connection closed by the PSM server")
            buf += chunk
        return bytes(buf)


# --------------------------------------------------------------------------- PSM script

_SCRIPT = '''\
#                  - OpenPLC Python SubModule (PSM) -
#
# PLC Lab: runs the {stand} stand's plant model as OpenPLC's PSM I/O.
# Generated by `plclab psm-script {stand}`; paste it into OpenPLC's PSM editor (the file
# core/psm/main.py). OpenPLC starts this script and connects to it 2 s later, so the PSM
# server is started first and the plant model imported afterwards.
#
# Once per plant period the plant reads PLC outputs ({outputs})
# with psm.get_var() and sets PLC inputs with psm.set_var(), until OpenPLC sends its stop
# request (psm.should_quit()). The plant code is plain Python (no pymodbus needed) found in:
#     {harness}
# Use contiguous %QW from %QW0: OpenPLC packs analog outputs without gaps.

import sys
import time

import psm

HARNESS = {harness!r}
STAND = {stand!r}


def hardware_init():
    psm.start()


if __name__ == "__main__":
    hardware_init()
    try:
        if HARNESS not in sys.path:
            sys.path.insert(0, HARNESS)
        import plclab.plants.{stand}  # noqa: F401  (the stand's plant model)
        from plclab.plants import psm_plant

        plant = psm_plant(STAND)
        last = time.monotonic()
        while not psm.should_quit():
            now = time.monotonic()
            outputs = {{loc: int(psm.get_var(loc)) for loc in plant.outputs}}
            for loc, value in plant.step(outputs, now - last).items():
                psm.set_var(loc, value)
            last = now
            time.sleep(plant.period)
    finally:
        psm.stop()
'''


def psm_script(stand: str, *, harness_dir: str | Path | None = None) -> str:
    """The text of an OpenPLC PSM script (core/psm/main.py) that runs `stand`'s plant model.

    It imports `plclab.plants.<stand>` and gets the plant from the entry point
    `plclab.plants.psm_plant(stand) -> PsmPlant` (see PsmPlant). `harness_dir` is the
    directory holding the `plclab` package (default: this installation's), put on sys.path
    because OpenPLC runs the script with its own virtualenv, where plclab is not installed.
    """
    if stand not in STANDS:
        raise PlcLabError(f"psm-script: unknown stand {stand!r} (one of {', '.join(STANDS)})")
    if harness_dir is None:
        harness_dir = Path(__file__).resolve().parents[2]
    return _SCRIPT.format(stand=stand, harness=str(harness_dir),
                          outputs="%QX0.0..%QX49.7, %QW0..%QW49")
