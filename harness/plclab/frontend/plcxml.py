"""A plc.xml (OpenPLC Editor's TC6 project) read as the ST OpenPLC Editor's generator writes for it.

OpenPLC never compiles a project file: the Editor's generator (PLCGenerator.py) writes ST and
matiec compiles that. So a project means here what that ST means, rule by rule (the table in
docs/ladder.md names each rule and the test that holds it):

* Variable lists. Each list (`localVars`, `inputVars`, `outputVars`, `inOutVars`,
  `externalVars`, `tempVars`) becomes up to two VAR blocks of its section: its variables
  without an address, then its located ones (`START AT %IX0.0`), each keeping the list's order;
  a list with no variable writes no block. So a ladder POU may keep its I/O and its TON in one
  table. Both halves carry the list's one qualifier: CONSTANT, else RETAIN, else NON_RETAIN
  (the Editor writes only the first one set).
* Variables. `name [AT address] : type [:= initial value];` with the type as the Editor spells
  it (derived types by name, `ARRAY [1..5] OF INT`); a STRING / WSTRING initial value
  without quotes gets them. A variable whose type is a function block is an instance: the
  Editor writes it without address or initial value, so those are refused here by name rather
  than silently dropped; so are what the Editor cannot spell (a STRING length, an inline enum,
  subrange or structure, an array of arrays): it would write no or broken ST for them.
* Global lists of a configuration or resource: one VAR_GLOBAL block each (located and not
  mixed, as IEC allows there), the same qualifier rule.
* Data types, POU headers, tasks and program instances as the Editor writes them; a POU with
  no variable at all is refused (the Editor refuses to generate it).
* Documentation: the Editor writes none; plclab keeps it as ST comments (no code).

LD and FBD bodies go through `frontend.graphical`; ST bodies are taken as written.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Callable, Optional

from lxml import etree

from plclab.errors import PlcLabError
from plclab.frontend.graphical import (GRAPHICAL, GeneratedSource, Library, Place, PouGenerator, TextBuilder,
                                       generation_error, library_block, st_library, xml_structs)
from plclab.frontend.tc6 import NS, comment, documented, local, q, read_formatted_text, type_text

LIST_SECTIONS = {"localVars": "VAR", "tempVars": "VAR_TEMP", "inputVars": "VAR_INPUT", "outputVars": "VAR_OUTPUT",
                 "inOutVars": "VAR_IN_OUT", "externalVars": "VAR_EXTERNAL", "globalVars": "VAR_GLOBAL"}
POU_KINDS = {"function": "FUNCTION", "functionBlock": "FUNCTION_BLOCK", "program": "PROGRAM"}
_ELEMENTARY = {"BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT",
               "ULINT", "REAL", "LREAL", "TIME", "DATE", "DT", "TOD"}
_DURATION = re.compile(r"P(?:(\d+(?:\.\d+)?)D)?(?:T(?:(\d+(?:\.\d+)?)H)?(?:(\d+(?:\.\d+)?)M)?(?:(\d+(?:\.\d+)?)S)?)?$", re.I)


def qualifier(var_list: etree._Element) -> Optional[str]:
    """The one qualifier the Editor writes for a list: CONSTANT, else RETAIN, else NON_RETAIN."""
    for attr, word in (("constant", "CONSTANT"), ("retain", "RETAIN"), ("nonretain", "NON_RETAIN")):
        if var_list.get(attr) in ("true", "1"):
            return word
    return None


class Declarations:
    """The declarations of one project as the Editor writes them (`is_block`: whether a type
    name is a function block or function of its library, so a variable of it is an instance)."""

    def __init__(self, root: etree._Element, is_block: Callable[[str], bool]):
        self.is_block = is_block
        self.data_types = {dt.get("name", ""): dt for dt in root.findall("ppx:types/ppx:dataTypes/ppx:dataType", NS)}

    # -- types ---------------------------------------------------------------------------------
    def _string(self, c: etree._Element, where: str) -> str:
        word = local(c).upper()
        if c.get("length"):
            raise PlcLabError(f"{where}: {word}[{c.get('length')}]: OpenPLC Editor drops the length and writes "
                              f"{word}; declare it {word} (or use a data type written in ST)")
        return word

    def _content(self, el: Optional[etree._Element], where: str) -> etree._Element:
        content = [c for c in el if isinstance(c.tag, str)] if el is not None else []
        if len(content) != 1:
            raise PlcLabError(f"{where}: a type element needs exactly one child")
        return content[0]

    def _cannot(self, tag: str, where: str) -> PlcLabError:
        return PlcLabError(f"{where}: an inline <{tag}> type: OpenPLC Editor writes no ST that compiles for it; "
                           "declare it as a data type and use its name")

    def _array(self, c: etree._Element, where: str) -> str:
        base = self._content(c.find("ppx:baseType", NS), where)
        tag = local(base)
        if tag == "derived":
            base_name = base.get("name", "")
        elif tag in ("string", "wstring"):
            base_name = self._string(base, where)
        elif tag in _ELEMENTARY:
            base_name = tag
        else:
            raise self._cannot(f"array of {tag}", where)
        dims = ",".join(f"{d.get('lower')}..{d.get('upper')}" for d in c.findall("ppx:dimension", NS))
        return f"ARRAY [{dims}] OF {base_name}"

    def type_of(self, type_el: Optional[etree._Element], where: str) -> str:
        """A variable's type as the Editor spells it (its gettypeAsText)."""
        c = self._content(type_el, where)
        tag = local(c)
        if tag == "derived":
            return c.get("name", "")
        if tag in ("string", "wstring"):
            return self._string(c, where)
        if tag == "array":
            return self._array(c, where)
        if tag in _ELEMENTARY:
            return tag
        raise self._cannot(tag, where)

    def base_type(self, type_name: str) -> str:
        """A type name down to its base (STRING for a data type that is a STRING...)."""
        seen: set[str] = set()
        while type_name in self.data_types and type_name not in seen:
            seen.add(type_name)
            base = self.data_types[type_name].find("ppx:baseType", NS)
            content = [c for c in base if isinstance(c.tag, str)] if base is not None else []
            if len(content) != 1:
                break
            tag = local(content[0])
            if tag == "derived":
                type_name = content[0].get("name", "")
            else:
                return tag.upper()
        return type_name.upper()

    # -- values ----------------------------------------------------------------------------------
    def value(self, el: Optional[etree._Element], type_name: str) -> Optional[str]:
        """An initial value as the Editor writes it: its text, quoted when a STRING's is not."""
        if el is None:
            return None
        text = _value_text(el)
        base = self.base_type(type_name)
        if base == "STRING" and not text.startswith("'") and not text.endswith("'"):
            return f"'{text}'"
        if base == "WSTRING" and not text.startswith('"') and not text.endswith('"'):
            return f'"{text}"'
        return text

    # -- variables -------------------------------------------------------------------------------
    def variable(self, var: etree._Element, where: str, indent: str, instances: bool) -> tuple[str, bool]:
        """One declaration line and whether it is located (`instances`: a variable of a block
        type is an instance, written without address or value, as in a POU's lists)."""
        name = var.get("name", "")
        here = f"{where}, variable {name}"
        type_name = self.type_of(var.find("ppx:type", NS), here)
        address = var.get("address") or None
        init = var.find("ppx:initialValue", NS)
        if instances and local(self._content(var.find("ppx:type", NS), here)) == "derived" and self.is_block(type_name):
            if address is not None:
                raise PlcLabError(f"{here}: {type_name} instance located at {address}: OpenPLC Editor drops the "
                                  "address; clear the Location")
            if init is not None:
                raise PlcLabError(f"{here}: {type_name} instance with an initial value: OpenPLC Editor drops it "
                                  "(OpenPLC would run the instance without it); clear Initial Value and wire "
                                  "the inputs instead")
        text = name + (f" AT {address}" if address is not None else "") + f" : {type_name}"
        value = self.value(init, type_name)
        if value is not None:
            text += f" := {value}"
        return documented(text + ";", read_formatted_text(var.find("ppx:documentation", NS)), indent), \
            address is not None

    def var_list(self, var_list: etree._Element, where: str, indent: str = "", split: bool = True) -> str:
        """The VAR blocks of one variable list: its unlocated variables, then its located ones
        (`split`); a global list is one block."""
        tag = local(var_list)
        section = LIST_SECTIONS.get(tag)
        if section is None:
            raise PlcLabError(f"{where}: <{tag}> variables have no ST form in OpenPLC Editor")
        head = section + (f" {qualifier(var_list)}" if qualifier(var_list) else "")
        lines = [self.variable(v, where, indent + "    ", split) for v in var_list.findall("ppx:variable", NS)]
        halves = ([[t for t, located in lines if not located], [t for t, located in lines if located]]
                  if split else [[t for t, _ in lines]])
        doc = comment(read_formatted_text(var_list.find("ppx:documentation", NS)), "")
        out = indent + doc + "\n" if doc and lines else ""
        for half in halves:
            if half:
                out += f"{indent}{head}\n" + "".join(half) + f"{indent}END_VAR\n"
        return out

    # -- data types ------------------------------------------------------------------------------
    def data_type(self, dt: etree._Element) -> str:
        """One declaration of the TYPE block, as the Editor's GenerateDataType writes it."""
        name = dt.get("name", "")
        where = f"type {name}"
        c = self._content(dt.find("ppx:baseType", NS), where)
        tag = local(c)
        doc = read_formatted_text(dt.find("ppx:documentation", NS))
        if tag == "struct":
            fields = ""
            for v in c.findall("ppx:variable", NS):
                fname = v.get("name", "")
                there = f"{where}, field {fname}"
                ftype = self.type_of(v.find("ppx:type", NS), there)
                text = f"{fname} : {ftype}"
                value = self.value(v.find("ppx:initialValue", NS), ftype)
                if value is not None:
                    text += f" := {value}"
                fields += documented(text + ";", read_formatted_text(v.find("ppx:documentation", NS)), " " * 8)
            return documented(f"{name} : STRUCT", doc, " " * 4) + fields + "    END_STRUCT;\n"
        if tag == "derived":
            base = c.get("name", "")
        elif tag in ("subrangeSigned", "subrangeUnsigned"):
            inner = local(self._content(c.find("ppx:baseType", NS), where))
            if inner not in _ELEMENTARY:
                raise self._cannot(f"{tag} of {inner}", where)
            rng = c.find("ppx:range", NS)
            base = f"{inner} ({rng.get('lower')}..{rng.get('upper')})"
        elif tag == "enum":
            base = "(" + ", ".join(v.get("name", "") for v in c.findall("ppx:values/ppx:value", NS)) + ")"
        elif tag == "array":
            base = self._array(c, where)
        elif tag in ("string", "wstring"):
            base = self._string(c, where)
        elif tag in _ELEMENTARY:
            base = tag
        else:
            raise self._cannot(tag, where)
        text = f"{name} : {base}"
        value = self.value(dt.find("ppx:initialValue", NS), name)
        if value is not None:
            text += f" := {value}"
        return documented(text + ";", doc, " " * 4)

    # -- POUs --------------------------------------------------------------------------------------
    def pou_head(self, el: etree._Element) -> tuple[str, str]:
        """The ST kind (PROGRAM...) and the text of one `<pou>` before its statements: its
        documentation as a comment, header, VAR blocks."""
        name = el.get("name")
        kind = POU_KINDS.get(el.get("pouType", ""))
        where = f"POU {name}"
        if kind is None:
            raise PlcLabError(f"{where}: unknown pouType '{el.get('pouType')}'")
        doc = comment(read_formatted_text(el.find("ppx:documentation", NS)), "")
        header = f"{kind} {name}"
        interface = el.find("ppx:interface", NS)
        blocks = ""
        if interface is not None:
            ret = interface.find("ppx:returnType", NS)
            if ret is not None:
                c = self._content(ret, f"{where}, return type")
                tag = local(c)
                if tag == "derived":
                    header += f" : {c.get('name')}"
                elif tag in ("string", "wstring"):
                    header += f" : {self._string(c, f'{where}, return type')}"
                elif tag in _ELEMENTARY:
                    header += f" : {tag}"
                else:
                    raise self._cannot(tag, f"{where}, return type")
            blocks = "".join(self.var_list(c, where) for c in interface
                             if isinstance(c.tag, str) and local(c) not in ("returnType", "addData", "documentation"))
        if not blocks:
            raise PlcLabError(f"{where}: no variable defined in this POU (OpenPLC Editor refuses to generate it)")
        return kind, (doc + "\n" if doc else "") + header + "\n" + blocks

    # -- configurations ------------------------------------------------------------------------------
    def configuration(self, el: etree._Element) -> str:
        """The ST CONFIGURATION of one `<configuration>`, as the Editor writes it."""
        name = el.get("name")
        lines = [f"CONFIGURATION {name}\n"]
        lines += [self.var_list(g, f"configuration {name}", "    ", split=False)
                  for g in el.findall("ppx:globalVars", NS)]
        for r in el.findall("ppx:resource", NS):
            rwhere = f"resource {r.get('name')}"
            lines.append(f"    RESOURCE {r.get('name')} ON PLC\n")
            lines += [self.var_list(g, rwhere, "        ", split=False) for g in r.findall("ppx:globalVars", NS)]
            instances = []
            for t in r.findall("ppx:task", NS):
                lines.append(f"        TASK {t.get('name')} ({', '.join(_task_params(t, rwhere))});\n")
                instances += [f"        PROGRAM {p.get('name')} WITH {t.get('name')} : {p.get('typeName')};\n"
                              for p in t.findall("ppx:pouInstance", NS)]
            instances += [f"        PROGRAM {p.get('name')} : {p.get('typeName')};\n"
                          for p in r.findall("ppx:pouInstance", NS)]
            lines += instances
            lines.append("    END_RESOURCE\n")
        lines.append("END_CONFIGURATION\n")
        return "".join(lines)


