"""ST source text -> AST (plclab.frontend.ast), with `file:line:col` diagnostics.

The lark LALR parser builds the AST directly through an inline transformer (no parse tree is
kept), which is what keeps a 5,000-line program well under the benchmark's 0.5 s.
"""
from __future__ import annotations

import hashlib
import pickle
import re
import sys
import threading
from collections import OrderedDict
from functools import lru_cache
from importlib import resources
from typing import Any, Iterable

import lark
from lark import Lark, Token, Transformer
from lark.exceptions import LarkError, UnexpectedCharacters, UnexpectedEOF, UnexpectedToken

from plclab.errors import Diagnostic
from plclab.fileio import user_cache_dir
from plclab.frontend import ast as A
from plclab.frontend import literals as L
from plclab.frontend.s7names import bit_address_hint, word_address_hint

MAX_SOURCE_BYTES = 8 * 1024 * 1024
MAX_NESTING = 200   # statement/expression nesting deeper than this is refused, not a crash

# Terminal names shown to users in "expected ..." messages.
_PRETTY = {
    "SEMICOLON": "';'", "COLON": "':'", "COMMA": "','", "LPAR": "'('", "RPAR": "')'",
    "LSQB": "'['", "RSQB": "']'", "DOT": "'.'", "__ANON_0": "':='", "IDENT": "an identifier",
    "INTEGER": "a number", "REAL_NUMBER": "a number", "$END": "end of file", "ELEMENTARY": "a type name",
    "STRING_KW": "STRING", "WSTRING_KW": "WSTRING",
}


class _Positioned(Exception):
    def __init__(self, line: int, col: int, message: str):
        super().__init__(message)
        self.line, self.col, self.message = line, col, message


def _first_pos(c: Any) -> tuple[int, int] | None:
    if isinstance(c, Token):
        return c.line or 1, c.column or 1
    if isinstance(c, A.Node):
        return c.line, c.col
    if isinstance(c, (list, tuple)):
        for x in c:
            pos = _first_pos(x)
            if pos:
                return pos
    return None


def _words(children: Iterable[Any]) -> list[Any]:
    """Children without keyword tokens (IF, THEN, END_IF, ...): what the AST is made of."""
    return [c for c in children if not (isinstance(c, Token) and c.type not in _VALUE_TOKENS)]


_VALUE_TOKENS = {"IDENT", "ELEMENTARY", "INTEGER", "BASED_INTEGER", "REAL_NUMBER", "TIME_LITERAL",
                 "DATE_LITERAL", "TOD_LITERAL", "DT_LITERAL", "SSTRING", "DSTRING", "TYPED_PREFIX",
                 "LOCATION", "EQ_OP", "REL_OP", "ADD_OP", "MUL_OP", "MINUS", "PLUS", "TRUE", "FALSE",
                 "CONSTANT", "RETAIN", "NON_RETAIN", "R_EDGE", "F_EDGE", "VAR", "VAR_INPUT",
                 "VAR_OUTPUT", "VAR_IN_OUT", "VAR_EXTERNAL", "VAR_GLOBAL", "VAR_TEMP", "STRING_KW",
                 "WSTRING_KW", "AT", "SINGLE", "INTERVAL", "ELSE", "BY", "WITH"}


