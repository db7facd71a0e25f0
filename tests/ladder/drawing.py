"""Draw small LD / FBD diagrams and save them as OpenPLC Editor saves a plc.xml.

The Editor's file: TC6 v2.01, default namespace tc6_0201, `xhtml` for text; each element has
a localId, height/width, a position, `connectionPointIn` with `connection refLocalId` (and the
wire's points, the last one at the source), `connectionPointOut` with a relPosition; contacts
and coils carry negated / edge / storage and a `<variable>`; blocks carry typeName /
instanceName and input / output variables with formalParameter; wires from a block output
name it in `formalParameter` (as the Editor writes them). Used by the tests here and to write
the example projects stored beside them.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional, Union

from lxml import etree

PPX = "http://www.plcopen.org/xml/tc6_0201"
XHTML = "http://www.w3.org/1999/xhtml"

ROW = 40         # grid: a rung row is 40 px high, a column 100 px wide
COL = 100
RAIL_X = 20


def q(tag: str) -> str:
    return f"{{{PPX}}}{tag}"


def sub(parent, tag: str, **attrs) -> etree._Element:
    return etree.SubElement(parent, q(tag), {k: str(v) for k, v in attrs.items() if v is not None})


@dataclass
class Item:
    """One drawn element; `out` is its output point (absolute), `param` the pin wired from."""
    local_id: int
    kind: str
    x: float
    y: float
    outs: dict = field(default_factory=dict)     # pin name ('' for the one output) -> (x, y)


Source = Union[Item, tuple]   # an Item, or (block Item, "Q") for a block output, or "rail"


class Diagram:
    """One LD or FBD body being drawn: elements are placed on a grid (row, col)."""

    def __init__(self, lang: str = "LD"):
        self.lang = lang
        self.body = etree.Element(q(lang))
        self.next_id = 1
        self.rail = None
        self.rail_outs: list[float] = []
        self.right_ins: list[tuple[int, float, float]] = []
        if lang == "LD":
            self.rail = self._new("leftPowerRail", 0, 0)

    def _new(self, kind: str, row: float, col: float, **attrs) -> Item:
        lid = self.next_id
        self.next_id += 1
        x, y = (RAIL_X if kind == "leftPowerRail" else 60 + col * COL), 20 + row * ROW
        el = sub(self.body, kind, localId=lid, height=20, width=30, **attrs)
        sub(el, "position", x=x, y=y)
        item = Item(lid, kind, x, y)
        item.el = el
        return item

    def _wire_in(self, el: etree._Element, sources: list[Source], at: tuple[float, float]) -> None:
        point = sub(el, "connectionPointIn")
        sub(point, "relPosition", x=0, y=10)
        for s in sources:
            self._connection(point, s, at)

    def _connection(self, point: etree._Element, s: Source, at: tuple[float, float]) -> None:
        if isinstance(s, str) and s == "rail":
            s = self.rail
        param = None
        if isinstance(s, tuple):
            s, param = s
        if s.kind == "leftPowerRail":
            y = at[1]
            if y - s.y not in self.rail_outs:
                self.rail_outs.append(y - s.y)
            end = (s.x + 10, y)
        else:
            end = s.outs[param or ""]
        c = sub(point, "connection", refLocalId=s.local_id,
                formalParameter=param if param else None)
        sub(c, "position", x=at[0], y=at[1])
        sub(c, "position", x=end[0], y=end[1])

    # -- LD ------------------------------------------------------------------------------------
    def contact(self, var: str, row: float, col: float, after: Union[Source, list] = "rail",
                negated: bool = False, edge: Optional[str] = None) -> Item:
        item = self._new("contact", row, col, negated="true" if negated else "false",
                         edge=edge)
        self._wire_in(item.el, after if isinstance(after, list) else [after], (item.x, item.y + 10))
        out = sub(item.el, "connectionPointOut")
        sub(out, "relPosition", x=30, y=10)
        sub(item.el, "variable").text = var
        item.outs[""] = (item.x + 30, item.y + 10)
        return item

    def coil(self, var: str, row: float, col: float, after: Union[Source, list], negated: bool = False,
             storage: Optional[str] = None, edge: Optional[str] = None) -> Item:
        item = self._new("coil", row, col, negated="true" if negated else "false", storage=storage, edge=edge)
        self._wire_in(item.el, after if isinstance(after, list) else [after], (item.x, item.y + 10))
        out = sub(item.el, "connectionPointOut")
        sub(out, "relPosition", x=30, y=10)
        sub(item.el, "variable").text = var
        item.outs[""] = (item.x + 30, item.y + 10)
        self.right_ins.append((item.local_id, item.x + 30, item.y + 10))
        return item

    # -- both ----------------------------------------------------------------------------------
    def invar(self, expression: str, row: float, col: float) -> Item:
        width = max(30, 7 * len(expression) + 10)      # the Editor sizes a variable to its text
        item = self._new("inVariable", row, col, negated="false")
        item.el.set("width", str(width))
        out = sub(item.el, "connectionPointOut")
        sub(out, "relPosition", x=width, y=10)
        sub(item.el, "expression").text = expression
        item.outs[""] = (item.x + width, item.y + 10)
        return item

    def outvar(self, expression: str, row: float, col: float, src: Source, order: int = 0) -> Item:
        item = self._new("outVariable", row, col, negated="false", executionOrderId=order or None)
        item.el.set("width", str(max(30, 7 * len(expression) + 10)))
        self._wire_in(item.el, [src], (item.x, item.y + 10))
        sub(item.el, "expression").text = expression
        return item

    def block(self, type_name: str, row: float, col: float, inputs: list[tuple[str, Optional[Source]]],
              outputs: list[str], instance: Optional[str] = None, order: int = 0,
              pins: Optional[dict] = None) -> Item:
        """A function / FB box; `inputs` in pin order (None: unwired), `pins`: pin -> modifier
        attributes (negated / edge) as the Editor writes them on the block's variables."""
        item = self._new("block", row, col, typeName=type_name, instanceName=instance,
                         executionOrderId=order or None)
        item.el.set("height", str(40 + 20 * max(len(inputs), len(outputs))))
        item.el.set("width", "80")
        ins = sub(item.el, "inputVariables")
        for i, (name, src) in enumerate(inputs):
            v = sub(ins, "variable", formalParameter=name, **(pins or {}).get(name, {}))
            at = (item.x, item.y + 30 + 20 * i)
            if src is None:
                p = sub(v, "connectionPointIn")
                sub(p, "relPosition", x=0, y=30 + 20 * i)
            else:
                self._wire_in(v, [src], at)
        sub(item.el, "inOutVariables")
        outs = sub(item.el, "outputVariables")
        for i, name in enumerate(outputs):
            v = sub(outs, "variable", formalParameter=name, **(pins or {}).get(name, {}))
            p = sub(v, "connectionPointOut")
            sub(p, "relPosition", x=80, y=30 + 20 * i)
            item.outs[name] = (item.x + 80, item.y + 30 + 20 * i)
        return item

    def connector(self, name: str, row: float, col: float, src: Source) -> Item:
        item = self._new("connector", row, col, name=name)
        self._wire_in(item.el, [src], (item.x, item.y + 10))
        return item

    def continuation(self, name: str, row: float, col: float) -> Item:
        item = self._new("continuation", row, col, name=name)
        out = sub(item.el, "connectionPointOut")
        sub(out, "relPosition", x=60, y=10)
        item.outs[""] = (item.x + 60, item.y + 10)
        return item

    def jump(self, label: str, row: float, col: float, after: Source) -> Item:
        item = self._new("jump", row, col, label=label)
        self._wire_in(item.el, [after], (item.x, item.y + 10))
        return item

    def label(self, name: str, row: float, col: float) -> Item:
        return self._new("label", row, col, label=name)

    def return_(self, row: float, col: float, after: Source) -> Item:
        item = self._new("return", row, col)
        self._wire_in(item.el, [after], (item.x, item.y + 10))
        return item

    def inoutvar(self, expression: str, row: float, col: float, src: Source) -> Item:
        width = max(30, 7 * len(expression) + 10)
        item = self._new("inOutVariable", row, col)      # TC6: negatedIn / negatedOut, no negated
        item.el.set("width", str(width))
        self._wire_in(item.el, [src], (item.x, item.y + 10))
        out = sub(item.el, "connectionPointOut")
        sub(out, "relPosition", x=width, y=10)
        sub(item.el, "expression").text = expression
        item.outs[""] = (item.x + width, item.y + 10)
        return item

    def comment(self, text: str, row: float, col: float) -> Item:
        item = self._new("comment", row, col)
        content = sub(item.el, "content")
        etree.SubElement(content, f"{{{XHTML}}}p").text = etree.CDATA(text)
        return item

    def finish(self) -> etree._Element:
        """Power rails sized to what was drawn (the Editor writes one point per rung)."""
        if self.rail is not None:
            for dy in sorted(self.rail_outs):
                p = sub(self.rail.el, "connectionPointOut", formalParameter="")
                sub(p, "relPosition", x=10, y=dy)
            bottom = max([float(e.find(q("position")).get("y")) + float(e.get("height", 20))
                          for e in self.body if e.find(q("position")) is not None] + [ROW])
            height = int(bottom + 10 - 20)
            self.rail.el.set("height", str(height))
            self.rail.el.set("width", "10")
            right = sub(self.body, "rightPowerRail", localId=self.next_id, height=height, width=10)
            self.next_id += 1
            sub(right, "position", x=60 + 8 * COL, y=20)
            for lid, x, y in self.right_ins:
                p = sub(right, "connectionPointIn")
                sub(p, "relPosition", x=0, y=y - 20)
                c = sub(p, "connection", refLocalId=lid)
                sub(c, "position", x=60 + 8 * COL, y=y)
                sub(c, "position", x=x, y=y)
        return self.body


