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
    sb1.hover()
    page.mouse.down()                                   # SB1 held: power through Pressed to the timer
    expect(pressed).to_have_attribute("data-state", "on", timeout=WAIT)
    expect(held).to_have_attribute("data-state", "on", timeout=WAIT)          # after the 50 ms debounce
    expect(was_held).to_have_attribute("data-state", "on", timeout=WAIT)
    expect(page.locator('#ladder [data-value$=".var"]').first).to_have_text("TRUE")   # Held's variable
    # the 3 s timer: LongGiven's set coil gets its variable once Long came (x1 while held)
    long_given = page.get_by_label("ladder diagram").locator('g[aria-label="coil LongGiven"] >> nth=0')
    expect(page.locator(f'#ladder [data-value="{long_given.get_attribute("data-id")}.var"]')).to_have_text(
        "TRUE", timeout=10_000)
    box = page.locator("#online").bounding_box()            # a full-page capture: nothing scrolls away
    scroll = page.evaluate("({x: scrollX, y: scrollY})")     # from under the pointer holding SB1
    page.screenshot(path=str(shots / "lab-ladder-online.png"), full_page=True,
                    clip={"x": box["x"] + scroll["x"], "y": box["y"] + scroll["y"],
                          "width": box["width"], "height": box["height"]})
    expect(pressed).to_have_attribute("data-state", "on")   # still held when the picture was taken
    page.mouse.up()                                     # released: nothing conducts on rung 1
    expect(pressed).to_have_attribute("data-state", "off", timeout=WAIT)
    expect(held).to_have_attribute("data-state", "off", timeout=WAIT)
    expect(was_held).to_have_attribute("data-state", "off", timeout=WAIT)
