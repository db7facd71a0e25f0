"""The PLC's side in the page (issue 22, "Beyond"): the recorded program (the frames in the
PLC's frame memory, decoded, the frame being executed highlighted); the watch and force table;
online monitoring (the ST with live values beside each use, a fault's statement)."""
from __future__ import annotations

import json
import re

from playwright.sync_api import expect
from test_page import WAIT, flip, lamp, off, on, tap_sb1


def test_mp9c_recorded_program_table_decodes_the_frames_and_follows_playback(lab_page, shots):
    lp = lab_page("mp9c", speed=2)
    page = lp.page
    status = page.locator("#frames-status")
    expect(status).to_have_text("no frame recorded (a short SB1 press in manual mode records one)", timeout=WAIT)
    flip(page, "SA5", True)
    on(lamp(page, "SQ2"))
    tap_sb1(page)                                     # frame 1: arm down (I0.7 off: 0.5 s pause)
    flip(page, "SA5", False)
    on(lamp(page, "SQ1"))
    flip(page, "I0.7", True)
    tap_sb1(page)                                     # frame 2: arm up (I0.7 on: 3 s pause)
    table = page.get_by_role("table", name="recorded frames")
    expect(status).to_have_text("2 frame(s); stopped (next: frame 1)", timeout=WAIT)
    cells = table.locator("tbody tr").evaluate_all("rows => rows.map(r => [...r.cells].map(c => c.textContent))")
    assert cells == [
        ["1", "L3 arm down, L4 rotate left, L7 arm backward",
         "SQ2 arm down, SQ3 gripper released, SQ4 rotated left, SQ7 arm backward", "0.5 s"],
        ["2", "L2 arm up, L4 rotate left, L7 arm backward",
         "SQ1 arm up, SQ3 gripper released, SQ4 rotated left, SQ7 arm backward", "3 s"]], cells
    # the same words the PLC holds (Main.Cp.Frames[i].Data[1] = the valve byte, [2] the sensor byte)
    plc = lp.lab.session.plc
    assert [plc.read(f"Main.Cp.Frames[{i}].Data[{w}]") for i in (1, 2) for w in (1, 2)] == [76, 78, 74, 77]
    flip(page, "SA1", True)                           # automatic: start
    tap_sb1(page)
    current = table.locator("tr[aria-current='true']")
    expect(current).to_contain_text("L3 arm down", timeout=WAIT)          # frame 1 executing
    expect(status).to_have_text("2 frame(s); executing frame 1")
    on(lamp(page, "SQ2"))
    expect(current).to_contain_text("L2 arm up", timeout=WAIT)            # then frame 2
    expect(status).to_have_text("2 frame(s); executing frame 2")
    page.screenshot(path=str(shots / "lab-mp9c-frames.png"), full_page=True)


