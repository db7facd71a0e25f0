"""FUNCTION / FUNCTION_BLOCK / PROGRAM <-> TC6 `<pou>`.

A POU is its interface (return type, variable lists) and one ST body:
`<body><ST><xhtml:p><![CDATA[...]]></xhtml:p></ST></body>` holding the statement text exactly
as written, which is what Beremiz / OpenPLC Editor show in their ST editor and compile. The
comment written before the POU becomes its documentation.
"""
from __future__ import annotations

from lxml import etree

from plclab.errors import PlcLabError
from plclab.frontend import ast as A
from plclab.plcopen.datatypes import (NS, comment, formatted_text, local, read_formatted_text, sub,
                                      type_element, type_text)
from plclab.plcopen.interface import var_list_element, var_list_text
from plclab.plcopen.source import SourceText

POU_TYPES = {"FUNCTION": "function", "FUNCTION_BLOCK": "functionBlock", "PROGRAM": "program"}
ST_KINDS = {v: k for k, v in POU_TYPES.items()}


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


def pou_head(el: etree._Element) -> tuple[str, str]:
    """The ST kind (PROGRAM...) and the text of one `<pou>` before its statements: its
    documentation as a comment, header, VAR blocks."""
    name = el.get("name")
    kind = ST_KINDS.get(el.get("pouType", ""))
    where = f"POU {name}"
    if kind is None:
        raise PlcLabError(f"{where}: unknown pouType '{el.get('pouType')}'")
    lines = []
    doc = comment(read_formatted_text(el.find("ppx:documentation", NS)), "")
    if doc:
        lines.append(doc)
    header = f"{kind} {name}"
    interface = el.find("ppx:interface", NS)
    blocks = []
    if interface is not None:
        ret = interface.find("ppx:returnType", NS)
        if ret is not None:
            header += f" : {type_text(ret, where)}"
        blocks = [var_list_text(c, where) for c in interface
                  if isinstance(c.tag, str) and local(c) not in ("returnType", "addData", "documentation")]
    lines.append(header)
    return kind, "\n".join(lines) + "\n" + "".join(blocks)


def pou_body(el: etree._Element) -> tuple[str, etree._Element]:
    """The language (ST, IL, LD, FBD, SFC) and element of a `<pou>`'s one body."""
    bodies = el.findall("ppx:body", NS)
    inner = [c for b in bodies for c in b if isinstance(c.tag, str) and local(c) != "documentation"]
    if len(bodies) != 1 or len(inner) != 1:
        langs = ", ".join(local(c) for c in inner) or "no body"
        raise PlcLabError(f"POU {el.get('name')}: a POU needs exactly one body (found {langs})")
    return local(inner[0]), inner[0]


def pou_text(el: etree._Element) -> str:
    """The ST text of one `<pou>` with an ST body: its documentation as a comment, header,
    VAR blocks, body."""
    kind, head = pou_head(el)
    lang, body_el = pou_body(el)
    if lang != "ST":
        raise PlcLabError(f"POU {el.get('name')}: only a single ST body can be turned into ST text (found {lang})")
    body = read_formatted_text(body_el) or ""
    return head + body.strip("\n") + f"\nEND_{kind}\n"
