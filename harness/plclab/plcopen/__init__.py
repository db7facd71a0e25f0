"""PLCopen TC6 v2.01 XML: the project format OpenPLC Editor and Beremiz open, written from ST.

One module per concern: `datatypes` (types, values, variables), `interface` (VAR blocks),
`pous`, `configuration`, `project` (the document), `schema` (XSD validation), `compare` (same
program?), `source` (bodies and comments cut from the ST text). Reading a project back is the
front end's (frontend.plcxml, as OpenPLC Editor reads it).
"""
from __future__ import annotations

from plclab.plcopen.compare import first_difference
from plclab.plcopen.project import project_tree, to_bytes
from plclab.plcopen.schema import schema_path, validate

__all__ = ["first_difference", "project_tree", "schema_path", "to_bytes", "validate"]
