"""What a student hit at the console in a full lab (issue 31): the speed after an input
script, the frame the step mode shows, why playback does not start, the header's words,
faults, forces, the thermo and CNC drawings.

The replay test is the one wall-clock check of the lab's tests: the bug it guards against is
the plant running 40-74 times faster than the wall clock while the header says x1, so it
compares the plant clock with the wall clock, with a wide tolerance (0.7 .. 1.4)."""
from __future__ import annotations

import re

from playwright.sync_api import expect
from test_page import WAIT, flip, lamp, let_time_pass, on, plant_time, switch, tap_sb1
from test_script import replay

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
    replay(page, "ops.csv", SHORT_SCRIPT)
    expect(page.get_by_role("status", name="input script")).to_have_text(
        "ops.csv: finished (the console log lists each step)", timeout=WAIT)
    expect(page.locator("#speed-shown")).to_have_text("x1")
    t0, w0 = clock_and_wall(page)
    page.wait_for_timeout(3000)
    t1, w1 = clock_and_wall(page)
    rate = (t1 - t0) / (w1 - w0)
    assert 0.7 <= rate <= 1.4, f"the plant ran at x{rate:.1f} after the script while the header says x1"


def frame_rows(page) -> list[tuple[str, str]]:
    """Each recorded frame's number and how the table marks it (current / done / '')."""
    rows = page.locator("#frame-table tbody tr").evaluate_all(
        "rows => rows.map(r => [r.cells[0].textContent, r.className])")
    return [tuple(r) for r in rows]


def record_down_and_up(page) -> None:
    """MP-9C, manual mode: frame 1 the arm down, frame 2 the arm up."""
    flip(page, "SA5", True)
    on(lamp(page, "SQ2"))
    tap_sb1(page)                                     # frame 1: arm down
    flip(page, "SA5", False)
    on(lamp(page, "SQ1"))
    tap_sb1(page)                                     # frame 2: arm up


def test_mp9c_step_mode_shows_the_frame_done_while_it_waits_for_the_next_press(lab_page):
    lp = lab_page("mp9c", speed=2, variant="baseline")
    page = lp.page
    status = page.locator("#frames-status")
    record_down_and_up(page)
    expect(status).to_have_text("2 frame(s); stopped (next: frame 1)", timeout=WAIT)
    flip(page, "SA6", True)                           # step by step
    flip(page, "SA1", True)                           # automatic
    tap_sb1(page)                                     # step: frame 1
    on(lamp(page, "SQ2"))
    expect(status).to_have_text("2 frame(s); frame 1 done; waiting for the next SB1 press (step mode; next: frame 2)",
                                timeout=WAIT)
    assert frame_rows(page) == [("1", "done"), ("2", "")]
    assert page.locator("#frame-table tr[aria-current='true']").count() == 0
    tap_sb1(page)                                     # step: frame 2
    on(lamp(page, "SQ1"))
    expect(status).to_have_text("2 frame(s); frame 2 done; waiting for the next SB1 press (step mode; next: frame 1)",
                                timeout=WAIT)
    assert frame_rows(page) == [("1", ""), ("2", "done")]


def test_tur10_pause_after_a_frame_is_not_shown_as_executing_it(lab_page):
    lp = lab_page("tur10", speed=2, variant="baseline")
    page = lp.page
    sb1 = lp.lab.session.labels["SB1"]
    flip(page, "SA7", False)
    tap_sb1(page, address=sb1)                        # frame 1: where the links are
    tap_sb1(page, address=sb1)                        # frame 2: the same place
    flip(page, "SA7", True)
    tap_sb1(page, address=sb1)                        # start: each frame is reached at once, then its pause
    status = page.locator("#frames-status")
    expect(status).to_have_text(re.compile(r"2 frame\(s\); frame 1 done, its pause \(then frame 2\)"), timeout=WAIT)
    assert frame_rows(page) == [("1", "done"), ("2", "")]
    expect(status).to_have_text("2 frame(s); frame 2 done, its pause (then frame 1)", timeout=WAIT)


def test_the_lab_runs_the_starting_program_unless_told_otherwise():
    from plclab.lab import open_lab
    from plclab.stands import get_stand
    for stand in ("mp9c", "tur10"):
        server = open_lab(stand, port=0, modbus_port=None)
        assert server.lab.variant == get_stand(stand).starting_variant == "baseline"
        assert server.lab.program_name == "baseline (shipped)"
        server.lab.stop()
    server = open_lab("mp9c", variant="task3", port=0, modbus_port=None)
    assert server.lab.program_name == "task3 (shipped)"
    server.lab.stop()


