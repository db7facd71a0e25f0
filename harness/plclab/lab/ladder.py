"""Ladder online for the lab's page: an LD POU of a plc.xml drawn as its rungs, with power
flow live (which contacts conduct, which coils are energised), as a PLC programming tool
shows a ladder online.

`layout` reads the drawing once per program: every element where the Editor's file puts it
(position, size, pins) and every wire with the points the file stores. `PowerFlow` then
works out, from the variables of one POU instance as the last scan left them, the power on
every element's output: the left rail is powered; a contact conducts when power reaches it
and its variable is TRUE (FALSE for a negated one); wires into one point are OR'ed; a coil
is energised when power reaches it (its variable is shown beside it); a box's outputs are
the values its call left (`DebounceTimer.Q`, `_TMP_ADD5_OUT`: the names the translation
gives them, frontend.graphical.generator). An edge contact (|P|, |N|) conducts for the one
scan of its trigger; the page, ten snapshots a second, shows the variable's level on it.

The semantics are the translation's (plclab.frontend.graphical.read_elements), not a second
reading of the XML: only the geometry (sizes, pin and wire points) is read here.
"""
from __future__ import annotations

from typing import Any, Callable, Optional

from lxml import etree

from plclab.errors import PlcLabError
from plclab.iec import types as T
from plclab.frontend.tc6 import NS, local

MAX_ELEMENTS = 2000          # elements drawn per POU (a bigger drawing: shown as its ST)


def drawings(sources: list[tuple[str, str]]) -> dict[str, dict]:
    """POU name (upper case) -> its LD layout, for every LD POU of the plc.xml sources (a
    source read from a plc.xml carries its bytes as `xml`, frontend.plcxml.source_from_xml)."""
    out: dict[str, dict] = {}
    for _name, text in sources:
        data = getattr(text, "xml", None)
        if not data:
            continue
        try:
            root = etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=False))
        except etree.XMLSyntaxError:
            continue
        for pou in root.iterfind("ppx:types/ppx:pous/ppx:pou", NS):
            body = pou.find("ppx:body/ppx:LD", NS)
            if body is not None:
                drawn = layout(body)
                if drawn is not None:
                    out[pou.get("name", "").upper()] = drawn
    return out


def _num(el: Optional[etree._Element], attr: str, default: float = 0.0) -> float:
    try:
        return float(el.get(attr, default)) if el is not None else default
    except ValueError:
        return default


def _rel(point: Optional[etree._Element]) -> Optional[list[float]]:
    r = point.find("ppx:relPosition", NS) if point is not None else None
    return [_num(r, "x"), _num(r, "y")] if r is not None else None


def _pin_at(var: etree._Element, block: dict) -> Optional[list[float]]:
    """Where a box's input pin is, relative to the box: where its wire ends (the wire's first
    point), else the relPosition the file gives it."""
    point = var.find("ppx:connectionPointIn", NS)
    first = point.find("ppx:connection/ppx:position", NS) if point is not None else None
    if first is not None:
        return [_num(first, "x") - block["x"], _num(first, "y") - block["y"]]
    return _rel(point)


def layout(body: etree._Element) -> Optional[dict]:
    """The drawing of one LD body as the page draws it: elements (id, kind, box, name,
    modifier, pins) and wires (points, the source element and pin whose power they carry)."""
    from plclab.frontend.graphical import read_elements
    elements = read_elements(body)
    if len(elements) > MAX_ELEMENTS:
        return None
    by_id = {int(el.get("localId")): el for el in body
             if isinstance(el.tag, str) and (el.get("localId") or "").isdigit()}
    out_elements, wires = [], []
    for e in elements:
        xml = by_id.get(e.local_id)
        if xml is None or e.kind == "comment":
            continue
        pos = xml.find("ppx:position", NS)
        item: dict[str, Any] = {"id": e.local_id, "kind": e.kind, "x": _num(pos, "x"), "y": _num(pos, "y"),
                                "w": _num(xml, "width", 30), "h": _num(xml, "height", 20), "name": e.name}
        mod = ""
        if e.kind == "contact":
            mod = "/" if e.pin_in.negated else {"rising": "P", "falling": "N"}.get(e.pin_in.edge, "")
        elif e.kind == "coil":
            mod = "/" if e.pin_in.negated else {"set": "S", "reset": "R"}.get(
                e.pin_in.storage, {"rising": "P", "falling": "N"}.get(e.pin_in.edge, ""))
        item["mod"] = mod
        if e.kind == "block":
            item["type"] = e.type_name
            item["inputs"] = [[v.get("formalParameter", ""), _pin_at(v, item)]
                              for v in xml.iterfind("ppx:inputVariables/ppx:variable", NS)]
            item["outputs"] = [[v.get("formalParameter", ""), _rel(v.find("ppx:connectionPointOut", NS))]
                               for v in xml.iterfind("ppx:outputVariables/ppx:variable", NS)]
        out_elements.append(item)
        for point in xml.iter(f"{{{NS['ppx']}}}connectionPointIn"):
            for c in point.iterfind("ppx:connection", NS):
                pts = [[_num(p, "x"), _num(p, "y")] for p in c.iterfind("ppx:position", NS)]
                ref = c.get("refLocalId", "")
                if len(pts) >= 2 and ref.isdigit():
                    wires.append({"points": pts, "from": _key(int(ref), c.get("formalParameter"), by_id)})
    return {"elements": out_elements, "wires": wires}


