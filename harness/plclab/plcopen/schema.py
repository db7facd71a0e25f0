"""Validation against the PLCopen TC6 v2.01 schema (tc6_xml_v201.xsd), with lxml.

The schema is PLCopen's file; this project does not ship a copy. It is looked up at run time:
1. the file named by the environment variable PLCLAB_TC6_XSD;
2. a `tc6_xml_v201.xsd` shipped by any installed Python distribution (the schema travels
   inside some PLCopen tool packages);
3. `tc6_xml_v201.xsd` next to this module (where a packager may put the file);
4. the copy inside an OpenPLC Editor checkout in the user's home (`~/OpenPLC_Editor`).
Whether or not the file is there, every document is also checked against the TC6 v2.01
data model that the PyPI package `plcopen` generates from that schema (xsdata bindings): a
strict parse refuses any element or attribute TC6 does not have and any value of the wrong
type, and every element TC6 requires must be present (`validate_bindings`).
"""
from __future__ import annotations

import os
from functools import lru_cache
from importlib import metadata
from pathlib import Path
from typing import Optional

from lxml import etree

from plclab.errors import PlcLabError

SCHEMA_FILE = "tc6_xml_v201.xsd"
ENV = "PLCLAB_TC6_XSD"


def schema_path() -> Optional[Path]:
    """Where the TC6 schema is on this machine, or None."""
    env = os.environ.get(ENV)
    if env:
        path = Path(env)
        if not path.is_file():
            raise PlcLabError(f"{ENV}={env}: no such file")
        return path
    return _installed_schema()


@lru_cache(maxsize=1)
def _installed_schema() -> Optional[Path]:
    for dist in metadata.distributions():
        for f in dist.files or ():
            if f.name == SCHEMA_FILE:
                path = Path(str(dist.locate_file(f)))
                if path.is_file():
                    return path
    for path in (Path(__file__).with_name(SCHEMA_FILE),
                 Path.home() / "OpenPLC_Editor" / "editor" / "plcopen" / SCHEMA_FILE):
        if path.is_file():
            return path
    return None


@lru_cache(maxsize=4)
def _schema(path: Path) -> etree.XMLSchema:
    try:
        return etree.XMLSchema(etree.parse(str(path)))
    except (etree.XMLSyntaxError, etree.XMLSchemaParseError, OSError) as e:
        raise PlcLabError(f"{path}: not a usable XML schema: {e}") from None


def validate_bindings(data: bytes, where: str) -> None:
    """Check a document against the TC6 v2.01 model of the `plcopen` package; raises
    PlcLabError naming the first problem."""
    import dataclasses

    from plcopen.project import Project
    from xsdata.exceptions import ParserError
    from xsdata.formats.dataclass.parsers import XmlParser
    from xsdata.formats.dataclass.parsers.config import ParserConfig

    config = ParserConfig(fail_on_unknown_properties=True, fail_on_unknown_attributes=True,
                          fail_on_converter_warnings=True)
    try:
        project = XmlParser(config=config).from_bytes(data, Project)
    except (ParserError, ValueError, TypeError) as e:
        raise PlcLabError(f"{where}: not valid PLCopen TC6 XML: {e}") from None

    def walk(obj, path: str) -> None:
        if isinstance(obj, list):
            for i, item in enumerate(obj):
                walk(item, f"{path}[{i}]")
            return
        if not dataclasses.is_dataclass(obj):
            return
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            name = f.metadata.get("name", f.name)
            if f.metadata.get("required") and value is None:
                raise PlcLabError(f"{where}: not valid PLCopen TC6 XML: {path}: required <{name}> missing")
            walk(value, f"{path}/{name}")
    walk(project, "project")


def validate(tree: etree._ElementTree, where: str, schema: Optional[Path] = None) -> Optional[Path]:
    """Validate `tree` against the TC6 data model (always) and the TC6 schema file (`schema`
    or the one found, if any); raises PlcLabError naming the first error. Returns the schema
    file used, None when there is none."""
    validate_bindings(etree.tostring(tree), where)
    path = schema or schema_path()
    if path is None:
        return None
    xsd = _schema(path)
    # validate what will be written: the serialized bytes, so line numbers match the file
    doc = etree.fromstring(etree.tostring(tree, pretty_print=True))
    if not xsd.validate(doc):
        err = xsd.error_log[0]
        raise PlcLabError(f"{where}: not valid PLCopen TC6 XML: line {err.line}: {err.message}")
    return path
