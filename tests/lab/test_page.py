"""The virtual lab page in a real browser: what a student sees and does.

Controls are found the way a screen reader finds them (role + accessible name = console
label), lamps and limit switches by aria-label and data-state. Waits are on what the page
shows (states, plant time), bounded; durations are checked on the virtual-time trace.
"""
from __future__ import annotations

import csv
import io
import re

import pytest
from playwright.sync_api import expect

from plclab.modbus.rawclient import RawModbusClient

WAIT = 20_000          # ms: an upper bound on any wait for a state (a loaded 2-core machine)


def switch(page, label: str):
    return page.get_by_role("switch", name=label, exact=True)


def lamp(page, label: str):
    return page.locator(f'[aria-label="{label}"][data-state]')


def plant_time(page) -> float:
    return float(re.search(r"t = ([\d.]+) s", page.locator("#clock").inner_text()).group(1))


def let_time_pass(page, seconds: float) -> None:
    """Wait until the page shows `seconds` more of plant time."""
    until = plant_time(page) + seconds
    page.wait_for_function(f"parseFloat(document.querySelector('#clock').textContent.slice(4)) >= {until}",
                           timeout=WAIT)


def flip(page, label: str, on: bool) -> None:
    sw = switch(page, label)
    if (sw.get_attribute("aria-checked") == "true") != on:
        sw.click()
    expect(sw).to_have_attribute("aria-checked", "true" if on else "false", timeout=WAIT)


def tap_sb1(page, seconds: float = 0.3, address: str = "%IX1.6") -> None:
    """A short press: pointer down, `seconds` of plant time after the stand saw the press,
    pointer up. The release waits for the press to show in the trace (a loaded machine may
    deliver it, or draw the clock, late), so the press lasts what the test says. The labs of
    these tests run at x2, so a press stays well under the 3 s of a reset."""
    sb1 = page.get_by_role("button", name="SB1", exact=True)
    presses_before = len(rising(trace_rows(page), address))
    sb1.hover()
    page.mouse.down()
    down = press_seen(page, address, presses_before)
    page.wait_for_function(f"parseFloat(document.querySelector('#clock').textContent.slice(4)) >= {down + seconds}",
                           timeout=WAIT)
    page.mouse.up()
    expect(sb1).to_have_attribute("aria-pressed", "false")
    let_time_pass(page, 0.1)
    rows = trace_rows(page)
    up = [t for t, n, v in rows if n == address and v == "0"][-1]
    assert 0.05 < up - down < 3.0, f"the tap lasted {up - down:.2f} s of plant time (the machine was too slow)"


def press_seen(page, address: str, presses_before: int) -> float:
    """The plant time at which the stand's trace shows the newest rising edge of `address`,
    waiting (bounded) for it to appear."""
    for _ in range(200):
        edges = rising(trace_rows(page), address)
        if len(edges) > presses_before:
            return edges[-1]
        page.wait_for_timeout(100)
    raise AssertionError(f"the press of {address} never reached the stand's trace")


def on(locator) -> None:
    expect(locator).to_have_attribute("data-state", "on", timeout=WAIT)


def off(locator) -> None:
    expect(locator).to_have_attribute("data-state", "off", timeout=WAIT)


def trace_rows(page) -> list[tuple[float, str, str]]:
    text = page.request.get(page.url + "trace.csv").text()
    return [(float(r["time_s"]), r["name"], r["value"]) for r in csv.DictReader(io.StringIO(text))]


def rising(rows, name: str) -> list[float]:
    return [t for t, n, v in rows if n == name and v == "1" and t > 0]


# --------------------------------------------------------------------------- power-up