def _key(ref: int, param: Optional[str], by_id: dict) -> str:
    """How the page names an element's output: its localId, and the pin for a box."""
    src = by_id.get(ref)
    if src is not None and local(src) == "block" and param:
        return f"{ref}.{param}"
    return str(ref)


class PowerFlow:
    """The power on every output of one LD POU instance's elements, from its variables."""

    def __init__(self, body_elements: list, instance: Optional[str], read: Callable[[str], Any]):
        self.elements = {e.local_id: e for e in body_elements}
        self.instance = instance
        self.read = read
        self.connectors = {e.name.upper(): e for e in body_elements if e.kind == "connector"}

    def value(self, name: str) -> Any:
        """A variable as the POU sees it: its own (instance path) first, then a global."""
        word = name.strip()
        up = word.upper()
        if up in ("TRUE", "FALSE"):
            return up == "TRUE"
        paths = ([f"{self.instance}.{word}"] if self.instance else []) + [word]
        for p in paths:
            try:
                return self.read(p)
            except (PlcLabError, KeyError, IndexError, AttributeError, TypeError, ValueError):
                continue
        return None

    def state(self) -> dict[str, Any]:
        """{output key: True / False / a value / None (unknown)} and the coils' variables."""
        memo: dict[tuple[int, str], Any] = {}
        out: dict[str, Any] = {}

        def power_in(conns: list, depth: int) -> Any:
            seen = [output(c.ref, c.param or "", depth + 1) for c in conns]
            if not seen:
                return False
            if len(seen) == 1:
                return seen[0]
            bools = [bool(v) for v in seen if v is not None]
            return any(bools) if bools else None

        def output(ref: int, param: str, depth: int) -> Any:
            key = (ref, param)
            if key in memo:
                return memo[key]
            memo[key] = None                      # a loop (feedback through a variable): unknown
            e = self.elements.get(ref)
            v: Any = None
            if e is None or depth > 400:
                v = None
            elif e.kind == "leftPowerRail":
                v = True
            elif e.kind == "contact":
                p = power_in(e.pin_in.conns, depth)
                var = self.value(e.name)
                if p is False:
                    v = False
                elif p is None or var is None:
                    v = None
                else:
                    v = bool(p) and (not bool(var) if e.pin_in.negated else bool(var))
            elif e.kind in ("coil", "outVariable", "inOutVariable") and e.pin_in.conns:
                v = power_in(e.pin_in.conns, depth)
                if e.kind == "inOutVariable":
                    v = self.value(e.name)
            elif e.kind in ("inVariable", "inOutVariable"):
                v = self.value(e.name)
            elif e.kind == "continuation":
                c = self.connectors.get(e.name.upper())
                v = power_in(c.pin_in.conns, depth) if c is not None else None
            elif e.kind == "connector":
                v = power_in(e.pin_in.conns, depth)
            elif e.kind == "block":
                if e.name:                                    # a function block: its instance
                    v = self.value(f"{e.name}.{param or 'ENO'}")
                else:                                         # a function: the Editor's temporaries
                    v = self.value(f"{e.type_name}{e.local_id}" if not param
                                   else f"_TMP_{e.type_name}{e.local_id}_{param}")
            memo[key] = v
            return v

        for e in self.elements.values():
            if e.kind == "block":
                for pin in e.outputs:
                    out[f"{e.local_id}.{pin.param}"] = _plain(output(e.local_id, pin.param, 0))
            elif e.kind not in ("leftPowerRail", "rightPowerRail", "comment", "label", "jump", "return"):
                out[str(e.local_id)] = _plain(output(e.local_id, "", 0))
                if e.kind == "coil":
                    out[f"{e.local_id}.var"] = _plain(self.value(e.name))
        return out


def _plain(v: Any) -> Any:
    if v is None or isinstance(v, (bool, str)):
        return v
    if isinstance(v, float):
        return round(v, 4)
    if isinstance(v, int):
        return v
    return str(v)[:40]


def pou_elements(sources: list[tuple[str, str]], pou: str) -> Optional[list]:
    """The translation's elements of LD POU `pou` (what PowerFlow evaluates)."""
    from plclab.frontend.graphical import read_elements
    for _name, text in sources:
        data = getattr(text, "xml", None)
        if not data:
            continue
        root = etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True))
        for p in root.iterfind("ppx:types/ppx:pous/ppx:pou", NS):
            if p.get("name", "").upper() == pou.upper():
                body = p.find("ppx:body/ppx:LD", NS)
                return read_elements(body) if body is not None else None
    return None


def time_aware(plc: Any) -> Callable[[str], Any]:
    """plc.read with TIME values as T#... text (as the ST listing shows them)."""
    def read(path: str) -> Any:
        container, key, ty = plc.resolve_typed(path)
        value = container[key] if isinstance(container, list) else getattr(container, key)
        base = T.base_of(ty)
        if isinstance(base, T.ElementaryType) and base.kind == "time":
            return f"T#{value / 1e6:g}ms" if abs(value) < 1e9 else f"T#{value / 1e9:g}s"
        if not isinstance(base, T.ElementaryType):
            raise PlcLabError("not elementary")
        return value
    return read
