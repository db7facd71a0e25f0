"""`plclab handout`: a student gets the starting program, the I/O map and the task sheet, no
solution; the hand-out never replaces a file it did not write; the task sheets and I/O maps
agree with the stand documentation in docs/."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from plclab.cli import main
from plclab.errors import PlcLabError
from plclab.frontend import check_sources
from plclab.handout import HANDOUTS_DIR, handout_files, write_handout
from plclab.stands import PLC_DIR, SOLUTIONS_DIR, STANDS, bundle, get_stand

DOCS = Path(__file__).resolve().parents[1] / "docs"
FILES = {"mp9c": "mp9c.st", "tur10": "tur10.st", "thermo": "thermo.st", "cnc": "cnc.st"}


def _solution_only_names() -> set[str]:
    """POUs that exist only as reference solutions, and the names only the references'
    edits declare (SHORT_PAUSE...)."""
    shipped = {p.stem for p in (PLC_DIR / "POUs").glob("*.st")}
    names = {p.stem for p in (SOLUTIONS_DIR / "POUs").glob("*.st")} - shipped
    for s in map(get_stand, STANDS):
        start = bundle(s, s.starting_variant)
        for v in (n for n, w in s.variants.items() if w.edited):
            names |= {m for m in re.findall(r"^\+\s*([A-Za-z_]\w*)\s*:\s*[A-Za-z_]", s.outline(v), re.M)
                      if not re.search(rf"\b{m}\b", start)}
    return names


def _solution_only_lines(stand: str) -> set[str]:
    """The code lines a task's reference adds to the starting program (the model answer)."""
    s = get_stand(stand)
    start = {line.strip() for line in bundle(s, s.starting_variant).splitlines()}
    added = {line[1:].strip() for v, w in s.variants.items() if w.edited
             for line in s.outline(v).splitlines() if line.startswith("+") and not line.startswith("+++")}
    code = {line for line in added if line.endswith((";", "THEN")) and not line.startswith("(*")}
    return code - start


@pytest.mark.parametrize("stand", STANDS)
def test_handout_is_the_checked_starting_program_map_and_sheet(stand, tmp_path, capsys):
    assert main(["handout", stand, "-o", str(tmp_path / "lab")]) == 0
    out = tmp_path / "lab"
    assert sorted(p.name for p in out.iterdir()) == sorted([FILES[stand], "io-map.md", "tasks.md", f"{stand}-openplc"])
    st = (out / FILES[stand]).read_text(encoding="utf-8")
    s = get_stand(stand)
    assert st.splitlines()[1:] == bundle(s, s.starting_variant).splitlines()
    assert not s.variant(s.starting_variant).reference
    check_sources([(str(out / FILES[stand]), st)])          # loads as it is
    sheet = (out / "tasks.md").read_text(encoding="utf-8")
    assert sheet.split("\n", 1)[1].startswith((HANDOUTS_DIR / f"{stand}-tasks.md").read_text(encoding="utf-8"))
    assert sheet.count("## What the grader checks") == 1
    assert capsys.readouterr().out.count("wrote ") == 5
    # the OpenPLC Editor project: the same program, in the TC6 XML the Editor opens
    editor = out / f"{stand}-openplc"
    assert sorted(p.name for p in editor.iterdir()) == ["beremiz.xml", "plc.xml"]
    from plclab import plcopen
    from plclab.frontend import plcxml
    from plclab.frontend import load_files
    tree = plcxml.parse_xml((editor / "plc.xml").read_bytes(), "plc.xml")
    plcopen.validate(tree, "plc.xml")
    assert plcopen.first_difference(check_sources([(str(out / FILES[stand]), st)]),
                                    load_files([editor / "plc.xml"])) is None


@pytest.mark.parametrize("stand", STANDS)
def test_no_solution_is_handed_out(stand):
    text = "\n".join(handout_files(stand).values())
    names = _solution_only_names()
    assert {"SHORT_PAUSE", "LONG_PAUSE"} <= names                     # the check sees the references
    leaked = {name for name in names if re.search(rf"\b{name}\b", text)}
    assert leaked == set()
    handed = {line.strip() for line in text.splitlines()}
    assert _solution_only_lines(stand) & handed == set()
    if stand != "thermo":
        assert "Pause : TIME" not in text and not re.search(r"\(\s*Task\s*\d", text)


@pytest.mark.parametrize("stand", STANDS)
def test_io_map_lists_every_located_variable_of_the_gvl(stand):
    io = handout_files(stand)["io-map.md"]
    gvl = "\n".join((PLC_DIR / "GVL" / f"{g}.st").read_text(encoding="utf-8") for g in get_stand(stand).gvl)
    located = re.findall(r"(\w+)\s+AT\s+(%\w+(?:\.\d+)?)", gvl)
    assert located and all(f"| {name} | {addr.upper()} |" in io for name, addr in located)