def test_mp9c_power_up_state(lab_page, shots):
    page = lab_page("mp9c").page
    for label in ("SA1", "SA2", "SA3", "SA4", "SA5", "SA6", "I0.7"):
        expect(switch(page, label)).to_have_attribute("aria-checked", "false")
    expect(page.get_by_role("button", name="SB1", exact=True)).to_be_visible()
    for label in ("SQ1", "SQ3", "SQ4", "SQ7"):          # up, released, left, backward
        on(lamp(page, label))
    for label in ("SQ2", "SQ5", "SQ6"):
        off(lamp(page, label))
    on(lamp(page, "HL1"))                                 # no frame recorded yet
    for label in ("L2", "L4", "L7"):                      # manual mode: the valves follow the switches
        on(lamp(page, label))
    for label in ("L1", "L3", "L5", "L6"):
        off(lamp(page, label))
    expect(page.locator("#plc-state")).to_have_text("RUN")
    page.screenshot(path=str(shots / "lab-mp9c-power-up.png"))


def test_tur10_power_up_state(lab_page, shots):
    page = lab_page("tur10").page
    for k in range(1, 6):
        for way in ("forward", "backward"):       # jog push buttons, as on the stand
            expect(page.get_by_role("button", name=f"SA{k} {way}", exact=True)).to_have_attribute("aria-pressed", "false")
    for label in ("SA6", "SA7", "I1.5"):
        expect(switch(page, label)).to_have_attribute("aria-checked", "false")
    on(lamp(page, "HL1"))
    expect(page.locator("#mimic")).to_contain_text("code 16000")
    page.screenshot(path=str(shots / "lab-tur10-power-up.png"))


def test_thermo_power_up_state(lab_page, shots):
    page = lab_page("thermo").page
    expect(switch(page, "DISTURBANCE")).to_have_attribute("aria-checked", "false")
    expect(page.get_by_label("value of %MW0", exact=True)).to_have_text("0 (manual)", timeout=WAIT)   # manual mode
    expect(page.get_by_label("value of %MW3", exact=True)).to_have_text("22", timeout=WAIT)      # ambient
    expect(page.get_by_label("value of %MW6", exact=True)).to_have_text("40", timeout=WAIT)      # setpoint
    expect(page.locator("#mimic")).to_contain_text("22.0 \u00b0C")
    page.screenshot(path=str(shots / "lab-thermo-power-up.png"))


# --------------------------------------------------------------------------- MP-9C console

def test_the_page_draws_the_newest_state_at_most_25_times_a_second(lab_page):
    """The page is drawn with the newest state it has, at most once every 40 ms: drawing at
    the display's rate cost the browser most of a core for nothing the eye sees. The
    stand's states may come faster (40 a second at x5, 100 at x1); each drawing shows the last."""
    page = lab_page("mp9c").page
    page.evaluate("""() => {
        window.__draws = [];
        const draw = window.render;
        window.render = (s) => {
            const at = performance.now();
            draw(s);
            window.__draws.push({at, shown: document.querySelector('#clock').textContent,
                                 newest: `t = ${lab.state.t.toFixed(2)} s`, drawn: s === lab.state});
        };
    }""")
    page.wait_for_function("window.__draws.length >= 12", timeout=WAIT)
    draws = page.evaluate("window.__draws")
    gaps = [b["at"] - a["at"] for a, b in zip(draws, draws[1:])]
    assert min(gaps) >= 39, f"drawn {min(gaps):.1f} ms after the drawing before"
    assert all(d["drawn"] and d["shown"] == d["newest"] for d in draws), draws
    assert len({d["shown"] for d in draws}) == len(draws)          # the stand ran on between drawings


def test_mp9c_short_press_records_a_frame_and_a_3s_hold_resets(lab_page):
    lp = lab_page("mp9c", speed=2)
    page = lp.page
    flip(page, "SA5", True)                               # manual mode: arm down
    on(lamp(page, "SQ2"))
    on(lamp(page, "HL1"))
    tap_sb1(page)                                         # a short press records a frame
    off(lamp(page, "HL1"))
    assert lp.lab.session.plc.read("Main.Cp.Count") == 1
    # a 3 s hold (space key on the focused button) resets: HL1 on again while still held
    page.get_by_role("button", name="SB1", exact=True).focus()
    page.keyboard.down(" ")
    on(lamp(page, "HL1"))
    page.keyboard.up(" ")
    expect(page.get_by_role("button", name="SB1", exact=True)).to_have_attribute("aria-pressed", "false")
    rows = trace_rows(page)
    press = rising(rows, "%IX1.6")[-1]                    # SB1
    reset = rising(rows, "%QX1.0")[-1]                    # HL1
    assert abs((reset - press) - 3.0) <= 0.02, f"reset {reset - press:.3f} s after the press, expected 3.0 s"
    assert lp.lab.session.plc.read("Main.Cp.Count") == 0