def _value_text(el: etree._Element) -> str:
    """A value element's text as the Editor's getvalue gives it: `[1, 3(0)]` (a repetition of
    1 or none is the value alone), `(a := 1, b := 2)`."""
    content = [c for c in el if isinstance(c.tag, str)]
    if not content:
        return ""
    c = content[0]
    tag = local(c)
    if tag == "simpleValue":
        return c.get("value", "")
    if tag == "arrayValue":
        items = []
        for v in c.findall("ppx:value", NS):
            try:
                rep = int(v.get("repetitionValue", ""))
            except ValueError:
                rep = 1
            items.append(f"{rep}({_value_text(v)})" if rep > 1 else _value_text(v))
        return f"[{', '.join(items)}]"
    if tag == "structValue":
        return "(" + ", ".join(f"{v.get('member')} := {_value_text(v)}" for v in c.findall("ppx:value", NS)) + ")"
    return ""


def _task_params(t: etree._Element, where: str) -> list[str]:
    """SINGLE, INTERVAL and PRIORITY of a task: the Editor pastes the attributes as written."""
    here = f"{where}, task {t.get('name')}"
    params = []
    single = t.get("single")
    if single is not None:
        if not single or (single.startswith("[") and single.endswith("]")):
            raise PlcLabError(f"{here}: SINGLE needs one BOOL variable (OpenPLC Editor writes MULTI for a list, "
                              "which OpenPLC cannot compile)")
        params.append(f"SINGLE := {single}")
    interval = t.get("interval")
    if interval:
        params.append(f"INTERVAL := {interval_literal(interval)}")
    try:
        params.append(f"PRIORITY := {int(t.get('priority', ''))}")
    except ValueError:
        raise PlcLabError(f"{here}: PRIORITY needs a number (found '{t.get('priority')}')") from None
    return params


