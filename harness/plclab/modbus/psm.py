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

The plant side is `PsmServer`: it serves a ProcessImage with that layout. With a PlantHost
it steps the plant in lockstep with the PLC: the first request of each of psm.cpp's polls
(FC 2 from 0) steps the plant once with the outputs the previous scan wrote, before the
inputs are read back, so the one scan of sensor latency holds whatever the scan time.
Writes from the PLC land in the image at once, under its lock. `PlantService` is the whole
plant process: the PSM server and the console face (plclab.modbus.console) on one plant.

The PLC side is `PsmClient`, sending the same frames as psm.cpp for this project's real-time
runtime, but reading each response whole and checking it.

`psm_script(stand)` is the text of an OpenPLC `core/psm/main.py` that runs a stand's plant:
the modules it needs are embedded in it, so it runs with nothing but OpenPLC's own Python.
"""
from __future__ import annotations

import base64
import importlib
import importlib.util
import socket
import struct
import textwrap
import zlib
from typing import Any, Callable, Optional, Protocol

from plclab.errors import PlcLabError
from plclab.iec.address import AddressError
from plclab.runtime.image import image_slot

from .console import CONSOLE_PORT, FAULT_LAMP, start_console_face
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
STANDS = ("mp9c", "tur10", "thermo", "cnc")


class PsmError(PlcLabError):
    """The PSM link failed (connect, timeout, malformed or exception response)."""


class PsmImage(Protocol):
    """What the PSM faces need of a ProcessImage."""

    def snapshot(self, area: str, start: int, count: int) -> list[int]: ...

    def publish(self, fn: Callable[[dict[str, list[int]]], None]) -> None: ...


# --------------------------------------------------------------------------- locations

def parse_location(location: str) -> tuple[str, int]:
    """'IX1.2' or '%IX1.2' -> ('IX', 10); 'QW3' -> ('QW', 3), within the PSM layout (an
    AddressError, a ValueError, otherwise)."""
    area, index = image_slot(location, percent=False)
    if area not in ("IX", "QX", "IW", "QW") or index >= (PSM_BITS if area[1] == "X" else PSM_WORDS):
        raise AddressError(f"{location}: outside OpenPLC's PSM layout (%IX0.0..%IX49.7, %QX0.0..%QX49.7, "
                           f"%IW0..%IW49, %QW0..%QW49)")
    return area, index


# --------------------------------------------------------------------------- plant side

class PsmMap(RegisterMap):
    """OpenPLC's PSM layout over a process image; holding register 50 is the stop request.
    `on_poll` runs before each read of the discrete inputs from 0: psm.cpp's first request
    of every poll, sent once per scan."""

    def __init__(self, image: PsmImage, on_stop: Callable[[], None] = lambda: None,
                 on_poll: Callable[[], None] = lambda: None):
        self.image = image
        self.on_stop = on_stop
        self.on_poll = on_poll
        self.stop_register = 0

    def read(self, table: Table, start: int, count: int) -> list[int]:
        if table is Table.DISCRETE_INPUTS and start == 0:
            self.on_poll()
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
    """The plant side of PSM: OpenPLC's PSM layout on 127.0.0.1:2605, serving `image`, and
    with `plant` (a PlantHost) stepping it once per poll of the PLC.

    No idle timeout by default: OpenPLC's client connects once and never reconnects, and a
    stopped PLC leaves its connection idle (closing it would kill OpenPLC with SIGPIPE).
    Writing 127 to holding register 50 stops the server (after the reply is sent);
    `should_quit()` then turns True.
    """

    def __init__(self, image: PsmImage, host: str = DEFAULT_HOST, port: int = PSM_PORT, *,
                 plant: Any = None, idle_timeout: float | None = None, max_clients: int = 16):
        self.image = image
        self.plant = plant
        self._outs = [(loc, *parse_location(loc)) for loc in plant.outputs] if plant is not None else []
        self._where: dict[str, tuple[str, int]] = {}      # input location -> (area, index)
        self.psm_map = PsmMap(image, on_stop=self._on_stop,
                              on_poll=self._step_plant if plant is not None else lambda: None)
        self._quit = False
        super().__init__(self.psm_map, host, port, idle_timeout=idle_timeout,
                         max_clients=max_clients, name="psm")

    def _step_plant(self) -> None:
        """Outputs of the last scan -> one plant step -> inputs for the next scan."""
        image = self.image
        outputs = {loc: image.snapshot(area, index, 1)[0] for loc, area, index in self._outs}
        where = self._where
        inputs = []
        for loc, value in self.plant.exchange(outputs).items():
            if loc not in where:
                where[loc] = parse_location(loc)
            inputs.append((*where[loc], value))

        def put(areas: dict[str, list[int]]) -> None:
            for area, index, value in inputs:
                areas[area][index] = (1 if value else 0) if area == "IX" else int(value) & 0xFFFF
        image.publish(put)

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




# --------------------------------------------------------------------------- plant process

class PlantService:
    """The plant side as a whole: the lockstep PSM server and the console face, one plant.

    `plant` is a PlantHost (plclab.plants.host). `console=None` serves no console face; a
    console port that cannot be had costs a warning (through `report`), not the plant.
    """

    def __init__(self, plant: Any, psm: tuple[str, int] = (DEFAULT_HOST, PSM_PORT),
                 console: tuple[str, int] | None = (DEFAULT_HOST, CONSOLE_PORT),
                 report: Callable[[str], None] = print):
        from plclab.runtime.image import ProcessImage

        self.plant = plant
        self.psm = PsmServer(ProcessImage(), psm[0], psm[1], plant=plant)
        self.console_address = console
        self.console = None
        self.report = report

    def start(self) -> "PlantService":
        self.psm.start()
        if self.console_address is not None:
            self.console = start_console_face(self.plant, self.console_address, self.report)
        return self

    def where(self) -> str:
        console = (f"console face on {self.console.host}:{self.console.port}" if self.console is not None
                   else "no console face")
        return f"PSM I/O on {self.psm.host}:{self.psm.port}, {console}"

    def wait(self, timeout: float | None = None) -> bool:
        """Until OpenPLC's stop request (or timeout); True once stopped."""
        return self.psm.wait(timeout)

    def stop(self) -> None:
        self.psm.stop()
        if self.console is not None:
            self.console.stop()

    def __enter__(self) -> "PlantService":
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


