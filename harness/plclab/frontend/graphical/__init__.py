"""LD and FBD bodies of a plc.xml -> ST, exactly as OpenPLC Editor makes it for matiec.

`places` (where generated text came from on the drawing), `diagram` (the body as elements
and wires), `library` (the boxes a drawing may use), `generator` (the translation of one
POU, with the Editor's rules in its docstring). `frontend.plcxml.project_source` puts the
POUs of a project together.
"""
from __future__ import annotations

from plclab.frontend.graphical.diagram import Element, read_elements, sections
from plclab.frontend.graphical.generator import MAX_VISITS, PouGenerator
from plclab.frontend.graphical.library import BlockInfo, Library, library_block, st_library, xml_structs
from plclab.frontend.graphical.places import (GeneratedSource, Place, TextBuilder, drawing_location,
                                             generation_error, locate)

GRAPHICAL = ("LD", "FBD")

__all__ = ["BlockInfo", "Element", "GRAPHICAL", "GeneratedSource", "Library", "MAX_VISITS", "Place", "PouGenerator",
           "TextBuilder", "drawing_location", "generation_error", "library_block", "locate", "read_elements",
           "sections", "st_library", "xml_structs"]
