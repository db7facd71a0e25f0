"""In Chromium: another site's page cannot drive the lab, a DNS-rebinding name gets a
refusal, and the lab's own page works (issue 25, item 3). Chromium resolves evil.example and
attacker.example to 127.0.0.1 here, as an attacker's DNS would."""
from __future__ import annotations

from playwright.sync_api import expect

from plclab.lab import LabThread, open_lab

EVIL_PAGE = """<!DOCTYPE html><html><body><form id="f" method="POST" enctype="multipart/form-data" target="sink">
<input type="hidden" name="x" value="1"></form><iframe name="sink"></iframe><script>
window.report = {ws: "pending"};
const lab = "LAB";
try {
  const ws = new WebSocket(lab.replace("http", "ws") + "ws");
  ws.onopen = () => { window.report.ws = "open"; ws.send(JSON.stringify({op: "set", label: "SA1", value: 1, id: 1})); };
  ws.onclose = () => { if (window.report.ws === "pending") window.report.ws = "refused"; };
} catch (e) { window.report.ws = "refused"; }
const form = new FormData();
form.append("files", new Blob([`PROGRAM`], {type: "text/plain"}), "evil.st");
Promise.allSettled([
  fetch(lab + "api/program", {method: "POST", mode: "no-cors", body: form}),
  fetch(lab + "api/grade", {method: "POST", mode: "no-cors", headers: {"content-type": "text/plain"},
                            body: JSON.stringify({task: "task1"})}),
]).then(() => { window.report.fetched = true; });
const f = document.getElementById("f"); f.action = lab + "api/program"; f.submit();
</script></body></html>"""


def test_another_site_s_page_cannot_drive_the_lab_and_its_own_page_can(rebinding_browser):
    thread = LabThread(open_lab("mp9c", port=0, speed=2.0, modbus_port=0))
    url = thread.start()
    lab = thread.server.lab
    context = rebinding_browser.new_context()
    try:
        evil = context.new_page()
        evil.route("http://evil.example/", lambda route: route.fulfill(
            status=200, content_type="text/html", body=EVIL_PAGE.replace("LAB", url)))
        evil.goto("http://evil.example/")
        evil.wait_for_function("window.report.ws !== 'pending' && window.report.fetched === true", timeout=20_000)
        assert evil.evaluate("window.report.ws") == "refused"
        # a rebinding name that resolves to the lab: the lab refuses to serve it
        port = thread.server.port
        rebound = context.new_page()
        rebound.goto(f"http://attacker.example:{port}/")
        expect(rebound.locator("body")).to_contain_text(
            f"refused: this lab answers to localhost or an IP address on port {port}, not to the host "
            f"'attacker.example:{port}'")
        # nothing above changed the lab: no program, no grade, no console change
        assert lab.program_name == "baseline (shipped)"
        assert thread.server._grade_runs == 0
        assert not [a for a in lab.call(lambda: list(lab.session.actions)).result(10) if "SA1" in a.text]
        # the lab's own page works: it flips a switch, and by the name localhost too
        for address in (url, url.replace("127.0.0.1", "localhost")):
            page = context.new_page()
            page.goto(address)
            expect(page.locator("#plc-state")).to_have_text("RUN", timeout=20_000)
            sw = page.get_by_role("switch", name="SA5", exact=True)
            before = sw.get_attribute("aria-checked")
            sw.click()
            expect(sw).not_to_have_attribute("aria-checked", before, timeout=20_000)
            page.close()
    finally:
        context.close()
        thread.stop()