def test_mp9c_playback_moves_the_mimic(lab_page, shots):
    page = lab_page("mp9c", speed=2).page
    flip(page, "SA5", True)
    on(lamp(page, "SQ2"))
    tap_sb1(page)                                         # frame 1: arm down
    off(lamp(page, "HL1"))
    flip(page, "SA5", False)
    on(lamp(page, "SQ1"))
    tap_sb1(page)                                         # frame 2: arm up
    flip(page, "I0.7", True)                              # Task 3: I0.7 enables automatic execution
    flip(page, "SA1", True)                               # automatic
    lift = page.locator("#mimic-lift")
    up = lift.get_attribute("transform")
    tap_sb1(page)                                         # start
    on(lamp(page, "L3"))                                  # frame 1 drives the arm down ...
    expect(lift).not_to_have_attribute("transform", up, timeout=WAIT)     # ... and the drawing moves
    on(lamp(page, "SQ2"))
    page.screenshot(path=str(shots / "lab-mp9c.png"))
    on(lamp(page, "SQ1"))                                 # frame 2: back up, by itself
    on(lamp(page, "SQ2"))                                 # continuous: frame 1 again


def test_injected_plant_fault_appears(lab_page):
    page = lab_page("mp9c", speed=5).page
    page.get_by_label("fault", exact=True).select_option("jammed")
    page.get_by_label("mechanism").select_option("lift")
    page.get_by_role("button", name="Inject").click()
    expect(page.locator("#events")).to_contain_text("fault injected: jammed", timeout=WAIT)
    expect(page.locator("#mimic")).to_contain_text("injected: jammed")
    flip(page, "SA5", True)
    on(lamp(page, "L3"))                                  # the valve is told to go down ...
    let_time_pass(page, 2.0)
    on(lamp(page, "SQ1"))                                 # ... the jammed arm stays up
    off(lamp(page, "SQ2"))
    page.get_by_role("button", name="Clear faults").click()
    on(lamp(page, "SQ2"))
    expect(page.locator("#mimic")).not_to_contain_text("injected:")


# --------------------------------------------------------------------------- program

BAD = """PROGRAM Broken
VAR x : BOOL; END_VAR
x := TRUE
IF x THEN x := FALSE; END_IF;
END_PROGRAM
"""


def test_program_with_a_syntax_error_shows_its_line(lab_page):
    lp = lab_page("mp9c", speed=2)
    page = lp.page
    page.get_by_label("Load ST files").set_input_files(
        files=[{"name": "broken.st", "mimeType": "text/plain", "buffer": BAD.encode()}])
    errors = page.get_by_label("check errors")
    expect(errors).to_contain_text(re.compile(r"broken\.st:4:\d+: error: "), timeout=WAIT)
    expect(errors.locator("pre")).to_contain_text("IF x THEN x := FALSE; END_IF;")
    expect(page.locator("#program-message")).to_contain_text("keeps the program it runs")
    # not UTF-8: one line, with where the bad byte is
    page.get_by_label("Load ST files").set_input_files(
        files=[{"name": "latin1.st", "mimeType": "text/plain", "buffer": "(* d\xe9j\xe0 *)".encode("latin-1")}])
    expect(page.locator("#program-message")).to_contain_text("latin1.st:1:5: error: not UTF-8 text", timeout=WAIT)
    expect(page.locator("#plc-state")).to_have_text("RUN")
    expect(page.locator("#program-name")).to_have_text("full (shipped)")