def test_a_start_press_the_program_refuses_says_what_it_reads_of_the_console(lab_page, shots):
    lp = lab_page("mp9c", speed=2, variant="full")    # Task 3: I0.7 enables automatic execution
    page = lp.page
    record_down_and_up(page)
    flip(page, "SA1", True)
    tap_sb1(page)                                     # start, with I0.7 off: refused by the program
    why = page.get_by_role("status", name="why playback did not start")
    expect(why).to_have_text("SB1 pressed in automatic mode: the program started nothing (L1..L7 unchanged 1 s "
                             "after the release). It reads SA1 on (automatic), SA6 off (continuous), I0.7 off; "
                             "2 frame(s) recorded. Is one of them off that the program needs on?", timeout=WAIT)
    expect(page.locator("#actions")).to_contain_text("SB1 pressed in automatic mode: the program started nothing")
    page.screenshot(path=str(shots / "lab-mp9c-start.png"))
    expect(page.locator("#frames-status")).to_have_text("2 frame(s); stopped (next: frame 1)")
    flip(page, "I0.7", True)
    tap_sb1(page)                                     # now it starts
    expect(page.locator("#frames-status")).to_contain_text("executing frame", timeout=WAIT)
    expect(why).to_be_hidden()


TWO_LINES = "(two lines)\nG21 G90 G17\nG01 X10 Y0 F300\nY10\n"


def click_button(page, label: str) -> None:
    """A short click of a push button (pointer down, 100 ms, up)."""
    b = page.get_by_role("button", name=label, exact=True)
    b.hover()
    page.mouse.down()
    page.wait_for_timeout(100)
    page.mouse.up()


def path_points(page) -> int:
    return int(page.locator("#cnc-path").get_attribute("data-points") or 0)


def test_cnc_states_names_emergency_stop_missed_steps_and_the_path_after_a_reload(lab_page):
    lp = lab_page("cnc", speed=5)
    page = lp.page
    page.get_by_role("button", name="Load part program").click()
    frame = page.locator("#cnc-frame")
    expect(frame).to_have_text("frame 0 of 4 (square 20 mm, evaluation function, evalfn)", timeout=WAIT)
    click_button(page, "SB1")
    expect(frame).to_contain_text("frame 2 of 4", timeout=WAIT)
    click_button(page, "SB2")                                          # feed hold: said so, not "running"
    state = page.locator("#cnc-state")
    expect(state).to_have_text("feed hold (SB1 continues)", timeout=WAIT)
    cut = path_points(page)
    assert cut > 10
    page.reload()                                                      # the path cut so far is drawn again
    page.wait_for_selector("#plc-state[data-state='RUN']")
    page.wait_for_function(f"Number(document.querySelector('#cnc-path').dataset.points || 0) >= {cut}", timeout=WAIT)
    click_button(page, "SB1")                                          # continue to the end
    expect(state).to_have_text("program end", timeout=60_000)
    # a shorter part after it: its own name, and no frame number beyond its own frames
    page.get_by_label("part program").fill(TWO_LINES)
    page.get_by_role("button", name="Load part program").click()
    expect(frame).to_have_text("frame 0 of 2 (two lines, evalfn)", timeout=WAIT)
    # SB3 latches as a mushroom button does: pressed until pressed again
    sb3 = page.get_by_role("button", name="SB3", exact=True)
    sb3.click()
    expect(sb3).to_have_attribute("aria-pressed", "true", timeout=WAIT)
    on(lamp(page, "HL2"))
    t0 = plant_time(page)
    page.wait_for_function(f"parseFloat(document.querySelector('#clock').textContent.slice(4)) >= {t0 + 1}",
                           timeout=WAIT)
    expect(sb3).to_have_attribute("aria-pressed", "true")
    assert lp.lab.session.plant.console_bits["SB3"] == 0                # still pressed (normally closed: 0)
    sb3.click()
    expect(sb3).to_have_attribute("aria-pressed", "false", timeout=WAIT)
    # a drive that misses steps: counted for this part, and from 0 again once the fault is cleared
    page.get_by_label("fault", exact=True).select_option("slow_drive")
    page.get_by_label("axis").select_option("X")
    page.get_by_label("rate").fill("100")
    page.get_by_role("button", name="Inject").click()
    page.get_by_label("part program").fill("(square)\nG21 G90 G17\nG01 X20 Y0 F300\nY20\nX0\nY0\n")
    page.get_by_role("button", name="Load part program").click()
    expect(frame).to_have_text("frame 0 of 4 (square, evalfn)", timeout=WAIT)
    expect(page.locator("#cnc-missed")).to_have_text("missed steps X 0  Y 0  Z 0")
    click_button(page, "SB1")
    missed = page.locator("#cnc-missed")
    expect(missed).to_contain_text(re.compile(r"missed steps X [1-9]"), timeout=WAIT)
    verdict = page.locator("#cnc-verdict")
    expect(verdict).to_have_text("OUT OF BOUND", timeout=WAIT)         # the steps lost: the path leaves the contour
    assert verdict.get_attribute("fill") == "#b91c1c"
    box, svg = verdict.bounding_box(), page.locator("#mimic").bounding_box()
    assert box["x"] + box["width"] <= svg["x"] + svg["width"], (box, svg)   # not clipped by the drawing's edge
    click_button(page, "SB2")
    page.get_by_role("button", name="Clear faults").click()
    expect(missed).to_have_text("missed steps X 0  Y 0  Z 0", timeout=WAIT)