def run_plant(stand: str, psm: tuple[str, int] = (DEFAULT_HOST, PSM_PORT),
              console: tuple[str, int] | None = (DEFAULT_HOST, CONSOLE_PORT), *,
              traceback: bool = False, out: Callable[[str], None] = print,
              params: dict[str, Any] | None = None) -> int:
    """Run `stand`'s plant (made with `params`) as a PSM server with its console face until
    OpenPLC's stop request (the PSM script's and `plclab plant --psm`'s main loop); Ctrl-C
    also stops it."""
    import sys

    from plclab.plants import make_plant
    from plclab.plants.host import PlantHost

    def report(text: str) -> None:
        sys.stderr.write(text + "\n")
        sys.stderr.flush()

    host = PlantHost(make_plant(stand, **(params or {})), report=report, traceback=traceback)
    service = PlantService(host, psm, console, report=report).start()
    out(f"{stand} plant: {service.where()}; stops on 127 in holding register 50")
    try:
        while not service.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        service.stop()
    out(f"{stand} plant stopped after {host.steps} steps")
    return 0


# --------------------------------------------------------------------------- PSM script

# What the script embeds: the modules run_plant needs, standard library only. Packages whose
# __init__ imports more than these are embedded empty.
_EMBEDDED = ("plclab.errors", "plclab.iec.address", "plclab.runtime.image", "plclab.modbus.protocol",
             "plclab.modbus.profiles", "plclab.modbus.maps", "plclab.modbus.rawclient", "plclab.modbus.server",
             "plclab.modbus.console", "plclab.modbus.psm", "plclab.plants", "plclab.plants.base",
             "plclab.plants.host")
_EMPTY_PACKAGES = ("plclab", "plclab.iec", "plclab.runtime", "plclab.modbus")

