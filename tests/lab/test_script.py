"""Replaying an input script in the lab (issue #21 item 3): the page uploads a CSV in the
input-CSV format (time_s,name,value: console labels or addresses), the stand is reset and
each row is applied at its plant time; the console shows each step as it is applied."""
from __future__ import annotations

import asyncio

import aiohttp
from playwright.sync_api import expect
from test_page import WAIT, lamp, on, switch, trace_rows
from test_server import _token, running  # noqa: F401 - the fixture

SCRIPT = ("time_s,name,value\n"
          "0.2,SA1,0\n"            # manual mode
          "0.5,SA5,1\n"            # lift down
          "2.5,%IX1.6,1\n"         # SB1 (by its address) pressed ...
          "2.8,SB1,0\n"            # ... and released: a short press records a frame
          "3.5,END,0\n")


async def _post_script(url: str, name: str, data: bytes) -> dict:
    async with aiohttp.ClientSession() as http:
        token = await _token(http, url)
        async with http.post(url + f"api/script?name={name}", data=data,
                             headers={"X-PLCLab-Token": token, "content-type": "text/csv"}) as r:
            return await r.json()


def replay(page, name: str, text: str) -> None:
    """Replay input script `text` from the page's picker, as file `name`."""
    page.locator("#script-file").set_input_files(files=[{"name": name, "mimeType": "text/csv", "buffer": text.encode()}])


def test_a_bad_script_row_is_one_line_and_nothing_is_reset(running):  # noqa: F811
    server, url = running("mp9c")
    lab = server.lab
    lab.call(lambda: lab.advance(1.0)).result(10)
    before = lab.session.now
    answer = asyncio.run(_post_script(url, "ops.csv", b"time_s,name,value\n0.5,SA1,0\n0.7,SA9,1\n"))
    assert answer["ok"] is False
    assert answer["message"] == ("ops.csv:3: error: 'SA9' is no console input of mp9c (one of SA1, SA2, SA3, "
                                 "SA4, SA5, SA6, SB1, I0.7, or their addresses; PLC, FAULT, END)")
    answer = asyncio.run(_post_script(url, "ops.csv", b"time_s,name,value\n0.5,SB1,2\n"))
    assert answer["message"] == "ops.csv:2: error: SB1 takes 0 or 1, not '2'"
    assert lab.epoch == 0 and lab.session.now >= before           # the stand was not reset


def test_replayed_script_drives_the_stand_at_its_plant_times(lab_page):
    lp = lab_page("mp9c", speed=5)
    page = lp.page
    expect(page.locator("#clock")).not_to_have_text("t = 0.00 s", timeout=WAIT)
    replay(page, "ops.csv", SCRIPT)
    status = page.get_by_role("status", name="input script")
    expect(status).to_contain_text("replaying ops.csv", timeout=WAIT)
    expect(switch(page, "SA5")).to_have_attribute("aria-checked", "true", timeout=WAIT)   # the console follows
    on(lamp(page, "SQ2"))                                                             # the lift went down
    expect(page.locator("#frames-status")).to_contain_text("1 frame(s)", timeout=WAIT)   # SB1's short press
    expect(status).to_have_text("ops.csv: finished (the console log lists each step)", timeout=WAIT)
    log = page.locator("#actions")
    expect(log).to_contain_text("script step 3/5 (line 4, t=2.5 s): SB1 = 1")
    expect(log).to_contain_text("input script ops.csv: END reached")
    # the trace starts again at the reset and has the steps at their plant times (one scan)
    rows = [(t, v) for t, name, v in trace_rows(page) if name == "%IX1.6"]
    assert [v for _t, v in rows] == ["0", "1", "0"], rows
    assert abs(rows[1][0] - 2.5) <= 0.01 and abs(rows[2][0] - 2.8) <= 0.01, rows


def test_the_lab_replays_an_exploration_script_as_run_inputs_does(tmp_path):
    """A script the grader's exploration writes (switch flips, SB1 taps and holds, power
    cycles, plant faults) replayed by the lab gives the trace `plclab run --inputs` gives:
    the same steps at the same plant times, scan for scan."""
    import random

    from plclab.grader.explore import play
    from plclab.lab.engine import Lab
    from plclab.lab.script import parse_script
    from plclab.stands import stand_module
    from plclab.stands.base import stand_spec
    from plclab.trace import csv_text

    for stand in ("mp9c", "tur10"):
        spec = stand_spec(stand)
        wanted = {"PLC", "FAULT"} if stand == "mp9c" else {"PLC"}     # a power cycle (and a plant fault) in it
        script = next(sc for sc in (spec.explore.generate(random.Random(seed), "task1", 20.0) for seed in range(200))
                      if wanted <= {e.name for e in sc.events})
        lab = Lab(stand, variant="baseline", work_dir=tmp_path / stand)
        lab.session.run(lab.session.tick)
        lab.advance(1.0)                                  # something happened before: the reset undoes it
        steps = parse_script(script.csv_text().encode(), "ops.csv", lab.panel, lab.session.labels)
        assert {s.kind for s in steps} >= {"switch", "button", "power", "end"} | ({"fault"} if stand == "mp9c" else set())
        lab.start_script(steps, "ops.csv")
        lab.advance(script.duration + 0.5)
        assert lab.script is None
        run = stand_module(stand).session("baseline", watch_internals=False, retain_path=tmp_path / f"{stand}.json")
        play(run, script)
        run.run(0.5)
        def rows(trace, end=script.duration):
            return [r for r in csv_text(trace).splitlines()[1:] if float(r.split(",")[0]) < end]
        assert rows(lab.session.trace) == rows(run.trace), stand
        assert len(rows(run.trace)) > 20
        lab.stop()