FAULTY = """PROGRAM Faulty
VAR n : INT; d : INT; END_VAR
n := n + 1;
IF n > 20 THEN n := 10 / d; END_IF;
END_PROGRAM
CONFIGURATION Config0
    RESOURCE Res0 ON PLC
        TASK t (INTERVAL := T#10ms, PRIORITY := 0);
        PROGRAM Main WITH t : Faulty;
    END_RESOURCE
END_CONFIGURATION
"""


def test_a_program_that_faults_shows_fault_with_its_pou_file_and_line(lab_page):
    page = lab_page("mp9c", speed=2).page
    page.get_by_label("Load ST files").set_input_files(
        files=[{"name": "faulty.st", "mimeType": "text/plain", "buffer": FAULTY.encode()}])
    expect(page.locator("#program-message")).to_have_text("program loaded: faulty.st", timeout=WAIT)
    expect(page.locator("#plc-state")).to_have_text("FAULT", timeout=WAIT)
    detail = page.locator("#fault-detail")
    expect(detail).to_contain_text("faulty.st:4: PLC FAULT (division_by_zero) in Faulty")
    for label in ("L2", "L4", "L7", "HL1"):               # a faulted PLC: every output off
        off(lamp(page, label))
    page.get_by_role("button", name="Restart PLC").click()      # runs again, faults again 20 scans later
    expect(page.locator("#actions")).to_contain_text(re.compile(r"t=[\d.]+ s PLC restarted"), timeout=WAIT)
    expect(page.locator("#plc-state")).to_have_text("FAULT", timeout=WAIT)
    # the fault's time is on the header's clock (the PLC's own restarts at 0): 0.2 s after the restart
    expect(detail).to_contain_text("faulty.st:4: PLC FAULT (division_by_zero) in Faulty at t=")
    restarted = float(re.search(r"t=([\d.]+) s PLC restarted", page.locator("#actions").inner_text()).group(1))
    faulted = float(re.search(r"in Faulty at t=([\d.]+) s", detail.inner_text()).group(1))
    assert abs(faulted - restarted - 0.2) <= 0.011, (restarted, faulted)
    assert plant_time(page) >= faulted


def test_grade_shows_a_table(lab_page):
    page = lab_page("mp9c", speed=2, variant="baseline").page
    page.get_by_role("button", name="Grade task1").click()
    table = page.get_by_role("table", name="grade task1")
    expect(table).to_be_visible(timeout=120_000)
    fail = table.locator("tr", has=page.locator("td.FAIL")).first
    expect(fail).to_contain_text("expected:")
    expect(fail).to_contain_text("observed:")
    expect(fail.get_by_role("link").first).to_have_attribute("href", re.compile(r"^/grade/1-task1/.+\.(csv|vcd)$"))
    expect(page.locator("#grade-message")).to_contain_text("requirements passed: FAIL")
    assert ".:" not in page.locator("#grade-message").inner_text()          # the title, then its summary


def test_the_page_lists_what_each_task_checks_before_grading(lab_page):
    """A student opens "What task2 checks" and reads the requirement rows the grade will have."""
    from plclab.grader import requirement_table

    page = lab_page("mp9c", speed=2, variant="baseline").page
    page.get_by_text("What task2 checks").click()
    table = page.get_by_role("table", name="requirements task2")
    expect(table).to_be_visible(timeout=WAIT)
    cells = table.locator("tbody tr").evaluate_all("rows => rows.map(r => [...r.cells].map(c => c.textContent))")
    assert [tuple(c) for c in cells] == requirement_table("mp9c", "task2")
    expect(page.get_by_text("What task3 checks")).to_be_visible()


# --------------------------------------------------------------------------- thermo SCADA

