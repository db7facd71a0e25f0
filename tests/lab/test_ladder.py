"""Ladder programs in the lab (issue #23 item 3): a page uploads an OpenPLC Editor project
(plc.xml, alone or with .st files), a drawing's errors name the POU, rung and element, and
the program panel draws an LD POU as rungs with its power flow live.

The program is the MP-9C starting program with FB_Sb1Button drawn in ladder
(tests/ladder/examples/sb1_button.xml: debounce timer, 3 s timer, Press / Short / Long)."""
from __future__ import annotations

import asyncio
from pathlib import Path

from playwright.sync_api import expect
from test_page import WAIT
from test_server import _files, _post, running  # noqa: F401 - the fixture

from plclab.stands import get_stand, sources

SB1_XML = Path(__file__).resolve().parents[1] / "ladder" / "examples" / "sb1_button.xml"


def ladder_program(tmp_path: Path, xml: bytes | None = None) -> list[Path]:
    """The MP-9C starting program's files with FB_Sb1Button.st replaced by the ladder plc.xml."""
    stand = get_stand("mp9c")
    out = []
    for name, text in sources(stand, stand.starting_variant):
        base = "Config0.st" if name.startswith("<") else Path(name).name
        if base == "FB_Sb1Button.st":
            continue
        (tmp_path / base).write_text(text)
        out.append(tmp_path / base)
    (tmp_path / "plc.xml").write_bytes(SB1_XML.read_bytes() if xml is None else xml)
    return out + [tmp_path / "plc.xml"]


def test_a_plc_xml_uploaded_with_st_files_runs_and_its_errors_name_the_drawing(running, tmp_path):  # noqa: F811
    server, url = running("mp9c")
    lab = server.lab
    files = ladder_program(tmp_path)
    loaded = asyncio.run(_post(url + "api/program", _files(*[(p.name, p.read_bytes()) for p in files])))
    assert loaded["ok"] is True, loaded
    assert lab.program_name.endswith("plc.xml")
    pou = next(p for p in lab.call(lab.listing).result(10) if p["name"] == "FB_Sb1Button")
    assert {e["name"] for e in pou["ladder"]["elements"] if e["kind"] == "coil"} == \
        {"Held", "Press", "Long", "Short", "LongGiven", "WasHeld"}
    # a coil on an undeclared variable: refused, named on the drawing, the PLC keeps its program
    broken = SB1_XML.read_bytes().replace(b"<variable>Held</variable>", b"<variable>Helt</variable>", 1)
    files = ladder_program(tmp_path, broken)
    answer = asyncio.run(_post(url + "api/program", _files(*[(p.name, p.read_bytes()) for p in files])))
    assert answer["ok"] is False
    texts = [e["text"] for e in answer["errors"]]
    assert any(t.startswith("plc.xml: FB_Sb1Button (LD), rung 1, coil Helt (localId ") and "'Helt'" in t
               for t in texts), texts
    assert all(e["source"] is None for e in answer["errors"])     # no line of generated ST shown
    assert lab.program_name.endswith("plc.xml") and lab.session.plc.state == "RUN"
    # a project that is not XML at all: one line
    bad = asyncio.run(_post(url + "api/program", _files(("plc.xml", b"<project"))))
    assert bad["ok"] is False and len(bad["errors"]) == 1 and bad["errors"][0]["text"].startswith("plc.xml: ")


def test_editor_projects_with_located_io_beside_a_timer_or_counter_open_in_the_lab(running, tmp_path):  # noqa: F811
    """The Editor's commonest shapes (located I/O in one table with a TON, a CTU, FB instances)
    load in the lab, and an LD POU among them is drawn as its rungs."""
    from drawing import project
    from test_grading import handout_with_located_io
    from test_editor_variables import counter_ctu, latch_ton

    server, url = running("mp9c")
    lab = server.lab
    for program, data in (("LatchTon", project([latch_ton()], program="LatchTon")),
                          ("Counter", project([counter_ctu()], program="Counter")),
                          ("PRG_Mp9cBaseline", handout_with_located_io())):
        loaded = asyncio.run(_post(url + "api/program", _files(("plc.xml", data))))
        assert loaded["ok"] is True, (program, loaded)
        assert lab.program_name.endswith("plc.xml")
        listing = {p["name"]: p for p in lab.call(lab.listing).result(10)}
        assert program in listing, sorted(listing)
    drawn = listing["FB_Mp9cManual"]["ladder"]
    assert any(e["kind"] == "coil" for e in drawn["elements"])


def _element(page, label: str):
    return page.get_by_label("ladder diagram").locator(f'g[aria-label="{label}"]').first


