"""The lab stands: which ST files make each program variant, its tasks, its plant and its
Modbus face. `bundle()` assembles one OpenPLC-loadable ST text (types, POUs, the GVL's
globals inside CONFIGURATION Config0 / RESOURCE Res0 ON PLC), the single source of truth
for `plclab build`, `run`, `serve` and `grade`.

Where the ST lives: what the project ships to users (each stand's GVL, the building blocks,
the students' starting programs, thermo's program) lives in the repository's `plc/` (POUs/,
GVL/) and is package data under `plclab/plc/` in the wheel, so an installed package carries it. The reference solutions of the lab tasks live apart, in the
repository's `solutions/` tree: a checkout has them (tests, grader tests, instructors), an
installed package never does, and asking for one there is one clear error. A robot task's
reference is the starting program with that task's edits (`solutions/<stand>.toml`, applied
by `plclab.stands.references`); the CNC stand's is a whole block (`solutions/POUs/`).
"""
from __future__ import annotations

import functools
import importlib
import re
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

from plclab.errors import PlcLabError
from plclab.stands import references

def _plc_dir() -> Path:
    """The shipped ST: `plc/` at the top of the repository (its one copy, where an OpenPLC
    user or a CI job looks for `plc/POUs` and `plc/GVL`), which the wheel carries as
    `plclab/plc` (pyproject.toml maps the folder into the package at build time). An
    installed package reads its own copy; a checkout or an editable install reads the
    repository's."""
    packaged = Path(__file__).resolve().parents[1] / "plc"
    if packaged.is_dir():
        return packaged
    return Path(__file__).resolve().parents[3] / "plc"


PLC_DIR = _plc_dir()


def _checkout_solutions() -> Path | None:
    """`solutions/` of the repository this package runs from, or None when installed (a
    wheel's `plclab/` sits in site-packages, with no repository around it)."""
    root = Path(__file__).resolve().parents[3]
    if (root / "pyproject.toml").is_file() and (root / "solutions" / "POUs").is_dir():
        return root / "solutions"
    return None


SOLUTIONS_DIR = _checkout_solutions()
STANDS = ("mp9c", "tur10", "thermo", "cnc")


@dataclass(frozen=True)
class Task:
    name: str
    interval: str          # ST literal, e.g. 'T#10ms'
    priority: int
    programs: tuple[tuple[str, str], ...]   # (instance name, PROGRAM type), in run order


@dataclass(frozen=True)
class Variant:
    name: str
    pous: tuple[str, ...]                   # file stems, in bundle order (see pou_path)
    tasks: tuple[Task, ...]
    doc: str = ""
    reference: bool = False                 # a task's reference solution: checkout only
    edited: bool = False                    # reference = these POUs with solutions/<stand>.toml [name]
    observables: dict[str, str] = field(default_factory=dict)   # where this variant's paths differ


