"""A ladder program is graded like ST: the handed-out OpenPLC Editor project, with a POU
redrawn in ladder, goes to `plclab grade` as the student saves it (plc.xml)."""
from __future__ import annotations

import re

import copy

from lxml import etree

from examples import mp9c_manual
from plclab.cli import main
from plclab.grader import grade
from plclab.handout import handout_files

PPX = {"ppx": "http://www.plcopen.org/xml/tc6_0201"}


def handout_with_ladder_manual(every_mechanism: bool) -> bytes:
    """The mp9c hand-out's plc.xml with FB_Mp9cManual replaced by the drawn one (what a
    student does in OpenPLC Editor: delete the ST POU, draw a ladder POU of the same name)."""
    text = handout_files("mp9c")["mp9c-openplc/plc.xml"]
    root = etree.fromstring(text.encode("utf-8"))
    drawn = etree.fromstring(mp9c_manual(every_mechanism))
    new = drawn.find("ppx:types/ppx:pous/ppx:pou[@name='FB_Mp9cManual']", PPX)
    old = root.find("ppx:types/ppx:pous/ppx:pou[@name='FB_Mp9cManual']", PPX)
    old.getparent().replace(old, copy.deepcopy(new))
    return etree.tostring(root, xml_declaration=True, encoding="utf-8")


def test_task1_drawn_in_ladder_passes(tmp_path):
    path = tmp_path / "plc.xml"
    path.write_bytes(handout_with_ladder_manual(every_mechanism=True))
    report = grade("mp9c", "task1", [str(path)])
    assert report.exit_code == 0, report.text()


def test_starting_program_in_ladder_fails_task1_on_the_valves(tmp_path, capsys):
    path = tmp_path / "plc.xml"
    path.write_bytes(handout_with_ladder_manual(every_mechanism=False))
    assert main(["grade", "mp9c", "task1", str(path), "--out", str(tmp_path / "out")]) == 1
    out = capsys.readouterr().out
    assert "FAIL" in out and "Traceback" not in out


def test_grade_class_takes_plc_xml_submissions(tmp_path):
    from plclab.grader.classroom import grade_class

    folder = tmp_path / "class"
    (folder / "alice").mkdir(parents=True)
    (folder / "alice" / "plc.xml").write_bytes(handout_with_ladder_manual(every_mechanism=True))
    (folder / "bob.xml").write_bytes(handout_with_ladder_manual(every_mechanism=False))
    report = grade_class("mp9c", "task1", folder, tmp_path / "out", jobs=1)
    verdicts = {r.student: r.status for r in report.results}
    assert verdicts == {"alice": "PASS", "bob": "FAIL"}
    assert report.ignored == []


def test_exploration_names_the_rung_and_element_that_last_wrote_the_output(tmp_path):
    """The grader's row names the student's statement that last wrote the first differing
    output; in a ladder POU that is the rung and the coil, never a line of generated ST."""
    path = tmp_path / "plc.xml"
    path.write_bytes(handout_with_ladder_manual(every_mechanism=False))
    report = grade("mp9c", "task1", [str(path)], explore=2)
    [e1] = [r for r in report.rows if r.id == "E1"]
    assert not e1.passed
    assert "last written in plc.xml: FB_Mp9cManual (LD), rung " in e1.written, e1.written
    assert ", coil L" in e1.written and "localId" in e1.written
    assert "plc.xml:" not in e1.written.replace("plc.xml: FB_", "")      # no generated line number
    # the ranked lines too: each on the drawing, none a line of the generated ST
    assert e1.lines, report.text()
    for line in e1.lines:
        assert line.startswith("plc.xml: ") and (", rung " in line or " line " in line), line
        assert not re.search(r"plc\.xml:\d", line), line



def handout_with_located_io() -> bytes:
    """The ladder Task 1 project, with the I/O the program uses declared as a student often does
    in OpenPLC Editor: SB1 and HL1 at their addresses in the program's own table, among its
    function block instances (the Editor writes that table as two VAR blocks), not as globals."""
    root = etree.fromstring(handout_with_ladder_manual(every_mechanism=True))
    program = root.find("ppx:types/ppx:pous/ppx:pou[@name='PRG_Mp9cBaseline']", PPX)
    externals = program.find("ppx:interface/ppx:externalVars", PPX)
    table = program.findall("ppx:interface/ppx:localVars", PPX)[-1]
    assert table.find("ppx:variable[@name='Button']", PPX) is not None       # the instances' table
    for name, address, position in (("SB1", "%IX1.6", 1), ("HL1", "%QX1.0", 3)):
        variable = externals.find(f"ppx:variable[@name='{name}']", PPX)
        externals.remove(variable)
        variable.set("address", address)
        table.insert(position, variable)
    for globals_ in root.iterfind(".//ppx:globalVars", PPX):
        for variable in list(globals_):
            if variable.get("name") in ("SB1", "HL1"):
                globals_.remove(variable)
    return etree.tostring(root, xml_declaration=True, encoding="utf-8")


def test_located_io_in_the_program_table_checks_and_passes_task1(tmp_path, capsys):
    path = tmp_path / "plc.xml"
    path.write_bytes(handout_with_located_io())
    assert main(["check", str(path)]) == 0, capsys.readouterr()
    report = grade("mp9c", "task1", [str(path)])
    assert report.exit_code == 0, report.text()
