"""A whole TC6 project: made from a checked ST text, and turned back into ST.

Layout (the order the TC6 v2.01 schema requires): fileHeader, contentHeader (with the
bundle's title as Comment and the coordinateInfo every editor expects), types/dataTypes,
types/pous, instances/configurations. Namespaces as Beremiz writes them: TC6 as the default
namespace, `xhtml` for formatted text.
"""
from __future__ import annotations

import datetime as _dt
import os
from importlib import metadata
from pathlib import Path
from typing import Optional

from lxml import etree

from plclab.errors import PlcLabError
from plclab.frontend.checked import CheckedUnit
from plclab.plcopen.configuration import configuration_text, configurations_element
from plclab.plcopen.datatypes import NS, PPX, XHTML, data_type_element, data_type_text, q, sub
from plclab.plcopen.pous import pou_element, pou_text
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
    """ST text for a TC6 project: TYPE block, POUs, configurations, in the XML's order."""
    root = tree.getroot()
    parts = []
    title = root.findtext("ppx:contentHeader/ppx:Comment", namespaces=NS)
    if title:
        parts.append(f"(* {title.replace('*)', '* )')} *)\n")
    data_types = root.findall("ppx:types/ppx:dataTypes/ppx:dataType", NS)
    if data_types:
        parts.append("TYPE\n" + "".join(data_type_text(dt) for dt in data_types) + "END_TYPE\n")
    parts += [pou_text(p) for p in root.findall("ppx:types/ppx:pous/ppx:pou", NS)]
    parts += [configuration_text(c) for c in root.findall("ppx:instances/ppx:configurations/ppx:configuration", NS)]
    return "\n".join(parts)


def st_from_xml(path: str | Path) -> str:
    """Read a PLCopen TC6 XML project file and return it as one ST text."""
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        raise PlcLabError(f"{path}: cannot read: {e.strerror}") from None
    return st_from_tree(parse_xml(data, str(path)))