@dataclass(frozen=True)
class Stand:
    name: str
    title: str
    gvl: tuple[str, ...]                    # file stems under plc/GVL
    variants: dict[str, Variant]
    register_map: str = "openplc"           # Modbus face: 'openplc' | 'twido'
    types: tuple[str, ...] = ()             # file stems under plc/POUs holding TYPE blocks
    extra: dict = field(default_factory=dict)

    def variant(self, name: str) -> Variant:
        if name not in self.variants:
            raise PlcLabError(f"{self.name}: unknown variant '{name}' (one of {', '.join(self.variants)})")
        return self.variants[name]

    def files(self, variant: str) -> list[Path]:
        """The ST files `variant` is made of (an edited reference: the starting program's
        files, which `pou_sources` changes), GVL files last."""
        v = self.variant(variant)
        if v.reference and SOLUTIONS_DIR is None:
            raise PlcLabError(f"{self.name} {variant} is a reference solution: it is only in a checkout of the "
                              f"PLC Lab repository (solutions/), not in the installed package; "
                              f"students start from '{self.name} {self.starting_variant}'")
        return [pou_path(s, v.reference and not v.edited) for s in self.types + v.pous] + \
               [PLC_DIR / "GVL" / f"{s}.st" for s in self.gvl]

    def pou_sources(self, variant: str) -> list[tuple[str, str]]:
        """The variant's types and POUs as (file name, text), in bundle order. An edited
        reference's changed POUs are named `<stand task: FILE.st>`: no file on disk holds
        that text, the starting file plus solutions/<stand>.toml make it."""
        v = self.variant(variant)
        paths = self.files(variant)[:len(self.types) + len(v.pous)]
        if not v.edited:
            return [(str(p), _read(p)) for p in paths]
        start = {p.stem: _read(p) for p in paths}
        answer = references.apply(self.solutions_file, variant, start)
        return [(str(p) if answer[p.stem] == start[p.stem] else f"<{self.name} {variant}: {p.name}>",
                 answer[p.stem]) for p in paths]

    def outline(self, variant: str) -> str:
        """The unified diff from the starting program to reference `variant`: the model
        answer's changes, file by file. Only for an edited reference: anything else is one
        clear error."""
        v = self.variant(variant)
        if not v.edited:
            edited = [n for n, w in self.variants.items() if w.edited]
            raise PlcLabError(f"{self.name} {variant}: not a task reference made from the starting program "
                              + (f"(those are: {', '.join(edited)})" if edited else
                                 f"({self.name} has none: --outline is for the robots' tasks)"))
        paths = self.files(variant)[:len(self.types) + len(v.pous)]
        start = {p.stem: (str(p.relative_to(PLC_DIR.parent)), _read(p)) for p in paths}
        answer = {p.stem: text for p, (_name, text) in zip(paths, self.pou_sources(variant))}
        return references.outline(start, answer)

    @property
    def solutions_file(self) -> Path:
        """solutions/<stand>.toml of the checkout: the edits that make the task references."""
        assert SOLUTIONS_DIR is not None
        return SOLUTIONS_DIR / f"{self.name}.toml"

    def available(self, variant: str) -> bool:
        """Whether `variant` can be built here (a reference solution needs a checkout)."""
        return not self.variant(variant).reference or SOLUTIONS_DIR is not None

    @property
    def richest_variant(self) -> str:
        """The most complete program available here: 'full' in a checkout, else the shipped one
        (what `plclab bench` measures)."""
        return "full" if "full" in self.variants and self.available("full") else self.starting_variant

    @property
    def starting_variant(self) -> str:
        """The program a student starts from: the first variant that is no reference."""
        return next(n for n, v in self.variants.items() if not v.reference)

    def make_plant(self, **params):
        from plclab.plants import make_plant
        return make_plant(self.name, **params)


def stand_module(name: str) -> ModuleType:
    """The module `plclab.stands.<name>` (one clear error for an unknown stand)."""
    if name not in STANDS:
        raise PlcLabError(f"unknown stand '{name}' (one of {', '.join(STANDS)})")
    try:
        return importlib.import_module(f"plclab.stands.{name}")
    except ModuleNotFoundError as e:
        if e.name != f"plclab.stands.{name}":
            raise
        raise PlcLabError(f"stand '{name}' has no programs yet; run your own with --program FILE.st") from None


def get_stand(name: str) -> Stand:
    return stand_module(name).STAND


# `NAME AT %IX0.1 : INT := 40;` in a GVL: the label, its located address, type, initial value
_LOCATED = re.compile(r"\b([A-Za-z_]\w*)\s+AT\s+(%[IQM][XBWDL]?\d+(?:\.\d+)?)\s*:\s*([A-Za-z_]\w*)"
                      r"(?:\s*:=\s*([^;]*?))?\s*;", re.IGNORECASE)
_COMMENT = re.compile(r"\(\*.*?\*\)", re.DOTALL)
_TRAILING_COMMENT = re.compile(r"[ \t]*\(\*(.*?)\*\)")


@dataclass(frozen=True)
class GvlVariable:
    """One located global of a stand's GVL, as written there."""

    name: str                    # the label: 'SETPOINT'
    address: str                 # '%MW6'
    type: str                    # 'INT'
    initial: str | None = None   # the initial value as written ('40'), None if not given
    comment: str = ""            # the comment after it on its line: what it means, its range


def gvl_variables(stand: Stand) -> list[GvlVariable]:
    """The stand's located globals in declaration order, read from its GVL files: the one
    source of each stand's I/O map and register contract (plants are tested against it;
    Modbus profiles, scenarios and the grader name I/O by these labels)."""
    return [v for stem in stand.gvl for v in _located_in(_gvl_text(PLC_DIR / "GVL" / f"{stem}.st"))]


_GVL_TEXTS: dict[Path, tuple[tuple[int, int], str]] = {}


