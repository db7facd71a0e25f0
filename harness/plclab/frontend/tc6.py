"""The TC6 v2.01 XML a plc.xml is written in: namespaces, element names, formatted text (ST
bodies, documentation) and a type spelled as ST.

The one place both directions share: the front end reads a plc.xml with it (frontend.plcxml,
frontend.graphical), the PLCopen writer (plcopen/) writes one with it.
"""
from __future__ import annotations

from typing import Optional

from lxml import etree

from plclab.errors import PlcLabError

PPX = "http://www.plcopen.org/xml/tc6_0201"
XHTML = "http://www.w3.org/1999/xhtml"
NS = {"ppx": PPX, "xhtml": XHTML}

# TC6's elementary type elements (TIME_OF_DAY and DATE_AND_TIME have only their short names there)
ELEMENTARY_TAGS = ("BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT", "USINT",
                   "UINT", "UDINT", "ULINT", "REAL", "LREAL", "TIME", "DATE", "DT", "TOD")


def q(tag: str) -> str:
    """A TC6 element name with its namespace."""
    return f"{{{PPX}}}{tag}"


def local(el: etree._Element) -> str:
    return etree.QName(el).localname


def read_formatted_text(el: Optional[etree._Element]) -> Optional[str]:
    """The text of `<tag><xhtml:p>text</xhtml:p></tag>` (the layout around <xhtml:p> is not part of it)."""
    if el is None:
        return None
    inner = [c for c in el if isinstance(c.tag, str)]
    return "".join(inner[0].itertext()) if inner else (el.text or "").strip()


def type_text(el: etree._Element, where: str) -> str:
    """The ST spelling of a dataType-typed element (type, baseType, returnType), lengths kept:
    how the blocks of a project and its variables are typed for the drawing's temporaries
    (frontend.plcxml spells declarations as the Editor does)."""
    content = [c for c in el if isinstance(c.tag, str)]
    if len(content) != 1:
        raise PlcLabError(f"{where}: a type element needs exactly one child")
    c = content[0]
    name = local(c)
    if name in ("string", "wstring"):
        word = name.upper()
        return f"{word}[{c.get('length')}]" if c.get("length") else word
    if name == "derived":
        return c.get("name")
    if name == "array":
        dims = ", ".join(f"{d.get('lower')}..{d.get('upper')}" for d in c.findall("ppx:dimension", NS))
        return f"ARRAY[{dims}] OF {type_text(c.find('ppx:baseType', NS), where)}"
    if name == "enum":
        return "(" + ", ".join(v.get("name") for v in c.findall("ppx:values/ppx:value", NS)) + ")"
    if name in ("subrangeSigned", "subrangeUnsigned"):
        rng = c.find("ppx:range", NS)
        return f"{type_text(c.find('ppx:baseType', NS), where)} ({rng.get('lower')}..{rng.get('upper')})"
    if name in ELEMENTARY_TAGS:
        return name
    raise PlcLabError(f"{where}: type <{name}> has no ST form here")


def documented(line: str, doc: Optional[str], indent: str) -> str:
    """A declaration line with its documentation: a one-line comment after it, a longer one
    on the lines before it."""
    if not doc:
        return f"{indent}{line}\n"
    if "\n" in doc:
        return f"{indent}{comment(doc, '')}\n{indent}{line}\n"
    return f"{indent}{line}{comment(doc, '    ')}\n"


def comment(doc: Optional[str], sep: str) -> str:
    """A documentation text as an ST comment after `sep` ('' when there is none)."""
    if not doc:
        return ""
    return f"{sep}(* {doc.replace('*)', '* )')} *)"
