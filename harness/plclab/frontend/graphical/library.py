"""The boxes a drawing may hold: what OpenPLC Editor's block library says of each.

The standard functions and function blocks (their signatures from the front end's table),
the project's own POUs, and the FUNCTIONs / FUNCTION_BLOCKs of ST files compiled with the
plc.xml; plus the structures of the TYPEs, to type the temporaries the Editor adds.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

from lxml import etree

from plclab.frontend.stdsigs import FUNCTION_BLOCKS, FUNCTIONS
from plclab.frontend.tc6 import NS, local, type_text

@dataclass(frozen=True)
class BlockInfo:
    kind: str                                  # 'function' | 'functionBlock'
    inputs: tuple[tuple[str, str], ...]
    outputs: tuple[tuple[str, str], ...]
    extensible: bool = False
    generic: tuple[str, ...] = ()              # inputs sharing the result's generic type


@dataclass
class Library:
    """What a drawing may use beyond its own project: the FUNCTIONs and FUNCTION_BLOCKs of ST
    files compiled with the plc.xml (as boxes) and the structures of the TYPEs of both (to
    type the Editor's temporaries, as its GetVariableType follows `a.b` into structures)."""

    blocks: dict[str, "BlockInfo"] = field(default_factory=dict)
    structs: dict[str, dict[str, str]] = field(default_factory=dict)   # TYPE -> field -> type


def st_library(texts: list[tuple[str, str]]) -> Library:
    """The blocks and structures of ST files compiled with a plc.xml."""
    from plclab.frontend import ast as A
    from plclab.frontend.parser import parse_source
    from plclab.frontend import sttext

    lib = Library()
    for name, text in texts:
        unit, _ = parse_source(text, name)
        if unit is None:
            continue
        for t in unit.types:
            if isinstance(t.type_ref, A.StructTypeRef):
                lib.structs[t.name.upper()] = {f.name.upper(): sttext.type_ref(f.type_ref) for f in t.type_ref.fields}
        for pou in unit.pous:
            if pou.kind == "PROGRAM":
                continue
            ins = [(d.name, sttext.type_ref(d.type_ref)) for b in pou.blocks if b.section in ("VAR_INPUT", "VAR_IN_OUT")
                   for d in b.decls]
            outs = [(d.name, sttext.type_ref(d.type_ref)) for b in pou.blocks
                    if b.section in ("VAR_OUTPUT", "VAR_IN_OUT") for d in b.decls]
            if pou.kind == "FUNCTION":
                ret = sttext.type_ref(pou.return_type) if pou.return_type is not None else "ANY"
                lib.blocks[pou.name] = BlockInfo("function", tuple(ins), (("OUT", ret),) + tuple(outs))
            else:
                lib.blocks[pou.name] = BlockInfo("functionBlock", tuple(ins), tuple(outs))
    return lib


def xml_structs(root: etree._Element) -> dict[str, dict[str, str]]:
    """TYPE -> field -> type of the structures among a project's data types."""
    found: dict[str, dict[str, str]] = {}
    for dt in root.iterfind("ppx:types/ppx:dataTypes/ppx:dataType", NS):
        struct = dt.find("ppx:baseType/ppx:struct", NS)
        if struct is None:
            continue
        fields = {}
        for v in struct.findall("ppx:variable", NS):
            t = v.find("ppx:type", NS)
            fields[v.get("name", "").upper()] = type_text(t, f"type {dt.get('name')}") if t is not None else "ANY"
        found[dt.get("name", "").upper()] = fields
    return found


def library_block(type_name: str, project_pous: dict[str, etree._Element],
                  others: Optional[Library] = None) -> Optional[BlockInfo]:
    """What the Editor's block library (the standard one plus the project's POUs, plus the
    ST files compiled with it) says of a block."""
    key = type_name.upper()
    f = FUNCTIONS.get(key)
    if f is not None:
        return BlockInfo("function", f.params, (("OUT", f.result),), f.extensible, f.generic_params)
    fb = FUNCTION_BLOCKS.get(key)
    if fb is not None:
        return BlockInfo("functionBlock", fb.inputs, fb.outputs)
    pou = project_pous.get(type_name)
    if pou is None:
        return others.blocks.get(type_name) if others is not None else None
    ins: list[tuple[str, str]] = []
    outs: list[tuple[str, str]] = []
    where = f"POU {type_name}"
    interface = pou.find("ppx:interface", NS)
    for vl in (interface if interface is not None else []):
        if not isinstance(vl.tag, str):
            continue
        tag = local(vl)
        for v in vl.findall("ppx:variable", NS):
            t = v.find("ppx:type", NS)
            item = (v.get("name", ""), type_text(t, where) if t is not None else "ANY")
            if tag in ("inputVars", "inOutVars"):
                ins.append(item)
            if tag in ("outputVars", "inOutVars"):
                outs.append(item)
    if pou.get("pouType") == "function":
        ret = interface.find("ppx:returnType", NS) if interface is not None else None
        outs.insert(0, ("OUT", type_text(ret, where) if ret is not None else "ANY"))
        return BlockInfo("function", tuple(ins), tuple(outs))
    if pou.get("pouType") == "functionBlock":
        return BlockInfo("functionBlock", tuple(ins), tuple(outs))
    return None
