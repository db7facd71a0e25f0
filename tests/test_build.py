"""`plclab build`: the OpenPLC bundle and the PLCopen TC6 XML project of every MP-9C variant.

What a user relies on: the .st file is exactly the checked bundle; the XML opens in OpenPLC
Editor / Beremiz (TC6 v2.01, validated when the schema is on the machine: PLCLAB_TC6_XSD or
an installed copy) and means the same program (it reads back, through ST and the front end,
to the bundle); a build that fails writes nothing and says why in one line (or the
checker's lines).
"""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from lxml import etree

from plclab import plcopen
from plclab.frontend import plcxml
from plclab.build import build_outputs, write_build, xml_project
from plclab.errors import CompileError, PlcLabError
from plclab.frontend import check_sources, load_files
from plclab.plcopen import schema as schema_mod
from plclab.frontend.plcxml import interval_literal
from plclab.plcopen.source import SourceText
from plclab.stands import PLC_DIR, bundle, get_stand

VARIANTS = ["baseline", "task1", "task2", "task3", "full"]
NS = {"ppx": "http://www.plcopen.org/xml/tc6_0201", "xhtml": "http://www.w3.org/1999/xhtml"}
CASES = Path(__file__).parent / "frontend" / "cases" / "valid"
# valid ST that TC6 v2.01 has no element or attribute for: refused with one clear line
NO_TC6_FORM = {"config_program_without_task.st": "RETAIN of program instance",
               "var_located_anonymous.st": "unnamed located variable",
               "var_direct_addresses_in_code.st": "unnamed located variable",
               # forms OpenPLC Editor reads as another program (docs/ladder.md, the Editor's rules)
               "pou_fb_instance_init.st": "variable t: TON instance with an initial value: OpenPLC Editor drops it",
               "type_subrange.st": "variable level: an inline <subrangeUnsigned> type"}


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> dict[str, list[Path]]:
    """Every MP-9C variant built once into a fresh directory: variant -> [.st, .xml]."""
    out = tmp_path_factory.mktemp("build")
    return {v: write_build("mp9c", v, str(out / f"mp9c_{v}.st"), str(out / f"mp9c_{v}.xml")) for v in VARIANTS}


def xml_of(path: Path) -> etree._Element:
    return etree.parse(str(path)).getroot()


def body_of(pou: etree._Element) -> str:
    return "".join(pou.find("ppx:body/ppx:ST/xhtml:p", NS).itertext())


# --------------------------------------------------------------------------- the bundle

@pytest.mark.parametrize("variant", VARIANTS)
def test_st_file_is_the_checked_bundle(built, variant):
    st, xml = built[variant]
    assert st.name == f"mp9c_{variant}.st" and xml.name == f"mp9c_{variant}.xml"
    assert st.read_text(encoding="utf-8") == bundle(get_stand("mp9c"), variant)
    unit = load_files([st])
    assert len(unit.unit.configs) == 1 and unit.config.name == "Config0"
    assert [r.name for r in unit.config.resources] == ["Res0"]


def test_default_st_path_is_stand_variant_in_current_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert write_build("mp9c", "baseline", None, None) == [tmp_path / "mp9c_baseline.st"]
    assert [p.name for p in tmp_path.iterdir()] == ["mp9c_baseline.st"]


# --------------------------------------------------------------------------- the XML

@pytest.mark.parametrize("variant", VARIANTS)
def test_xml_validates_against_the_tc6_schema(built, variant):
    """Against the TC6 v2.01 model of the `plcopen` package always, and against the XSD file
    too where one is installed (PLCLAB_TC6_XSD)."""
    data = built[variant][1].read_bytes()
    schema_mod.validate_bindings(data, built[variant][1].name)
    xsd = plcopen.schema_path()
    if xsd is not None:
        schema = etree.XMLSchema(etree.parse(str(xsd)))
        doc = etree.parse(str(built[variant][1]))
        assert schema.validate(doc), f"{built[variant][1].name}: {schema.error_log[0] if schema.error_log else ''}"