def test_watch_and_force_from_the_program_tree(lab_page, shots):
    lp = lab_page("mp9c", speed=2)
    page = lp.page
    page.get_by_role("button", name="Pick variables from the program").click()
    tree = page.get_by_label("program variables")
    tree.get_by_text("Main : PRG_Mp9cBaseline", exact=True).click()
    tree.get_by_text("Cp : ST_ControlProgram", exact=True).click()
    tree.get_by_role("button", name="watch Main.Cp.Count").click()
    tree.get_by_text("globals", exact=True).click()
    tree.get_by_role("button", name="watch SA5", exact=True).click()
    tree.get_by_role("button", name="watch L7", exact=True).click()
    table = page.get_by_role("table", name="watched variables")
    count = table.get_by_label("value of Main.Cp.Count", exact=True)
    expect(count).to_have_text("0", timeout=WAIT)
    expect(table.get_by_label("value of SA5", exact=True)).to_have_text("FALSE")
    # force an input: the program sees it (manual mode: the arm goes down), the console switch
    # shows the forced value the PLC reads, and SA5 is marked forced on the console and in the table
    page.get_by_label("force value of SA5").fill("TRUE")
    page.get_by_role("button", name="force SA5", exact=True).click()
    expect(table.get_by_label("value of SA5", exact=True)).to_have_text("TRUE (forced)", timeout=WAIT)
    on(lamp(page, "L3"))
    on(lamp(page, "SQ2"))
    expect(switch_(page, "SA5")).to_have_attribute("aria-checked", "true")
    expect(switch_(page, "SA5")).to_have_attribute("data-forced", "true")
    expect(page.get_by_label("forces")).to_have_text("1 forced")
    expect(page.locator("#actions")).to_contain_text("FORCE SA5 := TRUE")
    page.get_by_role("button", name="Show the program").click()          # the program online marks it too
    page.get_by_label("POU", exact=True).select_option("FB_Mp9cManual")
    use = page.get_by_label("program source").locator('li[data-text^="L3 := SA5;"]').get_by_label("value of SA5")
    expect(use).to_have_text("TRUE", timeout=WAIT)
    expect(use).to_have_attribute("data-forced", "true")
    # force an output: the valve coil stays off whatever the program says
    on(lamp(page, "L7"))
    page.get_by_label("force value of L7").fill("FALSE")
    page.get_by_role("button", name="force L7", exact=True).click()
    off(lamp(page, "L7"))
    expect(lamp(page, "L7")).to_have_attribute("data-forced", "true")
    expect(page.get_by_label("forces")).to_have_text("2 forced")
    page.screenshot(path=str(shots / "lab-mp9c-force.png"), full_page=True)
    # a value the type does not take: one line, nothing forced
    page.get_by_label("force value of Main.Cp.Count").fill("70000")
    page.get_by_role("button", name="force Main.Cp.Count", exact=True).click()
    expect(page.locator("#watch-message")).to_have_text("70000 is outside INT (-32768..32767)")
    expect(count).to_have_text("0")
    # release: the program has its inputs and outputs back
    page.get_by_role("button", name="release SA5", exact=True).click()
    expect(table.get_by_label("value of SA5", exact=True)).to_have_text("FALSE", timeout=WAIT)
    on(lamp(page, "SQ1"))
    expect(switch_(page, "SA5")).not_to_have_attribute("data-forced", "true")
    expect(switch_(page, "SA5")).to_have_attribute("aria-checked", "false")       # where the switch is
    page.get_by_role("button", name="Release all forces").click()
    on(lamp(page, "L7"))
    expect(page.get_by_label("forces")).to_have_text("")
    assert lp.lab.forces.values == {}


def switch_(page, label: str):
    return page.get_by_role("switch", name=label, exact=True)


def test_online_monitoring_shows_values_beside_their_use_and_a_fault_opens_its_statement(lab_page, shots):
    from test_page import FAULTY

    lp = lab_page("mp9c", speed=2)
    page = lp.page
    page.get_by_role("button", name="Show the program").click()
    page.get_by_label("POU", exact=True).select_option("FB_Mp9cManual")
    expect(page.get_by_label("instance", exact=True)).to_have_value("Main.Manual")
    source = page.get_by_label("program source")
    lift = source.locator('li[data-text^="L3 := SA5;"]')                  # the line as written ...
    expect(lift).to_have_count(1)
    sa5 = lift.get_by_label("value of SA5")                                # ... a value beside each use
    expect(sa5).to_have_text("FALSE", timeout=WAIT)
    flip(page, "SA5", True)
    expect(sa5).to_have_text("TRUE", timeout=WAIT)                         # live
    expect(lift.get_by_label("value of L3")).to_have_text("TRUE")
    expect(source.get_by_label("value of Cp.Count").first).to_have_text("0")
    page.screenshot(path=str(shots / "lab-mp9c-online.png"), full_page=True)
    # a program that faults: the fault opens its statement, the values as they were then
    page.get_by_label("Load ST files").set_input_files(
        files=[{"name": "faulty.st", "mimeType": "text/plain", "buffer": FAULTY.encode()}])
    expect(page.locator("#plc-state")).to_have_text("FAULT", timeout=WAIT)
    page.locator("#fault-detail").click()
    expect(page.get_by_label("POU", exact=True)).to_have_value("Faulty", timeout=WAIT)
    line = source.locator("#src-4")
    expect(line).to_have_class(re.compile(r"\bfault-line\b"))
    expect(line).to_have_class(re.compile(r"\btarget-line\b"))
    expect(line).to_have_attribute("data-text", "IF n > 20 THEN n := 10 / d; END_IF;")
    expect(line.get_by_label("value of n").first).to_have_text("21", timeout=WAIT)
    expect(line.get_by_label("value of d")).to_have_text("0")
    # a grade row naming the statement opens it too
    source.locator("#src-3").click()
    page.get_by_role("button", name="Grade task1").click()
    opener = page.get_by_role("button", name="open faulty.st:4", exact=True)
    expect(opener).to_be_visible(timeout=120_000)
    page.get_by_label("POU", exact=True).select_option("Faulty")
    opener.click()
    expect(line).to_have_class(re.compile(r"\btarget-line\b"), timeout=WAIT)


