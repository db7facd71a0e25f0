"""CSV traces: `time_s,name,value`, one change per row, the format of traces and input scripts.

Writer rules (docs/timing.md): rows sorted by time, rows of one instant in
declaration order, every signal's initial value at time 0, BOOL as 0/1, times printed exactly
from integer ns (`1.25`, `0.01`, no float noise). Two further rules make a round trip exact:
REAL values are written with `repr` (always a `.`, `e`, `inf` or `nan`, and enough digits to
give back the same double), and STRING values are always quoted, so `"1"` stays a string.

The reader infers each signal's kind unless `kinds` says it: a located address fixes it
(`%IX0.1`, `%QX`, `%MX` are BOOL; `%IW`/`%QW`/`%MW` 16-bit, `%ID`/`%QD`/`%MD` 32-bit,
`%IL`/`%QL`/`%ML` 64-bit, `%IB`/`%QB`/`%MB` 8-bit integers); otherwise quoted values make a
string, values all 0/1 (or TRUE/FALSE) a BOOL, integers an int, other numbers a REAL.
Every problem is a TraceFormatError whose message is the one line `FILE:LINE: error: ...`.
"""
from __future__ import annotations

import csv
import io
import os
import re
from dataclasses import dataclass
from operator import itemgetter
from typing import Any, Callable, Iterator, Mapping, Optional, Sequence, TextIO, Union

from plclab.errors import PlcLabError, quoted
from plclab.fileio import open_atomic
from plclab.iec.address import AddressError, parse_address

from .times import format_seconds, parse_seconds
from .trace import KINDS, Trace

HEADER = ("time_s", "name", "value")

Source = Union[str, "os.PathLike[str]", TextIO]

_BOOL_TEXT = {"0": False, "1": True, "false": False, "true": True}
_INT_RE = re.compile(r"[+-]?\d+")
_NEEDS_QUOTES = re.compile(r'[",\r\n]|^\s|\s$')


class TraceFormatError(PlcLabError, ValueError):
    """A bad row in a trace or input CSV; str() is `FILE:LINE: error: message`."""

    def __init__(self, file: str, line: int, message: str):
        self.file, self.line, self.message = file, line, message
        super().__init__(f"{file}:{line}: error: {message}")


# ---------------------------------------------------------------------------- writing

def format_value(kind: str, value: Any) -> str:
    """One value as the CSV shows it (also used by diff messages): BOOL 0/1, REAL by repr."""
    return _VALUE_TEXT.get(kind, str)(value)


# a value's text by its signal's kind; none of them can need quotes but a STRING's, which
# always has them (a quoted value reads back as a string)
_VALUE_TEXT: dict[str, Callable[[Any], str]] = {
    "bool": lambda v: "1" if v else "0",
    "int": str,
    "real": lambda v: repr(float(v)),
    "str": str,
}


def _field(text: str, quote: bool = False) -> str:
    if quote or _NEEDS_QUOTES.search(text):
        return '"' + text.replace('"', '""') + '"'
    return text


def iter_rows(trace: Trace, names: Optional[Sequence[str]] = None) -> list[tuple[int, int, str, Any]]:
    """(time_ns, declaration index, name, value) of every change, in the file's order."""
    wanted = trace.signals() if names is None else list(names)
    rows: list[tuple[int, int, str, Any]] = []
    for name in wanted:
        info = trace.info(name)
        rows.extend((t, info.index, info.name, v) for t, v in trace.changes(name))
    rows.sort(key=_FILE_ORDER)
    return rows


_FILE_ORDER = itemgetter(0, 1)      # by time, then declaration index (a stable sort: as listed)


def write_csv(trace: Trace, dest: Source, names: Optional[Sequence[str]] = None) -> None:
    """Write `trace` (or only `names`) to a path or an open text file."""
    if isinstance(dest, (str, os.PathLike)):
        with open_atomic(dest, newline="") as f:      # plclab.fileio: refuses links and devices
            _write(trace, f, names)
    else:
        _write(trace, dest, names)


def csv_text(trace: Trace, names: Optional[Sequence[str]] = None) -> str:
    """The CSV as a string (handy for golden files and tests)."""
    buf = io.StringIO()
    _write(trace, buf, names)
    return buf.getvalue()


