"""One LD / FBD POU -> ST, the way OpenPLC Editor (its PLCGenerator) turns it into ST.

OpenPLC Editor (Beremiz's PLCGenerator) never compiles a drawing: it writes ST and hands it to
matiec. A drawing behaves the way that ST behaves, so this module produces the same ST: the
same statement order, the same temporaries (`R_TRIG1`, `_TMP_ADD5_OUT`, ...), the same
expressions. The rules, as that generator applies them:

* Statement order. Out-variables, in-out variables and blocks with an `executionOrderId` > 0
  come first, by that id. Then every coil and out-variable, then every block, then every
  connector, each group in the order the elements stand in the XML (the generator's position
  sort compares with `operator.eq`, which never says "less", so the sort keeps that order).
* A coil or out-variable is assigned the expression of what feeds it. Series contacts AND
  (the contact nearest the coil first), parallel branches OR (factorised on a common contact
  towards the rail, operands sorted the way Python 2 sorted them), the power rail is TRUE.
* Contacts: normally open `X`, negated `NOT(X)`, rising / falling edge `R_TRIGn(CLK := X);` /
  `F_TRIGn(...)` emitted where the contact is met, and `R_TRIGn.Q` used. Coils: normal,
  negated `NOT(...)`, set / reset `IF e THEN X := TRUE; (*set*) END_IF;`, edge coils through
  a trigger. The same modifiers apply to block pins.
* Function blocks are called once, when first needed (or at their place in the order);
  functions likewise, their result into `<TYPE><localId>` / `_TMP_<TYPE><localId>_<PIN>`.
  An out-variable fed by a block whose EN is wired is assigned inside `IF <ENO> THEN` (a
  coil fed by it is not guarded).
* Connectors compute their expression once; continuations use it.
* Jumps, labels and returns: the generator writes no code for them (the drawing would do
  something else than it shows), so they are refused here with one clear line.

Every piece of generated text remembers the element it came from (`Place`), so a diagnostic
in generated ST names the POU, the rung / network and the element instead of a line of text
the student never wrote (`places.locate` / `places.drawing_location`).
"""
from __future__ import annotations

import itertools
from typing import Any, Optional

from lxml import etree

from plclab.errors import CompileError
from plclab.frontend.graphical.diagram import Conn, Element, Pin, read_elements, sections
from plclab.frontend.graphical.library import BlockInfo, Library, library_block
from plclab.frontend.graphical.places import Place, generation_error

MAX_VISITS = 200_000   # elements walked per POU: parallel branches fed by parallel branches multiply
_LITERAL_TYPES = {"T": "TIME", "TIME": "TIME", "D": "DATE", "DATE": "DATE", "TOD": "TOD", "TIME_OF_DAY": "TOD",
                  "DT": "DT", "DATE_AND_TIME": "DT", "2": None, "8": None, "16": None}

Tokens = list[tuple[str, tuple]]


def _python2_sorted(items: list) -> list:
    """Sort as Python 2 sorted a list of mixed strings, lists, tuples and None: items that
    compare form groups (in order of first appearance), each group sorted in itself."""
    groups: list[list] = []
    for item in items:
        for g in groups:
            try:
                item < g[0]
            except TypeError:
                continue
            g.append(item)
            break
        else:
            groups.append([item])
    return list(itertools.chain.from_iterable(sorted(g) for g in groups))


