"""FUNCTION / FUNCTION_BLOCK / PROGRAM -> TC6 `<pou>` (read back by frontend.plcxml).

A POU is its interface (return type, variable lists) and one ST body:
`<body><ST><xhtml:p><![CDATA[...]]></xhtml:p></ST></body>` holding the statement text exactly
as written, which is what Beremiz / OpenPLC Editor show in their ST editor and compile. The
comment written before the POU becomes its documentation.
"""
from __future__ import annotations

from lxml import etree

from plclab.frontend import ast as A
from plclab.plcopen.datatypes import formatted_text, sub, type_element
from plclab.plcopen.interface import var_list_element
from plclab.plcopen.source import SourceText

POU_TYPES = {"FUNCTION": "function", "FUNCTION_BLOCK": "functionBlock", "PROGRAM": "program"}


def pou_element(parent: etree._Element, pou: A.PouDecl, src: SourceText) -> etree._Element:
    el = sub(parent, "pou", name=pou.name, pouType=POU_TYPES[pou.kind])
    interface = sub(el, "interface")
    if pou.return_type is not None:
        type_element(interface, "returnType", pou.return_type)
    for block in pou.blocks:
        var_list_element(interface, block, src)
    formatted_text(sub(el, "body"), "ST", src.pou_body(pou))
    doc = src.leading_comment(pou, skip_words=1)
    if doc:
        formatted_text(el, "documentation", doc)
    return el
