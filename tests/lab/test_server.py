"""The virtual lab's server and engine without a browser: bad input gets one line and the
server goes on; the console is applied so the PLC sees every change; the CLI starts and stops."""
from __future__ import annotations

import asyncio
import re
import signal
import subprocess
import sys
import urllib.request

import aiohttp
import pytest

from plclab.cli import main
from plclab.lab import LabThread, open_lab
from plclab.lab.engine import Lab
from plclab.lab.server import MAX_UPLOAD


@pytest.fixture
def running():
    threads = []

    def make(stand: str = "mp9c", speed: float = 2.0, **kw):
        t = LabThread(open_lab(stand, port=0, speed=speed, modbus_port=0, **kw))
        url = t.start()
        threads.append(t)
        return t.server, url
    yield make
    for t in threads:
        t.stop()


def test_a_press_and_its_release_sent_at_once_are_both_seen_by_the_plc():
    lab = Lab("mp9c", speed=1.0).start()
    try:
        down = lab.call(lambda: lab.press("SB1", True), console=True)
        up = lab.call(lambda: lab.press("SB1", False), console=True)
        down.result(10), up.result(10)
        lab.call(lambda: lab.advance(0.05)).result(10)
        changes = lab.call(lambda: lab.session.trace.changes("SB1")).result(10)
    finally:
        lab.stop()
    values = [v for _t, v in changes]
    assert values[:3] == [False, True, False], f"SB1 as the PLC saw it: {changes}"
    assert changes[2][0] - changes[1][0] >= 10_000_000           # pressed for at least one 10 ms scan


async def _ws_exchange(url: str, messages: list) -> list[dict]:
    replies = []
    async with aiohttp.ClientSession() as http:
        async with http.ws_connect(url + "ws") as ws:
            for m in messages:
                await ws.send_str(m if isinstance(m, str) else __import__("json").dumps(m))
                while True:
                    msg = await asyncio.wait_for(ws.receive_json(), 10)
                    if msg["type"] == "reply":
                        replies.append(msg)
                        break
    return replies


def test_bad_commands_get_one_line_and_the_server_goes_on(running):
    server, url = running("mp9c")
    replies = asyncio.run(_ws_exchange(url, [
        "not json",
        {"op": "fly", "id": 1},
        {"op": "set", "label": "SA9", "value": 1, "id": 2},
        {"op": "inject", "fault": "jammed", "params": {"mechanism": "wing"}, "id": 3},
        {"op": "inject", "fault": "low_pressure", "params": {"factor": "lots"}, "id": 4},
        {"op": "trends", "names": ["Main.NoSuchThing"], "id": 5},
        {"op": "speed", "value": 500, "id": 6},
        {"op": "scan", "id": 7},
        {"op": "set", "label": "SA5", "id": 8},
        {"op": "set", "label": "SA5", "value": 1, "id": 9},
    ]))
    messages = [r.get("message") for r in replies]
    assert messages[0] == "not a command (a JSON object was expected)"
    assert messages[1] == "unknown command 'fly'"
    assert messages[2].startswith("mp9c has no console control 'SA9' (one of SA1, SA2")
    assert messages[3] == "jammed: mechanism must be one of lift, rotation, extension, gripper, not 'wing'"
    assert messages[4] == "low_pressure: factor must be a number, not 'lots'"
    assert "'Main.NoSuchThing' is neither a located address" in messages[5]
    assert messages[6] == "speed x500: from x0.1 to x50"
    assert messages[7] == "single scan: pause first"
    assert messages[8].startswith("set: bad or missing value")
    assert replies[9]["ok"] is True
    assert all("Traceback" not in (m or "") for m in messages)
    assert urllib.request.urlopen(url, timeout=10).status == 200          # still serving


async def _post(url: str, data) -> dict:
    async with aiohttp.ClientSession() as http:
        async with http.post(url, data=data) as r:
            return await r.json()


def _files(*files: tuple[str, bytes]) -> aiohttp.FormData:
    form = aiohttp.FormData()
    for name, data in files:
        form.add_field("files", data, filename=name, content_type="text/plain")
    return form