@dataclass
class Pou:
    name: str
    pou_type: str                      # program | functionBlock | function
    body: Union[Diagram, str]          # a Diagram, or ST text
    vars: dict = field(default_factory=dict)     # list tag (localVars, inputVars...) -> [(name, type, init)]
    return_type: Optional[str] = None


def _type(parent, type_name: str, tag: str = "type") -> None:
    """A type as the Editor's variable table writes it: elementary, STRING (with a length only
    if asked: `STRING[10]`), `ARRAY [1..3] OF INT`, or a derived (user type, block) name."""
    t = sub(parent, tag)
    word = type_name.upper()
    if word in ("BOOL", "INT", "DINT", "UINT", "REAL", "TIME", "WORD", "BYTE", "SINT", "LREAL", "DWORD"):
        sub(t, word)
    elif word.startswith("STRING"):
        sub(t, "string", length=word[7:-1] if "[" in word else None)
    elif word.startswith("ARRAY"):
        dims, base = type_name.split("[", 1)[1].split("] OF ")
        arr = sub(t, "array")
        for dim in dims.split(","):
            lower, upper = dim.strip().split("..")
            sub(arr, "dimension", lower=lower, upper=upper)
        _type(arr, base.strip(), "baseType")
    else:
        sub(t, "derived", name=type_name)


