"""TC6 data types, values and variable declarations, AST -> XML (the front end reads them back:
frontend.tc6, frontend.plcxml).

TC6 spells a type as one child element: an elementary type (`<INT/>`, `<TOD/>`,
`<string length="20"/>`), `<derived name="..."/>` for user types and FB instances,
`<array>`, `<enum>`, `<subrangeSigned>`/`<subrangeUnsigned>` or `<struct>`. A value is
`<simpleValue value="..."/>`, `<arrayValue>` (with `repetitionValue` for `n(v)`) or
`<structValue>` (one `value member="..."` per field). Everything here is what Beremiz /
OpenPLC Editor read and write.
"""
from __future__ import annotations

from typing import Any, Optional

from lxml import etree

from plclab.errors import PlcLabError
from plclab.frontend import ast as A
from plclab.frontend import sttext
from plclab.frontend.tc6 import ELEMENTARY_TAGS, XHTML, q
from plclab.plcopen.source import SourceText


# ST type name -> TC6 element (TIME_OF_DAY and DATE_AND_TIME have only their short names there)
ELEMENTARY = {n: n for n in ELEMENTARY_TAGS}
ELEMENTARY.update({"TIME_OF_DAY": "TOD", "DATE_AND_TIME": "DT"})
_UNSIGNED = {"USINT", "UINT", "UDINT", "ULINT", "BYTE", "WORD", "DWORD", "LWORD"}


def sub(parent: etree._Element, tag: str, **attrs: str) -> etree._Element:
    return etree.SubElement(parent, q(tag), {k: v for k, v in attrs.items() if v is not None})


def formatted_text(parent: etree._Element, tag: str, text: str) -> etree._Element:
    """`<tag><xhtml:p><![CDATA[text]]></xhtml:p></tag>`: how TC6 carries ST bodies and comments."""
    el = sub(parent, tag)
    p = etree.SubElement(el, f"{{{XHTML}}}p")
    p.text = etree.CDATA(text) if "]]>" not in text else text
    return el


# --------------------------------------------------------------------------- AST -> XML

def type_element(parent: etree._Element, tag: str, t: A.TypeRef,
                 src: Optional[SourceText] = None) -> etree._Element:
    """`<tag>` (type, baseType, returnType) holding the TC6 form of `t` (`src`: where the
    comments documenting a struct's fields are)."""
    el = sub(parent, tag)
    _type_content(el, t, src)
    return el


def _type_content(el: etree._Element, t: A.TypeRef, src: Optional[SourceText]) -> None:
    if isinstance(t, A.NamedType):
        if t.key in ELEMENTARY:
            sub(el, ELEMENTARY[t.key])
        else:
            sub(el, "derived", name=t.name)
    elif isinstance(t, A.StringTypeRef):
        sub(el, "wstring" if t.wide else "string",
            length=sttext.expr(t.length) if t.length is not None else None)
    elif isinstance(t, A.ArrayTypeRef):
        arr = sub(el, "array")
        for lo, hi in t.ranges:
            sub(arr, "dimension", lower=sttext.expr(lo), upper=sttext.expr(hi))
        type_element(arr, "baseType", t.elem)
    elif isinstance(t, A.EnumTypeRef):
        values = sub(sub(el, "enum"), "values")
        for name, _line, _col in t.values:
            sub(values, "value", name=name)
    elif isinstance(t, A.SubrangeTypeRef):
        rng = sub(el, "subrangeUnsigned" if t.base.key in _UNSIGNED else "subrangeSigned")
        sub(rng, "range", lower=sttext.expr(t.lo), upper=sttext.expr(t.hi))
        type_element(rng, "baseType", t.base)
    elif isinstance(t, A.StructTypeRef):
        struct = sub(el, "struct")
        for f in t.fields:
            variable_element(struct, f, src)
    else:  # pragma: no cover - the parser makes no other TypeRef
        raise PlcLabError(f"line {t.line}: no PLCopen form for {type(t).__name__}")


def value_element(parent: etree._Element, tag: str, init: Any, **attrs: str) -> etree._Element:
    """`<tag>` (initialValue, value) holding a simple, array or struct value."""
    el = sub(parent, tag, **attrs)
    if isinstance(init, A.ArrayInit):
        arr = sub(el, "arrayValue")
        for count, value in init.items:
            rep = {"repetitionValue": sttext.expr(count)} if count is not None else {}
            if value is None:   # `3()`: three default values
                sub(sub(arr, "value", **rep), "simpleValue")
            else:
                value_element(arr, "value", value, **rep)
    elif isinstance(init, A.StructInit):
        st = sub(el, "structValue")
        for name, _line, _col, value in init.fields:
            value_element(st, "value", value, member=name)
    else:
        sub(el, "simpleValue", value=sttext.expr(init))
    return el


def variable_element(parent: etree._Element, d: A.VarDecl, src: Optional[SourceText]) -> etree._Element:
    """One `<variable>`: name, `address` if located, type, initial value, documentation."""
    if not d.name:
        raise PlcLabError(f"line {d.line}: PLCopen XML has no form for an unnamed located variable "
                          f"(AT {d.location.text}); give it a name")
    if d.edge:
        raise PlcLabError(f"line {d.line}: PLCopen XML has no form for {d.edge} on '{d.name}'")
    var = sub(parent, "variable", name=d.name, address=d.location.text if d.location else None)
    type_element(var, "type", d.type_ref)
    if d.init is not None:
        value_element(var, "initialValue", d.init)
    doc = src.line_comment(d) if src is not None else None
    if doc:
        formatted_text(var, "documentation", doc)
    return var


def data_type_element(parent: etree._Element, t: A.TypeDecl, src: SourceText) -> etree._Element:
    """One `<dataType>` of `types/dataTypes`; the comment before a TYPE block documents its
    first type, the comment after a declaration documents that declaration."""
    el = sub(parent, "dataType", name=t.name)
    type_element(el, "baseType", t.type_ref, src)
    if t.init is not None:
        value_element(el, "initialValue", t.init)
    docs = []
    if src.keyword_before(t) == "TYPE":
        docs.append(src.leading_comment(t, skip_words=1))
    if not isinstance(t.type_ref, A.StructTypeRef):
        docs.append(src.line_comment(t))
    doc = "\n".join(d for d in docs if d)
    if doc:
        formatted_text(el, "documentation", doc)
    return el


# --------------------------------------------------------------------------- XML -> ST text
