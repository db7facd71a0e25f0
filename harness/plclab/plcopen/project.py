"""A whole TC6 project: made from a checked ST text, and turned back into ST.

Layout (the order the TC6 v2.01 schema requires): fileHeader, contentHeader (with the
bundle's title as Comment and the coordinateInfo every editor expects), types/dataTypes,
types/pous, instances/configurations. Namespaces as Beremiz writes them: TC6 as the default
namespace, `xhtml` for formatted text.
"""
from __future__ import annotations

import datetime as _dt
import os
import re
from importlib import metadata
from pathlib import Path
from typing import Optional

from lxml import etree

from plclab.errors import PlcLabError
from plclab.frontend.checked import CheckedUnit
from plclab.plcopen.configuration import configuration_text, configurations_element
from plclab.plcopen.datatypes import NS, PPX, XHTML, data_type_element, data_type_text, q, sub
from plclab.plcopen.graphical import (GRAPHICAL, GeneratedSource, Library, Place, PouGenerator, TextBuilder,
                                      generation_error, xml_structs)
from plclab.plcopen.pous import pou_body, pou_element, pou_head
from plclab.plcopen.datatypes import read_formatted_text, type_text
from plclab.plcopen.source import SourceText

_XSD_NS = "http://www.w3.org/2001/XMLSchema"


def project_tree(checked: CheckedUnit, text: str, name: str,
                 created: Optional[_dt.datetime] = None) -> etree._ElementTree:
    """The TC6 project of `checked`, the front end's result for `text` (positions in the AST
    refer to `text`, from which bodies and comments are cut)."""
    src = SourceText(text)
    unit = checked.unit
    stamp = (created or _build_time()).replace(microsecond=0).isoformat()
    root = etree.Element(q("project"), nsmap={None: PPX, "xhtml": XHTML, "xsd": _XSD_NS})
    sub(root, "fileHeader", companyName="plclab", productName=name, productVersion=_version(),
        creationDateTime=stamp)
    header = sub(root, "contentHeader", name=name, modificationDateTime=stamp)
    title = src.first_comment()
    if title:
        sub(header, "Comment").text = title
    coords = sub(header, "coordinateInfo")
    for lang in ("fbd", "ld", "sfc"):
        sub(sub(coords, lang), "scaling", x="10", y="10")
    types = sub(root, "types")
    data_types = sub(types, "dataTypes")
    for t in unit.types:
        data_type_element(data_types, t, src)
    pous = sub(types, "pous")
    for pou in unit.pous:
        pou_element(pous, pou, src)
    if unit.gvls and checked.config is None:
        raise PlcLabError("PLCopen XML keeps global variables in a CONFIGURATION; this program has none")
    configurations_element(sub(root, "instances"), checked.config, src)
    return etree.ElementTree(root)


def _version() -> str:
    try:
        return metadata.version("plclab")
    except metadata.PackageNotFoundError:
        return "0"


def to_bytes(tree: etree._ElementTree) -> bytes:
    return etree.tostring(tree, xml_declaration=True, encoding="utf-8", pretty_print=True)