def test_tc6_model_check_refuses_unknown_and_missing_elements(built):
    data = built["full"][1].read_bytes()
    bad = data.replace(b"<pous>", b"<pous><notAPou/>", 1)
    with pytest.raises(PlcLabError, match="not valid PLCopen TC6 XML"):
        schema_mod.validate_bindings(bad, "x.xml")
    root = etree.fromstring(data)
    header = root.find("ppx:fileHeader", NS)
    root.remove(header)
    with pytest.raises(PlcLabError, match="fileHeader"):
        schema_mod.validate_bindings(etree.tostring(root), "x.xml")


@pytest.mark.parametrize("variant", VARIANTS)
def test_xml_reads_back_to_the_same_program(built, variant):
    st, xml = built[variant]
    original = load_files([st])
    again = check_sources([(f"{xml.name} (as ST)", plcxml.st_from_xml(xml))])
    assert plcopen.first_difference(original, again) is None
    # the same POU names and kinds, tasks and instances, said plainly
    assert [(p.kind, p.name) for p in again.unit.pous] == [(p.kind, p.name) for p in original.unit.pous]
    res, res0 = again.config.resources[0], original.config.resources[0]
    assert [(t.name, t.interval_ns, t.priority.value) for t in res.tasks] == \
           [(t.name, t.interval_ns, t.priority.value) for t in res0.tasks] == [("MainTask", 10_000_000, 1)]
    assert [(p.name, p.task, p.type_name) for p in res.programs] == [(p.name, p.task, p.type_name) for p in res0.programs]


@pytest.mark.parametrize("variant", VARIANTS)
def test_pou_bodies_are_the_statement_text_as_written(built, variant):
    st, xml = built[variant]
    text = st.read_text(encoding="utf-8")
    unit = load_files([st])
    src = SourceText(text)
    pous = {p.get("name"): p for p in xml_of(xml).findall("ppx:types/ppx:pous/ppx:pou", NS)}
    for pou in unit.unit.pous:
        body = body_of(pous[pou.name])
        assert body == src.pou_body(pou)
        assert body in text and "END_VAR" not in body and f"END_{pou.kind}" not in body


def test_xml_contents_of_the_full_program(built):
    root = xml_of(built["full"][1])
    assert root.find("ppx:fileHeader", NS).get("creationDateTime")
    assert root.find("ppx:contentHeader", NS).get("name") == "mp9c_full"
    assert "Tasks 1 + 2 + 3" in root.findtext("ppx:contentHeader/ppx:Comment", namespaces=NS)

    types = {t.get("name"): t for t in root.findall("ppx:types/ppx:dataTypes/ppx:dataType", NS)}
    assert list(types) == ["T_FrameData", "ST_Frame", "T_FrameTable", "ST_ControlProgram", "ST_Playback"]
    table = types["T_FrameTable"].find("ppx:baseType/ppx:array", NS)
    assert [(d.get("lower"), d.get("upper")) for d in table.findall("ppx:dimension", NS)] == [("1", "32")]
    assert table.find("ppx:baseType/ppx:derived", NS).get("name") == "ST_Frame"
    pause = types["ST_Frame"].find("ppx:baseType/ppx:struct/ppx:variable[@name='Pause']", NS)
    assert pause.find("ppx:type/ppx:TIME", NS) is not None
    assert "Task 2" in "".join(pause.find("ppx:documentation", NS).itertext())

    pous = {p.get("name"): p for p in root.findall("ppx:types/ppx:pous/ppx:pou", NS)}
    assert pous["FC_PackBits7"].get("pouType") == "function"
    assert pous["FC_PackBits7"].find("ppx:interface/ppx:returnType/ppx:INT", NS) is not None
    manual = pous["FB_Mp9cManual"]
    assert manual.get("pouType") == "functionBlock"
    lists = manual.find("ppx:interface", NS)
    assert [etree.QName(c).localname for c in lists] == ["inputVars", "inOutVars", "outputVars", "externalVars",
                                                        "localVars"]
    assert [v.get("name") for v in lists.findall("ppx:externalVars/ppx:variable", NS)][:5] == \
        ["SA2", "SA3", "SA4", "SA5", "I07"]
    assert lists.find("ppx:localVars", NS).get("constant") == "true"
    short = lists.find("ppx:localVars[@constant='true']/ppx:variable[@name='SHORT_PAUSE']", NS)
    assert short.find("ppx:initialValue/ppx:simpleValue", NS).get("value") == "T#500ms"
    assert "I0.7 = 0" in "".join(short.find("ppx:documentation", NS).itertext())
    prg = pous["PRG_Mp9cBaseline"]
    assert prg.get("pouType") == "program"
    lists = prg.find("ppx:interface", NS)
    assert [v.get("name") for v in lists.findall("ppx:externalVars/ppx:variable", NS)][:2] == ["SQ1", "SQ2"]
    retained = lists.find("ppx:localVars[@retain='true']", NS)
    assert retained.find("ppx:variable", NS).get("name") == "Cp"
    assert retained.find("ppx:variable/ppx:type/ppx:derived", NS).get("name") == "ST_ControlProgram"
    assert body_of(prg).startswith("Sensors := FC_PackBits7(SQ1,")
    assert "Task 1: every mechanism" in "".join(prg.find("ppx:documentation", NS).itertext())

    config = root.find("ppx:instances/ppx:configurations/ppx:configuration", NS)
    assert config.get("name") == "Config0"
    resource = config.find("ppx:resource", NS)
    assert resource.get("name") == "Res0"
    task = resource.find("ppx:task", NS)
    assert (task.get("name"), task.get("interval"), task.get("priority")) == ("MainTask", "T#10ms", "1")
    assert [(i.get("name"), i.get("typeName")) for i in task.findall("ppx:pouInstance", NS)] == [("Main", "PRG_Mp9cBaseline")]
    globals_ = {v.get("name"): v for v in config.findall("ppx:globalVars/ppx:variable", NS)}
    assert globals_["SQ1"].get("address") == "%IX0.0" and globals_["SB1"].get("address") == "%IX1.6"
    assert globals_["HL1"].get("address") == "%QX1.0"
    assert globals_["SQ1"].find("ppx:type/ppx:BOOL", NS) is not None
    # CDATA in the file, as Beremiz writes it
    assert "<xhtml:p><![CDATA[Sensors := FC_PackBits7(SQ1," in built["full"][1].read_text(encoding="utf-8")