def interval_literal(text: str) -> str:
    """A task interval as an ST literal: IEC text as is; an XML duration (`PT0.01S`, as PLCopen
    v1 files have it) converted, as the Editor converts it when it opens such a file."""
    m = _DURATION.match(text.strip())
    if not m or not any(m.groups()):
        return text
    days, hours, minutes, seconds = (float(g) if g else 0.0 for g in m.groups())
    total_ms = round((((days * 24 + hours) * 60 + minutes) * 60 + seconds) * 1000, 3)
    return "T#" + f"{total_ms:f}".rstrip("0").rstrip(".") + "ms"


def pou_body(el: etree._Element) -> tuple[str, etree._Element]:
    """The language (ST, IL, LD, FBD, SFC) and element of a `<pou>`'s one body."""
    bodies = el.findall("ppx:body", NS)
    inner = [c for b in bodies for c in b if isinstance(c.tag, str) and local(c) != "documentation"]
    if len(bodies) != 1 or len(inner) != 1:
        langs = ", ".join(local(c) for c in inner) or "no body"
        raise PlcLabError(f"POU {el.get('name')}: a POU needs exactly one body (found {langs})")
    return local(inner[0]), inner[0]


# --------------------------------------------------------------------------- the project

def parse_xml(data: bytes, where: str) -> etree._ElementTree:
    """Parse TC6 XML bytes; anything but a TC6 `project` is one clear error."""
    try:
        tree = etree.ElementTree(etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True)))
    except etree.XMLSyntaxError as e:
        raise PlcLabError(f"{where}: not well-formed XML: {e}") from None
    if tree.getroot().tag != q("project"):
        raise PlcLabError(f"{where}: not a PLCopen TC6 v2.01 project (root <{tree.getroot().tag}>)")
    return tree