class _Builder(Transformer):
    """Builds AST nodes bottom-up while the LALR parser reduces."""

    def __init__(self, file: str):
        super().__init__()
        self.file = file
        self.text = ""          # the source being parsed (set with `file`)

    # -- helpers ------------------------------------------------------------------------
    def _at(self, children: Any) -> dict:
        """Position of a node: that of its first child that has one (a token or a node)."""
        line, col = _first_pos(children) or (1, 1)
        return {"line": line, "col": col, "file": self.file}

    def _tok(self, tok: Token) -> dict:
        return {"line": tok.line, "col": tok.column, "file": self.file}

    def _lit(self, fn, tok: Token, kind: str, type_name: str | None = None) -> A.Literal:
        try:
            value = fn(str(tok))
        except L.LiteralError as e:
            raise _Positioned(tok.line, tok.column, str(e)) from None
        except (ValueError, OverflowError):
            shown = tok if len(tok) <= 30 else tok[:27] + "..."
            raise _Positioned(tok.line, tok.column, f"malformed literal '{shown}'") from None
        return A.Literal(**self._tok(tok), kind=kind, value=value, type_name=type_name, text=str(tok))

    # -- top level ------------------------------------------------------------------------
    def start(self, children):
        unit = A.Unit(line=1, col=1, file=self.file)
        for c in children:
            if isinstance(c, A.TypeBlock):
                unit.types.extend(c.decls)
            elif isinstance(c, A.PouDecl):
                unit.pous.append(c)
            elif isinstance(c, A.Configuration):
                unit.configs.append(c)
            elif isinstance(c, A.GlobalBlock):
                unit.gvls.append(c.block)
        return unit

    def gvl(self, children):
        (block,) = children
        return A.GlobalBlock(**self._at(children), block=block)

    # -- types ----------------------------------------------------------------------------
    def type_block(self, children):
        return A.TypeBlock(**self._at(children), decls=[c for c in children if isinstance(c, A.TypeDecl)])

    def type_decl(self, children):
        name, (type_ref, init) = children
        return A.TypeDecl(**self._tok(name), name=str(name), type_ref=type_ref, init=init)

    def type_def(self, children):
        return (children[0], children[1] if len(children) > 1 else None)

    def type_def_struct(self, children):
        return (children[0], None)

    def struct_spec(self, children):
        return A.StructTypeRef(**self._at(children), fields=[c for c in children if isinstance(c, A.VarDecl)])

    def struct_field(self, children):
        name, type_ref, init = children
        return A.VarDecl(**self._tok(name), name=str(name), type_ref=type_ref, init=init, section="STRUCT")

    def named_type(self, children):
        (tok,) = children
        return A.NamedType(**self._tok(tok), name=str(tok))

    def subrange_type(self, children):
        base, lo, hi = children
        return A.SubrangeTypeRef(**self._at(children), base=base, lo=lo, hi=hi)

    def string_type(self, children):
        return A.StringTypeRef(**self._at(children), wide=False, length=children[1])

    def wstring_type(self, children):
        return A.StringTypeRef(**self._at(children), wide=True, length=children[1])

    def array_type(self, children):
        w = _words(children)
        ranges = [c for c in w if isinstance(c, tuple)]
        elem = w[-1]
        return A.ArrayTypeRef(**self._at(children), ranges=ranges, elem=elem)

    def array_range(self, children):
        return (children[0], children[1])

    def enum_type(self, children):
        _lpar, values = children
        return A.EnumTypeRef(**self._at(children), values=values)

    def enum_values(self, children):
        return [(str(t), t.line, t.column) for t in children]

    # -- initializers ---------------------------------------------------------------------
    def array_init(self, children):
        return A.ArrayInit(**self._at(children), items=list(children[1:]))

    def array_item(self, children):
        return (None, children[0])

    def array_repeat(self, children):
        count, value = children
        return (self._lit(L.parse_int, count, "int"), value)

    def struct_init(self, children):
        return A.StructInit(**self._at(children), fields=list(children[1:]))

    def struct_init_item(self, children):
        name, value = children
        return (str(name), name.line, name.column, value)

    # -- POUs -------------------------------------------------------------------------------
    def _pou(self, kind, children, has_return=False):
        w = _words(children)
        name = w[0]
        keyword = children[0]
        if isinstance(keyword, Token) and "(*" in self.text[keyword.end_pos:name.start_pos]:
            # iec2c -p finds the POU names before it parses, and a comment in between makes it
            # fail on the whole POU ("unknown error in program declaration" at its end)
            raise _Positioned(keyword.line, keyword.column,
                              f"a comment between {kind} and its name: OpenPLC's compiler fails on the whole "
                              f"{kind}; move the comment")
        ret = w[1] if has_return else None
        rest = w[2:] if has_return else w[1:]
        blocks = [c for c in rest if isinstance(c, A.VarBlock)]
        body = rest[-1]
        end = children[-1]
        pou = A.PouDecl(**self._tok(name), kind=kind, name=str(name), return_type=ret,
                        blocks=blocks, body=body)
        pou.end_line = end.line if isinstance(end, Token) else 0
        return pou

    def function(self, children):
        return self._pou("FUNCTION", children, has_return=True)

    def function_block(self, children):
        return self._pou("FUNCTION_BLOCK", children)

    def program(self, children):
        return self._pou("PROGRAM", children)

    def var_kind(self, children):
        return children[0]

    def var_qualifier(self, children):
        return children[0]

    def edge(self, children):
        return str(children[0]).upper()

    def var_block(self, children):
        kind = children[0]
        return self._block(kind, str(kind).upper(), children[1:])

    def global_var_block(self, children):
        return self._block(children[0], "VAR_GLOBAL", children[1:])

    def _block(self, first: Token, section, rest):
        quals = [str(c).upper() for c in rest if isinstance(c, Token) and c.type in ("CONSTANT", "RETAIN", "NON_RETAIN")]
        decls = [d for c in rest if isinstance(c, list) for d in c]
        constant, retain = "CONSTANT" in quals, "RETAIN" in quals
        for d in decls:
            d.section, d.constant, d.retain = section, constant, retain
        block = A.VarBlock(**self._tok(first), section=section, constant=constant, retain=retain, decls=decls)
        block.qualifiers = quals
        return block

    def var_decl(self, children):
        names = []
        location = None
        type_ref = None
        edge = None
        init = None
        seen_colon_items = False
        for c in children:
            if isinstance(c, Token) and c.type == "IDENT" and not seen_colon_items:
                names.append(c)
            elif isinstance(c, Token) and c.type == "LOCATION":
                location = self._location(c)
            elif isinstance(c, Token) and c.type == "AT":
                continue
            elif c is None:
                continue
            elif type_ref is None and isinstance(c, A.TypeRef):
                type_ref = c
                seen_colon_items = True
            elif isinstance(c, str) and c in ("R_EDGE", "F_EDGE"):
                edge = c
            else:
                init = c
        decls = [A.VarDecl(**self._tok(n), name=str(n), type_ref=type_ref, init=init, location=location,
                           edge=edge) for n in names]
        for d in decls:
            d.group_size = len(names)
        return decls

    def anon_located(self, children):
        w = [c for c in children if c is not None and not (isinstance(c, Token) and c.type == "AT")]
        loc_tok, type_ref = w[0], w[1]
        init = w[2] if len(w) > 2 else None
        d = A.VarDecl(**self._tok(loc_tok), name="", type_ref=type_ref, init=init,
                      location=self._location(loc_tok))
        d.group_size = 1
        return [d]

    def _location(self, tok: Token) -> A.Location:
        text = str(tok)
        area = text[1].upper()
        rest = text[2:]
        size = "X"
        if rest and rest[0].upper() in "XBWDL":
            size = rest[0].upper()
            rest = rest[1:]
        elif "." not in rest:
            size = "X"  # `%I0` is a bit address in short form (IEC); matiec accepts it as BOOL
        parts = [int(p) if len(p) <= 18 else 10**18 for p in rest.split(".")]
        return A.Location(**self._tok(tok), text=text.upper(), area=area, size=size, parts=parts)

    def direct_name(self, children):
        # `%QX0.0` used in a body: it names the POU's variable located there (see the checker)
        # (`%I0.1` stays as written: OpenPLC's C names it apart from %IX0.1, see the checker)
        (tok,) = children
        loc = self._location(tok)
        return A.Name(**self._tok(tok), name=loc.text if loc.written_without_size else loc.key)

    # -- configuration --------------------------------------------------------------------
    def config_single(self, children):
        w = _words(children)
        name = w[0]
        globals_ = [c for c in w if isinstance(c, A.VarBlock)]
        tasks, programs = w[-1]
        res = A.Resource(**self._tok(name), name="", on="", globals=[], tasks=tasks, programs=programs)
        return A.Configuration(**self._tok(name), name=str(name), globals=globals_, resources=[res])

    def config(self, children):
        w = _words(children)
        name = w[0]
        return A.Configuration(**self._tok(name), name=str(name),
                               globals=[c for c in w if isinstance(c, A.VarBlock)],
                               resources=[c for c in w if isinstance(c, A.Resource)])

    def resource(self, children):
        w = _words(children)
        name, on = w[0], w[1]
        tasks, programs = w[-1]
        return A.Resource(**self._tok(name), name=str(name), on=str(on),
                          globals=[c for c in w if isinstance(c, A.VarBlock)], tasks=tasks, programs=programs)

    def resource_body(self, children):
        return ([c for c in children if isinstance(c, A.TaskDecl)],
                [c for c in children if isinstance(c, A.ProgramInstance)])

    def task(self, children):
        name = children[1]
        params = [c for c in children[2:] if isinstance(c, tuple)]
        found: dict[str, Any] = {}
        order = ["SINGLE", "INTERVAL", "PRIORITY"]
        last = -1
        for key_tok, value in params:
            key = str(key_tok).upper()
            if key not in order:
                raise _Positioned(key_tok.line, key_tok.column,
                                  f"unknown task parameter '{key_tok}' (SINGLE, INTERVAL, PRIORITY)")
            if order.index(key) <= last:
                raise _Positioned(key_tok.line, key_tok.column,
                                  "task parameters go in the order SINGLE, INTERVAL, PRIORITY, each once")
            last = order.index(key)
            found[key] = value
        if "PRIORITY" not in found:
            raise _Positioned(name.line, name.column, f"task '{name}' needs PRIORITY := n")
        return A.TaskDecl(**self._tok(name), name=str(name), single=found.get("SINGLE"),
                          interval=found.get("INTERVAL"), priority=found["PRIORITY"])

    def task_param(self, children):
        return (children[0], children[1])

    def program_config(self, children):
        retain = None
        idents = []
        args = []
        for c in children:
            if isinstance(c, Token) and c.type == "RETAIN":
                retain = True
            elif isinstance(c, Token) and c.type == "NON_RETAIN":
                retain = False
            elif isinstance(c, Token) and c.type == "IDENT":
                idents.append(c)
            elif isinstance(c, A.Arg):
                args.append(c)
        has_with = any(isinstance(c, Token) and c.type == "WITH" for c in children)
        if has_with:
            name, task, type_name = idents
        else:
            name, type_name = idents
            task = None
        return A.ProgramInstance(**self._tok(name), name=str(name), task=str(task) if task else None,
                                 type_name=str(type_name), args=args, retain=retain)

    # -- statements -------------------------------------------------------------------------
    def stmt_list(self, children):
        return list(children)

    def assign(self, children):
        target, value = children
        return A.Assign(line=target.line, col=target.col, file=self.file, target=target, value=value)

    def call_stmt(self, children):
        name = children[0]
        target = A.Name(**self._tok(name), name=str(name))
        return A.CallStmt(**self._tok(name), target=target, args=[a for a in children[1:] if a is not None])

    def call_stmt_path(self, children):
        target = children[0]
        return A.CallStmt(line=target.line, col=target.col, file=self.file, target=target,
                          args=[a for a in children[1:] if a is not None])

    def if_stmt(self, children):
        w = _words(children)
        branches = [(w[0], w[1])]
        rest = w[2:]
        else_body = None
        for c in rest:
            if isinstance(c, tuple):
                branches.append(c)
            elif isinstance(c, list):
                else_body = c
        return A.If(**self._at(children), branches=branches, else_body=else_body)

    def elsif(self, children):
        w = _words(children)
        return (w[0], w[1])

    def case_stmt(self, children):
        # children: CASE selector OF head (head | stmt)* [ELSE stmt_list] END_CASE
        sel = children[1]
        branches: list[A.CaseBranch] = []
        else_body = None
        for i, c in enumerate(children[3:], start=3):
            if isinstance(c, A.CaseBranch):
                branches.append(c)
            elif isinstance(c, A.Stmt):
                branches[-1].body.append(c)
            elif isinstance(c, Token) and c.type == "ELSE":
                else_body = children[i + 1]
                break
        return A.Case(**self._at(children), selector=sel, branches=branches, else_body=else_body)

    def case_head(self, children):
        labels = [c for c in children if isinstance(c, A.CaseLabel)]
        return A.CaseBranch(**self._at(children), labels=labels, body=[])

    def case_label(self, children):
        lo, hi = children
        return A.CaseLabel(line=lo.line, col=lo.col, file=self.file, lo=lo, hi=hi)

    def for_stmt(self, children):
        # children: FOR IDENT start TO end (BY step | None None) DO body END_FOR
        var, start, end, step, body = children[1], children[2], children[4], children[6], children[8]
        return A.For(**self._at(children), var=A.Name(**self._tok(var), name=str(var)),
                     start=start, end=end, step=step, body=body)

    def while_stmt(self, children):
        w = _words(children)
        return A.While(**self._at(children), cond=w[0], body=w[1])

    def repeat_stmt(self, children):
        w = _words(children)
        return A.Repeat(**self._at(children), body=w[0], cond=w[1])

    def exit_stmt(self, children):
        return A.Exit(**self._at(children))

    def continue_stmt(self, children):
        return A.Continue(**self._at(children))

    def return_stmt(self, children):
        return A.Return(**self._at(children))

    def empty_stmt(self, children):
        return A.Empty(**self._at(children))

    # -- arguments ----------------------------------------------------------------------------
    def arg_in(self, children):
        name, value = children
        return A.Arg(**self._tok(name), name=str(name), value=value)

    def arg_out(self, children):
        name, _arrow, target = children
        return A.Arg(**self._tok(name), name=str(name), value=target, is_output=True)

    def arg_out_not(self, children):
        _not, name, _arrow, target = children
        return A.Arg(**self._tok(name), name=str(name), value=target, is_output=True, negated=True)

    def arg_pos(self, children):
        (value,) = children
        return A.Arg(line=value.line, col=value.col, file=self.file, name=None, value=value)

    # -- expressions ----------------------------------------------------------------------------
    def _bin(self, children, op=None):
        left, optok, right = children[0], children[1], children[-1]
        return A.Binary(line=left.line, col=left.col, file=self.file,
                        op=op or str(optok).upper(), left=left, right=right)

    def bin_or(self, c):
        return self._bin(c, "OR")

    def bin_xor(self, c):
        return self._bin(c, "XOR")

    def bin_and(self, c):
        return A.Binary(line=c[0].line, col=c[0].col, file=self.file, op="AND", left=c[0], right=c[-1])

    def bin_cmp(self, c):
        return self._bin(c)

    def bin_arith(self, c):
        return self._bin(c)

    def bin_mod(self, c):
        return self._bin(c, "MOD")

    def bin_pow(self, c):
        return A.Binary(line=c[0].line, col=c[0].col, file=self.file, op="**", left=c[0], right=c[-1])

    def neg(self, children):
        minus, operand = children
        if isinstance(operand, A.Literal) and operand.kind in ("int", "real", "time") and operand.type_name is None \
                and not operand.parenthesized:
            # `-5` is a signed literal, not an operation: it must fit the target type as a whole.
            operand.value = -operand.value
            operand.text = "-" + operand.text
            operand.line, operand.col = minus.line, minus.column
            return operand
        return A.Unary(**self._tok(minus), op="-", operand=operand)

    def paren(self, children):
        (inner,) = children
        if isinstance(inner, A.Literal):
            inner.parenthesized = True
        return inner

    def pos(self, children):
        plus, operand = children
        operand.line, operand.col = plus.line, plus.column
        operand.text = "+" + operand.text
        return operand

    def neg_neg(self, children):
        minus, inner_minus, operand = children
        return A.Unary(**self._tok(minus), op="-", operand=self.neg([inner_minus, operand]))

    def neg_pos(self, children):
        minus, plus, operand = children
        return A.Unary(**self._tok(minus), op="-", operand=self.pos([plus, operand]))

    def not_(self, children):
        tok, operand = children
        return A.Unary(**self._tok(tok), op="NOT", operand=operand)

    def call(self, children):
        name = children[0]
        return A.Call(**self._tok(name), name=str(name), args=[a for a in children[1:] if a is not None])

    def call_operator_name(self, children):
        # `AND(a, b)`, `MOD(a, b)`: standard functions whose names are also operator keywords
        name = children[0]
        return A.Call(**self._tok(name), name=str(name).upper(), args=[a for a in children[1:] if a is not None])

    def name(self, children):
        (tok,) = children
        return A.Name(**self._tok(tok), name=str(tok))

    def variable_path(self, children):
        return children[0]

    def member(self, children):
        base, name = children
        return A.Member(line=base.line, col=base.col, file=self.file, base=base, name=str(name))

    def member_name(self, children):
        return children[0]

    def index(self, children):
        base = children[0]
        return A.Index(line=base.line, col=base.col, file=self.file, base=base, indexes=list(children[1:]))

    # -- literals ---------------------------------------------------------------------------
    def int_lit(self, c):
        return self._lit(L.parse_int, c[0], "int")

    def based_lit(self, c):
        return self._lit(L.parse_based, c[0], "int")

    def real_lit(self, c):
        return self._lit(L.parse_real, c[0], "real")

    def true_lit(self, c):
        return A.Literal(**self._tok(c[0]), kind="bool", value=True, text=str(c[0]))

    def false_lit(self, c):
        return A.Literal(**self._tok(c[0]), kind="bool", value=False, text=str(c[0]))

    def time_lit(self, c):
        return self._lit(L.parse_time, c[0], "time")

    def date_lit(self, c):
        return self._lit(L.parse_date, c[0], "date")

    def tod_lit(self, c):
        return self._lit(L.parse_tod, c[0], "tod")

    def dt_lit(self, c):
        return self._lit(L.parse_dt, c[0], "dt")

    def string_lit(self, c):
        return self._lit(L.parse_string, c[0], "string")

    def wstring_lit(self, c):
        return self._lit(L.parse_string, c[0], "wstring")

    def neg_typed(self, c):
        return ("-", c[1])

    def pos_typed(self, c):
        return ("+", c[1])

    def typed_lit(self, children):
        prefix, value = children
        type_name = str(prefix)[:-1].upper()
        sign = 1
        if isinstance(value, tuple):
            sign = -1 if value[0] == "-" else 1
            value = value[1]
        kinds = {"INTEGER": (L.parse_int, "int"), "BASED_INTEGER": (L.parse_based, "int"),
                 "REAL_NUMBER": (L.parse_real, "real")}
        text = str(prefix) + ("-" if sign < 0 else "") + str(value)
        if value.type in kinds:
            fn, kind = kinds[value.type]
            lit = self._lit(fn, value, kind, type_name)
            lit.value = sign * lit.value
        elif value.type in ("TRUE", "FALSE"):
            lit = A.Literal(**self._tok(value), kind="bool", value=value.type == "TRUE", type_name=type_name)
        else:  # IDENT: a qualified enumerated value `E_Mode#RUN`
            lit = A.Literal(**self._tok(value), kind="enum", value=str(value).upper(), type_name=type_name)
        lit.line, lit.col, lit.text = prefix.line, prefix.column, text
        return lit