def test_uploads_too_large_or_not_st_are_refused_and_a_good_one_loads(running, tmp_path):
    server, url = running("mp9c")
    huge = asyncio.run(_post(url + "api/program", _files(("huge.st", b"(*" + b" " * MAX_UPLOAD + b"*)"))))
    assert huge["ok"] is False and huge["message"].startswith("upload too large")
    form = asyncio.run(_post(url + "api/program", {"note": "no file"}))
    assert form["ok"] is False
    binary = asyncio.run(_post(url + "api/program", _files(("x.st", b"PROGRAM\x00"))))
    assert binary["message"] == "x.st:1:1: error: a binary file, not ST text"
    no_config = asyncio.run(_post(url + "api/program", _files(
        ("p.st", b"PROGRAM Blinker VAR x : BOOL; END_VAR x := NOT x; END_PROGRAM\n"))))
    assert no_config["errors"][0]["text"].startswith("p.st:1:1: error: no CONFIGURATION")
    assert server.lab.program_name == "full (shipped)"                    # the PLC kept its program
    # the baseline bundle, as `plclab build` writes it, loads
    assert main(["build", "mp9c", "baseline", "-o", str(tmp_path / "mp9c.st")]) == 0
    loaded = asyncio.run(_post(url + "api/program", _files(("mp9c.st", (tmp_path / "mp9c.st").read_bytes()))))
    assert loaded == {"ok": True, "message": "program loaded: mp9c.st", "errors": []}
    assert server.lab.program_name == "mp9c.st"
    running_sources = server.lab.call(lambda: server.lab.session.sources).result(10)
    assert [name for name, _ in running_sources] == ["mp9c.st"] and "PRG_Mp9cBaseline" in running_sources[0][1]
    again = asyncio.run(_post(url + "api/reload", None))
    assert again["ok"] is True and again["message"] == "program loaded: mp9c.st"


def test_a_trended_program_variable_is_in_the_downloads(running):
    server, url = running("mp9c", speed=5)
    replies = asyncio.run(_ws_exchange(url, [{"op": "trends", "names": ["SB1", "Main.Cp.Count"], "id": 1}]))
    assert replies[0]["ok"], replies
    lab = server.lab
    lab.call(lambda: lab.press("SB1", True), console=True).result(10)     # a short press records a frame
    lab.call(lambda: lab.advance(0.3)).result(10)
    lab.call(lambda: lab.press("SB1", False), console=True).result(10)
    lab.call(lambda: lab.advance(0.2)).result(10)
    csv = urllib.request.urlopen(url + "trace.csv", timeout=10).read().decode()
    counts = [line for line in csv.splitlines() if line.split(",")[1:2] == ["Main.Cp.Count"]]
    assert counts[0].endswith(",0") and counts[-1].endswith(",1"), counts
    vcd = urllib.request.urlopen(url + "trace.vcd", timeout=10).read().decode()
    assert "$var" in vcd and "Count" in vcd


def test_cli_refuses_a_program_that_fails_the_check(tmp_path, capsys):
    bad = tmp_path / "bad.st"
    bad.write_text("PROGRAM Broken\nVAR x : BOOL; END_VAR\nx := \nEND_PROGRAM\n")
    assert main(["lab", "mp9c", "--program", str(bad), "--port", "0"]) == 1
    err = capsys.readouterr().err
    assert re.search(rf"{re.escape(str(bad))}:4:1: error: ", err), err
    assert "Traceback" not in err


def test_cli_serves_the_page_until_stopped(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "plclab.cli", "lab", "tur10", "--port", "0", "--speed", "2"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        first = proc.stdout.readline()
        second = proc.stdout.readline()
        assert first.startswith("virtual lab: TUR-10 positional robot, program full (shipped), x2"), first
        url = re.search(r"open (http://127\.0\.0\.1:\d+/) in a browser", second).group(1)
        page = urllib.request.urlopen(url, timeout=10).read().decode()
        assert '<script src="/static/lab.js">' in page
        assert urllib.request.urlopen(url + "static/mimic.js", timeout=10).status == 200
    finally:
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=20)
    assert proc.returncode == 0, err
    assert "lab stopped" in out and "Traceback" not in err


def test_bench_lab_reports_what_a_page_receives():
    from plclab.lab.bench import bench_lab

    (r,) = bench_lab("mp9c", speeds=(2,), seconds=1.0, pages=2)
    assert r["speed"] == 2 and r["pages"] == 2
    assert r["updates_per_s"] > 0
    assert r["lag_p50_scans"] >= 0 and r["lag_max_scans"] >= r["lag_p99_scans"] >= r["lag_p50_scans"]
