"""The page as the stand has it (issue 22, "Wrong against the stand"): TUR-10 jog push
buttons held by mouse, keyboard and touch; the TUR-10 targets during playback; SB1 at x50
(a click records, only a 3-s hold of the student's own time resets); a 390x844 phone.

Timing is checked on the plant-time trace; the only wall-clock waits are the student's own
holds (a 150 ms click), which is what these tests are about."""
from __future__ import annotations

from playwright.sync_api import expect
from test_page import WAIT, flip, lamp, let_time_pass, off, on, press_seen, rising, tap_sb1, trace_rows


def button(page, label: str):
    return page.get_by_role("button", name=label, exact=True)


def levels(lp, name: str) -> list[str]:
    """The levels a console input had in the downloaded trace (its address: %IX0.0 for SA1_FWD)."""
    address = lp.lab.session.labels[name]
    return [v for _t, n, v in trace_rows(lp.page) if n == address]


def test_tur10_jog_buttons_move_a_link_only_while_held(lab_page):
    lp = lab_page("tur10", speed=5)
    page = lp.page
    # mouse: held, the link moves (at x1 while held); the pointer leaves, the link stops
    fwd = button(page, "SA1 forward")
    fwd.hover()
    page.mouse.down()
    expect(fwd).to_have_attribute("aria-pressed", "true")
    expect(page.locator("#speed-shown")).to_have_text("x1 while SA1 forward held (then x5)", timeout=WAIT)
    expect(page.locator("#dac-1")).not_to_have_text("DAC 0", timeout=WAIT)
    page.mouse.move(5, 5)                                   # off the button: let go
    expect(fwd).to_have_attribute("aria-pressed", "false")
    page.mouse.up()
    expect(page.locator("#dac-1")).to_have_text("DAC 0", timeout=WAIT)    # the drive stops
    expect(page.locator("#speed-shown")).to_have_text("x5", timeout=WAIT)
    let_time_pass(page, 0.5)
    code = int(page.locator("#code-1").text_content().split()[1])
    let_time_pass(page, 1.0)
    drift = int(page.locator("#code-1").text_content().split()[1]) - code
    assert abs(drift) <= 3, f"link 1 moved on {drift} codes in 1 s after its button was let go"
    assert code - 16000 > 100, code                         # it had moved while held
    # the robot drawn as it stands: the shoulder's angle follows link 1's position code
    # (-60 deg at the lower stop, code 1000, to +60 deg at the upper, 31000), the rest at mid travel
    drawn = page.evaluate("""() => ({code: document.querySelector('#code-1').textContent,
        shoulder: document.querySelector('#robot-shoulder').dataset.angle,
        elbow: document.querySelector('#robot-elbow').dataset.angle,
        platform: document.querySelector('#robot-platform').dataset.angle})""")
    code_now = int(drawn["code"].split()[1])
    assert abs(float(drawn["shoulder"]) - (-60 + 120 * (code_now - 1000) / 30000)) < 0.01, drawn
    assert float(drawn["shoulder"]) > 0.4 and float(drawn["elbow"]) == 0 and float(drawn["platform"]) == 0, drawn
    assert levels(lp, "SA1_FWD")[-2:] == ["1", "0"]
    # keyboard: space holds, the focus moving away lets go
    bwd = button(page, "SA2 backward")
    bwd.focus()
    page.keyboard.down(" ")
    expect(bwd).to_have_attribute("aria-pressed", "true")
    expect(page.locator("#dac-2")).not_to_have_text("DAC 0", timeout=WAIT)
    page.keyboard.press("Tab")
    expect(bwd).to_have_attribute("aria-pressed", "false")
    page.keyboard.up(" ")
    expect(page.locator("#dac-2")).to_have_text("DAC 0", timeout=WAIT)
    # touch: a finger holds; a cancelled touch (the browser took the gesture) lets go
    three = button(page, "SA3 forward")
    three.dispatch_event("pointerdown", {"pointerType": "touch", "button": 0, "isPrimary": True})
    expect(three).to_have_attribute("aria-pressed", "true")
    expect(page.locator("#dac-3")).not_to_have_text("DAC 0", timeout=WAIT)
    three.dispatch_event("pointercancel", {"pointerType": "touch"})
    expect(three).to_have_attribute("aria-pressed", "false")
    # the window losing the focus (another application) lets go of what the mouse holds
    four = button(page, "SA4 forward")
    four.hover()
    page.mouse.down()
    expect(four).to_have_attribute("aria-pressed", "true")
    page.evaluate("window.dispatchEvent(new Event('blur'))")
    expect(four).to_have_attribute("aria-pressed", "false")
    page.mouse.up()
    let_time_pass(page, 0.3)
    for name in ("SA2_BWD", "SA3_FWD", "SA4_FWD"):
        assert levels(lp, name)[-2:] == ["1", "0"], name
    assert lp.lab.held == set()


def test_tur10_playback_shows_each_link_s_target(lab_page, shots):
    lp = lab_page("tur10", speed=5)
    page = lp.page
    flip(page, "SA7", False)
    sb1 = lp.lab.session.labels["SB1"]
    tap_sb1(page, address=sb1)                              # frame 1: where the links are
    fwd = button(page, "SA1 forward")
    fwd.hover()
    page.mouse.down()
    let_time_pass(page, 1.0)
    page.mouse.up()
    expect(page.locator("#dac-1")).to_have_text("DAC 0", timeout=WAIT)
    tap_sb1(page, address=sb1)                              # frame 2: link 1 further forward
    assert lp.lab.session.value("FrameCount") == 2
    target = page.locator("#target-1")
    expect(target).to_have_attribute("visibility", "hidden")   # no frame played yet
    expect(page.locator("#robot-target")).to_have_attribute("visibility", "hidden")
    flip(page, "I1.5", True)
    flip(page, "SA7", True)                                 # automatic ...
    tap_sb1(page, address=sb1)                              # ... start
    expect(target).to_have_attribute("visibility", "visible", timeout=WAIT)
    expect(page.locator("#robot-target")).to_have_attribute("visibility", "visible")   # the ghost robot
    targets = [link["target"] for link in lp.lab.call(lambda: lp.lab.snapshot()).result(10)["mimic"]["links"]]
    assert all(t is not None for t in targets), targets
    page.screenshot(path=str(shots / "lab-tur10-playback.png"))


