"""A Modbus traffic log: every request a client sent to a server face, with its time.

Why: the SCADA exercises are graded on what a student's client did on the wire (which
registers it read, how often, what it wrote), whatever the client is (the project's HMI,
mbpoll, FUXA, ClearSCADA). The server records each answered request through its `on_request`
hook; the log is a CSV file an instructor keeps and can grade again later:

    # plclab modbus traffic; duration_s=120.000
    time_s,unit,request,response,what
    0.300,1,0300000007,...,read %MW0..%MW6
    2.100,1,0600020bb8,8603,write %MW2 = 3000 -> exception 03 (illegal data value)

`request` and `response` are the PDUs in hex (function code and data, no MBAP header), so the
log is exact; `what` is for people and is not read back. `time_s` is the PLC's time when the
request was answered (wall-clock time of `serve`, or virtual time), to the microsecond.
"""
from __future__ import annotations

import csv
import io
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

from plclab import fileio
from plclab.errors import PlcLabError

from .protocol import ALL_FUNCTIONS, ExceptionCode, ModbusException, Request, Table, decode_request

HEADER = ("time_s", "unit", "request", "response", "what")
MAGIC = "# plclab modbus traffic"
MAX_TIME_S = 86400.0                # a log is replayed scan by scan: a day of lab session at most
FUNCTION_NAMES = {1: "read coils", 2: "read discrete inputs", 3: "read holding registers",
                  4: "read input registers", 5: "write single coil", 6: "write single register",
                  15: "write multiple coils", 16: "write multiple registers",
                  23: "read/write multiple registers"}


@dataclass(frozen=True)
class Exchange:
    """One request and the server's answer."""

    time_s: float
    unit: int
    request: bytes                  # PDU: function code + data
    response: bytes                 # PDU; an exception response has function | 0x80

    @property
    def function(self) -> int:
        return self.request[0] if self.request else 0

    @property
    def exception(self) -> Optional[int]:
        """The exception code the server answered with, or None if it was accepted."""
        if len(self.response) >= 2 and self.response[0] & 0x80:
            return self.response[1]
        return None

    def decoded(self) -> Optional[Request]:
        """The request decoded (any function the protocol knows), or None if malformed."""
        try:
            return decode_request(self.request, ALL_FUNCTIONS)
        except ModbusException:
            return None

    def what(self) -> str:
        """The request in words: `read %MW0..%MW6`, `write %MW2 = 1500`, `read input registers 3`."""
        return describe(self.request) + (f" -> exception {self.exception:02d} ({exception_name(self.exception)})"
                                         if self.exception is not None else "")


def exception_name(code: int) -> str:
    """`illegal data value` for 03: the specification's name of an exception code."""
    try:
        return ExceptionCode(code).name.lower().replace("_", " ")
    except ValueError:
        return "unknown exception"


def describe(pdu: bytes) -> str:
    """A request PDU in words, holding registers as %MWn (the Twido map)."""
    function = pdu[0] if pdu else 0
    try:
        req = decode_request(pdu, ALL_FUNCTIONS)
    except ModbusException:
        return f"function {function} ({FUNCTION_NAMES.get(function, 'unknown')}), malformed: {pdu.hex()}"
    parts = []
    if req.read is not None:
        parts.append("read " + _span(req.read.table, req.read.start, req.read.count))
    if req.write is not None:
        w = req.write
        values = ", ".join(str(v - 0x10000 if w.table is Table.HOLDING_REGISTERS and v >= 0x8000 else v)
                           for v in w.values)
        parts.append(f"write {_span(w.table, w.start, len(w.values))} = {values}")
    return "; ".join(parts)


def _span(table: Table, start: int, count: int) -> str:
    if table is Table.HOLDING_REGISTERS:
        return f"%MW{start}" if count == 1 else f"%MW{start}..%MW{start + count - 1}"
    where = f"{start}" if count == 1 else f"{start}..{start + count - 1}"
    return f"{table.value} {where}"