ALL_KINDS = """
(* every kind of TC6 data type and value *)
TYPE
    E_Mode : (IDLE, RUN, FAULT) := IDLE;
    T_Pct : INT (-10..110) := 50;
    T_Code : UINT (1..9);
    T_Speed : INT := 500;
    T_Name : STRING := 'mp9c';        (* no length: OpenPLC Editor would drop it *)
    T_Grid : ARRAY[1..2, 0..3] OF INT := [1, 2, 6(0)];
    ST_Point : STRUCT
        X : REAL := 1.5;
        Mode : E_Mode := RUN;    (* how the point is reached *)
        Tags : ARRAY[1..3] OF BOOL := [TRUE, 2(FALSE)];
    END_STRUCT;
    T_Alias : ST_Point;
END_TYPE

FUNCTION FC_Scale : REAL
VAR_INPUT
    Raw : INT;
END_VAR
VAR CONSTANT
    K : REAL := 0.5;
END_VAR
FC_Scale := INT_TO_REAL(Raw) * K;
END_FUNCTION

FUNCTION_BLOCK FB_Holder
VAR_INPUT NON_RETAIN
    Set : BOOL;
END_VAR
VAR_OUTPUT
    Q : BOOL;
END_VAR
VAR_TEMP
    Scratch : INT;
END_VAR
VAR
    Delay : TON;                      (* no initial value: OpenPLC Editor would drop it *)
    Where : ST_Point := (X := 2.0);   (* an enumerated value here stops OpenPLC's compiler *)
END_VAR
Scratch := 1;
Delay(IN := Set, PT := T#2s);
Q := Delay.Q AND Scratch = 1;
END_FUNCTION_BLOCK

PROGRAM PRG_Main
VAR
    Out AT %QW0 : INT;
END_VAR
VAR
    Holder : FB_Holder;
    Pct : T_Pct;
    Name : T_Name;
    Grid : T_Grid;
    Timeout : TIME := T#1m30s;
    Stamp : TOD := TOD#12:00:00;
END_VAR
VAR_EXTERNAL
    Run : BOOL;
END_VAR
VAR_EXTERNAL CONSTANT
    MaxOut : INT;
END_VAR
Holder(Set := Run);
IF Holder.Q THEN
    Out := REAL_TO_INT(FC_Scale(Raw := MaxOut));
END_IF;
END_PROGRAM

PROGRAM PRG_Idle
VAR
    Count : DINT;
END_VAR
Count := Count + 1;
END_PROGRAM

CONFIGURATION Config0
    VAR_GLOBAL
        Run AT %IX0.0 : BOOL;
    END_VAR
    VAR_GLOBAL CONSTANT
        MaxOut : INT := 100;
    END_VAR
    RESOURCE Res0 ON PLC
        VAR_GLOBAL
            Shared : INT;
        END_VAR
        TASK Fast (INTERVAL := T#5ms, PRIORITY := 0);
        TASK Slow (INTERVAL := T#100ms, PRIORITY := 2);
        PROGRAM Main WITH Fast : PRG_Main;
        PROGRAM Idle WITH Slow : PRG_Idle;
        PROGRAM Spare : PRG_Idle;
    END_RESOURCE
END_CONFIGURATION
"""


