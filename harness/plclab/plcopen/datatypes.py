"""TC6 data types, values and variable declarations, both ways (AST -> XML, XML -> ST text).

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
from plclab.plcopen import sttext
from plclab.plcopen.source import SourceText

PPX = "http://www.plcopen.org/xml/tc6_0201"
XHTML = "http://www.w3.org/1999/xhtml"
NS = {"ppx": PPX, "xhtml": XHTML}

# ST type name -> TC6 element (TIME_OF_DAY and DATE_AND_TIME have only their short names there)
ELEMENTARY = {n: n for n in ("BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT", "USINT",
                             "UINT", "UDINT", "ULINT", "REAL", "LREAL", "TIME", "DATE", "DT", "TOD")}
ELEMENTARY.update({"TIME_OF_DAY": "TOD", "DATE_AND_TIME": "DT"})
_UNSIGNED = {"USINT", "UINT", "UDINT", "ULINT", "BYTE", "WORD", "DWORD", "LWORD"}


def q(tag: str) -> str:
    """A TC6 element name with its namespace."""
    return f"{{{PPX}}}{tag}"


def local(el: etree._Element) -> str:
    return etree.QName(el).localname


def sub(parent: etree._Element, tag: str, **attrs: str) -> etree._Element:
    return etree.SubElement(parent, q(tag), {k: v for k, v in attrs.items() if v is not None})


def formatted_text(parent: etree._Element, tag: str, text: str) -> etree._Element:
    """`<tag><xhtml:p><![CDATA[text]]></xhtml:p></tag>`: how TC6 carries ST bodies and comments."""
    el = sub(parent, tag)
    p = etree.SubElement(el, f"{{{XHTML}}}p")
    p.text = etree.CDATA(text) if "]]>" not in text else text
    return el


def read_formatted_text(el: Optional[etree._Element]) -> Optional[str]:
    """The text of `<tag><xhtml:p>text</xhtml:p></tag>` (the layout around <xhtml:p> is not part of it)."""
    if el is None:
        return None
    inner = [c for c in el if isinstance(c.tag, str)]
    return "".join(inner[0].itertext()) if inner else (el.text or "").strip()


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

def type_text(el: etree._Element, where: str) -> str:
    """The ST spelling of a dataType-typed element (type, baseType, returnType)."""
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
    if name in ELEMENTARY.values():
        return name
    raise PlcLabError(f"{where}: type <{name}> has no ST form here")


def value_text(el: etree._Element) -> str:
    """The ST initializer of a value-typed element (initialValue, value)."""
    content = [c for c in el if isinstance(c.tag, str)]
    if not content:
        return ""
    c = content[0]
    name = local(c)
    if name == "simpleValue":
        return c.get("value", "")
    if name == "arrayValue":
        items = []
        for v in c.findall("ppx:value", NS):
            rep = v.get("repetitionValue")
            items.append(f"{rep}({value_text(v)})" if rep is not None else value_text(v))
        return f"[{', '.join(items)}]"
    if name == "structValue":
        return "(" + ", ".join(f"{v.get('member')} := {value_text(v)}" for v in c.findall("ppx:value", NS)) + ")"
    return ""


def variable_text(var: etree._Element, where: str, indent: str) -> str:
    """`<indent>Name [AT %IX0.0] : TYPE [:= value];  (* doc *)` and a line break."""
    name = var.get("name")
    at = f" AT {var.get('address')}" if var.get("address") else ""
    text = f"{name}{at} : {type_text(var.find('ppx:type', NS), f'{where}, variable {name}')}"
    init = var.find("ppx:initialValue", NS)
    if init is not None:
        text += f" := {value_text(init)}"
    return documented(text + ";", read_formatted_text(var.find("ppx:documentation", NS)), indent)


def data_type_text(dt: etree._Element) -> str:
    """One declaration of a TYPE block (without the TYPE / END_TYPE around it)."""
    name = dt.get("name")
    base = dt.find("ppx:baseType", NS)
    doc = read_formatted_text(dt.find("ppx:documentation", NS))
    struct = base.find("ppx:struct", NS) if base is not None else None
    if struct is not None:
        fields = "".join(variable_text(v, f"type {name}", " " * 8) for v in struct.findall("ppx:variable", NS))
        return documented(f"{name} : STRUCT", doc, " " * 4) + fields + "    END_STRUCT;\n"
    text = f"{name} : {type_text(base, f'type {name}')}"
    init = dt.find("ppx:initialValue", NS)
    if init is not None:
        text += f" := {value_text(init)}"
    return documented(text + ";", doc, " " * 4)


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
