"""Retained variables on disk: written atomically, checked on load, set aside when bad.

File format: JSON {"format": "plclab-retain-1", "signature": ..., "values": {path: value}}.
The signature is a hash of the retained variables' names and types, so a file written by a
different program is recognised and not silently poured into the wrong variables.
"""
from __future__ import annotations

import hashlib
import json
import os
import time
from pathlib import Path
from typing import Any, Iterable, Optional

from plclab.iec import types as T

FORMAT = "plclab-retain-1"


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
        return {"fb": {n: to_json_value(getattr(v, n)) for n in names
                       if not n.startswith("_") and not callable(getattr(v, n, None))}}
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
            return T.wrapper_for(b)(float(data))
        raise RetainError(f"{data!r} is not of type {b.name}")
    if b is T.BOOL:
        if data in (True, False, 0, 1):
            return bool(data)
        raise RetainError(f"{data!r} is not of type BOOL")
    if isinstance(b, T.StringType) or isinstance(b, T.EnumType):
        if isinstance(data, str):
            return data
        raise RetainError(f"{data!r} is not of type {b.name}")
    if isinstance(data, int) and not isinstance(data, bool):
        normalise = T.wrapper_for(b)
        return normalise(data) if normalise is not None else data
    raise RetainError(f"{data!r} is not of type {getattr(b, 'name', '?')}")


def fb_values_from_json(data: Any, inst: Any) -> list[tuple[str, Any]]:
    """(variable, value) pairs of a saved FB instance, each of the type the variable holds
    now; RetainError (naming the variable) if one is not. Nested blocks are not saved (to_json_value
    leaves out what is callable), so they start afresh."""
    saved = data.get("fb", {}) if isinstance(data, dict) else {}
    values = []
    for k, v in saved.items():
        current = getattr(inst, k, None)
        if type(current) not in (bool, int, float, str):
            continue                          # not a variable of the block
        if type(v) is not type(current) and not (type(current) is float and type(v) is int):
            raise RetainError(f"{v!r} is not of the variable's type", field=k)
        values.append((k, float(v) if type(current) is float else v))
    return values


class RetainError(Exception):
    """A retain file, or a value in it, that cannot be used; `field` names the variable of a
    FB instance it is about."""

    def __init__(self, message: str, field: str = ""):
        super().__init__(message)
        self.field = field


class RetainStore:
    """One retain file. `save` is atomic (temp file, fsync, rename); `load` never trusts a bad file."""

    def __init__(self, path: str | Path, report=None):
        self.path = Path(path)
        self.report = report or (lambda msg: None)
        self.last_problem: Optional[str] = None

    def save(self, sig: str, values: dict[str, Any]) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(self.path.name + f".tmp{os.getpid()}")
        data = json.dumps({"format": FORMAT, "signature": sig, "saved_at": time.time(), "values": values},
                          separators=(",", ":"))
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self.path)
        try:
            dfd = os.open(self.path.parent, os.O_RDONLY)
            try:
                os.fsync(dfd)
            finally:
                os.close(dfd)
        except OSError:
            pass

    def load(self, sig: str) -> Optional[dict[str, Any]]:
        """The saved values, or None (no file, or a bad one that is reported and set aside)."""
        if not self.path.exists():
            return None
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
            if not isinstance(data, dict) or data.get("format") != FORMAT or not isinstance(data.get("values"), dict):
                raise RetainError("not a plclab retain file")
            if data.get("signature") != sig:
                raise RetainError("it was written by a different program (retained variables differ)")
            return data["values"]
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, RetainError) as e:
            self.reject(str(e) if isinstance(e, RetainError) else "corrupt or unreadable")
            return None

    def reject(self, reason: str) -> None:
        """The file cannot be used: report why and set it aside (the PLC starts with initial values)."""
        aside = self.path.with_name(self.path.name + f".bad-{int(time.time())}")
        try:
            os.replace(self.path, aside)
        except OSError:
            aside = self.path
        self.last_problem = f"retain file {self.path}: {reason}; set aside as {aside.name}, starting with initial values"
        self.report(self.last_problem)