def test_every_type_kind_and_value_maps_to_tc6():
    data, _schema = xml_project(ALL_KINDS, "all_kinds", "all_kinds.xml")
    root = etree.fromstring(data)
    t = {d.get("name"): d for d in root.findall("ppx:types/ppx:dataTypes/ppx:dataType", NS)}
    enum = t["E_Mode"].find("ppx:baseType/ppx:enum", NS)
    assert [v.get("name") for v in enum.findall("ppx:values/ppx:value", NS)] == ["IDLE", "RUN", "FAULT"]
    assert t["E_Mode"].find("ppx:initialValue/ppx:simpleValue", NS).get("value") == "IDLE"
    pct = t["T_Pct"].find("ppx:baseType/ppx:subrangeSigned", NS)
    assert (pct.find("ppx:range", NS).get("lower"), pct.find("ppx:range", NS).get("upper")) == ("-10", "110")
    assert pct.find("ppx:baseType/ppx:INT", NS) is not None
    assert t["T_Code"].find("ppx:baseType/ppx:subrangeUnsigned/ppx:baseType/ppx:UINT", NS) is not None
    assert t["T_Speed"].find("ppx:baseType/ppx:INT", NS) is not None                     # alias
    assert t["T_Speed"].find("ppx:initialValue/ppx:simpleValue", NS).get("value") == "500"
    assert t["T_Name"].find("ppx:baseType/ppx:string", NS) is not None
    grid = t["T_Grid"].find("ppx:baseType/ppx:array", NS)
    assert [(d.get("lower"), d.get("upper")) for d in grid.findall("ppx:dimension", NS)] == [("1", "2"), ("0", "3")]
    items = t["T_Grid"].findall("ppx:initialValue/ppx:arrayValue/ppx:value", NS)
    assert [(v.get("repetitionValue"), v.find("ppx:simpleValue", NS).get("value")) for v in items] == \
           [(None, "1"), (None, "2"), ("6", "0")]
    mode = t["ST_Point"].find("ppx:baseType/ppx:struct/ppx:variable[@name='Mode']", NS)
    assert mode.find("ppx:type/ppx:derived", NS).get("name") == "E_Mode"
    assert "how the point is reached" in "".join(mode.find("ppx:documentation", NS).itertext())
    assert t["T_Alias"].find("ppx:baseType/ppx:derived", NS).get("name") == "ST_Point"

    pous = {p.get("name"): p for p in root.findall("ppx:types/ppx:pous/ppx:pou", NS)}
    holder = pous["FB_Holder"].find("ppx:interface", NS)
    assert holder.find("ppx:inputVars", NS).get("nonretain") == "true"
    assert holder.find("ppx:tempVars/ppx:variable", NS).get("name") == "Scratch"
    delay = holder.find("ppx:localVars/ppx:variable[@name='Delay']", NS)
    assert delay.find("ppx:type/ppx:derived", NS).get("name") == "TON"
    where = holder.find("ppx:localVars/ppx:variable[@name='Where']", NS)
    member = where.find("ppx:initialValue/ppx:structValue/ppx:value", NS)
    assert (member.get("member"), member.find("ppx:simpleValue", NS).get("value")) == ("X", "2.0")
    main = pous["PRG_Main"].find("ppx:interface", NS)
    assert main.find("ppx:localVars/ppx:variable[@name='Out']", NS).get("address") == "%QW0"
    assert main.find("ppx:localVars/ppx:variable[@name='Stamp']/ppx:type/ppx:TOD", NS) is not None

    res = root.find("ppx:instances/ppx:configurations/ppx:configuration/ppx:resource", NS)
    assert [(k.get("name"), k.get("interval"), k.get("priority")) for k in res.findall("ppx:task", NS)] == \
           [("Fast", "T#5ms", "0"), ("Slow", "T#100ms", "2")]
    assert [i.get("name") for i in res.findall("ppx:pouInstance", NS)] == ["Spare"]      # no task
    assert res.find("ppx:globalVars/ppx:variable", NS).get("name") == "Shared"
    config_lists = root.findall("ppx:instances/ppx:configurations/ppx:configuration/ppx:globalVars", NS)
    assert [g.get("constant") for g in config_lists] == [None, "true"]