def test_online_monitoring_shows_an_indexed_use_s_element_as_the_program_records_and_plays(lab_page, shots):
    """`Cp.Frames[Cp.Count].Data[2]`: the element the live index names, the lab's own read of
    it; nothing while the index is out of range (no frame recorded: Cp.Count = 0)."""
    lp = lab_page("mp9c", speed=2)
    page, lab = lp.page, lp.lab

    def read(path: str):
        return lab.call(lambda: lab.session.plc.read(path)).result(10)

    page.get_by_role("button", name="Show the program").click()
    page.get_by_label("POU", exact=True).select_option("FB_Mp9cManual")
    source = page.get_by_label("program source")
    count = source.get_by_label("value of Cp.Count").first
    sensors = source.get_by_label("value of Cp.Frames[Cp.Count].Data[2]", exact=True)
    valves = source.get_by_label("value of Cp.Frames[Cp.Count].Data[1]", exact=True)
    expect(count).to_have_text("0", timeout=WAIT)
    expect(sensors).to_have_text("")                                # Frames[0]: out of range, nothing
    expect(sensors).to_be_hidden()
    flip(page, "SA5", True)
    on(lamp(page, "SQ2"))
    tap_sb1(page)                                                   # frame 1
    expect(count).to_have_text("1", timeout=WAIT)
    expect(sensors).to_have_text(str(read("Main.Cp.Frames[1].Data[2]")), timeout=WAIT)
    expect(valves).to_have_text(str(read("Main.Cp.Frames[1].Data[1]")))
    flip(page, "SA5", False)
    on(lamp(page, "SQ1"))
    flip(page, "I0.7", True)
    tap_sb1(page)                                                   # frame 2: other bytes
    expect(count).to_have_text("2", timeout=WAIT)
    assert read("Main.Cp.Frames[2].Data[2]") != read("Main.Cp.Frames[1].Data[2]")
    expect(sensors).to_have_text(str(read("Main.Cp.Frames[2].Data[2]")), timeout=WAIT)
    expect(valves).to_have_text(str(read("Main.Cp.Frames[2].Data[1]")))
    # playback: the frame the sequencer points at, as it moves
    page.get_by_label("POU", exact=True).select_option("FB_Mp9cAutomatic")
    playing = source.get_by_label("value of Cp.Frames[Sequencer.Ptr].Data[1]", exact=True)
    ptr = source.get_by_label("value of Sequencer.Ptr", exact=True).first
    status = page.locator("#frames-status")
    flip(page, "SA1", True)
    tap_sb1(page)
    expect(status).to_have_text("2 frame(s); executing frame 1", timeout=WAIT)
    expect(ptr).to_have_text("1", timeout=WAIT)
    expect(playing).to_have_text(str(read("Main.Cp.Frames[1].Data[1]")), timeout=WAIT)
    on(lamp(page, "SQ2"))
    expect(status).to_have_text("2 frame(s); executing frame 2", timeout=WAIT)
    expect(ptr).to_have_text("2", timeout=WAIT)
    expect(playing).to_have_text(str(read("Main.Cp.Frames[2].Data[1]")), timeout=WAIT)
    playing.scroll_into_view_if_needed()
    page.screenshot(path=str(shots / "lab-mp9c-online-indexed.png"), full_page=True)