def st_from_tree(tree: etree._ElementTree) -> str:
    """ST text for a TC6 project: TYPE block, POUs, configurations, in the XML's order (LD
    and FBD bodies turned into ST as OpenPLC Editor does it)."""
    return str(project_source(tree, ""))


def project_source(tree: etree._ElementTree, file: str, others: Optional[Library] = None) -> GeneratedSource:
    """The ST of a TC6 project, knowing for each piece what it was made from (`file`: the
    name diagnostics give the project; `others`: blocks of ST files compiled with it)."""
    root = tree.getroot()
    out = TextBuilder()
    first = True

    def part(text: str, place: Optional[Place]) -> None:
        nonlocal first
        if not first:
            out.add("\n")
        first = False
        for line in text.splitlines(keepends=True):
            out.add(line, place)

    pous = root.findall("ppx:types/ppx:pous/ppx:pou", NS)
    project_pous = {p.get("name", ""): p for p in pous}
    decls = Declarations(root, lambda name: library_block(name, project_pous, others) is not None)
    title = root.findtext("ppx:contentHeader/ppx:Comment", namespaces=NS)
    if title:
        part(f"(* {title.replace('*)', '* )')} *)\n", None)
    if decls.data_types:
        part("TYPE\n" + "".join(decls.data_type(dt) for dt in decls.data_types.values()) + "END_TYPE\n",
             Place("TYPE", detail="data types"))
    globals_ = global_types(root)
    library = Library(dict(others.blocks) if others else {}, {**(others.structs if others else {}), **xml_structs(root)})
    for p in pous:
        name = p.get("name", "")
        lang, body = pou_body(p)
        kind, head = decls.pou_head(p)
        if not first:
            out.add("\n")
        first = False
        if lang == "ST":
            for line in head.splitlines(keepends=True):
                out.add(line, _declaration_place(name, line))
            text = (read_formatted_text(body) or "").strip("\n")
            for n, line in enumerate(text.split("\n"), 1):
                out.add(line + "\n", Place(name, "ST", detail=f"line {n} of its body"))
        elif lang in GRAPHICAL:
            own = interface_types(p)
            gen = PouGenerator(p, lang, body, file, project_pous, {**globals_, **own}, library, set(own))
            try:
                gen.generate()
            except RecursionError:
                raise generation_error(file, Place(name, lang), "the diagram is wired too deep to translate "
                                                                "(a chain of hundreds of elements): split it") from None
            for line in head.splitlines(keepends=True):
                out.add(line, _declaration_place(name, line))
            if gen.extra:
                out.add("VAR\n", Place(name, lang, detail="variables the Editor adds"))
                for var, type_name, owner in gen.extra:
                    element = gen.by_id.get(owner) if owner is not None else None
                    out.add(f"    {var} : {type_name};\n",
                            gen.place(element) if element is not None else
                            Place(name, lang, detail=f"variable {var} the Editor adds"))
                out.add("END_VAR\n", Place(name, lang, detail="variables the Editor adds"))
            if not gen.program:
                raise generation_error(file, Place(name, lang), "the body is empty (OpenPLC Editor refuses to "
                                                                "generate it)")
            for text, info in gen.program:
                owner = gen.by_id.get(info[2]) if len(info) > 2 else None
                out.add(text, gen.place(owner) if owner is not None else None)
        else:
            what = "SFC (sequential function chart)" if lang == "SFC" else lang
            raise generation_error(file, Place(name, lang), f"{what} bodies are not supported: "
                                                            "write this POU in ST, LD or FBD")
        out.add(f"END_{kind}\n", Place(name, detail="declarations"))
    for c in root.findall("ppx:instances/ppx:configurations/ppx:configuration", NS):
        part(decls.configuration(c), Place(f"configuration {c.get('name')}"))
    return GeneratedSource(out.text(), out.spans, file)