@lru_cache(maxsize=1)
def _grammar() -> str:
    return resources.files("plclab.frontend").joinpath("st.lark").read_text(encoding="utf-8")


# One parser for the process: the LALR tables are built once, and the AST builder runs inline
# as the parser reduces (no parse tree is kept). `_builder().file` is set per parse, under a lock.
_BUILDER_LOCK = threading.Lock()


@lru_cache(maxsize=1)
def _builder() -> "_Builder":
    return _Builder("")


@lru_cache(maxsize=1)
def _lark() -> Lark:
    """The parser, its LALR tables read from the user's cache where an earlier process saved
    them: building them from the grammar costs half a second, more than parsing a whole
    stand's program, and every process that checks ST (a CLI command, a lab upload's trial,
    a student's grading process in a class) would pay it again. The file is lark's own cache
    (`cache=`): it starts with the hash of the grammar, the options, lark's version and
    Python's, and lark builds the tables anew (and writes them again) wherever the file does
    not match or cannot be read whole, e.g. while another process is still writing it.
    Without a cache folder the tables are built each time."""
    grammar = _grammar()
    options: dict[str, Any] = dict(parser="lalr", lexer="contextual", transformer=_builder(),
                                   lexer_callbacks={"IDENT": _keyword_token})
    key = hashlib.sha256(f"{grammar}\0{lark.__version__}\0{sys.version_info[:2]}".encode()).hexdigest()[:20]
    path = user_cache_dir("parser") / f"st-{key}.lark"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        cache: bool | str = str(path)
    except OSError:
        cache = False
    return Lark(grammar, cache=cache, **options)