def test_an_indexed_use_follows_its_index_and_is_marked_when_its_element_is_forced(lab_page):
    from test_monitor import PROGRAM

    lp = lab_page("mp9c", speed=2)
    page, lab = lp.page, lp.lab
    page.get_by_label("Load ST files").set_input_files(
        files=[{"name": "idx.st", "mimeType": "text/plain", "buffer": PROGRAM.encode()}])
    expect(page.locator("#program-message")).to_have_text("program loaded: idx.st", timeout=WAIT)
    page.get_by_role("button", name="Show the program").click()
    page.get_by_label("POU", exact=True).select_option("Idx")
    line = page.get_by_label("program source").locator('li[data-text^="x := Valves[i];"]')
    use = line.get_by_label("value of Valves[i]", exact=True)
    expect(use).to_have_text("20", timeout=WAIT)                       # i = 2
    lab.call(lambda: lab.force("Main.Valves[2]", "55")).result(10)
    expect(use).to_have_text("55", timeout=WAIT)
    expect(use).to_have_attribute("data-forced", "true")               # the element shown is forced
    lab.call(lambda: lab.force("Main.i", "3")).result(10)
    expect(use).to_have_text("30", timeout=WAIT)                       # another element: not forced
    expect(use).not_to_have_attribute("data-forced", "true")
    lab.call(lambda: lab.force("Main.i", "9")).result(10)              # out of range: nothing, no mark
    expect(use).to_have_text("", timeout=WAIT)
    expect(use).not_to_have_attribute("data-forced", "true")
    lab.call(lambda: lab.force("Main.i", "2")).result(10)
    expect(use).to_have_text("55", timeout=WAIT)
    expect(use).to_have_attribute("data-forced", "true")


def test_a_state_made_before_a_pick_and_drawn_after_its_reply_does_not_undo_the_pick(lab_page):
    """The page draws the newest state in an animation frame, so a state the lab made before
    a watch command can be drawn after the command's reply. Taken then for the lab's list, it
    made the next pick send the old list and drop the variable just picked (CI, under load:
    SA5's row vanished). Here the WebSocket is routed so that this happens every time: the
    last state made before Main.Cp.Count's pick is passed on together with the pick's reply,
    and newer states are held back while SA5 is picked."""
    lp = lab_page("mp9c", speed=2)
    held = {"on": False, "last": None, "replies": 0, "drawn": None}

    def route(page_side):
        lab_side = page_side.connect_to_server()

        def to_page(text):
            msg = json.loads(text)
            if held["on"] and msg["type"] == "state":
                held["last"] = text                    # made before the pick was done, or held back
                return
            if held["on"] and msg["type"] == "reply" and msg["op"] == "watch":
                if held["last"] and held["drawn"] is None:
                    page_side.send(held["last"])       # the older state, then the reply at once
                    held["drawn"] = json.loads(held["last"])["t"]
                held["replies"] += 1
            page_side.send(text)

        lab_side.on_message(to_page)
        page_side.on_message(lab_side.send)

    def replies(n):                                    # the page's WebSocket served meanwhile
        for _ in range(500):
            if held["replies"] >= n:
                return
            page.wait_for_timeout(20)
        raise AssertionError(f"the lab did not answer {n} watch command(s)")

    page = lp.context.new_page()
    page.set_default_timeout(20_000)
    page.route_web_socket(re.compile(r".*/ws\?.*"), route)
    page.goto(lp.url)
    page.wait_for_selector("#plc-state[data-state='RUN']")
    page.get_by_role("button", name="Pick variables from the program").click()
    tree = page.get_by_label("program variables")
    tree.get_by_text("Main : PRG_Mp9cBaseline", exact=True).click()
    tree.get_by_text("Cp : ST_ControlProgram", exact=True).click()
    held["on"] = True                                  # states from now on: made before the pick
    page.wait_for_timeout(100)
    tree.get_by_role("button", name="watch Main.Cp.Count").click()
    replies(1)
    assert held["drawn"] is not None, "no state came while the pick was on its way"
    expect(page.locator("#clock")).to_have_text(f"t = {held['drawn']:.2f} s", timeout=WAIT)   # drawn after the reply
    tree.get_by_text("globals", exact=True).click()
    tree.get_by_role("button", name="watch SA5", exact=True).click()
    replies(2)
    held["on"] = False
    rows = page.get_by_role("table", name="watched variables").locator("tbody tr")
    expect(rows).to_have_count(2, timeout=WAIT)
    assert rows.evaluate_all("rows => rows.map(r => r.dataset.path)") == ["Main.Cp.Count", "SA5"]
    assert lp.lab.watched == ["Main.Cp.Count", "SA5"]
