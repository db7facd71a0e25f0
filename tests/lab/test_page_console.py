"""What a student hit at the console in a full lab (issue 31): the speed after an input
script, the frame the step mode shows, why playback does not start, the header's words,
faults, forces, the thermo and CNC drawings.

The replay test is the one wall-clock check of the lab's tests: the bug it guards against is
the plant running 40-74 times faster than the wall clock while the header says x1, so it
compares the plant clock with the wall clock, with a wide tolerance (0.7 .. 1.4)."""
from __future__ import annotations

import re

from playwright.sync_api import expect
from test_page import WAIT, flip, lamp, on, plant_time, switch, tap_sb1

SHORT_SCRIPT = ("time_s,name,value\n"
                "0.2,SA1,0\n"
                "0.5,SA5,1\n"
                "1.0,END,0\n")


def clock_and_wall(page) -> tuple[float, float]:
    """The plant time the page shows and the browser's wall clock (s), read together."""
    t, wall = page.evaluate("() => [document.querySelector('#clock').textContent, performance.now()]")
    return float(re.search(r"t = ([\d.]+) s", t).group(1)), wall / 1000


def test_after_an_input_script_the_stand_runs_at_the_speed_the_header_says(lab_page):
    lp = lab_page("mp9c", speed=1)
    page = lp.page
    expect(page.locator("#clock")).not_to_have_text("t = 0.00 s", timeout=WAIT)
    page.locator("#script-file").set_input_files(files=[{"name": "ops.csv", "mimeType": "text/csv",
                                                          "buffer": SHORT_SCRIPT.encode()}])
    expect(page.get_by_role("status", name="input script")).to_have_text(
        "ops.csv: finished (the console log lists each step)", timeout=WAIT)
    expect(page.locator("#speed-shown")).to_have_text("x1")
    t0, w0 = clock_and_wall(page)
    page.wait_for_timeout(3000)
    t1, w1 = clock_and_wall(page)
    rate = (t1 - t0) / (w1 - w0)
    assert 0.7 <= rate <= 1.4, f"the plant ran at x{rate:.1f} after the script while the header says x1"
