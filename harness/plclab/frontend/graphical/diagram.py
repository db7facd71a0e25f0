"""An LD / FBD body of a TC6 project as data: its elements, their pins and wires, its rungs.

What the Editor's file says and nothing more: `Element`s in the order they stand in the XML,
each with its input wires (`Conn`: the element and pin a wire comes from) and, for a block,
its pins (`Pin`, with the negated / edge / storage modifiers the Editor writes on them).
`sections` numbers the rungs (LD) or networks (FBD) for the messages.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

from lxml import etree

from plclab.frontend.tc6 import NS, local

_PASSIVE = {"comment", "rightPowerRail", "leftPowerRail"}

@dataclass
class Conn:
    """One `<connection>`: the element it comes from and the pin of that element."""

    ref: int
    param: Optional[str]
    end: Optional[tuple[float, float]]     # the last point of the wire (at the source)


@dataclass
class Pin:
    """A block's input / output (or the one in / out point of a contact, coil, variable)."""

    param: str
    conns: list[Conn] = field(default_factory=list)
    rel: Optional[tuple[float, float]] = None
    negated: bool = False
    edge: str = "none"
    storage: str = "none"


@dataclass
class Element:
    kind: str
    local_id: int
    x: float
    y: float
    name: str = ""              # variable, expression, connector / label name, block instance
    type_name: str = ""         # blocks
    exec_order: int = 0
    pin_in: Pin = field(default_factory=lambda: Pin(""))
    inputs: list[Pin] = field(default_factory=list)
    outputs: list[Pin] = field(default_factory=list)
    rail_outs: list[tuple[float, float]] = field(default_factory=list)
    rail_ins: list[Pin] = field(default_factory=list)

    def describe(self) -> str:
        if self.kind == "block":
            return f"block {self.name} ({self.type_name})" if self.name else f"block {self.type_name}"
        words = {"inVariable": "input variable", "outVariable": "output variable",
                 "inOutVariable": "in-out variable", "leftPowerRail": "left power rail",
                 "rightPowerRail": "right power rail", "jump": "jump to", "return": "return"}
        word = words.get(self.kind, self.kind)
        return f"{word} {self.name}".strip()


def _truth(value: Optional[str]) -> bool:
    return value in ("true", "1")


def _pos(el: etree._Element) -> tuple[float, float]:
    p = el.find("ppx:position", NS)
    try:
        return (float(p.get("x", 0)), float(p.get("y", 0))) if p is not None else (0.0, 0.0)
    except ValueError:
        return (0.0, 0.0)


def _conns(point: Optional[etree._Element]) -> list[Conn]:
    out = []
    if point is None:
        return out
    for c in point.findall("ppx:connection", NS):
        pts = c.findall("ppx:position", NS)
        end = None
        if pts:
            try:
                end = (float(pts[-1].get("x", 0)), float(pts[-1].get("y", 0)))
            except ValueError:
                end = None
        try:
            ref = int(c.get("refLocalId", ""))
        except ValueError:
            ref = -1
        out.append(Conn(ref, c.get("formalParameter"), end))
    return out


def _rel(point: Optional[etree._Element]) -> Optional[tuple[float, float]]:
    r = point.find("ppx:relPosition", NS) if point is not None else None
    if r is None:
        return None
    try:
        return (float(r.get("x", 0)), float(r.get("y", 0)))
    except ValueError:
        return None


def _pin(var: etree._Element) -> Pin:
    return Pin(var.get("formalParameter", ""), _conns(var.find("ppx:connectionPointIn", NS)),
               _rel(var.find("ppx:connectionPointOut", NS)), _truth(var.get("negated")),
               var.get("edge", "none"), var.get("storage", "none"))


def read_elements(body: etree._Element) -> list[Element]:
    """The elements of one LD / FBD body, in the order they stand in the XML."""
    elements = []
    for el in body:
        if not isinstance(el.tag, str):
            continue
        kind = local(el)
        try:
            lid = int(el.get("localId", ""))
        except ValueError:
            lid = -1
        x, y = _pos(el)
        try:
            order = int(el.get("executionOrderId") or 0)
        except ValueError:
            order = 0
        e = Element(kind, lid, x, y, exec_order=order)
        e.pin_in = Pin("", _conns(el.find("ppx:connectionPointIn", NS)), None, _truth(el.get("negated")),
                       el.get("edge", "none"), el.get("storage", "none"))
        if kind in ("contact", "coil"):
            e.name = (el.findtext("ppx:variable", default="", namespaces=NS) or "").strip()
        elif kind in ("inVariable", "outVariable", "inOutVariable"):
            e.name = (el.findtext("ppx:expression", default="", namespaces=NS) or "").strip()
        elif kind in ("connector", "continuation"):
            e.name = el.get("name", "")
        elif kind in ("jump", "label"):
            e.name = el.get("label", "")
        elif kind == "block":
            e.name = el.get("instanceName") or ""
            e.type_name = el.get("typeName", "")
            e.inputs = [_pin(v) for v in el.findall("ppx:inputVariables/ppx:variable", NS)]
            e.outputs = [_pin(v) for v in el.findall("ppx:outputVariables/ppx:variable", NS)]
        elif kind == "leftPowerRail":
            e.rail_outs = [r for r in (_rel(p) for p in el.findall("ppx:connectionPointOut", NS)) if r]
        elif kind == "rightPowerRail":
            e.rail_ins = [Pin("", _conns(p)) for p in el.findall("ppx:connectionPointIn", NS)]
        elements.append(e)
    return elements


def sections(elements: list[Element]) -> dict[int, int]:
    """localId -> rung / network number: the wired groups of elements (the power rails do not
    join them), numbered from the top of the drawing down (then left to right)."""
    parent: dict[int, int] = {}

    def find(a: int) -> int:
        while parent.setdefault(a, a) != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    by_id = {e.local_id: e for e in elements}
    members = [e for e in elements if e.kind not in _PASSIVE]
    for e in members:
        find(e.local_id)
        wires = list(e.pin_in.conns) + [c for p in e.inputs for c in p.conns]
        for c in wires:
            src = by_id.get(c.ref)
            if src is not None and src.kind not in _PASSIVE:
                parent[find(e.local_id)] = find(c.ref)
    groups: dict[int, list[Element]] = {}
    for e in members:
        groups.setdefault(find(e.local_id), []).append(e)
    ordered = sorted(groups.values(), key=lambda g: (min(e.y for e in g), min(e.x for e in g)))
    return {e.local_id: n for n, g in enumerate(ordered, 1) for e in g}
