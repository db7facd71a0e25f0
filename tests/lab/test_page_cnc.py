"""`plclab lab cnc` in Chromium (issue 22, "Beyond" 9): a part program loaded from the page,
run with SB1, drawn as it is cut over its contour, the contour error against its bound, the
feed override, a feed hold (SB2), backlash and a drive that loses steps."""
from __future__ import annotations

import re

from playwright.sync_api import expect
from test_page import WAIT, let_time_pass


def test_cnc_part_program_cut_over_its_contour_with_error_bound_override_hold_and_lost_steps(lab_page, shots):
    lp = lab_page("cnc", speed=5)
    page = lp.page
    lab = lp.lab
    expect(page.get_by_label("part program")).to_have_value(re.compile(r"G01 X20 Y0 F300"))   # the example: a square
    page.get_by_role("button", name="Load part program").click()
    expect(page.locator("#part-message")).to_have_text("part program loaded: press SB1 to run it", timeout=WAIT)
    expect(page.locator("#cnc-frame")).to_have_text("frame 0 of 4 (square 20 mm, evaluation function, evalfn)",
                                                     timeout=WAIT)
    expect(page.locator("#cnc-contour")).to_have_attribute("data-points", "5", timeout=WAIT)
    sb1 = page.get_by_role("button", name="SB1", exact=True)
    sb1.hover()
    page.mouse.down()
    page.wait_for_timeout(100)
    page.mouse.up()
    expect(page.locator("#cnc-frame")).to_contain_text("frame 2 of 4", timeout=WAIT)
    expect(page.locator("#cnc-state")).to_have_text("program end", timeout=60_000)
    assert int(page.locator("#cnc-path").get_attribute("data-points")) > 100              # drawn as cut
    expect(page.locator("#cnc-verdict")).to_have_text("within the bound: ok")
    error = float(re.search(r"max ([\d.]+) mm", page.locator("#cnc-error").text_content()).group(1))
    assert 0 <= error <= 0.01 + 1e-9                                                       # within one step h
    assert (lab.session.plant.axes["X"].steps, lab.session.plant.axes["Y"].steps) == (0, 0)
    expect(page.locator("#cnc-steps")).to_have_text("steps X 0  Y 0  Z 0")
    page.screenshot(path=str(shots / "lab-cnc.png"))
    # feed override and backlash from the console; a drive that misses steps above 200/s
    page.get_by_label("RP1", exact=True).fill("150")
    expect(page.locator("#cnc-override")).to_have_text("feed override 150 %", timeout=WAIT)
    page.get_by_label("backlash", exact=True).fill("5")
    expect(page.locator("#actions")).to_contain_text("backlash 5 steps", timeout=WAIT)
    assert lab.session.plant.override == 150
    page.get_by_label("fault", exact=True).select_option("slow_drive")
    page.get_by_label("axis").select_option("X")
    page.get_by_label("rate").fill("200")
    page.get_by_role("button", name="Inject").click()
    page.get_by_role("button", name="Load part program").click()
    expect(page.locator("#actions")).to_contain_text(
        re.compile(r"4 frames of square 20 mm, evaluation function loaded \(evalfn\)[\s\S]*4 frames of square"),
        timeout=WAIT)
    sb1.hover()
    page.mouse.down()
    page.wait_for_timeout(100)
    page.mouse.up()
    expect(page.locator("#cnc-missed")).to_contain_text(re.compile(r"missed steps X [1-9]"), timeout=WAIT)
    # feed hold: SB2 stops the table where it is
    sb2 = page.get_by_role("button", name="SB2", exact=True)
    sb2.hover()
    page.mouse.down()
    page.wait_for_timeout(100)
    page.mouse.up()
    let_time_pass(page, 0.3)
    held = page.locator("#cnc-steps").text_content()
    let_time_pass(page, 1.0)
    assert page.locator("#cnc-steps").text_content() == held, "the table moved on during a feed hold"
    assert "program end" not in page.locator("#cnc-state").text_content()


def test_cnc_page_runs_the_fine_cycle_openplc_runs(lab_page):
    """The FINE_MS setting: the program's task and FINE_MS at 5 ms (as `plclab cnc
    --fine-cycle 5` and the OpenPLC build), downloaded again; the pulse generator follows."""
    lp = lab_page("cnc", speed=5)
    page, lab = lp.page, lp.lab
    assert lab.session.tick == 0.001
    page.get_by_label("FINE_MS", exact=True).fill("5")
    expect(page.locator("#actions")).to_contain_text("fine cycle 5 ms (FineTask and FINE_MS; the program restarted)",
                                                     timeout=WAIT)
    s = lab.session
    assert s.tick == 0.005 and s.plant.pulse_cycle == 0.02
    assert any("FINE_MS : LREAL := 5.0;" in text for _name, text in s.sources)
    page.get_by_role("button", name="Load part program").click()
    expect(page.locator("#part-message")).to_have_text("part program loaded: press SB1 to run it", timeout=WAIT)
