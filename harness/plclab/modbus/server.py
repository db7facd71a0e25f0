"""Modbus TCP server: an asyncio server in its own thread with its own event loop.

Why a thread with its own loop: the scan (real time or virtual time) must never wait on a
client, and the runtime is not asyncio code. The only contact with the scan is the process
image: reads take a snapshot under its lock, writes are queued and applied by the scan thread.

Robustness rules (a SCADA lab network has confused and hostile clients):
- a frame whose MBAP header cannot be trusted (protocol id != 0, length field < 2 or > 254)
  closes that connection: the byte stream cannot be resynchronised;
- a well-delimited but malformed PDU gets exception 03, an unknown function 01;
- every read of a frame and every drain is bounded by `idle_timeout`, so a silent or
  half-sent client costs one connection slot for at most that long, and never delays others;
- at most `max_clients` connections; more are closed on accept;
- each response goes out with one write (OpenPLC's PSM client reads each response once).
"""
from __future__ import annotations

import asyncio
import logging
import threading
from collections.abc import Iterable

from plclab.errors import PlcLabError

from .maps import RegisterMap
from .protocol import (MAX_LENGTH_FIELD, MBAP, MBAP_SIZE, ExceptionCode, ModbusException,
                       decode_request, encode_response, exception_response, frame)

log = logging.getLogger(__name__)

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 5020          # unprivileged stand-in for 502
DEFAULT_IDLE_TIMEOUT = 60.0
DEFAULT_MAX_CLIENTS = 100


class ServerError(PlcLabError):
    """The server could not start (address in use, permission denied...)."""


def handle_pdu(register_map: RegisterMap, pdu: bytes) -> bytes:
    """Answer one request PDU against a register map: a response PDU, never an exception.

    FC 23 reads first (so a bad read address refuses the whole request before the write is
    queued), writes, then overlays the written values onto the values read: the write is
    queued, not yet applied, and the client must still see its own write.
    """
    function = pdu[0] if pdu else 0
    try:
        request = decode_request(pdu, register_map.functions)
        values: list[int] | None = None
        if request.read is not None:
            r = request.read
            values = register_map.read(r.table, r.start, r.count)
        if request.write is not None:
            w = request.write
            register_map.write(w.table, w.start, w.values)
            if values is not None and request.read is not None:
                r = request.read
                for i, value in enumerate(w.values):
                    j = w.start + i - r.start
                    if 0 <= j < len(values):
                        values[j] = value
        return encode_response(request, values)
    except ModbusException as exc:
        log.debug("modbus: function %d refused: %s", function, exc)
        return exception_response(function, exc.code)
    except Exception:  # noqa: BLE001 - a map bug must cost one response (04), not the server
        log.exception("modbus: function %d failed", function)
        return exception_response(function, ExceptionCode.SERVER_DEVICE_FAILURE)