def test_a_fault_line_leads_to_its_statement_and_says_what_next_and_a_grade_survives_a_reload(lab_page):
    from test_page import FAULTY
    lp = lab_page("mp9c", speed=2)
    page = lp.page
    page.get_by_label("Load ST files").set_input_files(
        files=[{"name": "faulty.st", "mimeType": "text/plain", "buffer": FAULTY.encode()}])
    expect(page.locator("#plc-state")).to_have_text("FAULT", timeout=WAIT)
    detail = page.locator("#fault-detail")
    expect(detail).to_contain_text("Next: correct the program and load it again, or Restart PLC")
    opener = detail.get_by_role("button", name="open faulty.st:4 in Program online")
    expect(opener).to_have_css("text-decoration-line", "underline")          # it looks like the link it is
    opener.click()
    expect(page.get_by_label("POU", exact=True)).to_have_value("Faulty", timeout=WAIT)
    expect(page.locator("#src-4")).to_have_class(re.compile(r"\btarget-line\b"))
    page.get_by_role("button", name="Grade task1").click()
    table = page.get_by_role("table", name="grade task1")
    expect(table).to_be_visible(timeout=120_000)
    unchecked = table.locator("tr", has=page.locator("td", has_text="NOT CHECKED")).first
    expect(unchecked).to_contain_text("not checked: the scenario stopped first: the PLC stopped with a runtime fault")
    # a row's link to the program says the values there are live, and shows the graded run's
    g1 = table.locator("tbody tr").filter(has=page.get_by_role("cell", name="G1", exact=True))
    expect(g1).to_contain_text(re.compile(r"the graded run \(\w+\) at t = 0\.20 s: SA1=0 .*SB1=0 .*L1=0"))
    g1.get_by_role("button", name="open faulty.st:4").click()
    note = page.get_by_role("status", name="graded run")
    expect(note).to_contain_text(re.compile(r"Opened from grade row G1: the values beside the source are the graded "
                                            r"run \(\w+\) at t = 0\.20 s, not the lab's live ones\. The graded run \("),
                                 timeout=WAIT)
    rows = table.locator("tbody tr").count()
    page.reload()                                                            # the lab keeps the last grade
    page.wait_for_selector("#plc-state[data-state='FAULT']")
    table = page.get_by_role("table", name="grade task1")
    expect(table.locator("tbody tr")).to_have_count(rows, timeout=WAIT)
    expect(page.locator("#grade-message")).to_contain_text("requirements passed: FAIL (program: faulty.st)")


# counts its 10-ms scans and divides by zero once SA5 is on: the graded run faults when its
# scenario first sets SA5; the lab, where SA5 stays off, runs on
WATCHED = """PROGRAM Watched
VAR sa5 AT %IX1.4 : BOOL; END_VAR
VAR n : INT; d : INT; k : INT; END_VAR
n := n + 1;
IF sa5 THEN k := n / d; END_IF;
END_PROGRAM
CONFIGURATION Config0
    RESOURCE Res0 ON PLC
        TASK t (INTERVAL := T#10ms, PRIORITY := 0);
        PROGRAM Main WITH t : Watched;
    END_RESOURCE
END_CONFIGURATION
"""