@dataclass
class Traffic:
    """A recording: the exchanges in time order and how long the recording lasted."""

    exchanges: list[Exchange]
    duration_s: float

    def csv_text(self) -> str:
        buf = io.StringIO()
        buf.write(f"{MAGIC}; duration_s={self.duration_s:.3f}\n")
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(HEADER)
        for e in self.exchanges:
            w.writerow([_seconds(e.time_s), e.unit, e.request.hex(), e.response.hex(), e.what()])
        return buf.getvalue()


def _seconds(t: float) -> str:
    """Milliseconds always, microseconds when there are any: `2.500`, `0.000003`."""
    text = f"{t:.6f}"
    while text.endswith("0") and len(text.partition(".")[2]) > 3:
        text = text[:-1]
    return text


class TrafficRecorder:
    """The server's `on_request` hook: records each answered request with `clock()` (s)."""

    def __init__(self, clock: Callable[[], float]):
        self.clock = clock
        self._lock = threading.Lock()
        self._exchanges: list[Exchange] = []

    def __call__(self, unit: int, request: bytes, response: bytes) -> None:
        with self._lock:
            self._exchanges.append(Exchange(round(self.clock(), 6), unit, bytes(request), bytes(response)))

    def traffic(self, duration_s: float) -> Traffic:
        with self._lock:
            return Traffic(sorted(self._exchanges, key=lambda e: e.time_s), duration_s)


def parse_traffic(text: str, name: str = "<traffic>") -> Traffic:
    """Read a traffic log; a bad line is one error `name:line: error: ...`."""
    if "\x00" in text or "\ufffd" in text:      # bytes that are no UTF-8 text, decoded with replacement
        raise PlcLabError(f"{name}:1: error: not a text file (a plclab traffic log is UTF-8 CSV)")
    lines = text.splitlines()
    duration: Optional[float] = None
    body_start = 0
    if lines and lines[0].startswith(MAGIC):
        for item in lines[0][len(MAGIC):].split(";"):
            key, _, value = item.strip().partition("=")
            if key == "duration_s":
                duration = _number(value, name, 1, "duration_s")
        body_start = 1
    rows = list(csv.reader(lines[body_start:]))
    if not rows or tuple(c.strip() for c in rows[0][:4]) != HEADER[:4]:
        raise PlcLabError(f"{name}:{body_start + 1}: error: not a plclab traffic log: the header must be "
                          f"{','.join(HEADER)}")
    exchanges = []
    for i, row in enumerate(rows[1:], start=body_start + 2):
        if not row or not "".join(row).strip():
            continue
        if len(row) < 4:
            raise PlcLabError(f"{name}:{i}: error: expected time_s,unit,request,response[,what]")
        t = _number(row[0], name, i, "time_s")
        try:
            unit = int(row[1])
            request, response = bytes.fromhex(row[2]), bytes.fromhex(row[3])
        except ValueError:
            raise PlcLabError(f"{name}:{i}: error: unit must be a whole number and request/response "
                              f"hexadecimal PDUs") from None
        if not request or not 0 <= unit <= 255:
            raise PlcLabError(f"{name}:{i}: error: an empty request or a unit id outside 0..255")
        exchanges.append(Exchange(t, unit, request, response))
    exchanges.sort(key=lambda e: e.time_s)
    end = max((e.time_s for e in exchanges), default=0.0)
    if duration is None or duration < end:
        duration = end
    return Traffic(exchanges, duration)


MAX_TRAFFIC_BYTES = 64 * 1024 * 1024     # a day's session of a busy client is well below


def read_traffic(path: str | Path) -> Traffic:
    """A recorded traffic log; a FIFO, a device or an oversized file is refused before reading
    (the log is a student's hand-in)."""
    try:
        data = fileio.read_input(path, MAX_TRAFFIC_BYTES)
    except fileio.InputError as e:
        raise PlcLabError(f"{path}: cannot read the traffic log: {e}") from None
    return parse_traffic(data.decode("utf-8", errors="replace"), str(path))


def _number(text: str, name: str, line: int, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise PlcLabError(f"{name}:{line}: error: {what} '{text}' is not a number") from None
    if not 0 <= value <= MAX_TIME_S:
        raise PlcLabError(f"{name}:{line}: error: {what} {value:g} is not a time in seconds within 0..{MAX_TIME_S:g} "
                          f"(a lab session of at most a day)")
    return value