def load_parser() -> None:
    """Load (or build) the parser's tables now, once per process: a process that will hold a
    student's program to a memory limit loads them before setting it, so the harness's tables
    are not the student's share, and never loaded at the limit (lark takes a failed load from
    its cache as a reason to build the tables anew, allocation after allocation at the limit)."""
    _lark()


@lru_cache(maxsize=1)
def _keywords() -> frozenset[str]:
    """Every word the grammar uses as a keyword (never an identifier). Elementary type names
    may reach the parser as IDENT in type positions; the checker refuses them as names."""
    words = set(re.findall(r'^[A-Z_]+:\s*"([A-Z_]+)"i', _grammar(), re.M))
    return frozenset(words)


def _keyword_token(tok: Token) -> Token:
    # The contextual lexer lets `IF` through as an identifier where no keyword fits (e.g. a
    # variable name); matiec's lexer never does, so neither do we: the token goes to the parser
    # as the keyword it is, and the syntax error then says what is wrong there.
    word = tok.value.upper()
    if word in _keywords():
        tok.type = word
    return tok


def _describe_expected(expected: Iterable[str]) -> str:
    names = sorted({_PRETTY.get(e, e if e.isupper() and not e.startswith("__") else None) or "" for e in expected} - {""})
    if not names:
        return ""
    if len(names) > 6:
        return ""
    return "; expected " + ", ".join(names)