_SCRIPT = '''\
#                  - OpenPLC Python SubModule (PSM) -
#
# PLC Lab: the {stand} stand's plant model as OpenPLC's I/O, and its console face.
# Generated by `plclab psm-script {stand}`; paste it into OpenPLC's PSM editor (Hardware page,
# hardware layer "Python on Linux (PSM)"; it is saved as core/psm/main.py). See docs/openplc.md.
#
# - It serves OpenPLC's PSM client itself on {psm_host}:{psm_port} (OpenPLC's own `psm` module
#   and pymodbus are not used): each poll of the PLC, once per scan, steps the plant once with
#   the outputs of the last scan over the real time elapsed, then the PLC reads its inputs.
# - Console face: Modbus TCP on {console_host}:{console_port}:
{face}
#   Set CONSOLE below to ("0.0.0.0", {console_port}) to reach it from another machine.
# - A plant error never stops the PLC: the inputs freeze, the error and its traceback go to
#   OpenPLC's log once, the PLANT_FAULT lamp lights. Only OpenPLC's stop request ends it.
# - Nothing to install: the PLC Lab modules it needs (standard library only) are embedded
#   below, zlib-compressed and base64-encoded:
{modules}

import base64
import importlib.abc
import importlib.util
import linecache
import sys
import zlib

STAND = {stand!r}
PSM = ({psm_host!r}, {psm_port})            # OpenPLC's PSM client connects to 127.0.0.1:2605
CONSOLE = ({console_host!r}, {console_port})

PLANT = {plant!r}                        # the plant's parameters (cnc: as the OpenPLC bundle needs)
PACKAGES = {packages!r}
EMBEDDED = {{
{embedded}
}}


class EmbeddedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Imports the embedded modules (first, so no other copy of them is used)."""

    def find_spec(self, name, path=None, target=None):
        if name in EMBEDDED:
            return importlib.util.spec_from_loader(name, self, is_package=name in PACKAGES)
        return None

    def create_module(self, spec):
        return None

    def exec_module(self, module):
        source = zlib.decompress(base64.b64decode(EMBEDDED[module.__name__])).decode("utf-8")
        filename = "<plclab: " + module.__name__ + ">"
        linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)  # tracebacks
        exec(compile(source, filename, "exec"), module.__dict__)


if __name__ == "__main__":
    sys.meta_path.insert(0, EmbeddedModules())
    from plclab.modbus.psm import run_plant

    sys.exit(run_plant(STAND, PSM, CONSOLE, traceback=True, out=lambda line: print(line, flush=True),
                       params=PLANT))
'''


def _module_source(name: str) -> str:
    if name in _EMPTY_PACKAGES:
        return ""
    spec = importlib.util.find_spec(name)
    if spec is None or spec.origin is None:
        raise PlcLabError(f"psm-script: cannot find the source of {name}")
    with open(spec.origin, encoding="utf-8") as f:
        return f.read()


def psm_script(stand: str, *, psm: tuple[str, int] = (DEFAULT_HOST, PSM_PORT),
               console: tuple[str, int] = (DEFAULT_HOST, CONSOLE_PORT),
               plant: Optional[dict[str, Any]] = None) -> str:
    """The text of an OpenPLC PSM script (core/psm/main.py) that runs `stand`'s plant with
    run_plant(): the PLC Lab modules it needs are embedded, so it depends on no path of this
    installation and needs nothing but a Python 3 (OpenPLC's own). `plant`: the parameters
    the plant starts with (the cnc stand's come from the bundle it runs with, plclab.cnc.openplc,
    which the command line passes: the Modbus layer knows no stand's program)."""
    if stand not in STANDS:
        raise PlcLabError(f"psm-script: unknown stand {stand!r} (one of {', '.join(STANDS)})")
    modules = _EMBEDDED + (f"plclab.plants.{stand}",) + _EMPTY_PACKAGES
    packages = tuple(sorted(set(_EMPTY_PACKAGES) | {"plclab.plants"}))
    lines = []
    for name in sorted(modules):
        blob = base64.b64encode(zlib.compress(_module_source(name).encode("utf-8"), 9)).decode("ascii")
        chunks = [blob[i:i + 76] for i in range(0, len(blob), 76)] or [""]
        lines.append(f"    {name!r}: (\n" + "\n".join(f"        {c!r}" for c in chunks) + "),")
    face = importlib.import_module(f"plclab.plants.{stand}").FACE
    tables = (("coils", face.switches), ("discrete inputs", [label for label, _ in face.lamps] + [FAULT_LAMP]),
              ("input registers", [f"{name} ({unit})" for name, unit in face.readouts]))
    face_lines = [textwrap.fill(f"{table} 0..: " + ", ".join(names), 92, initial_indent="#   ",
                                subsequent_indent="#       ") for table, names in tables]
    if face.tape:
        face_lines.append(f"#   holding registers 0..{face.tape - 1}: the tape reader (plclab console {stand} --part)")
    return _SCRIPT.format(
        plant=dict(plant or {}), stand=stand, psm_host=psm[0], psm_port=psm[1], console_host=console[0], console_port=console[1],
        face="\n".join(face_lines), packages=packages, embedded="\n".join(lines),
        modules=textwrap.fill(", ".join(sorted(modules)), 92, initial_indent="#   ", subsequent_indent="#   "))
