"""`plclab handout STAND -o DIR`: what a student is handed for a lab, and nothing more.

Three files: the starting program as one OpenPLC-loadable bundle (`STAND.st`, the shipped
starting variant: never a reference solution), the I/O map (`io-map.md`, read from the
stand's GVL, the one source of its addresses) and the task sheet (`tasks.md`, package data
under `plclab/handouts/`, the same text as the Tasks section of `docs/STAND.md`, followed by
what the grader checks for each task: its requirement rows, read from the grader itself).
Plus the same starting program as an OpenPLC Editor project (`STAND-openplc/plc.xml` and
`beremiz.xml`), for students who draw in ladder.

The directory may hold other files; a file of ours may be replaced (a new hand-out after
an update), anything else is never overwritten: the whole hand-out is refused in one line
before anything is written. Our files are the ones whose first line is our marker.
"""
from __future__ import annotations

import re
from pathlib import Path

from plclab import fileio
from plclab.errors import PlcLabError
from plclab.stands import PLC_DIR, Stand, bundle, get_stand

HANDOUTS_DIR = Path(__file__).resolve().parent / "handouts"
MARKER = "plclab handout"
_GVL_LINE = re.compile(r"^\s*(\w+)\s+AT\s+(%\w+(?:\.\d+)?)\s*:\s*(\w+)[^;]*;[ \t]*(?:\(\*\s*(.*?)\s*\*\))?", re.M)


def io_map(stand: Stand) -> str:
    """The located variables of the stand's GVL as a markdown table: name, address, type, meaning."""
    rows = ["| name | address | type | meaning |", "|---|---|---|---|"]
    for stem in stand.gvl:
        text = (PLC_DIR / "GVL" / f"{stem}.st").read_text(encoding="utf-8")
        for name, addr, typ, comment in _GVL_LINE.findall(text):
            rows.append(f"| {name} | {addr.upper()} | {typ} | {comment} |")
    return (f"# {stand.title}: I/O map\n\n"
            "The located variables of the stand (its GVL): the program reaches each through a "
            "VAR_EXTERNAL of the same name.\n\n" + "\n".join(rows) + "\n")


def task_sheet(stand: Stand) -> str:
    path = HANDOUTS_DIR / f"{stand.name}-tasks.md"
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise PlcLabError(f"handout: no task sheet for stand '{stand.name}' ({path.name} is missing)") from None


def grader_checks(stand: Stand) -> str:
    """The requirements of each graded task of `stand` as markdown tables: the acceptance
    criteria in the words of the grade report's rows (empty for a stand with no grader)."""
    from plclab.grader import requirement_table, task_title, tasks

    names = tasks(stand.name, None)
    if not names:
        return ""
    out = ["", "## What the grader checks", "",
           f"`plclab grade {stand.name} TASK ...` gives one row per requirement below, PASS or FAIL with "
           f"what was expected, what your program did and when; `plclab grade {stand.name} TASK "
           "--requirements` prints the list."]
    tables = {task: requirement_table(stand.name, task, exploration=True) for task in names}
    if any(rid == "E1" for table in tables.values() for rid, _ in table):
        out += ["", "The last row, E1, is checked where the task's model answer is at hand (your instructor's "
                "grading): the grader plays random console histories on your program and on the model answer "
                "side by side; if your stand ever shows something else, the row gives the shortest history "
                "that shows it, as steps you can replay (`plclab run ... --inputs FILE.csv`)."]
    for task in names:
        out += ["", f"### {task}: {task_title(stand.name, task)}", "", "| id | requirement |", "|---|---|"]
        out += [f"| {rid} | {text.replace('|', chr(92) + '|')} |" for rid, text in tables[task]]
    return "\n".join(out) + "\n"


def handout_files(stand_name: str) -> dict[str, str]:
    """File name (relative to the hand-out directory) -> text of the hand-out of `stand_name`,
    each with the marker on its first line."""
    stand = get_stand(stand_name)
    variant = stand.starting_variant
    tag = f"{MARKER} {stand.name}"
    program = f"(* {tag}: the starting program ('{variant}'). *)\n" + bundle(stand, variant)
    files = {
        f"{stand.name}.st": program,
        "io-map.md": f"<!-- {tag} -->\n" + io_map(stand),
        "tasks.md": f"<!-- {tag} -->\n" + task_sheet(stand) + grader_checks(stand),
    }
    files.update(editor_project(stand, program, tag))
    return files


def editor_project(stand: Stand, program: str, tag: str) -> dict[str, str]:
    """The starting program as an OpenPLC Editor project folder (`STAND-openplc/`: plc.xml and
    the beremiz.xml the Editor's "Open Project" looks for), so a student can add ladder POUs.
    The plc.xml is the one `plclab build --xml` makes: schema-valid TC6, proven to read back
    to the same program."""
    from plclab.build import xml_project

    data, _ = xml_project(program, stand.name, f"{stand.name}-openplc/plc.xml")
    head, _, rest = data.decode("utf-8").partition("\n")
    folder = f"{stand.name}-openplc"
    return {
        f"{folder}/plc.xml": f"{head}<!-- {tag} -->\n{rest}",
        f"{folder}/beremiz.xml": f"<?xml version='1.0' encoding='utf-8'?><!-- {tag} -->\n"
                                 "<BeremizRoot xmlns:xsd=\"http://www.w3.org/2001/XMLSchema\" URI_location=\"LOCAL://\">\n"
                                 "  <TargetType/>\n</BeremizRoot>\n",
    }


def _ours(path: Path) -> bool:
    try:
        with path.open(encoding="utf-8") as f:
            return MARKER in f.readline()
    except (OSError, UnicodeDecodeError):
        return False


def write_handout(stand_name: str, out_dir: str) -> list[Path]:
    """Write the hand-out into `out_dir` (created if missing); the paths written."""
    files = handout_files(stand_name)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise PlcLabError(f"{out}: exists and is not a directory")
    targets = [out / name for name in files]
    for target in targets:
        if target.is_symlink() or (target.exists() and not (target.is_file() and _ours(target))):
            raise PlcLabError(f"{target}: exists and is not a hand-out file; nothing written "
                              f"(choose another directory, or move it away)")
    for target in targets:
        fileio.check_output(target)
    return [fileio.write_text(out / name, text) for name, text in files.items()]