def load(page, name: str, text: str) -> None:
    page.get_by_label("Load ST files").set_input_files(files=[{"name": name, "mimeType": "text/plain",
                                                                "buffer": text.encode()}])
    expect(page.locator("#program-message")).to_have_text(f"program loaded: {name}", timeout=WAIT)


def test_a_grade_rows_link_shows_the_graded_runs_values_at_the_rows_time_not_the_live_ones(lab_page):
    lp = lab_page("mp9c", speed=2)
    page = lp.page
    load(page, "watched.st", WATCHED)
    page.get_by_role("button", name="Grade task1").click()
    table = page.get_by_role("table", name="grade task1")
    expect(table).to_be_visible(timeout=120_000)
    g1 = table.locator("tbody tr").filter(has=page.get_by_role("cell", name="G1", exact=True))
    expect(g1).to_contain_text("watched.st:5: PLC FAULT (division_by_zero) in Watched")
    t = float(re.search(r"at t = ([\d.]+) s", g1.inner_text()).group(1))
    g1.get_by_role("button", name="open watched.st:5").click()
    note = page.get_by_role("status", name="graded run")
    expect(note).to_contain_text(f"Opened from grade row G1: the values beside the source are the graded run "
                                 f"(manual) at t = {t:.2f} s, not the lab's live ones.", timeout=WAIT)
    source = page.get_by_label("program source")
    expect(source).to_have_attribute("data-graded", "true")
    sa5 = source.locator('li[data-text^="IF sa5"]').get_by_label("value of sa5")
    n = source.locator('li[data-text^="n := n + 1;"]').get_by_label("value of n").first
    expect(sa5).to_have_text("TRUE")                  # the graded run's SA5, on when it faulted (the lab's is off)
    expect(sa5).to_have_attribute("title", f"value in the graded run (manual) at t = {t:.2f} s")
    counted = int(n.inner_text())
    assert abs(counted - (round(t / 0.01) + 1)) <= 1, (counted, t)     # its scans up to t, within one scan
    let_time_pass(page, 1.0)                          # the lab runs on; the graded run's moment does not
    expect(n).to_have_text(str(counted))
    expect(sa5).to_have_text("TRUE")
    # back to the lab: live values, moving
    note.get_by_role("button", name="Show live values").click()
    expect(note).to_be_hidden()
    expect(sa5).to_have_text("FALSE", timeout=WAIT)
    live = n.inner_text()
    let_time_pass(page, 0.5)
    expect(n).not_to_have_text(live, timeout=WAIT)
    # another program loaded since the grade: its run cannot be shown, and no live value stands in
    load(page, "watched.st", WATCHED.replace("n := n + 1;", "n := n + 1; (* changed *)"))
    expect(source.locator('li[data-text="n := n + 1; (* changed *)"]')).to_have_count(1, timeout=WAIT)
    g1.get_by_role("button", name="open watched.st:5").click()
    expect(note).to_contain_text("Opened from grade row G1: the values of the graded run (manual) at "
                                 f"t = {t:.2f} s are not available (the lab runs another program than the one "
                                 "graded: grade again to see its run); none are shown beside the source.",
                                 timeout=WAIT)
    expect(sa5).to_have_text("?")
    let_time_pass(page, 0.5)
    expect(n).to_have_text("?")


