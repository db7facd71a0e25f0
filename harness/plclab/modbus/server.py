"""Modbus TCP server: an asyncio server in its own thread with its own event loop.

Why a thread with its own loop: the scan (real time or virtual time) must never wait on a
client, and the runtime is not asyncio code. The only contact with the scan is the process
image: reads take a snapshot under its lock, writes are queued and applied by the scan thread.

Robustness rules (a SCADA lab network has confused and hostile clients):
- a frame whose MBAP header cannot be trusted (protocol id != 0, length field < 2 or > 254)
  closes that connection: the byte stream cannot be resynchronised;
- a well-delimited but malformed PDU gets exception 03, an unknown function 01;
- a whole request must arrive within `idle_timeout` of the previous one, and the first one
  within `first_request_timeout` of connecting (short: a connection that never asks for
  anything is a port scan or a stuck client), so a silent or half-sent client costs one
  connection slot for a bounded time, and never delays others;
- a client that does not read its replies is not read from until it does (flow control);
- at most `max_clients` connections; when the face is full, the connection idle the longest
  is closed to admit the new one (counted in stats["evicted"]), so idle clients can never lock
  the others out (`evict_when_full=False`: the new connection is closed instead);
- while `health()` names a problem (the PLC is in FAULT, its scan loop stopped), every request
  is answered with exception 04 (server device failure): a SCADA client sees the fault instead
  of stale values behind a live face;
- each response goes out with one write (OpenPLC's PSM client reads each response once).
"""
from __future__ import annotations

import asyncio
import logging
import socket
import threading
from collections.abc import Callable, Iterable

from plclab.errors import PlcLabError

from .maps import RegisterMap
from .protocol import (MAX_LENGTH_FIELD, MBAP, MBAP_SIZE, ExceptionCode, ModbusException,
                       decode_request, encode_response, exception_response, frame)

log = logging.getLogger(__name__)

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 5020          # unprivileged stand-in for 502
DEFAULT_IDLE_TIMEOUT = 60.0
DEFAULT_FIRST_REQUEST_TIMEOUT = 5.0
DEFAULT_MAX_CLIENTS = 100


class ServerError(PlcLabError):
    """The server could not start (address in use, permission denied...)."""


def handle_pdu(register_map: RegisterMap, pdu: bytes) -> bytes:
    """Answer one request PDU against a register map: a response PDU, never an exception."""
    return answer_pdu(register_map, pdu)[0]


