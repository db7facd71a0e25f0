"""ST front end: parse and check one compilation unit made of one or more files.

`load_files` / `check_sources` are what the CLI, the build, the runtime and the tests call.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable

from plclab import fileio
from plclab.errors import CompileError, Diagnostic
from plclab.frontend import ast as A
from plclab.frontend.checked import CheckedUnit
from plclab.frontend.checker import check_unit
from plclab.frontend.parser import MAX_SOURCE_BYTES, parse_source

__all__ = ["CheckedUnit", "check_sources", "load_files", "read_source", "read_sources"]


def read_source(path: str | Path) -> tuple[str, list[Diagnostic]]:
    """The text of an ST file, or a diagnostic saying why it cannot be read."""
    name = str(path)
    try:                 # a regular file within the parser's size limit, checked before reading
        data = fileio.read_input(path, MAX_SOURCE_BYTES)
    except fileio.InputError as e:
        why = "is a directory, not an ST file" if os.path.isdir(path) else str(e)
        return "", [Diagnostic(name, 1, 1, why)]
    return data.decode("utf-8", errors="replace").replace("\ufffd", "\x00" if b"\x00" in data else "\ufffd"), []


def check_sources(sources: Iterable[tuple[str, str]]) -> CheckedUnit:
    """Parse and check (name, text) pairs as one compilation unit; raises CompileError."""
    merged = A.Unit(line=1, col=1, file="")
    diags: list[Diagnostic] = []
    names: list[str] = []
    for name, text in sources:
        names.append(name)
        unit, errs = parse_source(text, name)
        diags.extend(errs)
        if unit is not None:
            merged.types.extend(unit.types)
            merged.pous.extend(unit.pous)
            merged.configs.extend(unit.configs)
            merged.gvls.extend(unit.gvls)
    if diags:
        raise CompileError(diags)
    try:
        checked = check_unit(merged)
    except RecursionError as e:   # declarations nested beyond Python's stack (bodies are guarded per statement)
        node = _deepest_node(e)
        where = (node.file, node.line, node.col) if node is not None else (names[0] if names else "", 1, 1)
        raise CompileError([Diagnostic(*where, "declarations or initial values nested too deeply")]) from None
    if checked.diagnostics:
        raise CompileError(checked.diagnostics)
    return checked


def _deepest_node(exc: BaseException) -> A.Node | None:
    """The innermost AST node with a position that a frame of `exc`'s traceback was working
    on: where a recursion crossed the limit."""
    found = None
    tb = exc.__traceback__
    while tb is not None:
        for value in tb.tb_frame.f_locals.values():
            if isinstance(value, A.Node) and getattr(value, "line", 0) and getattr(value, "file", ""):
                found = value
                break
        tb = tb.tb_next
    return found


def read_sources(paths: Iterable[str | Path]) -> list[tuple[str, str]]:
    """(name, text) of each ST file; raises CompileError naming every file that cannot be read."""
    sources = []
    diags: list[Diagnostic] = []
    for p in paths:
        text, errs = read_source(p)
        diags.extend(errs)
        if not errs:
            sources.append((str(p), text))
    if diags:
        raise CompileError(diags)
    return sources


def load_files(paths: Iterable[str | Path]) -> CheckedUnit:
    """Read, parse and check ST files as one compilation unit; raises CompileError."""
    return check_sources(read_sources(paths))
