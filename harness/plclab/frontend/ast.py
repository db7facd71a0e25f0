"""The typed AST of an ST compilation unit, with source positions.

The parser builds it; the checker fills the annotations (`ty`, `sym`, ...) in place; the
compiler reads the annotated tree. Names keep the spelling the user wrote in `name`; lookups
use `key` (upper case), because ST identifiers are case-insensitive.

Checker annotations (the compiler's contract):
  Expr.ty           the expression's resolved Type (plclab.iec.types), after literal typing
  Name.sym          the Symbol the name refers to (variable, constant, enum value, POU)
  Call.pou          the PouDecl of a user FUNCTION, or None for a standard function (then
                    Call.std is the standard function's name and Call.arg_types its argument types)
  FbCall.fb_type    the FBType of the called instance
  Member.field_ty   set through Member.ty
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional


@dataclass(eq=False)
class Node:
    line: int
    col: int
    file: str


# --------------------------------------------------------------------------- expressions


@dataclass(eq=False)
class Expr(Node):
    pass


@dataclass(eq=False)
class Literal(Expr):
    """A constant: `value` is already in runtime representation when `type_name` is known;
    `kind` is 'int' | 'real' | 'bool' | 'time' | 'date' | 'tod' | 'dt' | 'string' | 'wstring'
    | 'enum' (typed enum literal `E#V`: value is the value's name)."""

    kind: str
    value: Any
    type_name: Optional[str] = None   # the `INT#` prefix, upper case, if any
    text: str = ""
    ty: Any = None
    parenthesized: bool = False       # `(5)`: a value, but not the literal an initial value must be


@dataclass(eq=False)
class Name(Expr):
    name: str
    key: str = ""
    ty: Any = None
    sym: Any = None

    def __post_init__(self) -> None:
        self.key = self.name.upper()


@dataclass(eq=False)
class Member(Expr):
    """`base.field` (struct field or FB instance variable)."""

    base: Expr
    name: str
    key: str = ""
    ty: Any = None
    sym: Any = None   # for FB instance variables: the VarDecl inside the FB

    def __post_init__(self) -> None:
        self.key = self.name.upper()


@dataclass(eq=False)
class Index(Expr):
    """`base[i, j]` array element."""

    base: Expr
    indexes: list[Expr]
    ty: Any = None


@dataclass(eq=False)
class Unary(Expr):
    op: str  # '-' | 'NOT'
    operand: Expr
    ty: Any = None


@dataclass(eq=False)
class Binary(Expr):
    op: str  # 'OR' 'XOR' 'AND' '=' '<>' '<' '>' '<=' '>=' '+' '-' '*' '/' 'MOD' '**'
    left: Expr
    right: Expr
    ty: Any = None
    operand_ty: Any = None  # the common type of the operands (for comparisons: not BOOL)


@dataclass(eq=False)
class Arg(Node):
    """One call argument: formal `name := value`, output `name => target` (negated with NOT),
    or positional (name is None)."""

    name: Optional[str]
    value: Expr
    is_output: bool = False
    negated: bool = False
    key: Optional[str] = None
    param: Any = None   # the VarDecl of the parameter it binds to (set by the checker)

    def __post_init__(self) -> None:
        self.key = self.name.upper() if self.name else None


@dataclass(eq=False)
class Call(Expr):
    """A function call in an expression (or as a statement)."""

    name: str
    args: list[Arg]
    key: str = ""
    ty: Any = None
    pou: Any = None           # user FUNCTION PouDecl
    std: Optional[str] = None  # standard function name
    arg_types: Any = None      # standard function: the chosen argument types
    bound_params: Optional[list[str]] = None   # checker: standard function: the parameter each arg binds

    def __post_init__(self) -> None:
        self.key = self.name.upper()


# --------------------------------------------------------------------------- statements


@dataclass(eq=False)
class Stmt(Node):
    pass


@dataclass(eq=False)
class Assign(Stmt):
    target: Expr
    value: Expr


@dataclass(eq=False)
class CallStmt(Stmt):
    """`name(args);` - an FB instance invocation or a function call whose result is dropped.
    After checking, exactly one of `fb_sym` (FB instance) / `call` (function) is set."""

    target: Expr            # Name or Member path of the FB instance / function name
    args: list[Arg]
    fb_type: Any = None
    call: Optional[Call] = None


@dataclass(eq=False)
class If(Stmt):
    branches: list[tuple[Expr, list[Stmt]]]
    else_body: Optional[list[Stmt]]


@dataclass(eq=False)
class CaseLabel(Node):
    lo: Expr
    hi: Optional[Expr] = None  # a range `lo..hi`
    lo_value: Any = None       # constant values (set by the checker)
    hi_value: Any = None


@dataclass(eq=False)
class CaseBranch(Node):
    labels: list[CaseLabel]
    body: list[Stmt]


@dataclass(eq=False)
class Case(Stmt):
    selector: Expr
    branches: list[CaseBranch]
    else_body: Optional[list[Stmt]]


@dataclass(eq=False)
class For(Stmt):
    var: Name
    start: Expr
    end: Expr
    step: Optional[Expr]
    body: list[Stmt]


@dataclass(eq=False)
class While(Stmt):
    cond: Expr
    body: list[Stmt]


@dataclass(eq=False)
class Repeat(Stmt):
    body: list[Stmt]
    cond: Expr


@dataclass(eq=False)
class Exit(Stmt):
    pass


@dataclass(eq=False)
class Continue(Stmt):
    pass


@dataclass(eq=False)
class Return(Stmt):
    pass


@dataclass(eq=False)
class Empty(Stmt):
    pass


# --------------------------------------------------------------------------- types


@dataclass(eq=False)
class TypeRef(Node):
    """A type as written: an elementary or derived name, STRING[n], ARRAY, inline enum/subrange."""


@dataclass(eq=False)
class NamedType(TypeRef):
    name: str
    key: str = ""

    def __post_init__(self) -> None:
        self.key = self.name.upper()


@dataclass(eq=False)
class StringTypeRef(TypeRef):
    wide: bool
    length: Optional[Expr] = None


@dataclass(eq=False)
class ArrayTypeRef(TypeRef):
    ranges: list[tuple[Expr, Expr]]
    elem: TypeRef


@dataclass(eq=False)
class EnumTypeRef(TypeRef):
    values: list[tuple[str, int, int]]  # (name, line, col)


@dataclass(eq=False)
class SubrangeTypeRef(TypeRef):
    base: NamedType
    lo: Expr
    hi: Expr


@dataclass(eq=False)
class StructTypeRef(TypeRef):
    fields: list["VarDecl"]


# --------------------------------------------------------------------------- initializers


@dataclass(eq=False)
class ArrayInit(Node):
    """`[1, 2, 3(0)]`: items are (repeat count or None, value)."""

    items: list[tuple[Optional[Expr], Any]]


@dataclass(eq=False)
class StructInit(Node):
    """`(a := 1, b := [1, 2])`."""

    fields: list[tuple[str, int, int, Any]]  # (field name, line, col, initializer)


# --------------------------------------------------------------------------- declarations


def address_without_size(address: str) -> bool:
    """Whether a direct address (`%I0.1`, `%IX0.1`) is written without its size letter."""
    return not address[2:3].isalpha()


@dataclass(eq=False)
class Location(Node):
    """`%IX1.6`: area 'I' | 'Q' | 'M', size 'X' | 'B' | 'W' | 'D' | 'L', address parts."""

    text: str
    area: str
    size: str
    parts: list[int]

    @property
    def written_without_size(self) -> bool:
        """`%I0.1`: the size letter left out (OpenPLC never connects it: the checker)."""
        return address_without_size(self.text)

    @property
    def key(self) -> str:
        """The canonical spelling: `%ix0.1` and `%I0.1` are both `%IX0.1`."""
        return f"%{self.area}{self.size}{'.'.join(map(str, self.parts))}"


@dataclass(eq=False)
class VarDecl(Node):
    name: str
    type_ref: TypeRef
    init: Any = None                 # Expr | ArrayInit | StructInit | None
    location: Optional[Location] = None
    section: str = "VAR"             # VAR VAR_INPUT VAR_OUTPUT VAR_IN_OUT VAR_EXTERNAL VAR_GLOBAL VAR_TEMP
    constant: bool = False
    retain: bool = False
    edge: Optional[str] = None       # R_EDGE | F_EDGE on VAR_INPUT BOOL
    key: str = ""
    ty: Any = None                   # resolved Type (checker)
    init_value: Any = None           # initial value in runtime representation (checker)
    global_decl: Any = None          # VAR_EXTERNAL: the VarDecl of the VAR_GLOBAL it names
    fb_init: Optional[dict] = None   # checker: a FB instance's initial values, by member path
    group_size: int = 1              # how many names its declaration line declares (`a, b : INT`)
    constant_in_openplc: bool = False  # checker: a FUNCTION's VAR after VAR CONSTANT (iec2c: constant)

    def __post_init__(self) -> None:
        self.key = self.name.upper()


@dataclass(eq=False)
class VarBlock(Node):
    section: str
    constant: bool
    retain: bool
    decls: list[VarDecl]
    qualifiers: list[str] = field(default_factory=list)   # CONSTANT / RETAIN / NON_RETAIN as written


@dataclass(eq=False)
class TypeDecl(Node):
    name: str
    type_ref: TypeRef
    init: Any = None
    key: str = ""
    ty: Any = None

    def __post_init__(self) -> None:
        self.key = self.name.upper()


@dataclass(eq=False)
class TypeBlock(Node):
    decls: list[TypeDecl]


@dataclass(eq=False)
class PouDecl(Node):
    kind: str                        # FUNCTION | FUNCTION_BLOCK | PROGRAM
    name: str
    return_type: Optional[TypeRef]
    blocks: list[VarBlock]
    body: list[Stmt]
    end_line: int = 0
    key: str = ""
    ret_ty: Any = None               # FUNCTION: resolved return type
    symbols: Any = None              # checker: upper-case name -> VarDecl
    ret_decl: Optional["VarDecl"] = None   # checker: FUNCTION: the variable named like it (its result)
    eno_decl: Optional["VarDecl"] = None   # checker: the implicit ENO, when the body or a call uses it

    def __post_init__(self) -> None:
        self.key = self.name.upper()

    @property
    def decls(self) -> list[VarDecl]:
        return [d for b in self.blocks for d in b.decls]


@dataclass(eq=False)
class TaskDecl(Node):
    name: str
    single: Optional[Expr]
    interval: Optional[Expr]
    priority: Expr
    key: str = ""
    interval_ns: Optional[int] = None  # checker

    def __post_init__(self) -> None:
        self.key = self.name.upper()


@dataclass(eq=False)
class ProgramInstance(Node):
    name: str
    task: Optional[str]
    type_name: str
    args: list[Arg]
    retain: Optional[bool] = None
    key: str = ""
    pou: Any = None      # checker: the PROGRAM PouDecl
    task_decl: Any = None

    def __post_init__(self) -> None:
        self.key = self.name.upper()


@dataclass(eq=False)
class Resource(Node):
    name: str
    on: str
    globals: list[VarBlock]
    tasks: list[TaskDecl]
    programs: list[ProgramInstance]


@dataclass(eq=False)
class Configuration(Node):
    name: str
    globals: list[VarBlock]
    resources: list[Resource]


@dataclass(eq=False)
class GlobalBlock(Node):
    """A VAR_GLOBAL block outside any CONFIGURATION: a GVL file (see docs/cli.md). The build places
    it inside the bundle's configuration; the checker treats it as configuration-level."""

    block: VarBlock


@dataclass(eq=False)
class Unit(Node):
    """One compilation unit: everything from all the files given together."""

    types: list[TypeDecl] = field(default_factory=list)
    pous: list[PouDecl] = field(default_factory=list)
    configs: list[Configuration] = field(default_factory=list)
    gvls: list[VarBlock] = field(default_factory=list)


def walk_statements(body: list[Stmt]):
    """Every statement of a body, nested ones included (in source order)."""
    for st in body:
        yield st
        if isinstance(st, If):
            for _cond, inner in st.branches:
                yield from walk_statements(inner)
            yield from walk_statements(st.else_body or [])
        elif isinstance(st, Case):
            for br in st.branches:
                yield from walk_statements(br.body)
            yield from walk_statements(st.else_body or [])
        elif isinstance(st, (For, While, Repeat)):
            yield from walk_statements(st.body)