def _token_text(tok: Token) -> str:
    if tok.type == "$END":
        return "end of file"
    return f"'{tok}'"


_SCAN = re.compile(r"'[^'$\n]*(?:\$[^\n][^'$\n]*)*'|\"[^\"$\n]*(?:\$[^\n][^\"$\n]*)*\"|\(\*.*?\*\)|\(\*", re.S)
"""String literals and comments (an unterminated comment: its opener), in source order."""
_NEST_SCAN = re.compile(_SCAN.pattern + r"|[()\[\]]", re.S)


def _too_deep(text: str) -> tuple[int, int] | None:
    """Where brackets in the code (not in comments or strings) first nest deeper than
    MAX_NESTING: the (line, column) of the '(' or '[' that crossed the limit."""
    depth = 0
    for m in _NEST_SCAN.finditer(text):
        tok = m.group(0)
        if tok == "(*":                  # an unterminated comment: the rest is comment
            return None
        if tok in ("(", "["):
            depth += 1
            if depth > MAX_NESTING:
                pos = m.start()
                return text.count("\n", 0, pos) + 1, pos - (text.rfind("\n", 0, pos) + 1) + 1
        elif tok in (")", "]"):
            depth -= 1
    return None


# Parsed units by their file name and text, pickled as the parser left them (before the
# checker annotates the tree in place): the same program is checked again and again (a
# grading's restarts, a lab's reloads, a class's model answer, the test suite), and reading a
# unit back from its pickle takes a tenth of parsing it. A text is kept from its second parse
# on (a file checked once pays nothing for it). Bounded: the most recent entries only.
PARSE_CACHE_BYTES = 32 * 1024 * 1024       # all entries together
PARSE_CACHE_MAX_BYTES = 2 * 1024 * 1024    # a unit that pickles larger is parsed each time
_PARSED: "OrderedDict[bytes, bytes]" = OrderedDict()
_PARSED_LOCK = threading.Lock()
_parsed_bytes = 0
_PARSED_ONCE: "OrderedDict[bytes, None]" = OrderedDict()     # keys of texts parsed once
PARSED_ONCE_KEYS = 4096


def parse_source(text: str, file: str) -> tuple[A.Unit | None, list[Diagnostic]]:
    """Parse one file. Returns the unit (None on a syntax error) and the diagnostics.
    A text parsed before under the same name comes back as a fresh copy of its tree."""
    if len(text) > MAX_SOURCE_BYTES:
        return None, [Diagnostic(file, 1, 1, f"file too large ({len(text)} bytes; the limit is {MAX_SOURCE_BYTES})")]
    key = hashlib.blake2b(f"{file}\0{text}".encode("utf-8", "surrogatepass"), digest_size=20).digest()
    with _PARSED_LOCK:
        pickled = _PARSED.get(key)
        if pickled is not None:
            _PARSED.move_to_end(key)
    if pickled is not None:
        return pickle.loads(pickled), []
    unit, diags = _parse(text, file)
    if unit is not None and _seen_before(key):
        try:
            pickled = pickle.dumps(unit, protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, TypeError, AttributeError, RecursionError):   # pragma: no cover
            pickled = None
        if pickled is not None and len(pickled) <= PARSE_CACHE_MAX_BYTES:
            _remember(key, pickled)
    return unit, diags


def _seen_before(key: bytes) -> bool:
    with _PARSED_LOCK:
        if key in _PARSED_ONCE:
            return True
        _PARSED_ONCE[key] = None
        while len(_PARSED_ONCE) > PARSED_ONCE_KEYS:
            _PARSED_ONCE.popitem(last=False)
        return False


def _remember(key: bytes, pickled: bytes) -> None:
    global _parsed_bytes
    with _PARSED_LOCK:
        if key in _PARSED:
            return
        _PARSED[key] = pickled
        _parsed_bytes += len(pickled)
        while _parsed_bytes > PARSE_CACHE_BYTES:
            _old, dropped = _PARSED.popitem(last=False)
            _parsed_bytes -= len(dropped)


