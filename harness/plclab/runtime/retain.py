"""Retained variables on disk: written atomically, checked on load, set aside when bad.

Promises (docs/reliability.md): a save is atomic (plclab.fileio: temporary file, fsync,
rename), so a power loss or kill -9 loses at most the changes since the last flush and never
leaves a corrupt file; a save that fails (unwritable path, full disk) is reported once and
retried at the next flush, it never stops the scan; a file that cannot be used (corrupt,
another program's, a value out of its variable's range) is reported with the reason and set
aside, and only a regular file is ever set aside (a retain_file naming a directory, a link or
a device is reported and left alone). Temporaries of saves interrupted by a kill are removed
when the store is opened.

File format: JSON {"format": "plclab-retain-1", "signature": ..., "values": {path: value}}.
The signature is a hash of the retained variables' names and types, so a file written by a
different program is recognised and not silently poured into the wrong variables.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import re
import stat
import time
from pathlib import Path
from typing import Any, Callable, Iterable, Optional

from plclab.errors import PlcLabError, quoted
from plclab.fileio import existing_kind, process_alive, remove_stale_temporaries, write_text
from plclab.iec import types as T

FORMAT = "plclab-retain-1"
MAX_FILE_BYTES = 64 * 1024 * 1024      # far beyond any program's retained variables


def signature(items: Iterable[tuple[str, T.Type]]) -> str:
    h = hashlib.sha256()
    for path, ty in items:
        h.update(f"{path}:{_type_text(ty)};".encode())
    return h.hexdigest()[:16]


def _type_text(ty: T.Type) -> str:
    b = T.base_of(ty)
    if isinstance(b, T.ArrayType):
        return f"ARRAY{list(b.dims)}OF{_type_text(b.elem)}"
    if isinstance(b, T.StructType):
        return "STRUCT(" + ",".join(f"{k}:{_type_text(t)}" for k, (t, _i) in b.fields.items()) + ")"
    if isinstance(b, T.FBType):
        return f"FB:{b.name}"
    return b.name


def to_json_value(v: Any) -> Any:
    if isinstance(v, list):
        return [to_json_value(x) for x in v]
    if isinstance(v, T.StructValue):
        return {k: to_json_value(x) for k, x in v.__dict__.items()}
    if isinstance(v, float) and (v != v or v in (float("inf"), float("-inf"))):
        return {"float": repr(v)}
    if isinstance(v, (bool, int, float, str)):
        return v
    if hasattr(v, "__slots__") or hasattr(v, "__dict__"):   # FB instance: its variables
        names = getattr(type(v), "__slots__", None) or list(vars(v))
        # a slot never set is no variable of the instance (a VAR_EXTERNAL lives in the globals)
        return {"fb": {n: to_json_value(getattr(v, n)) for n in names
                       if not n.startswith("_") and hasattr(v, n) and not callable(getattr(v, n, None))}}
    return None


def from_json_value(data: Any, ty: T.Type) -> Any:
    """A saved value back in the runtime's representation, stored as its type stores it;
    RetainError if it is not a value of that type (a file edited by hand, say)."""
    b = T.base_of(ty)
    if isinstance(b, T.ArrayType):
        if not isinstance(data, list) or len(data) != len(T.default_value(b)):
            raise RetainError(f"expected {b.name}")
        return [from_json_value(x, b.elem) for x in data]
    if isinstance(b, T.StructType):
        if not isinstance(data, dict):
            raise RetainError(f"expected a {b.name} structure")
        return T.StructValue(**{k: from_json_value(data[k], t) if k in data else T.default_value(t)
                                for k, (t, _i) in b.fields.items()})
    if isinstance(b, T.ElementaryType) and b.is_real:
        if isinstance(data, dict) and isinstance(data.get("float"), str):
            try:
                return T.wrapper_for(b)(float(data["float"]))
            except ValueError:
                raise RetainError(f"{data['float']!r} is not a number") from None
        if isinstance(data, (int, float)) and not isinstance(data, bool):
            value = float(data)
            if b is T.REAL and math.isfinite(value) and abs(value) > T.REAL_MAX:
                raise RetainError(f"{quoted(data)} is out of range for REAL")
            return T.wrapper_for(b)(value)
        raise RetainError(f"{quoted(data)} is not of type {b.name}")
    if b is T.BOOL:
        if data in (True, False, 0, 1):
            return bool(data)
        raise RetainError(f"{data!r} is not of type BOOL")
    if isinstance(b, T.EnumType):
        if isinstance(data, str) and data in b.values:
            return data
        raise RetainError(f"{quoted(data)} is not a value of {b.name}")
    if isinstance(b, T.StringType):
        if isinstance(data, str):
            return data
        raise RetainError(f"{quoted(data)} is not of type {b.name}")
    if isinstance(data, int) and not isinstance(data, bool):
        low, high = _int_range(b)
        if not low <= data <= high:
            raise RetainError(f"{quoted(data)} is out of range for {getattr(b, 'name', '?')} ({low}..{high})")
        return data
    raise RetainError(f"{quoted(data)} is not of type {getattr(b, 'name', '?')}")


def _int_range(b: T.Type) -> tuple[int, int]:
    """The values a variable of integer-like type `b` can hold (TIME and dates: 64-bit ns)."""
    if isinstance(b, T.ElementaryType) and b.kind in ("sint", "uint", "bits"):
        return b.min, b.max
    return -(1 << 63), (1 << 63) - 1



def fb_values_from_json(data: Any, inst: Any, types: Optional[dict[str, T.Type]] = None) -> list[tuple[str, Any]]:
    """(variable, value) pairs of a saved FB instance, each of the type the variable holds
    now (and in its declared range, when `types` gives the block's declarations); RetainError
    (naming the variable) if one is not; its arrays and structures whole, as declared (without
    `types`, they start afresh). Nested blocks are not saved (to_json_value leaves out what is
    callable), so they start afresh."""
    saved = data.get("fb", {}) if isinstance(data, dict) else {}
    values = []
    for k, v in saved.items():
        current = getattr(inst, k, None)
        declared = (types or {}).get(k)
        if isinstance(current, (list, T.StructValue)):      # an ARRAY or STRUCT variable of the block
            if declared is None:
                continue
            try:
                values.append((k, from_json_value(v, declared)))
            except RetainError as e:
                raise RetainError(str(e), field=k) from None
            continue
        if type(current) not in (bool, int, float, str):
            continue                          # not a variable of the block
        if type(v) is not type(current) and not (type(current) is float and type(v) is int):
            raise RetainError(f"{quoted(v)} is not of the variable's type", field=k)
        if declared is not None and isinstance(T.base_of(declared), T.ElementaryType):
            try:
                v = from_json_value(v, declared)
            except RetainError as e:
                raise RetainError(str(e), field=k) from None
        elif type(current) is int and not -(1 << 63) <= v < (1 << 64):
            raise RetainError(f"{quoted(v)} is out of range for a 64-bit integer", field=k)
        values.append((k, float(v) if type(current) is float else v))
    return values


class RetainError(Exception):
    """A retain file, or a value in it, that cannot be used; `field` names the variable of a
    FB instance it is about."""

    def __init__(self, message: str, field: str = ""):
        super().__init__(message)
        self.field = field


class RetainStore:
    """One retain file. `flush` saves atomically and reports a failure once instead of
    raising; `load` never trusts a bad file and never touches what is not a regular file."""

    def __init__(self, path: str | Path, report=None):
        self.path = Path(path)
        self.report = report or (lambda msg: None)
        self.last_problem: Optional[str] = None
        self.save_error: Optional[str] = None     # why the last save failed; None once one succeeds
        self.failed_saves = 0
        self._clean_temporaries()

    def _clean_temporaries(self) -> None:
        """Temporaries left by a save that a kill -9 interrupted: ours, and the ones an older
        version of this store named `NAME.tmp<pid>`, when their process is gone."""
        removed = remove_stale_temporaries(self.path)
        legacy = re.compile(re.escape(self.path.name) + r"\.tmp(\d+)")
        try:
            entries = list(self.path.parent.iterdir())
        except OSError:
            entries = []
        for entry in entries:
            m = legacy.fullmatch(entry.name)
            if m and int(m.group(1)) != os.getpid() and not process_alive(int(m.group(1))):
                try:
                    if stat.S_ISREG(os.lstat(entry).st_mode):
                        entry.unlink()
                        removed.append(entry)
                except OSError:
                    pass
        if removed:
            self.report(f"retain file {self.path}: removed {len(removed)} temporary file(s) left by "
                        f"an interrupted save")

    def save(self, sig: str, values: dict[str, Any]) -> None:
        """Write the file atomically and durably (plclab.fileio); raises PlcLabError."""
        data = json.dumps({"format": FORMAT, "signature": sig, "saved_at": time.time(), "values": values},
                          separators=(",", ":"))
        write_text(self.path, data, durable=True)

    def flush(self, sig: str, values: dict[str, Any]) -> bool:
        """Save; on failure report once (not at every flush), keep the PLC running and retry
        at the next flush. True if the file now holds `values`."""
        try:
            self.save(sig, values)
        except (PlcLabError, OSError, ValueError, RecursionError) as e:
            self.failed_saves += 1
            reason = str(e) if isinstance(e, PlcLabError) else f"{self.path}: cannot write: {e}"
            if self.save_error is None:
                self.report(f"retain: {reason}; retained values are not being saved, retrying at every flush")
            self.save_error = reason
            return False
        if self.save_error is not None:
            self.report(f"retain file {self.path}: saved again after {self.failed_saves} failed save(s)")
            self.save_error = None
        return True

    def load(self, sig: str) -> Optional[dict[str, Any]]:
        """The saved values, or None (no file, or a bad one that is reported and set aside)."""
        try:
            kind = existing_kind(self.path)
        except PlcLabError as e:
            self._not_used(str(e))
            return None
        if kind is not None:
            self._not_used(f"retain file {self.path} is {kind}, not a regular file")
            return None
        if not self.path.exists():
            return None
        try:
            with open(self.path, "rb") as f:
                raw = f.read(MAX_FILE_BYTES + 1)
            if len(raw) > MAX_FILE_BYTES:
                raise RetainError(f"larger than {MAX_FILE_BYTES // (1024 * 1024)} MB")
            data = json.loads(raw.decode("utf-8"))
            if not isinstance(data, dict) or data.get("format") != FORMAT or not isinstance(data.get("values"), dict):
                raise RetainError("not a plclab retain file")
            if data.get("signature") != sig:
                raise RetainError("it was written by a different program (retained variables differ)")
            return data["values"]
        except RecursionError:
            self.reject("corrupt (nested too deeply)")
        except (OSError, ValueError, RetainError) as e:     # ValueError: bad JSON, UTF-8, a 5000-digit number
            self.reject(str(e) if isinstance(e, RetainError) else "corrupt or unreadable")
        return None

    def _not_used(self, why: str) -> None:
        self.last_problem = f"{why}; not used and not touched, starting with initial values"
        self.report(self.last_problem)

    def reject(self, reason: str) -> None:
        """The file cannot be used: report why and set it aside (the PLC starts with initial
        values). Only a regular file is renamed, to a name no other file has."""
        aside = None
        try:
            if stat.S_ISREG(os.lstat(self.path).st_mode):
                stamp = int(time.time())
                for n in range(1000):
                    candidate = self.path.with_name(f"{self.path.name}.bad-{stamp}" + (f"-{n}" if n else ""))
                    if not os.path.lexists(candidate):
                        os.rename(self.path, candidate)
                        aside = candidate
                        break
        except OSError:
            aside = None
        where = f"set aside as {aside.name}" if aside is not None else "left in place (could not set it aside)"
        self.last_problem = f"retain file {self.path}: {reason}; {where}, starting with initial values"
        self.report(self.last_problem)



class MemoryRetainStore:
    """The retain memory of a PLC in virtual time (a grader's or an exploration's session):
    what a save writes is kept in memory and a restart of the same session loads it, through
    the same snapshot and signature check as a file. A grading saves every second of plant
    time, thousands of times per program; a file (written and fsynced each time) added
    nothing there but wall time, as nobody reads it after the session."""

    # written by one PLC at a time only: a flush of what it holds changes nothing, and a native
    # PLC flushes its retained memory for a snapshot made when loaded (flush_later)
    exclusive = True

    def __init__(self) -> None:
        self.last_problem: Optional[str] = None
        self.save_error: Optional[str] = None     # never set: memory does not fill up here
        self.failed_saves = 0
        self._saved: Optional[tuple[str, dict[str, Any]]] = None

    def flush(self, sig: str, values: dict[str, Any]) -> bool:
        self._saved = (sig, values)       # a fresh snapshot (to_json_value builds new objects)
        return True

    def flush_later(self, sig: str, snapshot: Callable[[], dict[str, Any]]) -> bool:
        """`flush` with the snapshot made only if it is loaded: `snapshot()` gives it as it
        was at this flush (PLC.persist_retain keeps the retained variables' memory for it)."""
        self._saved = (sig, snapshot)
        return True

    def load(self, sig: str) -> Optional[dict[str, Any]]:
        if self._saved is None:
            return None
        saved_sig, values = self._saved
        if saved_sig != sig:
            self.reject("it was written by a different program (retained variables differ)")
            return None
        if callable(values):
            values = values()
            self._saved = (saved_sig, values)
        return values

    def reject(self, reason: str) -> None:
        """Values that cannot be used are dropped (the PLC starts with initial values)."""
        self.last_problem = f"retained values not used: {reason}"
        self._saved = None
