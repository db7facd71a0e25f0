"""VCD output (for GTKWave) with pyvcd.

Variables: BOOL -> `wire 1`; integers -> `reg` of their width (declared width, else the
smallest of 8/16/32/64 bits that holds every value; negatives in two's complement); REAL ->
`real`; STRING -> GTKWave's `string`. Timescale 1 ns (exact) or 1 us (times rounded down).

Name mapping: VCD references must be plain identifiers, and a `.` separates scopes, so:
  - every variable lives under the top scope `plc`;
  - a located address goes under `plc.io` with `%` dropped and other non-identifier
    characters replaced by `_`: `%QX1.0` -> `plc.io.QX1_0`, `%IW3` -> `plc.io.IW3`;
  - a qualified name becomes scopes: `PRG_Main.fb1.Q` -> `plc.PRG_Main.fb1.Q`, each part
    cleaned the same way (`arr[3]` -> `arr_3`); a clash gets a `_2`, `_3`... suffix;
  - a trace alias (console label such as `SQ2`) is added as a second name of the same
    variable under `plc.alias`, so GTKWave shows `plc.alias.SQ2` next to `plc.io.IX0_2`.
The header `$comment` lists `VCD name = trace name` for every name that changed, so the
original stays visible in the file; `write_vcd` also returns the full mapping.
"""
from __future__ import annotations

import os
import re
from operator import itemgetter
from typing import Any, Optional, Sequence, TextIO, Union

from vcd import VCDWriter

from plclab.fileio import open_atomic

from .trace import Trace

TOP_SCOPE = "plc"
IO_SCOPE = "io"
ALIAS_SCOPE = "alias"
_TIMESCALES = {"1 ns": 1, "1 us": 1000}
_ILLEGAL = re.compile(r"[^A-Za-z0-9_]+")

Dest = Union[str, "os.PathLike[str]", TextIO]


def _clean(part: str) -> str:
    text = _ILLEGAL.sub("_", part).strip("_") or "_"
    return "_" + text if text[0].isdigit() else text


def vcd_path(name: str) -> tuple[str, ...]:
    """The VCD scope path and variable name for a trace name, before clash resolution."""
    if name.startswith("%"):
        return (TOP_SCOPE, IO_SCOPE, _clean(name))
    return (TOP_SCOPE, *(_clean(p) for p in name.split(".")))


def vcd_names(names: Sequence[str]) -> dict[str, str]:
    """Trace name -> dotted VCD reference (`%QX1.0` -> `plc.io.QX1_0`), clashes resolved."""
    used: set[tuple[str, ...]] = set()
    out: dict[str, str] = {}
    for name in names:
        path = vcd_path(name)
        candidate, n = path, 1
        while candidate in used:
            n += 1
            candidate = (*path[:-1], f"{path[-1]}_{n}")
        used.add(candidate)
        out[name] = ".".join(candidate)
    return out


def _int_width(values: list[int]) -> int:
    lo, hi = min(values), max(values)
    for width in (8, 16, 32, 64):
        if lo < 0 and -(1 << (width - 1)) <= lo and hi < (1 << (width - 1)):
            return width
        if lo >= 0 and hi < (1 << width):
            return width
    return max(hi.bit_length(), (-lo).bit_length()) + 1


def write_vcd(trace: Trace, dest: Dest, names: Optional[Sequence[str]] = None,
              timescale: str = "1 ns") -> dict[str, str]:
    """Write `trace` (or only `names`) as VCD; returns trace name -> VCD reference."""
    if timescale not in _TIMESCALES:
        raise ValueError(f"timescale must be one of {', '.join(_TIMESCALES)}, not {timescale!r}")
    if isinstance(dest, (str, os.PathLike)):
        with open_atomic(dest) as f:                  # plclab.fileio: refuses links and devices
            return _write(trace, f, names, timescale)
    return _write(trace, dest, names, timescale)


def _write(trace: Trace, f: TextIO, names: Optional[Sequence[str]], timescale: str) -> dict[str, str]:
    wanted = [trace.info(n).name for n in (trace.signals() if names is None else names)]
    mapping = vcd_names(wanted)
    aliases = {a: t for a, t in trace.aliases.items() if t in mapping}
    alias_refs = vcd_names([f"{ALIAS_SCOPE}.{a}" for a in aliases])
    renamed = [f"{ref} = {name}" for name, ref in mapping.items()
               if ref != f"{TOP_SCOPE}.{name}"]
    renamed += [f"{alias_refs[f'{ALIAS_SCOPE}.{a}']} = {t}" for a, t in aliases.items()]
    comment = "PLC Lab trace"
    if renamed:
        comment += "; VCD name = trace name:\n" + "\n".join(renamed)
    scale = _TIMESCALES[timescale]

    writer = VCDWriter(f, timescale=timescale, date="", comment=comment, version="PLC Lab")
    variables: dict[str, Any] = {}
    rows: list[tuple[int, int, Any, Any]] = []
    for name in wanted:
        info = trace.info(name)
        changes = trace.changes(name)
        scope, ref = mapping[name].rsplit(".", 1)
        declared_at_start = changes[0][0] == 0
        init = changes[0][1] if declared_at_start else None   # else 'x' until declared
        if info.kind == "bool":
            var = writer.register_var(scope, ref, "wire", size=1, init=init)
        elif info.kind == "int":
            values = [v for _t, v in changes]
            width = info.width or _int_width(values)
            if not -(1 << (width - 1)) <= min(values) <= max(values) < (1 << width):
                v = next(v for v in values if not -(1 << (width - 1)) <= v < (1 << width))
                raise ValueError(f"{name}: value {v} does not fit in {width} bits")
            var = writer.register_var(scope, ref, "reg", size=width, init=init)
        elif info.kind == "real":
            var = writer.register_var(scope, ref, "real", init=init)
        else:
            var = writer.register_var(scope, ref, "string", init=init)
        variables[name] = var
        rows.extend((t, info.index, var, v) for t, v in changes[1 if declared_at_start else 0:])
    for alias, target in aliases.items():
        scope, ref = alias_refs[f"{ALIAS_SCOPE}.{alias}"].rsplit(".", 1)
        writer.register_alias(scope, ref, variables[target])
    rows.sort(key=itemgetter(0, 1))                     # by time, then declaration index
    for t, _i, var, value in rows:
        writer.change(var, t // scale, value)
    writer.close(trace.end_ns // scale)
    return mapping