def _build_time() -> _dt.datetime:
    """Now, or SOURCE_DATE_EPOCH when set (reproducible builds: same sources, same bytes)."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    if epoch and epoch.isdigit():
        return _dt.datetime.fromtimestamp(int(epoch), _dt.timezone.utc).replace(tzinfo=None)
    return _dt.datetime.now()


# --------------------------------------------------------------------------- XML -> ST

def parse_xml(data: bytes, where: str) -> etree._ElementTree:
    """Parse TC6 XML bytes; anything but a TC6 `project` is one clear error."""
    try:
        tree = etree.ElementTree(etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True)))
    except etree.XMLSyntaxError as e:
        raise PlcLabError(f"{where}: not well-formed XML: {e}") from None
    if tree.getroot().tag != q("project"):
        raise PlcLabError(f"{where}: not a PLCopen TC6 v2.01 project (root <{tree.getroot().tag}>)")
    return tree


def st_from_tree(tree: etree._ElementTree) -> str:
    """ST text for a TC6 project: TYPE block, POUs, configurations, in the XML's order (LD
    and FBD bodies turned into ST as OpenPLC Editor does it)."""
    return str(project_source(tree, ""))


def project_source(tree: etree._ElementTree, file: str, others: Optional[Library] = None) -> GeneratedSource:
    """The ST of a TC6 project, knowing for each piece what it was made from (`file`: the
    name diagnostics give the project; `others`: blocks of ST files compiled with it)."""
    root = tree.getroot()
    out = TextBuilder()
    first = True

    def part(text: str, place: Optional[Place]) -> None:
        nonlocal first
        if not first:
            out.add("\n")
        first = False
        for line in text.splitlines(keepends=True):
            out.add(line, place)

    title = root.findtext("ppx:contentHeader/ppx:Comment", namespaces=NS)
    if title:
        part(f"(* {title.replace('*)', '* )')} *)\n", None)
    data_types = root.findall("ppx:types/ppx:dataTypes/ppx:dataType", NS)
    if data_types:
        part("TYPE\n" + "".join(data_type_text(dt) for dt in data_types) + "END_TYPE\n", Place("TYPE", detail="data types"))
    pous = root.findall("ppx:types/ppx:pous/ppx:pou", NS)
    project_pous = {p.get("name", ""): p for p in pous}
    globals_ = global_types(root)
    library = Library(dict(others.blocks) if others else {}, {**(others.structs if others else {}), **xml_structs(root)})
    for p in pous:
        name = p.get("name", "")
        kind, head = pou_head(p)
        lang, body = pou_body(p)
        if not first:
            out.add("\n")
        first = False
        if lang == "ST":
            for line in head.splitlines(keepends=True):
                out.add(line, _declaration_place(name, line))
            text = (read_formatted_text(body) or "").strip("\n")
            for n, line in enumerate(text.split("\n"), 1):
                out.add(line + "\n", Place(name, "ST", detail=f"line {n} of its body"))
        elif lang in GRAPHICAL:
            own = interface_types(p)
            gen = PouGenerator(p, lang, body, file, project_pous, {**globals_, **own}, library, set(own))
            try:
                gen.generate()
            except RecursionError:
                raise generation_error(file, Place(name, lang), "the diagram is wired too deep to translate "
                                                                "(a chain of hundreds of elements): split it") from None
            for line in head.splitlines(keepends=True):
                out.add(line, _declaration_place(name, line))
            if gen.extra:
                out.add("VAR\n", Place(name, lang, detail="variables the Editor adds"))
                for var, type_name, owner in gen.extra:
                    element = gen.by_id.get(owner) if owner is not None else None
                    out.add(f"    {var} : {type_name};\n",
                            gen.place(element) if element is not None else
                            Place(name, lang, detail=f"variable {var} the Editor adds"))
                out.add("END_VAR\n", Place(name, lang, detail="variables the Editor adds"))
            elif not interface_types(p):
                raise generation_error(file, Place(name, lang), "no variable defined in this POU (OpenPLC Editor "
                                                                "refuses to generate it)")
            if not gen.program:
                raise generation_error(file, Place(name, lang), "the body is empty (OpenPLC Editor refuses to "
                                                                "generate it)")
            for text, info in gen.program:
                owner = gen.by_id.get(info[2]) if len(info) > 2 else None
                out.add(text, gen.place(owner) if owner is not None else None)
        else:
            what = "SFC (sequential function chart)" if lang == "SFC" else lang
            raise generation_error(file, Place(name, lang), f"{what} bodies are not supported: "
                                                            "write this POU in ST, LD or FBD")
        out.add(f"END_{kind}\n", Place(name, detail="declarations"))
    for c in root.findall("ppx:instances/ppx:configurations/ppx:configuration", NS):
        part(configuration_text(c), Place(f"configuration {c.get('name')}"))
    return GeneratedSource(out.text(), out.spans, file)


_DECLARED = re.compile(r"^\s+([A-Za-z_]\w*)\s*(?:AT\s+\S+\s*)?:")


def _declaration_place(pou: str, line: str) -> Place:
    """A line of a POU's header and VAR blocks: the variable it declares, if it declares one."""
    m = _DECLARED.match(line)
    return Place(pou, detail=f"variable {m.group(1)}" if m else "declarations")


def interface_types(pou: etree._Element) -> dict[str, str]:
    """Name -> type (as ST text) of a POU's variables (a function's own name: its result)."""
    where = f"POU {pou.get('name')}"
    found: dict[str, str] = {}
    interface = pou.find("ppx:interface", NS)
    if interface is None:
        return found
    ret = interface.find("ppx:returnType", NS)
    if ret is not None:
        found[pou.get("name", "")] = type_text(ret, where)
    for v in interface.iterfind(".//ppx:variable", NS):
        t = v.find("ppx:type", NS)
        if t is not None:
            found[v.get("name", "")] = type_text(t, where)
    return found


def global_types(root: etree._Element) -> dict[str, str]:
    found: dict[str, str] = {}
    for v in root.iterfind("ppx:instances/ppx:configurations//ppx:globalVars/ppx:variable", NS):
        t = v.find("ppx:type", NS)
        if t is not None:
            found[v.get("name", "")] = type_text(t, "global variables")
    return found


def source_from_xml(path: str | Path, data: Optional[bytes] = None,
                    st_texts: Optional[list[tuple[str, str]]] = None) -> GeneratedSource:
    """A plc.xml as one ST source that knows its drawing (what `read_sources` gives the front
    end); `st_texts`: the ST files compiled with it (their FBs and functions may be boxes)."""
    if data is None:
        try:
            data = Path(path).read_bytes()
        except OSError as e:
            raise PlcLabError(f"{path}: cannot read: {e.strerror}") from None
    from plclab.plcopen.graphical import st_library
    source = project_source(parse_xml(data, str(path)), str(path), st_library(st_texts or []))
    source.xml = data          # the drawing itself: the lab draws its LD POUs online (plclab.lab.ladder)
    return source


def st_from_xml(path: str | Path) -> str:
    """Read a PLCopen TC6 XML project file and return it as one ST text."""
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        raise PlcLabError(f"{path}: cannot read: {e.strerror}") from None
    return st_from_tree(parse_xml(data, str(path)))