def _gvl_text(path: Path) -> str:
    """A GVL file's text, read again only when the file changed (its size or time): every
    session of a stand names its I/O by it, and an exploration starts thousands."""
    try:
        st = path.stat()
    except FileNotFoundError:
        raise PlcLabError(f"{path}: missing ST source") from None
    stamp = (st.st_mtime_ns, st.st_size)
    known = _GVL_TEXTS.get(path)
    if known is not None and known[0] == stamp:
        return known[1]
    text = _read(path)
    _GVL_TEXTS[path] = (stamp, text)
    return text


@functools.lru_cache(maxsize=64)
def _located_in(text: str) -> tuple[GvlVariable, ...]:
    """The located globals of one GVL file's text (worked out once per text: every session of
    a stand names its I/O by them, and a grading starts thousands)."""
    # comments blanked in place, so a match's end is where its own trailing comment starts
    code = _COMMENT.sub(lambda m: re.sub(r"[^\n]", " ", m.group()), text)
    out = []
    for m in _LOCATED.finditer(code):
        after = _TRAILING_COMMENT.match(text, m.end())
        out.append(GvlVariable(m.group(1), m.group(2).upper(), m.group(3).upper(), m.group(4),
                               " ".join(after.group(1).split()) if after else ""))
    return tuple(out)


def gvl_labels(stand: Stand) -> dict[str, str]:
    """The stand's located globals, label -> address (`'SQ2': '%IX0.1'`), from its GVL."""
    return {v.name: v.address for v in gvl_variables(stand)}


def pou_path(stem: str, reference: bool = False) -> Path:
    """The file of a POU. A reference solution's own version (`solutions/POUs`, checkout
    only) comes first for a whole-block reference: a block of the same name there is the
    model answer of the students' stub (the CNC lab's FB_CncEvalLinear). Everything else is
    shipped (`plc/POUs`)."""
    if reference and SOLUTIONS_DIR is not None:
        solution = SOLUTIONS_DIR / "POUs" / f"{stem}.st"
        if solution.is_file():
            return solution
    return PLC_DIR / "POUs" / f"{stem}.st"


def sources(stand: Stand, variant: str) -> list[tuple[str, str]]:
    """The variant as (file name, text) pairs: the ST files as they are (so diagnostics and
    faults name them) plus the generated configuration. Same program as `bundle()`."""
    return stand.pou_sources(variant) + [(str(p), _read(p)) for p in stand.files(variant)[-len(stand.gvl):]] + \
        [(f"<{stand.name}-{variant} configuration>", _configuration(stand, variant, ""))]


def bundle(stand: Stand, variant: str) -> str:
    """One self-contained OpenPLC-loadable ST text for `variant` of `stand`."""
    v = stand.variant(variant)
    parts = [f"(* {stand.title}: program '{variant}', generated by plclab build from plc/. {v.doc} *)"]
    parts += [text for _name, text in stand.pou_sources(variant)]
    globals_ = "\n".join(_read(p) for p in stand.files(variant)[-len(stand.gvl):])
    parts.append(_configuration(stand, variant, globals_))
    return "\n\n".join(p.strip() for p in parts) + "\n"


def _configuration(stand: Stand, variant: str, globals_: str) -> str:
    v = stand.variant(variant)
    cfg = ["CONFIGURATION Config0"]
    if globals_:
        cfg.append(_indent(globals_, 4))
    cfg.append("    RESOURCE Res0 ON PLC")
    for t in v.tasks:
        cfg.append(f"        TASK {t.name} (INTERVAL := {t.interval}, PRIORITY := {t.priority});")
    for t in v.tasks:
        for inst, prog in t.programs:
            cfg.append(f"        PROGRAM {inst} WITH {t.name} : {prog};")
    cfg += ["    END_RESOURCE", "END_CONFIGURATION"]
    return "\n".join(cfg)


def _read(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise PlcLabError(f"{path}: missing ST source") from None


def _indent(text: str, n: int) -> str:
    return "\n".join((" " * n + line) if line.strip() else line for line in text.strip().splitlines())


@functools.lru_cache(maxsize=None)
def twido_profile(name: str):
    """The Twido register table of stand `name` (the thermo stand's is docs/thermo.md's): its
    GVL's %MW globals under the stand's rules of plclab.modbus.profiles (TWIDO_RULES)."""
    from plclab.modbus.profiles import TWIDO_RULES, GvlRegister, profile_from_gvl

    gvl = {v.name: GvlRegister(int(v.address[3:]), v.type, v.comment)
           for v in gvl_variables(get_stand(name)) if v.address.startswith("%MW")}
    return profile_from_gvl(name, gvl, TWIDO_RULES[name])