def test_valid_frontend_cases_round_trip_or_are_refused_in_one_line(monkeypatch):
    """Every valid ST case of the front end either reads back from its XML as the same
    program, or has a construct TC6 cannot hold and is refused with one line saying which.
    (Schema checks are the other tests' business: some cases use matiec extensions, e.g.
    constant array bounds, that a strict schema rejects.)"""
    monkeypatch.setattr(schema_mod, "schema_path", lambda: None)
    refused = {}
    for case in sorted(CASES.glob("*.st")):
        try:
            xml_project(case.read_text(encoding="utf-8"), case.stem, case.name)
        except PlcLabError as e:
            refused[case.name] = str(e)
    assert set(refused) == set(NO_TC6_FORM), refused
    for name, text in refused.items():
        assert "\n" not in text and "PLCopen XML" in text and NO_TC6_FORM[name] in text


# --------------------------------------------------------------------------- refusals

def test_unknown_variant_is_one_clear_error(tmp_path):
    with pytest.raises(PlcLabError) as e:
        write_build("mp9c", "task9", str(tmp_path / "x.st"), str(tmp_path / "x.xml"))
    msg = str(e.value)
    assert "\n" not in msg and "unknown variant 'task9'" in msg and "baseline" in msg and "full" in msg
    assert list(tmp_path.iterdir()) == []


def test_broken_st_source_is_refused_with_the_checker_lines_and_nothing_written(tmp_path, monkeypatch):
    plc = tmp_path / "plc"
    shutil.copytree(PLC_DIR, plc)
    blink = plc / "POUs" / "FB_Blink.st"
    blink.write_text(blink.read_text(encoding="utf-8").replace("END_FUNCTION_BLOCK", "Undeclared := 1;\nEND_FUNCTION_BLOCK"),
                     encoding="utf-8")
    monkeypatch.setattr("plclab.stands.PLC_DIR", plc)
    out = tmp_path / "out"
    out.mkdir()
    with pytest.raises(CompileError) as e:
        write_build("mp9c", "full", str(out / "mp9c_full.st"), str(out / "mp9c_full.xml"))
    lines = str(e.value).splitlines()
    assert lines and all(": error: " in line for line in lines)
    assert any(line.startswith(f"{blink}:") and "Undeclared" in line for line in lines), lines
    assert list(out.iterdir()) == []


def test_xml_that_is_not_valid_tc6_is_refused_with_the_first_schema_error(tmp_path, monkeypatch):
    real = plcopen.project_tree

    def without_pou_type(*args, **kwargs):
        tree = real(*args, **kwargs)
        del tree.getroot().find("ppx:types/ppx:pous/ppx:pou", NS).attrib["pouType"]
        return tree
    monkeypatch.setattr(plcopen, "project_tree", without_pou_type)
    with pytest.raises(PlcLabError) as e:
        write_build("mp9c", "baseline", str(tmp_path / "b.st"), str(tmp_path / "b.xml"))
    msg = str(e.value)
    assert "\n" not in msg and "not valid PLCopen TC6 XML" in msg and "pouType" in msg
    assert list(tmp_path.iterdir()) == []