def answer_pdu(register_map: RegisterMap, pdu: bytes) -> tuple[bytes, ModbusException | None]:
    """`handle_pdu` with the refusal that made an exception response (its reason names the
    rule), for whoever explains refusals (the SCADA grader).

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
        return encode_response(request, values), None
    except ModbusException as exc:
        log.debug("modbus: function %d refused: %s", function, exc)
        return exception_response(function, exc.code), exc
    except Exception:  # noqa: BLE001 - a map bug must cost one response (04), not the server
        log.exception("modbus: function %d failed", function)
        failure = ModbusException(ExceptionCode.SERVER_DEVICE_FAILURE, "the server failed on this request")
        return exception_response(function, failure.code), failure


class ModbusTcpServer:
    """A Modbus TCP server for one register map. `start()` returns once it is listening.

    `port=0` picks a free port (see `.port` after start). `unit_ids=None` answers every unit
    id, like OpenPLC; otherwise requests for other unit ids are dropped unanswered, as a
    device on a serial line would.
    """

    def __init__(self, register_map: RegisterMap, host: str = DEFAULT_HOST,
                 port: int = DEFAULT_PORT, *, unit_ids: Iterable[int] | None = None,
                 idle_timeout: float | None = DEFAULT_IDLE_TIMEOUT,
                 max_clients: int = DEFAULT_MAX_CLIENTS, name: str = "modbus",
                 on_request: Callable[[int, bytes, bytes], None] | None = None,
                 first_request_timeout: float | None = DEFAULT_FIRST_REQUEST_TIMEOUT,
                 evict_when_full: bool = True, health: Callable[[], str | None] | None = None,
                 max_requests_per_s: float | None = None):
        if not 0 <= int(port) <= 65535:
            raise ServerError(f"{name}: port {port} is not a TCP port (1..65535, or 0 for any free port)")
        self.register_map = register_map
        self.host = host
        self.name = name
        self.unit_ids = None if unit_ids is None else frozenset(unit_ids)
        self.idle_timeout = idle_timeout if idle_timeout and idle_timeout > 0 else None
        self.first_request_timeout = first_request_timeout if first_request_timeout and first_request_timeout > 0 \
            else self.idle_timeout
        self.max_clients = max_clients
        self.on_request = on_request     # (unit, request PDU, response PDU) of each answered request
        self.evict_when_full = evict_when_full
        self.health = health
        self.stats = {"connections": 0, "refused": 0, "evicted": 0, "requests": 0, "bad_frames": 0,
                      "ignored": 0, "faulted": 0, "throttled": 0}
        # admission control (None: unlimited): a token bucket of max_requests_per_s, a burst of
        # 20 ms worth; a request with no token waits (its connection is not read) until one is
        self.max_requests_per_s = max_requests_per_s if max_requests_per_s and max_requests_per_s > 0 else None
        self._burst = max(1.0, (self.max_requests_per_s or 0) * 0.02)
        self._tokens = self._burst
        self._refilled = 0.0
        self._requested_port = port
        self._port: int | None = None
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop_event: asyncio.Event | None = None
        self._stop_requested = False
        self._ready = threading.Event()
        self._stopped = threading.Event()
        self._error: OSError | None = None
        self._connections: set[_Connection] = set()
        self._attaching = 0        # accepted sockets whose connection is not made yet

    # -- public API -----------------------------------------------------------------------
    @property
    def port(self) -> int:
        """The bound port (the requested one, or the one picked for port 0)."""
        return self._port if self._port is not None else self._requested_port

    @property
    def active_clients(self) -> int:
        """Connections open right now (for status lines)."""
        return len(self._connections)

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
            reason = self._error.strerror or str(self._error)
            raise ServerError(f"{self.name}: cannot listen on {self.host}:{self._requested_port}: "
                              f"{reason}")
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

    def _listen(self) -> socket.socket:
        family, kind, proto, _name, address = socket.getaddrinfo(
            self.host, self._requested_port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)[0]
        sock = socket.socket(family, kind, proto)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind(address)
            sock.listen(128)
            sock.setblocking(False)
        except OSError:
            sock.close()
            raise
        return sock

    async def _main(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._stop_event = asyncio.Event()
        try:
            listener = self._listen()
        except OSError as exc:
            self._error = exc
            return
        self._port = listener.getsockname()[1]
        self._ready.set()
        log.info("%s: listening on %s:%d", self.name, self.host, self._port)
        loop = self._loop
        attaching: set[asyncio.Task] = set()
        loop.add_reader(listener.fileno(), self._accept, listener, attaching)
        try:
            if not self._stop_requested:
                await self._stop_event.wait()
        finally:
            # Nothing that holds an accepted socket is ever cancelled (a cancelled accept or
            # attach can drop the socket unclosed): stop accepting, let attaches finish,
            # then close every connection.
            loop.remove_reader(listener.fileno())
            listener.close()       # the kernel resets connections never accepted
            if attaching:
                await asyncio.wait(attaching, timeout=5.0)
            for conn in list(self._connections):
                conn.close()       # flushes a reply already written (the PSM stop reply)
            await asyncio.sleep(0)
            log.info("%s: stopped", self.name)

    def _accept(self, listener: socket.socket, attaching: set[asyncio.Task]) -> None:
        """Reader callback of the listening socket: accept what is waiting, without awaiting."""
        for _ in range(64):        # a burst at most, then let the loop serve the others
            try:
                sock, _peer = listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:  # e.g. out of file descriptors: keep serving the others
                log.warning("%s: accept failed: %s", self.name, exc)
                return
            if self._stop_requested or (len(self._connections) + self._attaching >= self.max_clients
                                        and not self._evict_one()):
                self.stats["refused"] += 1
                sock.close()
                continue
            self.stats["connections"] += 1
            sock.setblocking(False)
            task = asyncio.get_running_loop().create_task(self._attach(sock))
            self._attaching += 1        # a slot taken until connection_made (or the attach fails)
            attaching.add(task)
            task.add_done_callback(attaching.discard)

    def _evict_one(self) -> bool:
        """The face is full: close the connection idle the longest to make room; False if
        there is none to close (eviction off, or every slot is still being attached)."""
        if not self.evict_when_full or not self._connections:
            return False
        victim = min(self._connections, key=lambda c: c.last_active)
        self._connections.discard(victim)       # its slot is free now, not when the loop notices
        victim.close(abort=True)
        self.stats["evicted"] += 1
        log.info("%s: full (%d clients): closed the connection idle the longest", self.name, self.max_clients)
        return True

    async def _attach(self, sock: socket.socket) -> None:
        made: list[_Connection] = []

        def connection() -> _Connection:
            made.append(_Connection(self))
            return made[0]
        try:
            await asyncio.get_running_loop().connect_accepted_socket(connection, sock)
        except OSError:
            sock.close()
            if not made or made[0].transport is None:
                self._attaching -= 1    # connection_made never ran: give the slot back here

    def _admit(self, now: float) -> float:
        """Admission control: 0 if a request may be answered now (a token is taken), else how
        many seconds until the next token."""
        rate = self.max_requests_per_s
        if rate is None:
            return 0.0
        self._tokens = min(self._burst, self._tokens + (now - self._refilled) * rate)
        self._refilled = now
        if self._tokens >= 1.0:
            self._tokens -= 1.0
            return 0.0
        self.stats["throttled"] += 1
        return (1.0 - self._tokens) / rate

    def _handle_frame(self, transaction: int, unit: int, pdu: bytes) -> bytes | None:
        """The response ADU for one request frame, or None to send nothing."""
        if self.unit_ids is not None and unit not in self.unit_ids:
            self.stats["ignored"] += 1
            return None
        self.stats["requests"] += 1
        if self.health is not None and self.health() is not None:
            self.stats["faulted"] += 1
            return frame(transaction, unit, exception_response(pdu[0], ExceptionCode.SERVER_DEVICE_FAILURE))
        response = handle_pdu(self.register_map, pdu)
        if self.on_request is not None:
            try:
                self.on_request(unit, pdu, response)
            except Exception:  # noqa: BLE001 - an observer's bug must not cost the client its answer
                log.exception("%s: request observer failed", self.name)
        return frame(transaction, unit, response)


class _Connection(asyncio.Protocol):
    """One client: frames are cut from the byte stream by their MBAP length and answered in
    order, synchronously (a request never waits on anything but the image lock)."""

    def __init__(self, server: ModbusTcpServer):
        self.server = server
        self.transport: asyncio.Transport | None = None
        self.buffer = bytearray()
        self.timer: asyncio.TimerHandle | None = None
        self.requests = 0                       # whole request frames received
        self.last_active = 0.0                  # loop time of connecting or of the last request
        self.write_paused = False               # the client does not read its replies
        self.throttled: asyncio.TimerHandle | None = None   # waiting for admission

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        transport.set_write_buffer_limits(high=64 * 1024)
        sock = transport.get_extra_info("socket")
        if sock is not None:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.server._attaching -= 1
        self.server._connections.add(self)
        self.last_active = asyncio.get_running_loop().time()
        self._arm()

    def connection_lost(self, exc: Exception | None) -> None:
        if self.timer is not None:
            self.timer.cancel()
        if self.throttled is not None:
            self.throttled.cancel()
            self.throttled = None
        self.server._connections.discard(self)

    def data_received(self, data: bytes) -> None:
        self.buffer += data
        server = self.server
        while len(self.buffer) >= MBAP_SIZE and not server._stop_requested and self.throttled is None \
                and not (self.transport is not None and self.transport.is_closing()):   # a client gone: answer no more
            transaction, protocol, length, unit = MBAP.unpack_from(self.buffer)
            if protocol != 0 or not 2 <= length <= MAX_LENGTH_FIELD:
                server.stats["bad_frames"] += 1
                log.info("%s: closing a connection: bad MBAP header %s", server.name,
                         bytes(self.buffer[:MBAP_SIZE]).hex())
                self.close()
                return
            end = MBAP_SIZE - 1 + length
            if len(self.buffer) < end:
                break
            loop = asyncio.get_running_loop()
            wait = server._admit(loop.time())
            if wait > 0:                     # over the face's request rate: read no more until admitted
                if self.transport is not None:
                    self.transport.pause_reading()
                self.throttled = loop.call_later(wait, self._admitted)
                break
            pdu = bytes(self.buffer[MBAP_SIZE:end])
            del self.buffer[:end]
            self.requests += 1
            self.last_active = asyncio.get_running_loop().time()
            reply = server._handle_frame(transaction, unit, pdu)
            if reply is not None and self.transport is not None:
                self.transport.write(reply)
            self._arm()

    def _admitted(self) -> None:
        """The wait for admission is over: answer what is buffered, then read again."""
        self.throttled = None
        if self.transport is None or self.transport.is_closing():
            return
        self.data_received(b"")
        if self.throttled is None and not self.write_paused:
            self.transport.resume_reading()

    def pause_writing(self) -> None:
        """The client does not read its replies: stop reading its requests until it does."""
        self.write_paused = True
        if self.transport is not None:
            self.transport.pause_reading()

    def resume_writing(self) -> None:
        self.write_paused = False
        if self.transport is not None and not self.transport.is_closing() and self.throttled is None:
            self.transport.resume_reading()

    def close(self, abort: bool = False) -> None:
        transport = self.transport
        if transport is None or transport.is_closing():
            return
        if abort or transport.get_write_buffer_size():
            transport.abort()      # a client that does not read gets no more time
        else:
            transport.close()

    def _arm(self) -> None:
        """(Re)start the idle timer: a whole request must arrive within idle_timeout (the
        first one within first_request_timeout)."""
        if self.timer is not None:
            self.timer.cancel()
        timeout = self.server.idle_timeout if self.requests else self.server.first_request_timeout
        if timeout is not None and self.transport is not None:
            self.timer = asyncio.get_running_loop().call_later(timeout, self._idle)

    def _idle(self) -> None:
        log.debug("%s: closing an idle connection", self.server.name)
        self.close()