def _parse(text: str, file: str) -> tuple[A.Unit | None, list[Diagnostic]]:
    if "\x00" in text:
        line = text.count("\n", 0, text.index("\x00")) + 1
        return None, [Diagnostic(file, line, 1, "binary data (NUL byte) in ST source")]
    deep = _too_deep(text)
    if deep:
        return None, [Diagnostic(file, *deep, f"expressions nested more than {MAX_NESTING} levels deep")]
    comment = _unterminated_comment(text)
    if comment:
        return None, [Diagnostic(file, *comment, "unterminated comment: '(*' without '*)'")]
    lark = _lark()
    try:
        with _BUILDER_LOCK:
            _builder().file, _builder().text = file, text
            unit = lark.parse(text)
        return unit, []
    except UnexpectedCharacters as e:
        return None, [_lex_error(text, file, e)]
    except UnexpectedToken as e:
        return None, [_syntax_error(file, e, text)]
    except UnexpectedEOF:
        return None, [Diagnostic(file, text.count("\n") + 1, 1, "unexpected end of file")]
    except _Positioned as e:
        return None, [Diagnostic(file, e.line, e.col, e.message)]
    except RecursionError:
        return None, [Diagnostic(file, 1, 1, "program nested too deeply")]


def _lex_error(text: str, file: str, e: UnexpectedCharacters) -> Diagnostic:
    rest = text[e.pos_in_stream:e.pos_in_stream + 2]
    if rest == "(*":
        return Diagnostic(file, e.line, e.column, "unterminated comment: '(*' without '*)'")
    ch = text[e.pos_in_stream]
    if ch == "'" or ch == '"':
        return Diagnostic(file, e.line, e.column, "unterminated string literal")
    if text[e.pos_in_stream:e.pos_in_stream + 2] == "//":
        return Diagnostic(file, e.line, e.column, "'//' comments are not IEC 61131-3; use (* ... *)")
    word = re.match(r"[A-Za-z0-9_]*", text[e.pos_in_stream:]).group(0)
    if ch == "_" or (text[e.pos_in_stream - 1:e.pos_in_stream] == "_" and ch.isalnum()) or \
            (word[:1].isalpha() and ("__" in word or word.endswith("_"))):
        shown = f" '{word}'" if word and word != "_" else ""
        return Diagnostic(file, e.line, e.column, f"malformed identifier{shown}: '_' only between letters or "
                                                  f"digits, never two in a row or at the end")
    if ch == "#" and text[e.pos_in_stream - 1:e.pos_in_stream].isdigit():
        return Diagnostic(file, e.line, e.column, "based numbers are written 2#..., 8#... or 16#... "
                                                  "(no other base exists)")
    if ch == "{":
        return Diagnostic(file, e.line, e.column, "pragmas '{...}' are not supported (OpenPLC pastes them "
                                                  "into C code); remove it")
    if ch == "%":
        if not re.match(r"%[IQM]", text[e.pos_in_stream:e.pos_in_stream + 2], re.I):
            return Diagnostic(file, e.line, e.column, "'%' is not an operator in ST: the remainder is MOD (a MOD b)")
        return Diagnostic(file, e.line, e.column, "malformed direct address (expected e.g. %IX0.0, %QW1, %MD4)")
    if ch in "!|":
        two = text[e.pos_in_stream:e.pos_in_stream + 2]
        shown = two if two in ("!=", "||") else ch
        instead = {"!=": "'<>'", "||": "OR", "|": "OR", "!": "NOT"}[shown]
        return Diagnostic(file, e.line, e.column, f"'{shown}' is not ST: write {instead}")
    printable = ch if ch.isprintable() else f"\\x{ord(ch):02x}"
    return Diagnostic(file, e.line, e.column, f"unexpected character '{printable}'")


_OPENERS = {"IF": "END_IF", "CASE": "END_CASE", "FOR": "END_FOR", "WHILE": "END_WHILE",
            "REPEAT": "END_REPEAT", "FUNCTION": "END_FUNCTION", "FUNCTION_BLOCK": "END_FUNCTION_BLOCK",
            "PROGRAM": "END_PROGRAM", "TYPE": "END_TYPE", "STRUCT": "END_STRUCT",
            "CONFIGURATION": "END_CONFIGURATION", "RESOURCE": "END_RESOURCE"}