def test_xml_that_reads_back_differently_is_refused(tmp_path, monkeypatch):
    real = plcxml.st_from_tree
    monkeypatch.setattr(plcxml, "st_from_tree", lambda tree: real(tree).replace("T#10ms", "T#20ms"))
    with pytest.raises(PlcLabError) as e:
        write_build("mp9c", "task1", str(tmp_path / "t.st"), str(tmp_path / "t.xml"))
    msg = str(e.value)
    assert "\n" not in msg and "does not read back to the same program" in msg and "interval" in msg
    assert list(tmp_path.iterdir()) == []


def test_missing_output_directory_is_one_clear_error(tmp_path):
    with pytest.raises(PlcLabError) as e:
        write_build("mp9c", "baseline", str(tmp_path / "nope" / "b.st"), None)
    assert "no such directory" in str(e.value) and "\n" not in str(e.value)


# --------------------------------------------------------------------------- reading XML

BEREMIZ_STYLE = b"""<?xml version='1.0' encoding='utf-8'?>
<project xmlns:ns1="http://www.plcopen.org/xml/tc6_0201" xmlns:xhtml="http://www.w3.org/1999/xhtml"
         xmlns="http://www.plcopen.org/xml/tc6_0201">
  <fileHeader companyName="Unknown" productName="Unnamed" productVersion="1" creationDateTime="2023-03-11T14:33:27"/>
  <contentHeader name="Unnamed" modificationDateTime="2023-03-27T09:12:21">
    <coordinateInfo><fbd><scaling x="8" y="8"/></fbd><ld><scaling x="0" y="0"/></ld><sfc><scaling x="0" y="0"/></sfc></coordinateInfo>
  </contentHeader>
  <types>
    <dataTypes/>
    <pous>
      <pou name="blink" pouType="program">
        <interface>
          <localVars>
            <variable name="lamp" address="%QX0.0"><type><BOOL/></type></variable>
          </localVars>
          <localVars>
            <variable name="t1"><type><derived name="TON"/></type></variable>
          </localVars>
        </interface>
        <body>
          <ST>
            <xhtml:p><![CDATA[
t1(IN := NOT t1.Q, PT := T#500ms);
IF t1.Q THEN lamp := NOT lamp; END_IF;
]]></xhtml:p>
          </ST>
        </body>
      </pou>
    </pous>
  </types>
  <instances>
    <configurations>
      <configuration name="Config0">
        <resource name="Res0">
          <task name="task0" priority="0" interval="PT0.02S">
            <pouInstance name="instance0" typeName="blink"/>
          </task>
        </resource>
      </configuration>
    </configurations>
  </instances>
</project>
"""


def test_st_from_xml_reads_a_file_written_by_the_editor(tmp_path):
    path = tmp_path / "plc.xml"
    path.write_bytes(BEREMIZ_STYLE)
    text = plcxml.st_from_xml(path)
    unit = check_sources([("plc.xml (as ST)", text)])
    assert [p.name for p in unit.unit.pous] == ["blink"]
    assert unit.config.resources[0].tasks[0].interval_ns == 20_000_000
    assert "PROGRAM instance0 WITH task0 : blink;" in text
    # Beremiz's own default names: OpenPLC's build looks for Config0.c and Res0.c
    path.write_bytes(BEREMIZ_STYLE.replace(b'"Config0"', b'"config"'))
    with pytest.raises(CompileError, match="OpenPLC builds a CONFIGURATION named Config0"):
        check_sources([("plc.xml (as ST)", plcxml.st_from_xml(path))])


def test_interval_literals():
    assert interval_literal("T#10ms") == "T#10ms"
    assert interval_literal("PT0.01S") == "T#10ms"
    assert interval_literal("PT1M30S") == "T#90000ms"
    assert interval_literal("PT0.0005S") == "T#0.5ms"


def test_st_from_xml_refuses_what_is_not_a_tc6_project(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text("<project><unclosed></project>", encoding="utf-8")
    with pytest.raises(PlcLabError, match="not well-formed XML"):
        plcxml.st_from_xml(bad)
    other = tmp_path / "other.xml"
    other.write_text("<html/>", encoding="utf-8")
    with pytest.raises(PlcLabError, match="not a PLCopen TC6"):
        plcxml.st_from_xml(other)


def test_build_without_xml_is_only_the_bundle():
    out = build_outputs("mp9c", "task2", xml=False)
    assert out.xml_bytes is None and out.st_text == bundle(get_stand("mp9c"), "task2")