_DECLARED = re.compile(r"^\s+([A-Za-z_]\w*)\s*(?:AT\s+\S+\s*)?:")


def _declaration_place(pou: str, line: str) -> Place:
    """A line of a POU's header and VAR blocks: the variable it declares, if it declares one."""
    m = _DECLARED.match(line)
    return Place(pou, detail=f"variable {m.group(1)}" if m else "declarations")


def interface_types(pou: etree._Element) -> dict[str, str]:
    """Name -> type (as ST text) of a POU's variables (a function's own name: its result)."""
    where = f"POU {pou.get('name')}"
    found: dict[str, str] = {}
    interface = pou.find("ppx:interface", NS)
    if interface is None:
        return found
    ret = interface.find("ppx:returnType", NS)
    if ret is not None:
        found[pou.get("name", "")] = type_text(ret, where)
    for v in interface.iterfind(".//ppx:variable", NS):
        t = v.find("ppx:type", NS)
        if t is not None:
            found[v.get("name", "")] = type_text(t, where)
    return found


def global_types(root: etree._Element) -> dict[str, str]:
    found: dict[str, str] = {}
    for v in root.iterfind("ppx:instances/ppx:configurations//ppx:globalVars/ppx:variable", NS):
        t = v.find("ppx:type", NS)
        if t is not None:
            found[v.get("name", "")] = type_text(t, "global variables")
    return found


def source_from_xml(path: str | Path, data: Optional[bytes] = None,
                    st_texts: Optional[list[tuple[str, str]]] = None) -> GeneratedSource:
    """A plc.xml as one ST source that knows its drawing (what `read_sources` gives the front
    end); `st_texts`: the ST files compiled with it (their FBs and functions may be boxes)."""
    if data is None:
        try:
            data = Path(path).read_bytes()
        except OSError as e:
            raise PlcLabError(f"{path}: cannot read: {e.strerror}") from None
    source = project_source(parse_xml(data, str(path)), str(path), st_library(st_texts or []))
    source.xml = data          # the drawing itself: the lab draws its LD POUs online (plclab.lab.ladder)
    return source


def st_from_xml(path: str | Path) -> str:
    """Read a PLCopen TC6 XML project file and return it as one ST text."""
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        raise PlcLabError(f"{path}: cannot read: {e.strerror}") from None
    return st_from_tree(parse_xml(data, str(path)))
