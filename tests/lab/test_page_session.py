"""The page and its connection to the lab, the thermo register box, what the log shows
(issue 22, "Minor, seen"): a server restart with the page open, a write box that writes only
whole numbers, an external SCADA client's writes in the log, the upload reloaded, a switch
moved while paused shown at once."""
from __future__ import annotations

import re

from playwright.sync_api import expect
from test_page import FAULTY, WAIT, flip, lamp, off, switch

from plclab.lab import LabThread, open_lab
from plclab.modbus.rawclient import RawModbusClient


def test_a_server_restart_with_the_page_open(lab_page):
    lp = lab_page("mp9c", speed=2)
    page = lp.page
    flip(page, "SA5", True)
    expect(page.locator("#actions")).to_contain_text("SA5=1", timeout=WAIT)
    port = lp.server.port
    lp.thread.stop()                                              # the lab goes away ...
    badge = page.locator("#plc-state")
    expect(badge).to_have_text("no connection", timeout=WAIT)
    expect(badge).to_have_attribute("data-state", "OFFLINE")
    expect(page.locator("#clock")).to_have_text("t = ? s")
    expect(page.locator("#conn")).to_contain_text("connection to the lab lost")
    expect(switch(page, "SA5")).to_be_disabled()
    expect(page.get_by_role("button", name="SB1", exact=True)).to_be_disabled()
    expect(page.get_by_role("button", name="Restart PLC")).to_be_disabled()
    lp.thread = LabThread(open_lab("mp9c", variant="full", port=port, speed=2.0, modbus_port=0))
    lp.server = lp.thread.server
    lp.thread.start()                                             # ... and comes back: a new session
    expect(badge).to_have_text("RUN", timeout=WAIT)
    expect(page.locator("#conn")).to_have_text("")
    expect(page.locator("#actions")).to_contain_text("the lab was restarted: a new session")
    expect(page.locator("#actions")).not_to_contain_text("SA5=1")        # a fresh log
    expect(switch(page, "SA5")).to_have_attribute("aria-checked", "false")
    flip(page, "SA5", True)                                       # the page drives the new lab (its new token)
    assert lp.server.lab.console_levels["SA5"] == 1


def test_thermo_write_box_takes_whole_numbers_and_the_scada_client_s_writes_are_logged(lab_page):
    lp = lab_page("thermo", speed=2)
    page = lp.page
    expect(page.locator("#h-trends")).to_have_text("Trends (last 600 s of plant time)")
    value6 = page.get_by_label("value of %MW6", exact=True)
    expect(value6).to_have_text("40", timeout=WAIT)
    page.get_by_role("button", name="write %MW6").click()                 # empty box
    expect(page.locator("#register-message")).to_have_text("%MW6: enter a value to write (a whole number)")
    page.get_by_label("new value of %MW6").fill("41.5")
    page.get_by_role("button", name="write %MW6").click()
    expect(page.locator("#register-message")).to_have_text("%MW6: '41.5' is not a whole number; nothing written")
    expect(value6).to_have_text("40")
    page.get_by_label("new value of %MW6").fill("42")
    page.get_by_role("button", name="write %MW6").click()
    expect(page.locator("#register-message")).to_have_text("%MW6 = 42 written")
    expect(value6).to_have_text("42", timeout=WAIT)
    # an external SCADA client: what it writes, done or refused, is in the page's log
    with RawModbusClient("127.0.0.1", lp.server.modbus.port, timeout=5.0) as client:
        client.write_register(6, 45)
        try:
            client.write_register(3, 5)                                   # read only
        except Exception as e:       # noqa: BLE001 - the client reports the exception response
            assert "03" in str(e) or "illegal" in str(e).lower(), e
    log = page.locator("#actions")
    expect(log).to_contain_text("SCADA client: %MW6=45 written", timeout=WAIT)
    expect(log).to_contain_text("SCADA client: %MW3=5 refused: exception 03 (illegal data value): %MW3 is read only")
    expect(value6).to_have_text("45", timeout=WAIT)


def test_paused_switches_show_at_once_and_reload_reloads_the_upload(lab_page):
    lp = lab_page("mp9c", speed=2)
    page = lp.page
    page.get_by_role("button", name="Pause").click()
    expect(page.locator("#speed-shown")).to_have_text("paused", timeout=WAIT)
    scans = lp.lab.scans_run
    flip(page, "SA5", True)                                       # shown at once, no scan run
    assert lp.lab.scans_run == scans
    off(lamp(page, "L3"))                                         # the PLC has not seen it yet
    page.get_by_role("button", name="Single scan").click()
    expect(lamp(page, "L3")).to_have_attribute("data-state", "on", timeout=WAIT)
    page.get_by_role("button", name="Run").click()
    page.get_by_label("Load ST files").set_input_files(
        files=[{"name": "faulty.st", "mimeType": "text/plain", "buffer": FAULTY.encode()}])
    expect(page.locator("#program-message")).to_have_text("program loaded: faulty.st", timeout=WAIT)
    page.get_by_role("button", name="Reload program").click()
    expect(page.locator("#actions")).to_contain_text(re.compile(r"program loaded: faulty\.st[\s\S]*program loaded: "
                                                                r"faulty\.st"), timeout=WAIT)
    expect(page.locator("#program-name")).to_have_text("faulty.st")