def test_sb1_at_x50_a_click_records_and_only_a_3s_hold_resets(lab_page):
    lp = lab_page("mp9c", speed=50)
    page = lp.page
    expect(page.locator("#hold-note")).to_contain_text("While you hold one the plant runs in real time (x1)")
    flip(page, "SA5", True)
    on(lamp(page, "SQ2"))
    sb1 = button(page, "SB1")
    presses = len(rising(trace_rows(page), "%IX1.6"))
    sb1.hover()
    page.mouse.down()
    press_seen(page, "%IX1.6", presses)                     # the stand has it (a loaded machine is late)
    page.wait_for_timeout(150)                              # a student's click: 150 ms of wall time
    page.mouse.up()
    expect(sb1).to_have_attribute("aria-pressed", "false")
    off(lamp(page, "HL1"))                                  # a frame recorded, no reset
    let_time_pass(page, 1.0)
    rows = trace_rows(page)
    down = rising(rows, "%IX1.6")[-1]
    up = [t for t, n, v in rows if n == "%IX1.6" and v == "0" and t > down][0]
    assert up - down < 1.5, f"a 150 ms click lasted {up - down:.2f} s of plant time at x50"
    assert lp.lab.session.plc.read("Main.Cp.Count") == 1
    # a hold of 3 s of the student's time resets: HL1 lights while it is still held
    sb1.focus()
    page.keyboard.down(" ")
    on(lamp(page, "HL1"))
    page.keyboard.up(" ")
    rows = trace_rows(page)
    press, reset = rising(rows, "%IX1.6")[-1], rising(rows, "%QX1.0")[-1]
    assert abs((reset - press) - 3.0) <= 0.02, f"reset {reset - press:.3f} s after the press, expected 3.0 s"
    assert lp.lab.session.plc.read("Main.Cp.Count") == 0


PHONE = """() => {
  const canvases = [...document.querySelectorAll('canvas[data-trend]')].map((c) => {
    const r = c.getBoundingClientRect();
    return {left: r.left, right: r.right, width: r.width, pixels: c.width};
  });
  const svg = document.querySelector('#mimic');
  const m = svg.getBoundingClientRect();
  const scale = m.width / svg.viewBox.baseVal.width;        // CSS px per drawing unit
  const texts = [...svg.querySelectorAll('text')].filter((t) => t.textContent.trim())
    .map((t) => ({text: t.textContent.slice(0, 30), px: parseFloat(getComputedStyle(t).fontSize) * scale}));
  const rows = (label) => { const b = document.querySelector(`[aria-label="${label}"]`); return b ? b.getBoundingClientRect().top : null; };
  const writes = [...document.querySelectorAll('#register-table button, #register-table input')]
    .filter((e) => e.getClientRects().length).map((e) => e.getBoundingClientRect().right);
  return {scroll: document.documentElement.scrollWidth, inner: window.innerWidth, dpr: window.devicePixelRatio,
          columns: getComputedStyle(document.querySelector('main')).gridTemplateColumns.split(' ').length,
          mimic: [m.width, m.height], canvases, texts, writes,
          pairs: [1, 2, 3, 4, 5].map((k) => [rows(`SA${k} forward`), rows(`SA${k} backward`)])};
}"""


def test_a_390x844_phone_gets_one_column_without_sideways_scroll(lab_page, shots):
    for stand in ("mp9c", "tur10", "thermo", "cnc"):
        lp = lab_page(stand, 2.0, variant="full", viewport={"width": 390, "height": 844}, mobile=True)
        try:
            page = lp.page
            page.wait_for_function("document.querySelectorAll('canvas[data-trend]').length > 0")
            page.get_by_role("button", name="Show the program").click()       # its POU selector too
            expect(page.get_by_label("POU", exact=True)).to_be_enabled(timeout=WAIT)
            let_time_pass(page, 0.2)
            got = page.evaluate(PHONE)
            assert got["inner"] == 390 and got["scroll"] <= 390, (stand, got)
            small = [t for t in got["texts"] if t["px"] < 9]
            assert not small, (stand, "drawing text under 9 CSS px", small)
            assert all(right <= 390 for right in got["writes"]), (stand, got["writes"])   # thermo: write on-screen
            if stand == "thermo":
                assert len(got["writes"]) >= 4, got["writes"]
            if stand == "tur10":
                assert all(fwd == bwd for fwd, bwd in got["pairs"]), got["pairs"]      # a link's pair on one row
            assert got["columns"] == 1, (stand, got)
            assert got["mimic"][0] >= 340 and got["mimic"][1] >= 170, (stand, got)   # was 160x81
            for c in got["canvases"]:
                assert c["left"] >= 0 and c["right"] <= 390 and c["width"] >= 200, (stand, c)
                assert abs(c["pixels"] - (c["width"] - 2) * got["dpr"]) <= 2, (stand, c)   # drawn at its size (inside its border)
            page.screenshot(path=str(shots / f"lab-{stand}-phone.png"), full_page=True)
        finally:
            lp.close()
