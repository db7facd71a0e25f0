"""A whole TC6 project made from a checked ST text (frontend.plcxml reads it back, as OpenPLC
Editor does).

Layout (the order the TC6 v2.01 schema requires): fileHeader, contentHeader (with the
bundle's title as Comment and the coordinateInfo every editor expects), types/dataTypes,
types/pous, instances/configurations. Namespaces as Beremiz writes them: TC6 as the default
namespace, `xhtml` for formatted text.
"""
from __future__ import annotations

import datetime as _dt
import os
from importlib import metadata
from typing import Optional

from lxml import etree

from plclab.errors import PlcLabError
from plclab.frontend.checked import CheckedUnit
from plclab.frontend.tc6 import PPX, XHTML, q
from plclab.plcopen.configuration import configurations_element
from plclab.plcopen.datatypes import data_type_element, sub
from plclab.plcopen.pous import pou_element
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
