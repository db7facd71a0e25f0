"""ST front end: parse and check one compilation unit made of one or more files.

`load_files` / `check_sources` are what the CLI, the build, the runtime and the tests call.
`read_sources` is the one entry for program files: an OpenPLC Editor project (plc.xml) is read
as the Editor's generator writes its ST (plcxml; its LD / FBD bodies through graphical/).
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
    sources_seen = list(sources)
    for name, text in sources_seen:
        names.append(name)
        unit, errs = parse_source(text, name)
        diags.extend(errs)
        if unit is not None:
            merged.types.extend(unit.types)
            merged.pous.extend(unit.pous)
            merged.configs.extend(unit.configs)
            merged.gvls.extend(unit.gvls)
    drawn = {name: text for name, text in sources_seen if hasattr(text, "place")}
    if diags:
        raise CompileError(_on_drawing(diags, drawn))
    try:
        checked = check_unit(merged)
    except RecursionError as e:   # declarations nested beyond Python's stack (bodies are guarded per statement)
        node = _deepest_node(e)
        where = (node.file, node.line, node.col) if node is not None else (names[0] if names else "", 1, 1)
        raise CompileError([Diagnostic(*where, "declarations or initial values nested too deeply")]) from None
    if checked.diagnostics:
        raise CompileError(_on_drawing(checked.diagnostics, drawn))
    checked.drawings = drawn
    return checked


def _on_drawing(diags: list[Diagnostic], drawn: dict) -> list[Diagnostic]:
    """Diagnostics in ST made from a plc.xml name the POU, rung and element they concern
    (the generated text's line means nothing to whoever drew it)."""
    if not drawn:
        return diags
    out = []
    for d in diags:
        text = drawn.get(d.file)
        place = text.place(d.line, d.col) if text is not None else None
        out.append(Diagnostic(d.file, d.line, d.col, d.message, where=str(place)) if place is not None else d)
    return out


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


MAX_PROJECT_BYTES = 32 * 2**20     # a plc.xml read as a program (a student's file: bounded)


def is_project_file(path: str | Path) -> bool:
    """A PLCopen TC6 XML project (OpenPLC Editor's plc.xml) rather than an ST file."""
    return str(path).lower().endswith(".xml")


def read_sources(paths: Iterable[str | Path]) -> list[tuple[str, str]]:
    """(name, text) of each ST file; raises CompileError naming every file that cannot be read.

    A `.xml` file is an OpenPLC Editor project (plc.xml): its text is the ST the Editor would
    make of it (LD / FBD bodies translated), a `GeneratedSource` that knows the drawing, so
    every command that takes ST files takes a plc.xml too."""
    paths = list(paths)
    texts: dict[int, tuple[str, list[Diagnostic]]] = {
        i: read_source(p) for i, p in enumerate(paths) if not is_project_file(p)}
    st_texts = [(str(paths[i]), t) for i, (t, errs) in texts.items() if not errs]
    sources = []
    diags: list[Diagnostic] = []
    for i, p in enumerate(paths):
        text, errs = texts[i] if i in texts else _read_project(p, st_texts)
        diags.extend(errs)
        if not errs:
            sources.append((str(p), text))
    if diags:
        raise CompileError(diags)
    return sources


def _read_project(path: str | Path, st_texts: list[tuple[str, str]]) -> tuple[str, list[Diagnostic]]:
    from plclab.errors import PlcLabError
    from plclab.frontend.plcxml import source_from_xml

    name = str(path)
    data, errs = _read_bytes(path)
    if errs:
        return "", errs
    try:
        return source_from_xml(name, data, st_texts), []
    except CompileError as e:
        return "", list(e.diagnostics)
    except PlcLabError as e:
        message = str(e)
        if message.startswith(name + ": "):
            message = message[len(name) + 2:]
        return "", [Diagnostic(name, 1, 1, message, where="project")]


def _read_bytes(path: str | Path) -> tuple[bytes, list[Diagnostic]]:
    """A plc.xml's bytes: a regular file within the project size limit, checked before reading."""
    try:
        return fileio.read_input(path, MAX_PROJECT_BYTES), []
    except fileio.InputError as e:
        why = "is a directory, not a plc.xml project" if os.path.isdir(path) else str(e)
        return b"", [Diagnostic(str(path), 1, 1, why)]


def load_files(paths: Iterable[str | Path]) -> CheckedUnit:
    """Read, parse and check ST files as one compilation unit; raises CompileError."""
    return check_sources(read_sources(paths))