class PouGenerator:
    """The ST body (and the extra VAR declarations) of one LD / FBD POU."""

    def __init__(self, pou: etree._Element, lang: str, body: etree._Element, file: str,
                 project_pous: dict[str, etree._Element], var_types: dict[str, str],
                 others: Optional[Library] = None, own: Optional[set[str]] = None):
        """`var_types`: name -> type of what the body may name (its variables, the globals),
        for the temporaries' types; `own`: the POU's own variable names (a trigger's name
        skips those, as the Editor's IsAlreadyDefined does)."""
        self.name = pou.get("name", "")
        self.pou_type = pou.get("pouType", "")
        self.lang = lang
        self.file = file
        self.tag = f"P::{self.name}"
        self.project_pous = project_pous
        self.others = others or Library()
        self.var_types = var_types                 # the POU's own declarations (and globals)
        self.declared = set(var_types if own is None else own)   # the interface's names, then the temporaries
        self.elements = read_elements(body)
        self.by_id: dict[int, Element] = {}
        for e in self.elements:            # a localId used twice: the first one, as the Editor finds it
            self.by_id.setdefault(e.local_id, e)
        self.section_of = sections(self.elements)
        self.indent = "  "
        self.program: Tokens = []
        self.extra: list[tuple[str, str, Optional[int]]] = []   # temporaries: (name, type, localId of its element)
        self.computed_blocks: set[int] = set()
        self.computed_connectors: dict[str, Tokens] = {}
        self.connectors: dict[str, list[Element]] = {}
        self.readers: dict[int, list[tuple[Element, Conn]]] = {}    # localId -> what reads it
        for e in self.elements:
            if e.kind == "connector":
                self.connectors.setdefault(e.name, []).append(e)
            for c in e.pin_in.conns + [c for p in e.inputs for c in p.conns]:
                self.readers.setdefault(c.ref, []).append((e, c))
        self.visits = 0                            # elements walked: a bound on a hostile drawing
        self.walking: set[int] = set()             # contacts / coils / continuations being expanded

    # -- places ----------------------------------------------------------------------------
    def place(self, e: Element) -> Place:
        return Place(self.name, self.lang, self.section_of.get(e.local_id, 0), e.describe(), e.local_id)

    def fail(self, e: Optional[Element], message: str) -> CompileError:
        place = self.place(e) if e is not None else Place(self.name, self.lang)
        return generation_error(self.file, place, message)

    def info(self, e: Element, *role: Any) -> tuple:
        kinds = {"contact": "contact", "coil": "coil", "block": "block"}
        return (self.tag, kinds.get(e.kind, "io_variable"), e.local_id) + role

    def emit(self, *tokens: tuple[str, tuple]) -> None:
        self.program.extend(tokens)

    def declare(self, name: str, type_name: str, owner: Optional[int] = None) -> None:
        self.extra.append((name, type_name, owner))
        self.declared.add(name)

    # -- the program ----------------------------------------------------------------------------
    def generate(self) -> None:
        for e in self.elements:
            if e.kind in ("jump", "label", "return"):
                raise self.fail(e, "OpenPLC Editor writes no code for jumps, labels and returns in an "
                                   f"{self.lang} body (it would silently leave this one out): use coils "
                                   "and contacts, or write this part in ST")
            if e.kind in ("step", "transition", "actionBlock", "selectionDivergence"):
                raise self.fail(e, f"SFC elements cannot stand in an {self.lang} body")
            if e.kind == "continuation":     # the Editor checks every one, used or not
                found = self.connectors.get(e.name, [])
                if len(found) != 1:
                    raise self.fail(e, f"more than one connector named '{e.name}' in this POU" if found else
                                       f"no connector named '{e.name}' for this continuation")
        ordered = sorted((e for e in self.elements if e.exec_order > 0
                          and e.kind in ("outVariable", "inOutVariable", "block")), key=lambda e: e.exec_order)
        first = {id(e) for e in ordered}
        rest = [e for e in self.elements if id(e) not in first]
        outs = [e for e in rest if e.kind in ("outVariable", "inOutVariable", "coil")]
        blocks = [e for e in rest if e.kind == "block"]
        connectors = [e for e in rest if e.kind == "connector"]
        for e in ordered + outs + blocks + connectors:
            if e.kind in ("outVariable", "inOutVariable"):
                self.assign_variable(e)
            elif e.kind == "block":
                self.block(e, None)
            elif e.kind == "connector":
                if not self.computed_connectors.get(e.name):
                    expr = self.expression(e.pin_in.conns)
                    if expr is not None:
                        self.computed_connectors[e.name] = expr
            elif e.kind == "coil":
                expr = self.expression(e.pin_in.conns)
                if expr is not None:
                    info = self.info(e)
                    expr = self.modifier(e.pin_in, expr, info)
                    self.emit((self.indent, ()), (e.name, info + ("reference",)), (" := ", ()), *expr,
                              (";\n", ()))

    def assign_variable(self, e: Element) -> None:
        expr = self.expression(e.pin_in.conns)
        if expr is None:
            return
        eno = self.used_eno(e.pin_in.conns)
        if eno is not None:
            self.emit((self.indent + f"IF {eno}", ()), (" THEN\n  ", ()))
            self.indent += "  "
        self.emit((self.indent, ()), (e.name, self.info(e, "expression")), (" := ", ()), *expr, (";\n", ()))
        if eno is not None:
            self.indent = self.indent[:-2]
            self.emit((self.indent + "END_IF;\n", ()))

    def used_eno(self, conns: list[Conn]) -> Optional[str]:
        if len(conns) != 1:
            return None
        blk = self.by_id.get(conns[0].ref)
        if blk is None or blk.kind != "block":
            return None
        for pin in blk.inputs:
            if pin.param == "EN" and pin.conns:
                return f"{blk.name}.ENO" if blk.name else f"_TMP_{blk.type_name}{blk.local_id}_ENO"
        return None

    # -- expressions ----------------------------------------------------------------------------
    def expression(self, conns: list[Conn], order: bool = False, to_inout: bool = False) -> Optional[Tokens]:
        paths = self.paths(conns, order, to_inout)
        if not paths:
            return None
        if len(paths) > 1:
            fact = self.factorize(paths)
            tree: Any = tuple(fact) if len(fact) > 1 else fact[0]
        else:
            tree = paths[0]
        return self.render(tree, True)

    def paths(self, conns: list[Conn], order: bool = False, to_inout: bool = False) -> list:
        """The paths back from a point to the rail: a contact's text (the repr of its tokens,
        as the Editor keeps it), a list (series), a tuple (parallel), None (the rail)."""
        out: list = []
        for c in conns:
            src = self.by_id.get(c.ref)
            if src is None:
                continue
            self.visits += 1
            if self.visits > MAX_VISITS:
                raise self.fail(src, f"this diagram has too many paths to translate (more than {MAX_VISITS:,} "
                                     "steps): split it into smaller rungs or POUs")
            if src.kind in ("contact", "coil", "continuation"):
                if src.local_id in self.walking:
                    raise self.fail(src, "the wiring loops back into this element: OpenPLC Editor cannot "
                                         "translate a loop that does not go through a block")
                self.walking.add(src.local_id)
                try:
                    out.extend(self._path_from(src, c, order, to_inout))
                finally:
                    self.walking.discard(src.local_id)
            else:
                out.extend(self._path_from(src, c, order, to_inout))
        return out

    def _path_from(self, src: Element, c: Conn, order: bool, to_inout: bool) -> list:
        """The paths (zero or one) that element `src` gives the wire `c` leaving it."""
        out: list = []
        if src.kind == "leftPowerRail":
            out.append(None)
        elif src.kind in ("inVariable", "inOutVariable"):
            out.append(str([(src.name, self.info(src, "expression"))]))
        elif src.kind == "block":
            out.append(str(self.block(src, c, order, to_inout)))
        elif src.kind == "continuation":
            value = self.computed_connectors.get(src.name)
            if value is not None:
                return [str(value)]
            found = self.connectors.get(src.name, [])
            if len(found) > 1:
                raise self.fail(src, f"more than one connector named '{src.name}' in this POU")
            if not found:
                raise self.fail(src, f"no connector named '{src.name}' for this continuation")
            value = self.expression(found[0].pin_in.conns, order)
            if value is not None:
                self.computed_connectors[src.name] = value
                out.append(str(value))
        elif src.kind == "contact":
            info = self.info(src)
            var = str(self.modifier(src.pin_in, [(src.name, info + ("reference",))], info))
            sub = self.paths(src.pin_in.conns, order)
            if not sub:
                raise self.fail(src, f"contact '{src.name}' must be connected on its left")
            if len(sub) > 1:
                fact = self.factorize(sub)
                out.append([var, tuple(fact)] if len(fact) > 1 else [var] + fact)
            elif isinstance(sub[0], list):
                out.append([var] + sub[0])
            elif sub[0] is not None:
                out.append([var, sub[0]])
            else:
                out.append(var)
        elif src.kind == "coil":
            out.append(self.paths(src.pin_in.conns, order))
        return out

    def factorize(self, paths: list) -> list:
        """Parallel branches that end in the same element (towards the rail) share it."""
        same: dict[str, list[tuple[list, int]]] = {}
        tails: dict[str, list] = {}
        left = list(range(len(paths)))
        result: list = []
        for num, path in enumerate(paths):
            if isinstance(path, list):
                if len(path) > 1:
                    key = str(path[-1:])
                    same.setdefault(key, []).append((path[:-1], num))
                    tails[key] = path[-1:]
            else:
                result.append(path)
                left.remove(num)
        for key, items in same.items():
            if len(items) > 1:
                inner = self.factorize([p for p, _ in items])
                result.append([tuple(inner)] + tails[key] if len(inner) > 1 else inner + tails[key])
                for _, num in items:
                    left.remove(num)
        result += [paths[num] for num in left]
        try:
            return _python2_sorted(result)
        except TypeError:
            return result

    def render(self, tree: Any, first: bool = False) -> Tokens:
        if isinstance(tree, tuple):
            if None in tree:
                return [("TRUE", ())]
            parts = [self.render(p) for p in tree]
            joined = self._join(parts, " OR ")
            return joined if first else [("(", ())] + joined + [(")", ())]
        if isinstance(tree, list):
            return self._join([self.render(p) for p in tree], " AND ")
        if tree is None:
            return [("TRUE", ())]
        return _tokens(tree)

    @staticmethod
    def _join(parts: list[Tokens], sep: str) -> Tokens:
        out: Tokens = []
        for i, p in enumerate(parts):
            if i:
                out.append((sep, ()))
            out.extend(p)
        return out

    def modifier(self, pin: Pin, expr: Tokens, info: tuple) -> Tokens:
        """Negation, set / reset, rising / falling edge of a contact, coil or block pin."""
        if pin.negated:
            return [("NOT(", info + ("negated",))] + expr + [(")", ())]
        if pin.storage in ("set", "reset"):
            self.emit((self.indent + "IF ", info + (pin.storage,)), *expr, (" THEN\n  ", ()))
            word = "TRUE; (*set*)" if pin.storage == "set" else "FALSE; (*reset*)"
            return [(word + "\n" + self.indent + "END_IF", ())]
        if pin.edge == "rising":
            return self.trigger("R_TRIG", expr, info + ("rising",))
        if pin.edge == "falling":
            return self.trigger("F_TRIG", expr, info + ("falling",))
        return expr

    def trigger(self, fb: str, expr: Tokens, info: tuple) -> Tokens:
        n = 1
        while f"{fb}{n}" in self.declared:
            n += 1
        name = f"{fb}{n}"
        self.declare(name, fb, info[2] if len(info) > 2 else None)
        self.emit((self.indent, ()), (name, info), ("(CLK := ", ()), *expr, (");\n", ()))
        return [(f"{name}.Q", info)]

    # -- blocks ----------------------------------------------------------------------------------
    def block_info(self, e: Element) -> BlockInfo:
        info = library_block(e.type_name, self.project_pous, self.others)
        if info is None:
            raise self.fail(e, f"undefined block type '{e.type_name}'")
        if info.kind == "functionBlock" and not e.name:
            raise self.fail(e, f"function block {e.type_name} has no instance name")
        return info

    def block(self, e: Element, link: Optional[Conn], order: bool = False, to_inout: bool = False) -> Optional[Tokens]:
        info = self.block_info(e)
        in_names = [n for n, _ in info.inputs]
        out_names = [n for n, _ in info.outputs]
        out_params = {p.param for p in e.outputs}
        inouts = {p.param for p in e.inputs if p.param in out_params}
        inout_exprs: dict[str, Tokens] = {}
        ordered = e.exec_order > 0
        if e.local_id not in self.computed_blocks and not order:
            self.computed_blocks.add(e.local_id)
            if info.kind == "function":
                self.call_function(e, info, in_names, out_names, inouts, inout_exprs, ordered)
            else:
                self.call_function_block(e, in_names, inouts, ordered)
        return self.block_output(e, info, link, out_names, inouts, to_inout, ordered)

    def call_function(self, e: Element, info: BlockInfo, in_names: list[str], out_names: list[str],
                      inouts: set[str], inout_exprs: dict[str, Tokens], ordered: bool) -> None:
        by_param = {p.param: p for p in e.inputs}
        if info.extensible:
            params = [p.param for p in e.inputs]
        else:
            params = (["EN"] if "EN" in by_param else []) + in_names
        args: list[tuple[str, Tokens]] = []
        one_connected = False
        all_connected = True
        for i, param in enumerate(params):
            pin = by_param.get(param)
            if pin is None:
                all_connected = False
                continue
            pin_info = (self.tag, "block", e.local_id, "input", i)
            if param != "EN":
                one_connected = True
            expr = self.expression(pin.conns, ordered, param in inouts)
            if param in inouts:
                if expr is None:
                    raise self.fail(e, f"in-out variable {param} must be connected")
                inout_exprs[param] = expr
            if expr is not None:
                args.append((param, self.modifier(pin, expr, pin_info)))
        named = len(e.outputs) > 1 or not all_connected
        values: list[Tokens] = [[(p, ()), (" := ", ())] + x if named else x for p, x in args]
        if not one_connected:
            return   # the Editor cancels the call (a warning); using its output fails to compile
        result_name, result_info = "", ()
        for i, pin in enumerate(e.outputs):
            param = pin.param
            if param in inouts or param not in out_names + ["", "ENO"]:
                continue
            name = f"{e.type_name}{e.local_id}" if param == "" else f"_TMP_{e.type_name}{e.local_id}_{param}"
            self.declare(name, self.pin_type(e, param), e.local_id)
            if len(e.outputs) > 1 and param not in ("", "OUT"):
                values.append([(param, (self.tag, "block", e.local_id, "output", i)), (f" => {name}", ())])
            else:
                result_name, result_info = name, (self.tag, "block", e.local_id, "output", i)
        if not result_name:
            raise self.fail(e, f"function {e.type_name} has no output to take its result")
        self.emit((self.indent, ()), (result_name, result_info), (" := ", ()),
                  (e.type_name, (self.tag, "block", e.local_id, "type")), ("(", ()),
                  *self._join(values, ", "), (");\n", ()))

    def call_function_block(self, e: Element, in_names: list[str], inouts: set[str], ordered: bool) -> None:
        args: list[Tokens] = []
        offset = 0
        for pin in e.inputs:
            param = pin.param
            if param not in in_names and param != "EN":
                continue
            if param == "EN":
                idx, offset = 0, 1
            else:
                idx = offset + in_names.index(param)
            pin_info = (self.tag, "block", e.local_id, "input", idx)
            expr = self.expression(pin.conns, ordered, param in inouts)
            if expr is not None:
                args.append([(param, pin_info), (" := ", ())] + self.modifier(pin, expr, pin_info))
            elif param in inouts:
                raise self.fail(e, f"in-out variable {param} must be connected")
        self.emit((self.indent, ()), (e.name, (self.tag, "block", e.local_id, "name")), ("(", ()),
                  *self._join(args, ", "), (");\n", ()))

    def block_output(self, e: Element, info: BlockInfo, link: Optional[Conn], out_names: list[str],
                     inouts: set[str], to_inout: bool, ordered: bool) -> Optional[Tokens]:
        wanted = link.param if link is not None else None
        chosen: Optional[Pin] = None
        idx = 0
        if wanted is not None:
            if wanted in out_names or wanted == "ENO":
                for pin in e.outputs:
                    if pin.param == wanted:
                        chosen = pin
                        if wanted != "ENO":
                            idx = out_names.index(wanted)
        else:
            end = link.end if link is not None else None
            for i, pin in enumerate(e.outputs):
                if end is None or (pin.rel is not None and (e.x + pin.rel[0], e.y + pin.rel[1]) == end):
                    chosen, wanted, idx = pin, pin.param, i
        if chosen is None:
            if link is not None:
                raise self.fail(e, f"no output {wanted or ''} on this block: the wire must be redrawn")
            return None
        out_info = (self.tag, "block", e.local_id, "output", idx)
        if info.kind == "function":
            if wanted in inouts:
                for pin in e.inputs:
                    if pin.param == wanted:
                        value = self.expression(pin.conns, ordered, True) or []
                        break
            else:
                name = f"{e.type_name}{e.local_id}" if wanted == "" else f"_TMP_{e.type_name}{e.local_id}_{wanted}"
                value = [(name, out_info)]
            return self.modifier(chosen, value, out_info)
        member = self.modifier(chosen, [(f"{e.name}.{wanted}", out_info)], out_info)
        if to_inout:
            copy = f"{e.name}_{wanted}"
            if copy not in self.declared:
                self.declare(copy, self.pin_type(e, wanted or ""), e.local_id)
                self.emit((self.indent, ()), (f"{copy} := ", ()), *member, (";\n", ()))
            return [(copy, ())]
        return member

    # -- types of temporaries -----------------------------------------------------------------------
    def var_type(self, expression: str) -> Optional[str]:
        text = expression.strip()
        head, _, rest = text.partition(".")
        t = self.var_types.get(head)
        if t is not None:
            while rest and t is not None:
                member, _, rest = rest.partition(".")
                t = self.member_type(t, member)
            return t
        if "#" in text:
            prefix = text.split("#", 1)[0].upper()
            return _LITERAL_TYPES.get(prefix, prefix)
        if text.upper() in ("TRUE", "FALSE"):
            return "BOOL"
        return None

    def member_type(self, type_name: str, member: str) -> Optional[str]:
        fields = self.others.structs.get(type_name.upper())
        if fields is not None:
            return fields.get(member.upper())
        info = library_block(type_name, self.project_pous, self.others)
        if info is None:
            return None
        for n, t in info.inputs + info.outputs:
            if n.upper() == member.upper():
                return t
        return None

    def source_type(self, conn: Conn, seen: set[int]) -> Optional[str]:
        src = self.by_id.get(conn.ref)
        if src is None or src.local_id in seen:
            return None
        if src.kind in ("leftPowerRail", "contact", "coil"):
            return "BOOL"
        if src.kind in ("inVariable", "inOutVariable"):
            return self.var_type(src.name)
        if src.kind == "continuation":
            for c in self.connectors.get(src.name, []):
                for cc in c.pin_in.conns:
                    t = self.source_type(cc, seen | {src.local_id})
                    if t:
                        return t
            return None
        if src.kind == "block":
            param = conn.param
            if param is None:
                for pin in src.outputs:
                    if pin.rel is not None and conn.end == (src.x + pin.rel[0], src.y + pin.rel[1]):
                        param = pin.param
            return self.pin_type(src, param or "", seen)
        return None

    def pin_type(self, e: Element, param: str, seen: Optional[set[int]] = None) -> str:
        """The type of an output of block `e`, as the Editor infers it to declare a temporary
        (generic outputs take the type of the generic inputs, or of what they feed)."""
        seen = (seen or set()) | {e.local_id}
        if param == "ENO":
            return "BOOL"
        info = library_block(e.type_name, self.project_pous, self.others)
        if info is None:
            return "ANY"
        declared = dict(info.outputs).get(param or "OUT")
        if declared and declared != "T" and not declared.startswith("ANY"):
            return declared
        if declared == "T":
            for pin in e.inputs:
                if pin.param in info.generic or (info.extensible and pin.param not in dict(info.inputs)
                                                 and pin.param != "EN"):
                    for c in pin.conns:
                        t = self.source_type(c, seen)
                        if t:
                            return t
        for other, c in self.readers.get(e.local_id, []):
            if other.kind in ("outVariable", "inOutVariable") and (c.param or "OUT") == (param or "OUT"):
                t = self.var_type(other.name)
                if t:
                    return t
        return "ANY"


def _tokens(text: str) -> Tokens:
    """A path element back from its repr (the generator keeps paths as repr strings)."""
    import ast
    return [tuple(t) for t in ast.literal_eval(text)]