def test_header_words_paused_badge_plant_events_tooltips_and_a_forced_switch(lab_page):
    lp = lab_page("tur10", speed=1)
    page = lp.page
    fwd = page.get_by_role("button", name="SA1 forward", exact=True)
    fwd.hover()
    page.mouse.down()
    expect(fwd).to_have_attribute("aria-pressed", "true")
    expect(page.locator("#mimic")).to_be_visible()
    page.wait_for_function("document.querySelector('#dac-1').textContent !== 'DAC 0'", timeout=WAIT)
    expect(page.locator("#speed-shown")).to_have_text("x1")             # at x1 nothing else to say
    page.mouse.up()
    # what a student does not know is explained where it shows
    tips = page.locator("#mimic title").all_text_contents()
    assert any("the raceme is the robot's wrist" in t for t in tips), tips
    assert any(t.startswith("the sensor bus: the five position sensors share one set of PLC inputs") for t in tips), tips
    # paused: the badge says so too
    page.get_by_role("button", name="Pause").click()
    expect(page.locator("#plc-state")).to_have_text("RUN, paused", timeout=WAIT)
    expect(page.locator("#plc-state")).to_have_attribute("data-state", "PAUSED")
    page.get_by_role("button", name="Run").click()
    expect(page.locator("#plc-state")).to_have_text("RUN", timeout=WAIT)
    # a plant fault in words
    page.get_by_label("fault", exact=True).select_option("stuck_drive")
    page.get_by_label("axis").select_option("2")
    page.get_by_role("button", name="Inject").click()
    expect(page.locator("#events")).to_contain_text("fault injected: stuck_drive (axis 2)", timeout=WAIT)
    expect(page.locator("#actions")).to_contain_text("fault injected: stuck_drive (axis 2)")
    assert "{" not in page.locator("#events").inner_text() + page.locator("#actions").inner_text()
    # a forced switch shows the value the PLC reads, marked forced
    sa7 = switch(page, "SA7")
    expect(sa7).to_have_attribute("aria-checked", "false")
    lab = lp.lab
    address = lab.session.labels["SA7"]
    lab.call(lambda: lab.force(address, "TRUE")).result(10)
    expect(sa7).to_have_attribute("aria-checked", "true", timeout=WAIT)
    expect(sa7).to_contain_text("forced")
    expect(sa7).to_have_attribute("title", re.compile(r"SA7 forced to on"))
    lab.call(lambda: lab.unforce(None)).result(10)
    expect(sa7).to_have_attribute("aria-checked", "false", timeout=WAIT)
    expect(sa7).not_to_contain_text("forced")


def test_a_forced_push_button_is_drawn_pressed_as_the_plc_reads_it_and_marked_forced(lab_page):
    lp = lab_page("tur10", speed=1)
    page, lab = lp.page, lp.lab
    for label in ("SB1", "SA1 forward"):
        button = page.get_by_role("button", name=label, exact=True)
        expect(button).to_have_attribute("aria-pressed", "false")
        address = lab.session.labels[lab.panel.control(label).signal]
        lab.call(lambda: lab.force(address, "TRUE")).result(10)
        expect(button).to_have_attribute("aria-pressed", "true", timeout=WAIT)     # the PLC reads it pressed
        expect(button).to_contain_text("forced")
        expect(button).to_have_attribute("title", f"{label} forced to pressed (watch and force table): "
                                                  "the PLC reads this, not the button")
        expect(button).to_have_attribute("data-forced", "true")                     # the orange frame, as a switch
        lab.call(lambda: lab.unforce(None)).result(10)
        expect(button).to_have_attribute("aria-pressed", "false", timeout=WAIT)
        expect(button).not_to_contain_text("forced")
    # a press of the pointer still shows while nothing is forced
    sb1 = page.get_by_role("button", name="SB1", exact=True)
    sb1.hover()
    page.mouse.down()
    expect(sb1).to_have_attribute("aria-pressed", "true")
    page.mouse.up()
    expect(sb1).to_have_attribute("aria-pressed", "false")


def test_a_forced_emergency_stop_shows_pressed_when_its_normally_closed_contact_reads_open(tmp_path):
    from plclab.lab.engine import Lab
    lab = Lab("cnc", work_dir=tmp_path)
    s = lab.session
    s.run(s.tick)
    address = s.labels[lab.panel.control("SB3").signal]
    assert lab.snapshot()["io"]["SB3"] == 0                     # released: its contact closed, reads 1
    lab.force(address, "FALSE")                                  # the PLC reads the contact open: pressed
    s.run(s.tick)
    snap = lab.snapshot()
    assert snap["forced_labels"] == ["SB3"] and snap["io"]["SB3"] == 1
    lab.force(address, "TRUE")
    s.run(s.tick)
    assert lab.snapshot()["io"]["SB3"] == 0
    lab.stop()


def test_cnc_interpolation_methods_are_explained(lab_page):
    page = lab_page("cnc", speed=5).page
    titles = page.locator("#part-method option").evaluate_all("os => os.map((o) => o.title)")
    assert titles[0].startswith("evalfn: the evaluation-function method") and titles[1].startswith("dda: the digital"), titles
    expect(page.locator("#hold-note")).to_contain_text("SB3, the emergency stop, is a mushroom button")
    expect(page.locator("#hold-note")).not_to_contain_text("3-s hold")