def test_ladder_online_shows_power_flow_as_sb1_is_held_and_released(lab_page, tmp_path, shots):
    lp = lab_page("mp9c", speed=2)
    page = lp.page
    page.locator("#program-files").set_input_files([str(p) for p in ladder_program(tmp_path)])
    expect(page.locator("#program-message")).to_contain_text("program loaded", timeout=WAIT)
    page.get_by_role("button", name="Show the program").click()
    page.get_by_label("POU", exact=True).select_option("FB_Sb1Button")
    expect(page.get_by_label("ladder diagram")).to_be_visible(timeout=WAIT)
    expect(page.get_by_label("program source")).to_be_hidden()
    pressed, held, was_held = _element(page, "contact Pressed"), _element(page, "coil Held"), \
        _element(page, "coil WasHeld")
    expect(pressed).to_have_attribute("data-state", "off", timeout=WAIT)
    expect(held).to_have_attribute("data-state", "off")
    expect(_element(page, "coil LongGiven")).to_have_attribute("data-state", "off")
    sb1 = page.get_by_role("button", name="SB1", exact=True)
    sb1.focus()                                         # held from the keyboard: the full-page capture
    page.keyboard.down(" ")                             # below moves nothing a pointer could leave
                                                        # SB1 held: power through Pressed to the timer
    expect(pressed).to_have_attribute("data-state", "on", timeout=WAIT)
    expect(held).to_have_attribute("data-state", "on", timeout=WAIT)          # after the 50 ms debounce
    expect(was_held).to_have_attribute("data-state", "on", timeout=WAIT)
    expect(page.locator('#ladder [data-value$=".var"]').first).to_have_text("TRUE")   # Held's variable
    # the 3 s timer: LongGiven's set coil gets its variable once Long came (x1 while held)
    long_given = page.get_by_label("ladder diagram").locator('g[aria-label="coil LongGiven"] >> nth=0')
    expect(page.locator(f'#ladder [data-value="{long_given.get_attribute("data-id")}.var"]')).to_have_text(
        "TRUE", timeout=10_000)
    box = page.locator("#online").bounding_box()            # a full-page capture of the online view
    scroll = page.evaluate("({x: scrollX, y: scrollY})")
    page.screenshot(path=str(shots / "lab-ladder-online.png"), full_page=True,
                    clip={"x": box["x"] + scroll["x"], "y": box["y"] + scroll["y"],
                          "width": box["width"], "height": box["height"]})
    expect(pressed).to_have_attribute("data-state", "on")   # still held when the picture was taken
    page.keyboard.up(" ")                               # released: nothing conducts on rung 1
    expect(pressed).to_have_attribute("data-state", "off", timeout=WAIT)
    expect(held).to_have_attribute("data-state", "off", timeout=WAIT)
    expect(was_held).to_have_attribute("data-state", "off", timeout=WAIT)


def test_power_flow_follows_the_translated_program_scan_by_scan(tmp_path):
    """Series and parallel contacts, a negated one, a function box (GT, its result in the
    Editor's temporary), an FB box (TON) and coils: after each scan of the translated program,
    the power the lab draws on each element is what the rung's logic gives for the values the
    PLC holds (and each coil's energised state is its variable, for a normal coil)."""
    import sys
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ladder"))
    from drawing import Diagram, Pou, project

    from plclab.frontend import load_files, read_sources
    from plclab.lab.ladder import PowerFlow, drawings, pou_elements, time_aware
    from plclab.runtime.compiler import compile_unit
    from plclab.runtime.plc import PLC
    from plclab.runtime.sim import Simulation

    d = Diagram()
    a = d.contact("A", 0, 0)
    nb = d.contact("B", 0, 1, after=a, negated=True)
    c = d.contact("C", 1, 0)
    q = d.coil("Q", 0, 4, after=[nb, c])                     # Q := (A AND NOT B) OR C
    x, y = d.invar("X", 3, 0), d.invar("Y", 4, 0)
    gt = d.block("GT", 3, 1, [("IN1", x), ("IN2", y)], ["OUT"])
    q2 = d.coil("Q2", 3, 4, after=(gt, "OUT"))               # Q2 := X > Y
    ton = d.block("TON", 6, 1, [("IN", a), ("PT", d.invar("T#30ms", 7, 0))], ["Q", "ET"], instance="T1")
    q3 = d.coil("Q3", 6, 4, after=(ton, "Q"))
    pou = Pou("main", "program", d, {"localVars": [(n, "BOOL", None) for n in ("A", "B", "C", "Q", "Q2", "Q3")]
                                     + [("X", "INT", None), ("Y", "INT", None), ("T1", "TON", None)]})
    path = tmp_path / "plc.xml"
    path.write_bytes(project([pou], program="main"))
    sources = read_sources([path])
    assert f"_TMP_GT{gt.local_id}_OUT" in sources[0][1]              # the name the lab reads
    assert "MAIN" in drawings(sources)
    sim = Simulation(PLC(compile_unit(load_files([path]))))
    elements = pou_elements(sources, "main")
    seen = []
    for a_, b_, c_, x_, y_ in [(1, 0, 0, 5, 3), (1, 1, 0, 1, 3), (0, 1, 1, 3, 3), (1, 0, 0, 9, 2),
                               (1, 0, 0, 9, 2), (1, 0, 0, 9, 2), (1, 0, 0, 9, 2), (0, 0, 0, 0, 0)]:
        for name, v in (("A", bool(a_)), ("B", bool(b_)), ("C", bool(c_)), ("X", x_), ("Y", y_)):
            sim.set(f"instance0.{name}", v)
        sim.step(1)
        power = PowerFlow(elements, "instance0", time_aware(sim.plc)).state()
        read = sim.plc.read
        assert power[str(a.local_id)] is bool(a_)
        assert power[str(nb.local_id)] is (bool(a_) and not b_)
        assert power[str(q.local_id)] is read("instance0.Q") is ((bool(a_) and not b_) or bool(c_))
        assert power[f"{gt.local_id}.OUT"] is power[str(q2.local_id)] is read("instance0.Q2") is (x_ > y_)
        assert power[f"{ton.local_id}.Q"] is power[str(q3.local_id)] is read("instance0.Q3")
        assert power[f"{q.local_id}.var"] is read("instance0.Q")
        seen.append(power[str(q3.local_id)])
        if power[str(q3.local_id)]:
            assert power[f"{ton.local_id}.ET"] == "T#30ms"
    assert seen[-1] is False and True in seen            # the 30 ms timer ran out while A stayed on, then reset