class ModbusTcpServer:
    """A Modbus TCP server for one register map. `start()` returns once it is listening.

    `port=0` picks a free port (see `.port` after start). `unit_ids=None` answers every unit
    id, like OpenPLC; otherwise requests for other unit ids are dropped unanswered, as a
    device on a serial line would.
    """

    def __init__(self, register_map: RegisterMap, host: str = DEFAULT_HOST,
                 port: int = DEFAULT_PORT, *, unit_ids: Iterable[int] | None = None,
                 idle_timeout: float | None = DEFAULT_IDLE_TIMEOUT,
                 max_clients: int = DEFAULT_MAX_CLIENTS, name: str = "modbus"):
        self.register_map = register_map
        self.host = host
        self.name = name
        self.unit_ids = None if unit_ids is None else frozenset(unit_ids)
        self.idle_timeout = idle_timeout if idle_timeout and idle_timeout > 0 else None
        self.max_clients = max_clients
        self.stats = {"connections": 0, "refused": 0, "requests": 0, "bad_frames": 0,
                      "ignored": 0}
        self._requested_port = port
        self._port: int | None = None
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop_event: asyncio.Event | None = None
        self._stop_requested = False
        self._ready = threading.Event()
        self._stopped = threading.Event()
        self._error: OSError | None = None
        self._tasks: set[asyncio.Task] = set()

    # -- public API -----------------------------------------------------------------------
    @property
    def port(self) -> int:
        """The bound port (the requested one, or the one picked for port 0)."""
        return self._port if self._port is not None else self._requested_port

    @property
    def running(self) -> bool:
        return self._thread is not None and self._ready.is_set() and not self._stopped.is_set()

    def start(self, timeout: float = 5.0) -> "ModbusTcpServer":
        if self._thread is not None:
            raise ServerError(f"{self.name}: already started")
        self._thread = threading.Thread(target=self._run, name=f"{self.name}-server", daemon=True)
        self._thread.start()
        if not self._ready.wait(timeout):
            raise ServerError(f"{self.name}: did not start listening within {timeout} s")
        if self._error is not None:
            self._thread.join(timeout)
            raise ServerError(f"{self.name}: cannot listen on {self.host}:{self._requested_port}: "
                              f"{self._error.strerror or self._error}")
        return self

    def request_stop(self) -> None:
        """Ask the server to stop; safe from any thread, including the server's own."""
        self._stop_requested = True
        loop, event = self._loop, self._stop_event
        if loop is not None and event is not None and not loop.is_closed():
            try:
                loop.call_soon_threadsafe(event.set)
            except RuntimeError:  # loop closed between the check and the call
                pass

    def stop(self, timeout: float = 5.0) -> None:
        """Stop and wait for the server thread; closes every client connection."""
        self.request_stop()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout)

    def wait(self, timeout: float | None = None) -> bool:
        """Block until the server has stopped; True if it has."""
        return self._stopped.wait(timeout)

    def __enter__(self) -> "ModbusTcpServer":
        return self.start() if self._thread is None else self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # -- event loop thread ----------------------------------------------------------------
    def _run(self) -> None:
        try:
            asyncio.run(self._main())   # cancels leftover tasks and closes the loop at the end
        finally:
            self._stopped.set()
            self._ready.set()

    async def _main(self) -> None:
        loop = asyncio.get_running_loop()
        self._loop = loop
        self._stop_event = asyncio.Event()
        transports: set[asyncio.BaseTransport] = set()

        def protocol() -> asyncio.StreamReaderProtocol:
            return _TrackedProtocol(asyncio.StreamReader(loop=loop), self._serve_client, transports)
        try:
            server = await loop.create_server(protocol, self.host, self._requested_port,
                                              reuse_address=True, backlog=128)
        except OSError as exc:
            self._error = exc
            return
        self._port = server.sockets[0].getsockname()[1]
        self._ready.set()
        log.info("%s: listening on %s:%d", self.name, self.host, self._port)
        try:
            if not self._stop_requested:
                await self._stop_event.wait()
        finally:
            server.close()
            # A connection accepted just before the stop gets its transport one or two loop
            # iterations later (asyncio's accept is itself a task); let those complete so
            # that every accepted connection is closed below. (The kernel resets those never
            # accepted when the listening socket closes.)
            for _ in range(3):
                await asyncio.sleep(0)
            # close() (not abort) still flushes a reply already written (PSM stop).
            for transport in list(transports):
                transport.close()
            for task in list(self._tasks):
                task.cancel()
            await asyncio.gather(*self._tasks, return_exceptions=True)
            await server.wait_closed()
            log.info("%s: stopped", self.name)

    async def _serve_client(self, reader: asyncio.StreamReader,
                            writer: asyncio.StreamWriter) -> None:
        if len(self._tasks) >= self.max_clients or self._stop_requested:
            self.stats["refused"] += 1
            writer.transport.abort()
            return
        task = asyncio.current_task()
        assert task is not None
        self._tasks.add(task)
        self.stats["connections"] += 1
        try:
            await self._session(reader, writer)
        except (asyncio.IncompleteReadError, ConnectionError, TimeoutError):
            pass  # the client went away, or idled past the timeout
        except asyncio.CancelledError:
            pass  # server stopping; ending normally keeps asyncio from logging the cancel
        finally:
            self._tasks.discard(task)
            if writer.transport.get_write_buffer_size():
                writer.transport.abort()   # a client that does not read gets no more time
            else:
                writer.close()

    async def _session(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        while True:
            async with asyncio.timeout(self.idle_timeout):
                header = await reader.readexactly(MBAP_SIZE)
                transaction, protocol, length, unit = MBAP.unpack(header)
                if protocol != 0 or not 2 <= length <= MAX_LENGTH_FIELD:
                    self.stats["bad_frames"] += 1
                    log.info("%s: closing a connection: bad MBAP header %s", self.name,
                             header.hex())
                    return
                pdu = await reader.readexactly(length - 1)
            if self.unit_ids is not None and unit not in self.unit_ids:
                self.stats["ignored"] += 1
                continue
            response = handle_pdu(self.register_map, pdu)
            self.stats["requests"] += 1
            writer.write(frame(transaction, unit, response))
            async with asyncio.timeout(self.idle_timeout):
                await writer.drain()


class _TrackedProtocol(asyncio.StreamReaderProtocol):
    """StreamReaderProtocol that records its transport, so stop() can close every connection."""

    def __init__(self, reader: asyncio.StreamReader, callback, transports: set):
        super().__init__(reader, callback)
        self._transports = transports
        self._tracked: asyncio.BaseTransport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self._tracked = transport
        self._transports.add(transport)
        super().connection_made(transport)

    def connection_lost(self, exc: Exception | None) -> None:
        self._transports.discard(self._tracked)
        super().connection_lost(exc)