ORANGE_PIXELS = """(name) => {
  const c = document.querySelector(`canvas[data-trend="${name}"]`);
  const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
  let n = 0;
  for (let i = 0; i < d.length; i += 4) if (d[i] > 200 && d[i + 1] > 60 && d[i + 1] < 120 && d[i + 2] < 60 && d[i + 3] > 96) n++;
  return n;
}"""


def test_thermo_modes_by_name_mode_and_setpoint_on_the_drawing_and_the_setpoint_over_the_temperature(lab_page):
    lp = lab_page("thermo", speed=5)
    page = lp.page
    mode = page.get_by_label("new value of %MW0")
    assert mode.locator("option").all_text_contents() == ["0 manual", "1 automatic-1", "2 automatic-2"]
    expect(page.get_by_label("value of %MW0", exact=True)).to_have_text("0 (manual)", timeout=WAIT)
    expect(page.locator("#thermo-mode")).to_have_text("mode %MW0 = 0, manual: %MW1 / %MW2 set the fan and the heater")
    expect(page.locator("#thermo-setpoint")).to_have_text("setpoint 40 \u00b0C")
    mode.select_option("1")
    page.get_by_role("button", name="write %MW0").click()
    expect(page.get_by_label("value of %MW0", exact=True)).to_have_text("1 (automatic-1)", timeout=WAIT)
    expect(page.locator("#thermo-mode")).to_have_text("mode %MW0 = 1, automatic-1: the heater regulates to the setpoint",
                                                      timeout=WAIT)
    page.get_by_label("new value of %MW6").fill("55")
    page.get_by_role("button", name="write %MW6").click()
    expect(page.locator("#thermo-setpoint")).to_have_text("setpoint 55 \u00b0C", timeout=WAIT)
    # the raw ADC trended in degC, the setpoint drawn over it on the same scale
    expect(page.locator('#trend-list .name[title="TEMP_ADC"]')).to_have_text("TEMP_ADC (\u00b0C) + SETPOINT")
    page.wait_for_function(f"({ORANGE_PIXELS})('TEMP_ADC') > 20", timeout=WAIT)


def press_sb1(lab) -> None:
    """SB1 on the engine (no page): held 0.3 s of plant time, then 1.5 s more run."""
    lab.press("SB1", True)
    lab.advance(0.3)
    lab.press("SB1", False)
    lab.advance(1.5)


def test_a_press_that_stops_playback_is_not_called_a_refused_start(tmp_path):
    from plclab.lab.engine import Lab
    lab = Lab("mp9c", variant="baseline", work_dir=tmp_path)
    s = lab.session
    s.run(s.tick)
    lab.set_control("SA5", 1)
    lab.advance(2.0)
    press_sb1(lab)                                             # frame 1: arm down
    lab.set_control("SA5", 0)
    lab.advance(2.0)
    press_sb1(lab)                                             # frame 2: arm up
    lab.set_control("SA1", 1)
    lab.advance(0.5)
    press_sb1(lab)                                             # start: playback runs
    assert s.value("Running") and lab.start_refused is None
    press_sb1(lab)                                             # stop: nothing to explain
    assert not s.value("Running") and lab.start_refused is None
    lab.stop()


def test_tur10_a_refused_start_names_its_mode_switches_and_spare_input(tmp_path):
    from plclab.lab.engine import Lab
    lab = Lab("tur10", variant="full", work_dir=tmp_path)     # Task 3: I1.5 enables automatic execution
    s = lab.session
    s.run(s.tick)
    lab.advance(1.0)
    press_sb1(lab)                                             # frame 1: where the links are
    lab.press("SA1 forward", True)
    lab.advance(1.0)
    lab.press("SA1 forward", False)
    lab.advance(0.5)
    press_sb1(lab)                                             # frame 2: link 1 further forward
    lab.set_control("SA7", 1)
    lab.advance(0.5)
    press_sb1(lab)
    assert lab.start_refused == ("SB1 pressed in automatic mode: the program started nothing (DRIVE1..DRIVE5 unchanged "
                                 "1 s after the release). It reads SA7 on (automatic), SA6 off (normal speed), I1.5 off; "
                                 "2 frame(s) recorded. Is one of them off that the program needs on?")
    lab.set_control("I1.5", 1)
    lab.advance(0.5)
    press_sb1(lab)                                             # now it starts: nothing to explain
    assert lab.start_refused is None
    lab.stop()
