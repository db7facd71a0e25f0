"""Issue 22, "Minor, seen": nothing on the page is drawn over something else. The trend's
value and scale stay off the trend line (read from the canvas's own pixels), the mimic's
labels never run into each other, TUR-10's "sensor N on the bus" stays off the gauges and off
the sensor-bus line below it, and the console's and plant-fault form's labels stay apart."""
from __future__ import annotations

from test_page import WAIT, let_time_pass

# Every visible, non-empty SVG text of `root` as a screen box; the pairs that overlap (more than
# half a pixel both ways: touching is fine, a glyph over a glyph is not).
_OVERLAPS = """
(function () {
  const visible = (e) => !e.closest("[visibility=hidden]") && getComputedStyle(e).display !== "none";
  const box = (e, name) => { const r = e.getBoundingClientRect(); return { name, x0: r.left, y0: r.top, x1: r.right, y1: r.bottom }; };
  const hit = (a, b) => Math.min(a.x1, b.x1) - Math.max(a.x0, b.x0) > 0.5 && Math.min(a.y1, b.y1) - Math.max(a.y0, b.y0) > 0.5;
  const pairs = (xs, ys) => {
    const out = [];
    xs.forEach((a, i) => ys.forEach((b, j) => { if ((xs !== ys || j > i) && a !== b && hit(a, b)) out.push([a.name, b.name]); }));
    return out;
  };
  const texts = (root) => [...root.querySelectorAll("text")].filter((t) => t.textContent.trim() && visible(t))
    .map((t) => box(t, t.textContent));
  const leaves = (sel) => [...document.querySelectorAll(sel)].filter((e) => e.getClientRects().length && visible(e))
    .map((e) => box(e, `${e.tagName.toLowerCase()} ${(e.textContent || e.getAttribute("aria-label") || e.id || "").trim().slice(0, 40)}`));
  return { box, pairs, texts, leaves };
})()
"""

# Each trend canvas's pixels: where the line (blue) ends on the right and where the text (the
# value and the scale, dark or grey) begins on the left, in canvas pixels.
_TREND_PIXELS = """
() => [...document.querySelectorAll("canvas[data-trend]")].map((c) => {
  const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
  let lineX0 = Infinity, lineX1 = -1, textX0 = Infinity, lineN = 0, textN = 0;
  for (let y = 0; y < c.height; y++) for (let x = 0; x < c.width; x++) {
    const i = (y * c.width + x) * 4, r = d[i], g = d[i + 1], b = d[i + 2];
    if (d[i + 3] < 96) continue;
    if (b - r > 80 && b - g > 60) { lineN++; lineX0 = Math.min(lineX0, x); lineX1 = Math.max(lineX1, x); }
    else if (Math.max(r, g, b) < 150 && Math.abs(b - r) < 40) { textN++; textX0 = Math.min(textX0, x); }
  }
  return { name: c.dataset.trend, width: c.width, lineX0, lineX1, textX0, lineN, textN };
})
"""


def _assert_trends_clear_of_text(page) -> None:
    """Once the window is full the line crosses the whole plot, where a value or a scale drawn
    over it would show; every text pixel must lie right of the line's last pixel."""
    trends = page.evaluate(_TREND_PIXELS)
    assert trends, "no trend drawn"
    for t in trends:
        assert t["lineN"] > 0 and t["textN"] > 0, t                 # a line and its value are drawn
        assert t["lineX0"] <= 2, t                                   # the window is full: the line starts at the left
        assert t["textX0"] > t["lineX1"], f"trend {t['name']}: text over the line: {t}"


def _assert_labels_apart(page, selector: str) -> None:
    overlaps = page.evaluate(f"(() => {{ const L = {_OVERLAPS}; const xs = L.leaves({selector!r}); return L.pairs(xs, xs); }})()")
    assert overlaps == [], f"{selector}: labels run together: {overlaps}"


def test_tur10_bus_text_gauges_trends_and_labels_do_not_overlap(lab_page):
    lp = lab_page("tur10", speed=50)
    page = lp.page
    let_time_pass(page, 62)                          # the 60-s trend window full
    # "sensor 5 on the bus" (the bus polls the sensors in turn): taken while it is shown, with
    # the boxes of that same frame
    found = page.wait_for_function(f"""() => {{
      const L = {_OVERLAPS};
      const svg = document.querySelector('#mimic');
      const bus = [...svg.querySelectorAll('.gauge text')].find((t) => t.textContent === 'sensor 5 on the bus');
      if (!bus) return null;
      const texts = L.texts(svg);
      const shapes = [...svg.querySelectorAll('.gauge rect, .gauge line, .gauge path')]
        .filter((e) => !e.closest('[visibility=hidden]') && e.getAttribute('visibility') !== 'hidden')
        .map((e, i) => L.box(e, `${{e.tagName}} ${{i}} of the gauges`));
      const busLine = texts.find((t) => t.name.startsWith('sensor bus:'));
      return {{ texts: L.pairs(texts, texts), shapes: L.pairs(texts, shapes), busLine: !!busLine,
               bus: L.box(bus, bus.textContent), line: busLine }};
    }}""", timeout=WAIT, polling="raf").json_value()
    assert found["busLine"]
    assert found["texts"] == [], f"mimic labels run together: {found['texts']}"
    assert found["shapes"] == [], f"a label over a gauge: {found['shapes']}"
    bus, line = found["bus"], found["line"]
    assert bus["y1"] <= line["y0"] + 0.5, f"'sensor 5 on the bus' over the bus line: {bus} {line}"
    _assert_trends_clear_of_text(page)
    _assert_labels_apart(page, "#controls button, #controls small, #plant-faults label, #plant-faults select, "
                               "#plant-faults input, #plant-faults button, #lamps .lamp")


def test_mp9c_mimic_labels_trends_and_fault_form_do_not_overlap(lab_page):
    lp = lab_page("mp9c", speed=50)
    page = lp.page
    let_time_pass(page, 62)
    overlaps = page.evaluate(f"(() => {{ const L = {_OVERLAPS}; const t = L.texts(document.querySelector('#mimic')); "
                             f"return L.pairs(t, t); }})()")
    assert overlaps == [], f"mimic labels run together: {overlaps}"
    _assert_trends_clear_of_text(page)
    _assert_labels_apart(page, "#controls button, #controls small, #plant-faults label, #plant-faults select, "
                               "#plant-faults input, #plant-faults button, #lamps .lamp")
    # a phone's width: the page in one column, each trend drawn at its narrower size, the same rules
    page.set_viewport_size({"width": 390, "height": 844})
    page.wait_for_function("document.querySelector('canvas[data-trend]').width < 390", timeout=WAIT)
    let_time_pass(page, 1)
    _assert_trends_clear_of_text(page)
    _assert_labels_apart(page, "#controls button, #controls small, #plant-faults label, #plant-faults select, "
                               "#plant-faults input, #plant-faults button, #lamps .lamp")


def test_thermo_and_cnc_mimic_labels_do_not_overlap(lab_page):
    for stand in ("thermo", "cnc"):
        lp = lab_page(stand, speed=5)
        let_time_pass(lp.page, 1)                    # the mimic's live texts filled in
        overlaps = lp.page.evaluate(f"(() => {{ const L = {_OVERLAPS}; const t = L.texts(document.querySelector('#mimic')); "
                                    f"return [t.length, L.pairs(t, t)]; }})()")
        assert overlaps[0] >= 5 and overlaps[1] == [], f"{stand}: mimic labels run together: {overlaps}"
        lp.close()