def _write(trace: Trace, f: TextIO, names: Optional[Sequence[str]]) -> None:
    # a trace of a robot's scenario is tens of thousands of rows: what depends on the signal
    # alone (its name's field, how its values are written) is worked out once per signal, and
    # a time's text once per instant; the text is what format_value and _field give
    out = [",".join(HEADER) + "\n"]
    prefixes: dict[int, str] = {}
    values: dict[int, Callable[[Any], str]] = {}
    for name in (trace.signals() if names is None else names):
        info = trace.info(name)
        prefixes[info.index] = "," + _field(info.name) + ","
        values[info.index] = _quoted_text if info.kind == "str" else _VALUE_TEXT[info.kind]
    last_t, time_text = None, ""
    for t, i, _name, value in iter_rows(trace, names):
        if t != last_t:
            last_t, time_text = t, format_seconds(t)
        out.append(f"{time_text}{prefixes[i]}{values[i](value)}\n")
    f.write("".join(out))


def _quoted_text(value: Any) -> str:
    return _field(str(value), quote=True)


# ---------------------------------------------------------------------------- reading

MAX_INPUT_BYTES = 64 * 1024 * 1024     # a trace or input script beyond this is not a CSV we made


@dataclass(frozen=True)
class CsvRow:
    """One data row as written: its line, time, signal name and value text (`quoted`: the
    value was in quotes, so it is a string)."""

    line: int
    time_ns: int
    name: str
    text: str
    quoted: bool


_Row = CsvRow


class _RawLines:
    """Feeds csv.reader line by line and keeps the raw text of the current record.

    The csv module drops quoting, but a quoted value means a string; the raw record tells.
    """

    def __init__(self, f: TextIO):
        self._f = f
        self.buf: list[str] = []

    def __iter__(self) -> Iterator[str]:
        return self

    def __next__(self) -> str:
        line = next(self._f)
        self.buf.append(line)
        return line


def decode_text(data: bytes, filename: str) -> str:
    """The text of a CSV file's bytes (UTF-8, a BOM allowed); anything else is one
    TraceFormatError naming the line: UTF-16, binary data, bytes that are not UTF-8."""
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise TraceFormatError(filename, 1, "the file is UTF-16; save it as UTF-8 (plain text CSV)")
    nul = data.find(b"\x00")
    if nul >= 0:
        raise TraceFormatError(filename, data.count(b"\n", 0, nul) + 1,
                               "a NUL byte: this is a binary file, not a CSV text file")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise TraceFormatError(filename, data.count(b"\n", 0, e.start) + 1,
                               f"byte 0x{data[e.start]:02x} is not UTF-8 text; save the file as UTF-8") from None


def _open_text(source: Source) -> tuple[TextIO, str]:
    if isinstance(source, (str, os.PathLike)):
        filename = os.fspath(source)
        with open(source, "rb") as f:
            data = f.read(MAX_INPUT_BYTES + 1)
        if len(data) > MAX_INPUT_BYTES:
            raise TraceFormatError(filename, 1, f"larger than {MAX_INPUT_BYTES // (1024 * 1024)} MB; "
                                                f"not a trace this project reads")
        return io.StringIO(decode_text(data, filename), newline=""), filename
    return source, getattr(source, "name", "<csv>")


def read_rows(source: Source) -> list[CsvRow]:
    """The data rows of a trace or input CSV (a path or an open text file), in file order,
    with the header, the field count, the times (sorted) and duplicates checked; values are
    left as text for the caller to type. Raises TraceFormatError (`FILE:LINE: error: ...`)."""
    f, filename = _open_text(source)
    return _rows(f, filename)


def read_csv(source: Source, kinds: Optional[Mapping[str, str]] = None,
             require_initial: bool = True) -> Trace:
    """Read a trace CSV (a path or an open text file) into a Trace, validating every row.

    `kinds` fixes the kind of some or all signals. `require_initial=False` accepts signals
    whose first row is after time 0 (input scripts); they are declared at that time.
    """
    f, filename = _open_text(source)
    return _read(f, filename, kinds or {}, require_initial)


def parse_csv(text: str, filename: str = "<csv>", kinds: Optional[Mapping[str, str]] = None,
              require_initial: bool = True) -> Trace:
    """Like read_csv, from a string; `filename` is what error messages name."""
    return _read(io.StringIO(text), filename, kinds or {}, require_initial)