def test_thermo_registers_refuse_like_the_twido_face_which_stays_up(lab_page, shots):
    lp = lab_page("thermo", speed=10)
    page = lp.page
    page.get_by_role("combobox", name="speed").select_option("10")
    page.get_by_label("new value of %MW0").select_option("1")             # automatic-1, chosen by name
    page.get_by_role("button", name="write %MW0").click()
    expect(page.get_by_label("value of %MW0", exact=True)).to_have_text("1 (automatic-1)", timeout=WAIT)
    page.get_by_label("new value of %MW2").fill("1500")                   # heater: manual mode only
    page.get_by_role("button", name="write %MW2").click()
    expect(page.locator("#register-message")).to_contain_text(
        "exception 03 (illegal data value): %MW2 is writable only when %MW0 = 0", timeout=WAIT)
    page.get_by_label("new value of %MW6").fill("55")
    page.get_by_role("button", name="write %MW6").click()
    expect(page.get_by_label("value of %MW6", exact=True)).to_have_text("55", timeout=WAIT)
    # the Twido Modbus face serves the same registers to an external SCADA client
    with RawModbusClient("127.0.0.1", lp.server.modbus.port, timeout=5.0) as client:
        assert client.read_holding_registers(0, 7)[6] == 55
        client.write_register(6, 45)
    expect(page.get_by_label("value of %MW6", exact=True)).to_have_text("45", timeout=WAIT)
    # the disturbance switch on the console: in automatic-1 the fan runs at 500
    flip(page, "DISTURBANCE", True)
    expect(page.get_by_label("value of %MW1", exact=True)).to_have_text("500", timeout=WAIT)
    page.get_by_label("fault", exact=True).select_option("sensor_open")
    page.get_by_role("button", name="Inject").click()
    expect(page.get_by_label("value of %MW3", exact=True)).to_have_text("100", timeout=WAIT)
    expect(page.locator("#mimic")).to_contain_text("sensor open circuit")
    expect(page.get_by_label("value of %MW2", exact=True)).to_have_text("0", timeout=WAIT)        # heater off
    page.screenshot(path=str(shots / "lab-thermo.png"), full_page=True)


# --------------------------------------------------------------------------- two pages

def test_two_pages_see_the_same_stand_and_a_closed_page_lets_go(lab_page, shots):
    lp = lab_page("tur10", speed=5)
    first, second = lp.page, lp.open()
    flip(first, "SA7", True)                              # a switch from the first page ...
    expect(switch(second, "SA7")).to_have_attribute("aria-checked", "true", timeout=WAIT)
    flip(second, "SA7", False)                            # ... the second page has the last word
    expect(switch(first, "SA7")).to_have_attribute("aria-checked", "false", timeout=WAIT)
    second.get_by_role("button", name="SA1 forward", exact=True).hover()
    second.mouse.down()                                   # jog drive 1 from the second page
    expect(first.locator("#dac-1")).not_to_have_text("DAC 0", timeout=WAIT)     # the regulator drives it
    second.screenshot(path=str(shots / "lab-tur10.png"))
    second.mouse.up()
    # the first page holds SB1 and goes away: the button is let go, the second page goes on
    first.get_by_role("button", name="SB1", exact=True).hover()
    first.mouse.down()
    expect(second.locator("#actions")).to_contain_text("SB1 pressed", timeout=WAIT)
    first.close()
    expect(second.locator("#actions")).to_contain_text("SB1 released", timeout=WAIT)
    let_time_pass(second, 0.5)
    assert lp.lab.session.value("SB1") is False


@pytest.mark.parametrize("stand", ["mp9c", "tur10", "thermo"])
def test_drawing_the_same_state_again_writes_nothing_into_the_page(lab_page, stand):
    """The page is drawn 25 times a second and most of what it shows stays as it was: what is
    unchanged is not written again (an unchanged text or attribute written still has the
    browser restyle and repaint it, a sixth of an open page's CPU). So the state drawn once
    more changes nothing in the document. (The CNC page is left out: each of its states
    carries the path cut since the one before, which the drawing adds to its path.)"""
    page = lab_page(stand).page
    written = page.evaluate("""() => {
        render(lab.state);                          // now the page shows this very state
        const seen = new MutationObserver(() => {});
        seen.observe(document.documentElement, { subtree: true, childList: true, attributes: true, characterData: true });
        render(lab.state);
        render(lab.state);
        const records = seen.takeRecords();
        seen.disconnect();
        return records.map((r) => `${r.type} ${r.attributeName || ""} of ${r.target.id || r.target.nodeName}`);
    }""")
    assert written == []
