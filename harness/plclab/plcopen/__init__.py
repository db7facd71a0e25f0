"""PLCopen TC6 v2.01 XML: the project format OpenPLC Editor and Beremiz open.

One module per concern: `datatypes` (types, values, variables), `interface` (VAR blocks),
`pous`, `configuration`, `project` (the document, and ST back from it), `schema` (XSD
validation), `compare` (same program?), `source` (bodies and comments cut from the ST text).
"""
from __future__ import annotations

from plclab.plcopen.compare import first_difference
from plclab.plcopen.project import parse_xml, project_tree, st_from_tree, st_from_xml, to_bytes
from plclab.plcopen.schema import schema_path, validate

__all__ = ["first_difference", "parse_xml", "project_tree", "schema_path", "st_from_tree", "st_from_xml",
           "to_bytes", "validate"]
