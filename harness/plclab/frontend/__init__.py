"""ST front end: parse and check one compilation unit made of one or more files.

`load_files` / `check_sources` are what the CLI, the build, the runtime and the tests call.
`read_sources` is the one entry for program files: an OpenPLC Editor project (plc.xml) is read
as the Editor's generator writes its ST (plcxml; its LD / FBD bodies through graphical/).
"""
from __future__ import annotations

import hashlib
import os
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Iterable, Optional

from plclab import fileio
from plclab.errors import CompileError, Diagnostic
from plclab.frontend import ast as A
from plclab.frontend import check_limits
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


CHECKED_CHARS = 256 * 1024            # the checked units kept, by their files' characters all together
CHECKED_MAX_CHARS = 128 * 1024        # a unit whose files are longer together is checked each time
_CHECKED: "OrderedDict[bytes, tuple[CheckedUnit, int]]" = OrderedDict()
_CHECKED_LOCK = threading.Lock()


def check_sources(sources: Iterable[tuple[str, str]]) -> CheckedUnit:
    """Parse and check (name, text) pairs as one compilation unit; raises CompileError.

    The same files (names and texts) checked again under the same limits give the same
    CheckedUnit, which is read-only from here on: the compiler, the native path and every
    session of a program only read it (the grader's sessions of one submission always shared
    one). A stand's session, a test's, a lab reload check one shipped program over and over;
    the checker's walk of it (a tenth of a second for the CNC stand) is done once. Kept: the
    units checked last, of CHECKED_CHARS characters together (a unit takes some 50 bytes a
    character: about 12 MiB in all); a unit longer than CHECKED_MAX_CHARS, a program drawn
    in a plc.xml, or one that fails, is checked each time."""
    sources_seen = list(sources)
    key = _checked_key(sources_seen)
    if key is not None:
        with _CHECKED_LOCK:
            known = _CHECKED.get(key)
            if known is not None:
                _CHECKED.move_to_end(key)
                return known[0]
    checked = _check(sources_seen)
    if key is not None:
        chars = sum(len(text) for _name, text in sources_seen)
        with _CHECKED_LOCK:
            _CHECKED[key] = (checked, chars)
            while sum(n for _unit, n in _CHECKED.values()) > CHECKED_CHARS:    # a short sum: few units
                _CHECKED.popitem(last=False)
    return checked


def _checked_key(sources: list[tuple[str, str]]) -> Optional[bytes]:
    """The cache key of a unit: its files' names and texts and the checker's limits (a test
    may lower one); None for a unit that is not kept."""
    if any(type(text) is not str or type(name) is not str for name, text in sources) \
            or sum(len(text) for _name, text in sources) > CHECKED_MAX_CHARS:
        return None              # a drawn program's text (frontend.graphical) names its drawing per check
    h = hashlib.blake2b(digest_size=20)
    limits = sorted((k, v) for k, v in vars(check_limits).items() if k.isupper() and isinstance(v, int))
    h.update(repr((limits, MAX_SOURCE_BYTES)).encode())
    for name, text in sources:
        h.update(f"\0{len(name)}\0{name}\0{len(text)}\0".encode("utf-8", "surrogatepass"))
        h.update(text.encode("utf-8", "surrogatepass"))
    return h.digest()


def _check(sources_seen: list[tuple[str, str]]) -> CheckedUnit:
    merged = A.Unit(line=1, col=1, file="")
    diags: list[Diagnostic] = []
    names: list[str] = []
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