def _rows(f: TextIO, filename: str) -> list[CsvRow]:
    def fail(line: int, message: str) -> TraceFormatError:
        return TraceFormatError(filename, line, message)

    raw = _RawLines(f)
    reader = csv.reader(raw)
    rows: list[CsvRow] = []
    last_time, last_line = 0, 0
    seen: dict[tuple[str, int], int] = {}
    header_seen = False
    line_end = 0
    try:
        for fields in reader:
            line = line_end + 1
            line_end = reader.line_num
            text = "".join(raw.buf)
            raw.buf.clear()
            if not fields or (len(fields) == 1 and not fields[0].strip()):
                continue                         # blank line
            if not header_seen:
                got = [x.strip() for x in fields]
                if got != list(HEADER):
                    got_text = text.strip() if len(text.strip()) <= 60 else text.strip()[:57] + "..."
                    raise fail(line, f"expected the header `{','.join(HEADER)}`, got `{got_text}`")
                header_seen = True
                continue
            if len(fields) != 3:
                raise fail(line, f"expected 3 fields (time_s,name,value), got {len(fields)}")
            try:
                t = parse_seconds(fields[0])
            except ValueError as e:
                raise fail(line, str(e)) from None
            name = fields[1].strip()
            if not name:
                raise fail(line, "empty signal name")
            if t < last_time:
                raise fail(line, f"time {fields[0].strip()} s is before the previous row's "
                                 f"{format_seconds(last_time)} s (line {last_line}); "
                                 f"rows must be sorted by time")
            if (name, t) in seen:
                raise fail(line, f"second value for {name} at t={format_seconds(t)} s "
                                 f"(first on line {seen[name, t]})")
            seen[name, t] = line
            last_time, last_line = t, line
            quoted = text.rstrip("\r\n").endswith('"')
            rows.append(CsvRow(line, t, name, fields[2], quoted))
    except csv.Error as e:
        raise fail(line_end + 1, f"bad CSV: {e}") from None
    if not header_seen:
        raise fail(1, f"empty file: expected the header `{','.join(HEADER)}`")
    return rows


def _read(f: TextIO, filename: str, kinds: Mapping[str, str], require_initial: bool) -> Trace:
    def fail(line: int, message: str) -> TraceFormatError:
        return TraceFormatError(filename, line, message)

    for name, kind in kinds.items():
        if kind not in KINDS:
            raise ValueError(f"kind {kind!r} for {name!r} is not one of {', '.join(KINDS)}")
    all_rows = _rows(f, filename)
    rows_by_name: dict[str, list[CsvRow]] = {}
    for r in all_rows:
        rows_by_name.setdefault(r.name, []).append(r)
    last_time = all_rows[-1].time_ns if all_rows else 0

    trace = Trace()
    for name, rows in rows_by_name.items():
        if require_initial and rows[0].time_ns != 0:
            raise fail(rows[0].line, f"{name} has no initial value at time 0 "
                                     f"(its first row is at t={format_seconds(rows[0].time_ns)} s)")
        kind, width = _kind_of(name, rows, kinds.get(name))
        values = [_parse_value(r, kind, fail) for r in rows]
        trace.declare(name, kind, values[0], time_ns=rows[0].time_ns, width=width)
    # replay in file order so every signal's changes go in in time order
    ordered = sorted(((r.time_ns, r.line, r) for rs in rows_by_name.values() for r in rs[1:]),
                     key=lambda x: (x[0], x[1]))
    for t, _line, r in ordered:
        trace.change(t, r.name, _parse_value(r, trace.info(r.name).kind, fail))
    trace.advance(last_time)
    return trace


def _address_kind(name: str) -> Optional[tuple[str, int]]:
    """A column named like a located address has its type: (kind, width in bits)."""
    try:
        address = parse_address(name)
    except AddressError:
        return None
    return ("bool", 1) if address.size == "X" else ("int", address.bits)


def _kind_of(name: str, rows: list[_Row], given: Optional[str]) -> tuple[str, Optional[int]]:
    located = _address_kind(name)
    if given is not None:
        if given == "bool":
            return given, 1
        return given, (located[1] if located is not None and given == "int" else None)
    if located is not None:
        return located
    texts = [r.text.strip() for r in rows]
    if any(r.quoted for r in rows):
        return "str", None
    if all(x.lower() in _BOOL_TEXT for x in texts):
        return "bool", 1
    if all(_INT_RE.fullmatch(x) for x in texts):
        return "int", None
    try:
        for x in texts:
            float(x)
    except ValueError:
        return "str", None
    return "real", None


def _parse_value(row: _Row, kind: str, fail: Any) -> Any:
    text = row.text if kind == "str" else row.text.strip()
    if kind == "str":
        return text
    if kind == "bool":
        if text.lower() in _BOOL_TEXT:
            return _BOOL_TEXT[text.lower()]
        raise fail(row.line, f"bad value {quoted(text)} for BOOL {row.name}: expected 0 or 1")
    if kind == "int":
        if _INT_RE.fullmatch(text) and len(text) <= 40:
            return int(text)
        raise fail(row.line, f"bad value {quoted(text)} for integer {row.name}")
    try:
        return float(text)
    except ValueError:
        raise fail(row.line, f"bad value {quoted(text)} for REAL {row.name}") from None