@pytest.mark.parametrize("stand", STANDS)
def test_docs_of_the_stand_carry_the_task_sheet_and_every_address(stand):
    doc = (DOCS / f"{stand}.md").read_text(encoding="utf-8")
    sheet = (HANDOUTS_DIR / f"{stand}-tasks.md").read_text(encoding="utf-8")
    end = sheet.find("## Working on it")
    tasks = sheet[sheet.index("## Task 1"):end if end >= 0 else None].strip()
    assert tasks in doc
    gvl = "\n".join((PLC_DIR / "GVL" / f"{g}.st").read_text(encoding="utf-8") for g in get_stand(stand).gvl)
    addresses = {a.upper() for a in re.findall(r"AT\s+(%\w+(?:\.\d+)?)", gvl)}
    missing = {a for a in addresses if a not in doc and not _in_a_range(a, doc)}
    assert missing == set()


def _in_a_range(addr: str, doc: str) -> bool:
    """%IX2.3 is documented by a row `%IX2.0..%IX2.6`."""
    m = re.fullmatch(r"%IX(\d+)\.(\d)", addr)
    if not m:
        return False
    return any(int(a) <= int(m.group(2)) <= int(b)
               for a, b in re.findall(rf"%IX{m.group(1)}\.(\d)\.\.%IX{m.group(1)}\.(\d)", doc))


def test_a_file_not_written_by_handout_is_never_replaced(tmp_path):
    out = tmp_path / "lab"
    out.mkdir()
    mine = out / "tasks.md"
    mine.write_text("my notes\n", encoding="utf-8")
    other = out / "notes.txt"
    other.write_text("keep\n", encoding="utf-8")
    with pytest.raises(PlcLabError) as e:
        write_handout("mp9c", str(out))
    assert "\n" not in str(e.value) and str(mine) in str(e.value) and "not a hand-out file" in str(e.value)
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "tasks.md"]
    assert mine.read_text(encoding="utf-8") == "my notes\n"


def test_the_students_saved_editor_project_is_never_replaced(tmp_path):
    """Saved in OpenPLC Editor, the plc.xml loses the hand-out's marker: it is the student's
    work now, and a new hand-out into the same folder is refused before anything is written."""
    out = tmp_path / "lab"
    write_handout("mp9c", str(out))
    saved = out / "mp9c-openplc" / "plc.xml"
    saved.write_text("<?xml version='1.0' encoding='utf-8'?>\n<project>my ladder</project>\n", encoding="utf-8")
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    with pytest.raises(PlcLabError) as e:
        write_handout("mp9c", str(out))
    assert str(saved) in str(e.value) and "\n" not in str(e.value)
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


def test_a_symlink_in_place_of_a_handout_file_is_refused(tmp_path):
    out = tmp_path / "lab"
    out.mkdir()
    target = tmp_path / "elsewhere.st"
    target.write_text("(* plclab handout mp9c *)\n", encoding="utf-8")
    (out / "mp9c.st").symlink_to(target)
    with pytest.raises(PlcLabError):
        write_handout("mp9c", str(out))
    assert target.read_text(encoding="utf-8") == "(* plclab handout mp9c *)\n"
    assert sorted(p.name for p in out.iterdir()) == ["mp9c.st"]


def test_its_own_files_are_replaced_by_a_new_handout(tmp_path):
    out = tmp_path / "lab"
    first = write_handout("tur10", str(out))
    (out / "io-map.md").write_text((out / "io-map.md").read_text(encoding="utf-8") + "stale\n", encoding="utf-8")
    assert write_handout("tur10", str(out)) == first
    assert "stale" not in (out / "io-map.md").read_text(encoding="utf-8")


def test_output_that_is_a_file_is_one_clear_error(tmp_path, capsys):
    f = tmp_path / "lab"
    f.write_text("x", encoding="utf-8")
    assert main(["handout", "mp9c", "-o", str(f)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a directory" in err and f.read_text(encoding="utf-8") == "x"


@pytest.mark.parametrize("stand", STANDS)
def test_the_task_sheet_lists_every_requirement_the_grader_checks(stand):
    """A student reads the acceptance criteria before handing in: every graded task's rows,
    id and sentence, exactly as the grader declares them (one source: the grader)."""
    from plclab.grader import requirement_table, tasks

    sheet = handout_files(stand)["tasks.md"]
    graded = tasks(stand, None)
    assert graded, stand
    for task in graded:
        section = sheet.split(f"### {task}: ", 1)[1].split("\n### ", 1)[0]
        rows = re.findall(r"^\| (\S+) \| (.*) \|$", section, re.M)[1:]          # after the header row
        assert [(rid, text.replace("\\|", "|")) for rid, text in rows] == requirement_table(stand, task, exploration=True)