def _value(parent, value, tag: str = "initialValue") -> None:
    """A value as the Editor writes it: text as `simpleValue`; a list of (repetition, text) as
    `arrayValue` (repetition None: one value)."""
    el = sub(parent, tag)
    if isinstance(value, list):
        arr = sub(el, "arrayValue")
        for rep, item in value:
            sub(sub(arr, "value", repetitionValue=rep), "simpleValue", value=item)
    else:
        sub(el, "simpleValue", value=value)


def _documentation(parent, text: str) -> None:
    etree.SubElement(sub(parent, "documentation"), f"{{{XHTML}}}p").text = etree.CDATA(text)


def var_list(parent, tag: str, variables: list) -> etree._Element:
    """One variable list: `tag` is its name and qualifiers ("localVars retain"); each variable
    (name, type, initial value[, address[, documentation]]) as the Editor's table saves it."""
    name, *words = tag.split()
    vl = sub(parent, name, **{w: "true" for w in words})
    for name, type_name, init, *rest in variables:
        address = rest[0] if rest else None
        v = sub(vl, "variable", name=name, address=address)
        _type(v, type_name)
        if init is not None:
            _value(v, init)
        if len(rest) > 1 and rest[1]:
            _documentation(v, rest[1])
    return vl


def project(pous: list[Pou], globals_: list[tuple[str, str, Optional[str]]] = (),
            program: Optional[str] = None, interval: str = "T#10ms",
            global_lists: tuple = (), resource_lists: tuple = ()) -> bytes:
    """The whole plc.xml: POUs, and a configuration running `program` (globals located with
    AT addresses: (name, type, address); `global_lists` / `resource_lists`: more lists of the
    configuration / resource, (tag, variables) as `var_list` takes them)."""
    root = etree.Element(q("project"), nsmap={None: PPX, "xhtml": XHTML,
                                              "xsd": "http://www.w3.org/2001/XMLSchema"})
    sub(root, "fileHeader", companyName="Unknown", productName="Unnamed", productVersion="1",
        creationDateTime="2026-01-01T00:00:00")
    header = sub(root, "contentHeader", name="Unnamed", modificationDateTime="2026-01-01T00:00:00")
    coords = sub(header, "coordinateInfo")
    for lang in ("fbd", "ld", "sfc"):
        sub(sub(coords, lang), "scaling", x=10, y=10)
    types = sub(root, "types")
    sub(types, "dataTypes")
    pous_el = sub(types, "pous")
    for p in pous:
        el = sub(pous_el, "pou", name=p.name, pouType=p.pou_type)
        interface = sub(el, "interface")
        if p.return_type:
            _type(interface, p.return_type, "returnType")
        for tag, variables in p.vars.items():
            var_list(interface, tag.split("#")[0], variables)     # "localVars#2": a second list of that kind
        body = sub(el, "body")
        if isinstance(p.body, Diagram):
            body.append(p.body.finish())
        else:
            st = sub(body, "ST")
            etree.SubElement(st, f"{{{XHTML}}}p").text = etree.CDATA(p.body)
    instances = sub(root, "instances")
    confs = sub(instances, "configurations")
    if program:
        conf = sub(confs, "configuration", name="Config0")
        res = sub(conf, "resource", name="Res0")
        if globals_:
            gv = sub(res, "globalVars")
            for name, type_name, address in globals_:
                v = sub(gv, "variable", name=name, address=address)
                _type(v, type_name)
        for tag, variables in resource_lists:
            var_list(res, tag, variables)
        task = sub(res, "task", name="task0", priority=0, interval=interval)
        sub(task, "pouInstance", name="instance0", typeName=program)
        for tag, variables in global_lists:       # TC6: a configuration's lists after its resources
            var_list(conf, tag, variables)
    return etree.tostring(root, xml_declaration=True, encoding="utf-8", pretty_print=True)