_VAR_OPENERS = {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_EXTERNAL", "VAR_GLOBAL", "VAR_TEMP"}
_CLOSERS = set(_OPENERS.values()) | {"END_VAR"}


def _unterminated_comment(text: str) -> tuple[int, int] | None:
    for m in _SCAN.finditer(text):
        if m.group(0) == "(*":
            pos = m.start()
            line = text.count("\n", 0, pos) + 1
            return line, pos - (text.rfind("\n", 0, pos) + 1) + 1
    return None


def _unclosed_block(text: str, err: Token) -> tuple[str, Token] | None:
    """The innermost block still open where `err` (an END_x or the end of file) stands; None
    also when `err` is an END_x that closes none of the open blocks (then it is misplaced)."""
    stack: list[Token] = []
    try:
        for tok in _lark().lex(text):
            if err.type != "$END" and (tok.line, tok.column) >= (err.line, err.column):
                break
            t = tok.type
            if t in _OPENERS or t in _VAR_OPENERS:
                # `PROGRAM x WITH t : p;` inside a RESOURCE opens nothing
                if t == "PROGRAM" and stack and stack[-1].type == "RESOURCE":
                    continue
                stack.append(tok)
            elif t in _CLOSERS:
                while stack:
                    top = stack.pop()
                    if _OPENERS.get(top.type, "END_VAR") == t:
                        break
    except (LarkError, _Positioned):
        return None
    if not stack:
        return None
    if err.type in _CLOSERS and all(_OPENERS.get(t.type, "END_VAR") != err.type for t in stack):
        return None
    top = stack[-1]
    return _OPENERS.get(top.type, "END_VAR"), top


def _tokens_before(text: str, err: Token, n: int = 2) -> list[Token]:
    """The last `n` tokens before `err` (error reporting only)."""
    out: list[Token] = []
    try:
        for tok in _lark().lex(text):
            if err.type != "$END" and (tok.line, tok.column) >= (err.line, err.column):
                break
            out.append(tok)
            del out[:-n]
    except (LarkError, _Positioned):
        pass
    return out


_HEADERS = {"IF": "THEN", "ELSIF": "THEN", "WHILE": "DO", "FOR": "DO", "CASE": "OF"}
_HEADER_ENDS = {"THEN", "DO", "OF", "SEMICOLON", "END_IF", "END_WHILE", "END_FOR", "END_CASE"}


def _open_header(text: str, err: Token) -> tuple[str, str, Token] | None:
    """(`IF`, `THEN`, the IF token) when `err` stands in an IF/ELSIF/WHILE/FOR/CASE header whose
    THEN/DO/OF has not come yet. (LALR merges lookaheads, so `expected` alone cannot tell.)"""
    for tok in reversed(_tokens_before(text, err, 200)):
        if tok.type in _HEADERS:
            return tok.type, _HEADERS[tok.type], tok
        if tok.type in _HEADER_ENDS:
            return None
    return None


def _nested_comment(text: str, err: Token) -> tuple[str, int, int] | None:
    """If `err` comes right after a comment that contains '(*' (comments do not nest), the
    message and the position of the first code after that comment."""
    err_pos = len(text) if err.type == "$END" else err.start_pos
    for m in _SCAN.finditer(text, 0, err_pos):
        body = m.group(0)
        if not body.startswith("(*") or "(*" not in body[2:]:
            continue
        end = m.end()
        code = re.compile(r"\s*").match(text, end).end()
        if code <= err_pos and "\n" not in text[end:err_pos].strip(" \t") and ";" not in text[end:err_pos]:
            line = text.count("\n", 0, m.start()) + 1
            col = m.start() - (text.rfind("\n", 0, m.start()) + 1) + 1
            cline = text.count("\n", 0, code) + 1
            ccol = code - (text.rfind("\n", 0, code) + 1) + 1
            return (f"comments do not nest in OpenPLC: the '(*' at line {line}, column {col} ends at the "
                    f"first '*)', so the text after it is read as code", cline, ccol)
    return None


_EMPTY_BLOCK = {
    "END_RESOURCE": "a RESOURCE needs at least one program instance (PROGRAM name WITH task : type;)",
    "END_CONFIGURATION": "a CONFIGURATION needs at least one program instance (PROGRAM name WITH task : type;)",
    "END_TYPE": "TYPE ... END_TYPE needs at least one type declaration",
    "END_STRUCT": "a STRUCT needs at least one field",
    "END_CASE": "a CASE needs at least one branch (label: statements)",
}
_EXPECTS_OPERAND = {":=", "(", ",", "+", "-", "*", "/", "**", "=", "<>", "<", ">", "<=", ">=", "&", "[",
                    "AND", "OR", "XOR", "MOD", "NOT", "IF", "ELSIF", "WHILE", "UNTIL", "CASE", "TO", "BY"}
_STATEMENT_START = {"IDENT", "IF", "CASE", "FOR", "WHILE", "REPEAT", "RETURN", "EXIT", "CONTINUE"} | _CLOSERS
_NOT_SUPPORTED_WORDS = {"VAR_ACCESS", "VAR_CONFIG", "ACTION", "TRANSITION", "STEP", "INITIAL_STEP", "REF", "DREF",
                        "REF_TO", "NULL"}


def _syntax_error(file: str, e: UnexpectedToken, text: str) -> Diagnostic:
    tok = e.token
    if tok.type != "$END" and tok.start_pos is not None and text[tok.start_pos:tok.start_pos + 2] in ("//", "/*"):
        return Diagnostic(file, tok.line, tok.column, f"'{text[tok.start_pos:tok.start_pos + 2]}' comments are not "
                                                      f"accepted by OpenPLC's compiler; use (* ... *)")
    expected = set(e.expected) if e.expected else set()
    if tok.type == "$END":
        line = text.count("\n") + 1
        col = len(text) - (text.rfind("\n") + 1) + 1
    else:
        line, col = tok.line, tok.column
    nested = _nested_comment(text, tok)
    if nested:
        return Diagnostic(file, nested[1], nested[2], nested[0])
    if tok.type in _EMPTY_BLOCK:
        unclosed = _unclosed_block(text, tok)
        if unclosed and unclosed[0] == tok.type:   # the block is closed right here, but empty
            return Diagnostic(file, line, col, _EMPTY_BLOCK[tok.type])
    if tok.type == "$END" or tok.type in _CLOSERS:
        unclosed = _unclosed_block(text, tok)
        if unclosed and unclosed[0] != tok.type:
            closer, opener = unclosed
            where = "end of file" if tok.type == "$END" else f"'{tok}'"
            if "SEMICOLON" in expected and tok.type != "$END":
                return Diagnostic(file, line, col, f"missing ';' before {where}")
            else_if = ""
            if closer == "END_IF" and re.search(r"\bELSE\s+IF\b", text[opener.start_pos:tok.start_pos
                                                                       if tok.type != "$END" else len(text)], re.I):
                else_if = "; ELSE IF opens a second IF: write ELSIF"
            return Diagnostic(file, line, col, f"missing {closer} before {where} "
                                               f"(the {opener} at line {opener.line}, column {opener.column} is not "
                                               f"closed){else_if}")
        if tok.type == "$END":
            return Diagnostic(file, line, col, "unexpected end of file")
    hint = _syntax_hint(text, tok, expected)
    if hint:
        return Diagnostic(file, hint[1], hint[2], hint[0])
    if tok.type != "IDENT" and "IDENT" in expected and re.fullmatch(r"[A-Za-z_]\w*", str(tok)):
        return Diagnostic(file, line, col, f"'{tok}' is a reserved word; it cannot be used as a name")
    if "SEMICOLON" in expected and len(expected) <= 16:
        return Diagnostic(file, line, col, f"unexpected {_token_text(tok)}; missing ';'?")
    return Diagnostic(file, line, col, f"unexpected {_token_text(tok)}{_describe_expected(expected)}")


def _s7_address(text: str, tok: Token, prev: list[Token], expected: set[str]) -> tuple[str, int, int] | None:
    """An S7-200 address where the error stands: `AT I0.1` (a name where the address goes) or
    `x := I0.1` (the name `I0`, then `.1`)."""
    word = str(tok)
    if tok.type == "IDENT" and "LOCATION" in expected:
        bit = re.match(r"\.(\d+)", text[tok.end_pos:]) if tok.end_pos is not None else None
        hint = bit_address_hint(word, bit.group(1)) if bit else word_address_hint(word)
        if hint:
            return hint, tok.line, tok.column
    if len(prev) == 2 and prev[0].type == "IDENT" and str(prev[1]) == "." and re.fullmatch(r"\d+", word):
        hint = bit_address_hint(str(prev[0]), word)
        if hint:
            return hint, prev[0].line, prev[0].column
    return None


_FUSED_END = re.compile(r"END(IF|WHILE|FOR|CASE|REPEAT|VAR|PROGRAM|FUNCTION|FUNCTION_BLOCK|TYPE|STRUCT)", re.I)


def _foreign_syntax(text: str, tok: Token, prev: list[Token], expected: set[str]) -> tuple[str, int, int] | None:
    """C, Python and ladder habits (`x = 1;`, `==`, `&&`, `n++`, `n += 1`, `ENDIF`, `0x10`,
    `ARRAY[10]`, `a : BOOL, b : BOOL;`) named as such, with the ST to write."""
    last = prev[-1] if prev else None
    line, col = tok.line, tok.column
    word, after = str(tok), text[tok.end_pos:tok.end_pos + 1] if tok.end_pos is not None else ""
    assign_expected = any(_PRETTY.get(e) == "':='" for e in expected)
    fused = _FUSED_END.fullmatch(str(last)) if last is not None and last.type == "IDENT" else None
    if fused and (tok.type in ("SEMICOLON", "$END") or tok.line > last.line):
        return f"'{last}' is written END_{fused.group(1).upper()}", last.line, last.column
    if word == "=" and last is not None and str(last) == "=" and last.end_pos == tok.start_pos:
        return "'==' is not ST: compare with '='", last.line, last.column
    if word == "&" and last is not None and str(last) == "&" and last.end_pos == tok.start_pos:
        return "'&&' is not ST: write AND", last.line, last.column
    if word in ("+", "-") and after in (word, "=") and assign_expected:
        op, name = word + after, str(last) if last is not None and last.type == "IDENT" else "v"
        return (f"'{op}' is not ST: write {name} := {name} {word} {'1' if after == word else '...'}", line, col)
    if word == "=" and assign_expected:
        return "'=' compares in ST; an assignment is written ':='", line, col
    if tok.type == "RSQB" and last is not None and last.type == "INTEGER" and len(prev) == 2 and str(prev[0]) == "[":
        n = int(str(last).replace("_", "") or 0)
        return (f"an array's bounds are written first..last: for {n} elements, [0..{max(n - 1, 0)}] "
                f"(or [1..{max(n, 1)}])", prev[0].line, prev[0].column)
    if tok.type == "COMMA" and len(prev) == 2 and str(prev[0]) == ":":
        return ("a declaration ends with ';', not ',': write a : BOOL; b : BOOL; (or a, b : BOOL;)", line, col)
    if tok.type == "IDENT" and re.fullmatch(r"[xX][0-9A-Fa-f_]+", word) and last is not None \
            and str(last) == "0" and last.end_pos == tok.start_pos:
        return f"a hexadecimal number is written 16#{word[1:]} in ST", last.line, last.column
    return None


def _syntax_hint(text: str, tok: Token, expected: set[str]) -> tuple[str, int, int] | None:
    """A precise message for the syntax errors students make most, else None."""
    line, col = tok.line, tok.column
    prev = _tokens_before(text, tok)
    last = prev[-1] if prev else None
    s7 = _s7_address(text, tok, prev, expected)
    if s7:
        return s7
    foreign = _foreign_syntax(text, tok, prev, expected)
    if foreign:
        return foreign
    if last is not None and last.type == "IDENT" and str(last).upper() in _NOT_SUPPORTED_WORDS:
        return (f"'{last}' is a reserved word of OpenPLC's compiler (and this construct is not supported)",
                last.line, last.column)
    if tok.type == "STRUCT":
        return ("a STRUCT must be declared in TYPE ... END_TYPE; a variable then uses the type's name", line, col)
    if str(tok) == "=" and text[tok.start_pos - 1:tok.start_pos] == ":" and len(prev) == 2:
        unclosed = _unclosed_block(text, tok)
        if unclosed and unclosed[0] == "END_VAR":
            opener = unclosed[1]
            return (f"missing END_VAR before this statement (the {opener} at line {opener.line}, column "
                    f"{opener.column} is not closed)", prev[0].line, prev[0].column)
    if last is not None and last.type == "RETURN":
        return ("RETURN takes no value: assign the result to the function's name, then RETURN", line, col)
    if tok.type == "IDENT" and re.fullmatch(r"[eE][0-9_]+", str(tok)) and text[tok.start_pos - 1:tok.start_pos].isdigit():
        return (f"a real literal needs a decimal point: write e.g. 1.0{tok}", line, col)
    if str(tok) == "." and text[tok.start_pos + 1:tok.start_pos + 2].isdigit():
        return ("a real literal needs a digit before the '.': write e.g. 0.5", line, col)
    if str(tok) == ":=" and expected and expected <= {"RPAR", "COMMA"}:
        return ("enumerated values cannot be given numbers in OpenPLC's compiler: write (A, B, C)", line, col)
    if last is not None and (str(last) in _EXPECTS_OPERAND or last.type in _EXPECTS_OPERAND) \
            and tok.type not in ("IDENT", "LOCATION", "LPAR", "MINUS", "PLUS", "NOT") and "IDENT" in expected:
        return (f"missing expression after {_token_text(last)} (before {_token_text(tok)})", line, col)
    if str(tok) == ";" and last is not None and last.type == "SEMICOLON":
        return ("a second ';': remove it (OpenPLC's compiler rejects empty declarations and statements)", line, col)
    opener = _open_header(text, tok)
    if opener is not None and opener[1] in expected and tok.type != opener[1]:
        return (f"missing {opener[1]} before {_token_text(tok)} (after the condition of the {opener[0]} at "
                f"line {opener[2].line}, column {opener[2].column})", line, col)
    if "RPAR" in expected and tok.type in ("SEMICOLON", "THEN", "DO", "OF", "$END"):
        return (f"missing ')' before {_token_text(tok)}", line, col)
    if "SEMICOLON" in expected and tok.type in _STATEMENT_START:
        return (f"missing ';' before {_token_text(tok)}", line, col)
    return None
