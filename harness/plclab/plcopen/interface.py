"""VAR blocks -> TC6 variable lists (`inputVars`, `localVars constant="true"`, ...).

Each ST block becomes one list, in the order written, so that the XML reads back (as OpenPLC
Editor reads it: frontend.plcxml) to the same blocks with the same qualifiers; the comment
before a block documents the list.
"""
from __future__ import annotations

from typing import Optional

from lxml import etree

from plclab.frontend import ast as A
from plclab.plcopen.datatypes import formatted_text, sub, variable_element
from plclab.plcopen.source import SourceText

LIST_TAGS = {"VAR": "localVars", "VAR_TEMP": "tempVars", "VAR_INPUT": "inputVars", "VAR_OUTPUT": "outputVars",
             "VAR_IN_OUT": "inOutVars", "VAR_EXTERNAL": "externalVars", "VAR_GLOBAL": "globalVars"}
_QUALIFIERS = (("constant", "CONSTANT"), ("retain", "RETAIN"), ("nonretain", "NON_RETAIN"))


def var_list_element(parent: etree._Element, block: A.VarBlock, src: SourceText,
                     tag: Optional[str] = None) -> etree._Element:
    """One TC6 variable list for `block` (`tag` overrides the section's list name)."""
    quals = set(getattr(block, "qualifiers", []))
    if block.constant:
        quals.add("CONSTANT")
    if block.retain:
        quals.add("RETAIN")
    attrs = {attr: "true" for attr, word in _QUALIFIERS if word in quals}
    el = sub(parent, tag or LIST_TAGS[block.section], **attrs)
    for d in block.decls:
        variable_element(el, d, src)
    doc = src.leading_comment(block)
    if doc:
        formatted_text(el, "documentation", doc)
    return el
