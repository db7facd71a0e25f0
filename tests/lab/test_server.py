"""The virtual lab's server and engine without a browser: bad input gets one line and the
server goes on; the console is applied so the PLC sees every change; the CLI starts and stops."""
from __future__ import annotations

import asyncio
import json
import re
import signal
import subprocess
import sys
import time
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


async def _token(http: aiohttp.ClientSession, url: str) -> str:
    async with http.get(url + "api/session") as r:
        return (await r.json())["token"]


async def _ws_exchange(url: str, messages: list) -> list[dict]:
    replies = []
    async with aiohttp.ClientSession() as http:
        async with http.ws_connect(url + "ws", params={"token": await _token(http, url)}) as ws:
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
    assert messages[6] == "speed x500: from x0.1 to x50 (x1: real time)"
    assert messages[7] == "single scan: pause first"
    assert messages[8] == "set: a switch is 0 or 1, not None"
    assert replies[9]["ok"] is True
    assert all("Traceback" not in (m or "") for m in messages)
    assert urllib.request.urlopen(url, timeout=10).status == 200          # still serving


async def _post(url: str, data) -> dict:
    async with aiohttp.ClientSession() as http:
        token = await _token(http, url[:url.index("/", 8) + 1])
        async with http.post(url, data=data, headers={"X-PLCLab-Token": token}) as r:
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
    assert server.lab.program_name == "baseline (shipped)"                    # the PLC kept its program
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
    answer = urllib.request.urlopen(url + "trace.csv", timeout=10)
    assert re.fullmatch(r'attachment; filename="mp9c-lab-t0-\d+s\.csv"', answer.headers["Content-Disposition"])
    csv = answer.read().decode()
    counts = [line for line in csv.splitlines() if line.split(",")[1:2] == ["Main.Cp.Count"]]
    assert counts[0].endswith(",0") and counts[-1].endswith(",1"), counts
    vcd = urllib.request.urlopen(url + "trace.vcd", timeout=10).read().decode()
    assert "$var" in vcd and "Count" in vcd


async def _states(url: str, count: int, first: list[dict]) -> list[dict]:
    """The next `count` state messages a page gets after sending the commands `first`."""
    states = []
    async with aiohttp.ClientSession() as http:
        async with http.ws_connect(url + "ws", params={"token": await _token(http, url)}) as ws:
            for command in first:
                await ws.send_json(command)
            async with asyncio.timeout(30):
                while len(states) < count:
                    m = json.loads((await ws.receive()).data)
                    if m.get("type") == "state":
                        states.append(m)
    return states


COUNTER = ("PROGRAM Counter\nVAR Scans : DINT; END_VAR\nScans := Scans + 1;\nEND_PROGRAM\n"
           "CONFIGURATION Config0\n RESOURCE Res0 ON PLC\n  TASK t (INTERVAL := T#10ms, PRIORITY := 0);\n"
           "  PROGRAM Main WITH t : Counter;\n END_RESOURCE\nEND_CONFIGURATION\n")


def test_faster_than_real_time_a_page_gets_a_state_every_25_ms_with_every_trend_point(running, tmp_path):
    """At x5 the lab sends at most 40 states a second (the page draws 25), and what comes
    between two of them is not lost: the trend points of every scan are in the next one."""
    program = tmp_path / "counter.st"
    program.write_text(COUNTER, encoding="utf-8")
    server, url = running("mp9c", speed=5, program=[str(program)])
    states = asyncio.run(_states(url, 24, [{"op": "trends", "names": ["Main.Scans"], "id": 1}]))
    states = [st for st in states if "Main.Scans" in st["trends"]][2:]     # past the command's own state
    assert len(states) >= 12
    rate = (len(states) - 1) / (states[-1]["wall"] - states[0]["wall"])      # each stamped as it was made
    assert rate <= 41, rate
    scans = [round((b["t"] - a["t"]) / a["tick"]) for a, b in zip(states, states[1:])]
    assert min(scans) >= 2, scans                                   # several scans between two states
    counted = [v for st in states[1:] for _t, v in st["trends"]["Main.Scans"]]
    first = states[0]["trends"]["Main.Scans"][-1][1]
    assert counted[-1] - first >= sum(scans) - 1 and set(range(first + 1, counted[-1] + 1)) <= set(counted), counted


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
        assert first.startswith("virtual lab: TUR-10 positional robot, program baseline (shipped), x2"), first
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


# --------------------------------------------------------------------------- issue 25, item 4

def test_out_of_range_values_another_stand_s_command_and_a_set_button_are_refused_on_a_live_connection(running):
    server, url = running("mp9c")
    replies = asyncio.run(_ws_exchange(url, [
        '{"op":"set","label":"SA1","value":1e400,"id":1}',          # json: inf
        {"op": "set", "label": "SA1", "value": 1.0e300, "id": 2},
        {"op": "set", "label": "SA1", "value": "1", "id": 3},
        {"op": "set", "label": "SB1", "value": 1, "id": 4},         # a push button is not latched
        {"op": "register", "address": 6, "value": 50, "id": 5},     # thermo's, not the MP-9C's
        {"op": "press", "label": "SA1", "id": 6},                   # a switch is not pressed
        {"op": "speed", "value": 1e400, "id": 7},
        {"op": "set", "label": "SA1", "value": 1, "id": 8},         # the same connection goes on
    ]))
    messages = [r.get("message") for r in replies]
    assert messages[:3] == ["set: a switch is 0 or 1, not inf", "set: a switch is 0 or 1, not 1e+300",
                            "set: a switch is 0 or 1, not 1"]
    assert messages[3] == "SB1 is a push button: it is pressed and released, not set"
    assert messages[4] == "mp9c has no 'register' command (that is another stand's)"
    assert messages[5] == "SA1 is a switch: it is set on or off, not pressed"
    assert messages[6] == "speed xinf: from x0.1 to x50 (x1: real time)"
    assert replies[7]["ok"] is True
    server.lab.call(lambda: server.lab.advance(0.05)).result(10)
    assert server.lab.call(lambda: server.lab.session.value("SB1")).result(10) is False


def test_thermo_register_values_are_whole_numbers_in_range(running):
    server, url = running("thermo")
    replies = asyncio.run(_ws_exchange(url, [
        {"op": "register", "address": 6, "value": 1e400, "id": 1},
        {"op": "register", "address": 6, "value": 1.5, "id": 2},
        {"op": "register", "address": 1e400, "value": 1, "id": 3},
        {"op": "register", "address": 6, "value": 70000, "id": 4},
        {"op": "register", "address": 6, "value": 45, "id": 5},
    ]))
    messages = [r.get("message") for r in replies]
    assert messages[:4] == ["value must be a whole number, not inf", "value must be a whole number, not 1.5",
                            "address must be a whole number, not inf", "value 70000 is outside -32768..65535"]
    assert replies[4]["ok"] is True


def test_a_button_held_by_a_connection_that_goes_away_is_released(running):
    server, url = running("mp9c")
    lab = server.lab

    async def hold_and_go():
        async with aiohttp.ClientSession() as http:
            async with http.ws_connect(url + "ws", params={"token": await _token(http, url)}) as ws:
                await ws.send_json({"op": "press", "label": "SB1", "id": 1})
                while (await asyncio.wait_for(ws.receive_json(), 10)).get("type") != "reply":
                    pass
                assert lab.call(lambda: lab.session.value("SB1")).result(10) in (0, 1)
        # closed: the server lets go
    asyncio.run(hold_and_go())
    for _ in range(100):                  # the server notices the closed connection
        texts = [a.text for a in lab.call(lambda: list(lab.session.actions)).result(10)]
        if texts[-1:] == ["SB1 released"]:
            break
        time.sleep(0.05)
    assert texts[-2:] == ["SB1 pressed", "SB1 released"], texts
    lab.call(lambda: lab.advance(0.1)).result(10)
    assert lab.call(lambda: lab.session.value("SB1")).result(10) is False


def test_a_garbage_multipart_body_gets_one_line_and_no_traceback(running):
    server, url = running("mp9c")

    async def go():
        async with aiohttp.ClientSession() as http:
            token = await _token(http, url)
            out = []
            for body in (b"--xyz\r\nContent-Type: multipart/mixed; boundary=q\r\n\r\n--q\r\nzz",
                         b"\x00\xff" * 100, b"garbage\r\n--xyz\r\nContent-Disposition: form-data; name=\"f\"; "
                                             b"filename=\"a.st\"\r\n\r\nxx"):
                async with http.post(url + "api/program", data=body, headers={
                        "Content-Type": "multipart/form-data; boundary=xyz", "X-PLCLab-Token": token}) as r:
                    out.append((r.status, await r.json()))
            return out
    for status, answer in asyncio.run(go()):
        assert status == 400 and answer["ok"] is False
        assert answer["message"].startswith("upload: the request could not be read as multipart/form-data (")
        assert "\n" not in answer["message"] and "Traceback" not in answer["message"]
    assert server.lab.program_name == "baseline (shipped)"


def test_the_trace_is_a_ring_of_the_last_minutes_and_the_download_says_which(monkeypatch):
    """Trimmed (the ring) and untrimmed, the same session records the same changes inside the
    window; outside it the ring holds nothing but the values at its start."""
    import plclab.lab.engine as engine

    def drive(lab: Lab) -> None:
        for k in range(12):                 # 60 s of plant time, a console change every 5 s
            lab.call(lambda k=k: lab.set_control("SA5", k % 2), console=True).result(10)
            lab.call(lambda: lab.advance(5.0)).result(30)
    whole = Lab("mp9c", speed=1.0)
    whole.paused = True
    whole.start()
    try:
        drive(whole)
        reference = whole.call(lambda: whole.session.trace).result(10)
    finally:
        whole.stop()
    monkeypatch.setattr(engine, "TRACE_KEEP_S", 20.0)
    monkeypatch.setattr(engine, "TRIM_EVERY_S", 5.0)
    ring = Lab("mp9c", speed=1.0)
    ring.paused = True
    ring.start()
    try:
        drive(ring)
        trace = ring.call(lambda: ring.session.trace).result(10)
        window = ring.call(ring.trace_window).result(10)
        sim_start = ring.call(lambda: ring.session.sim.trace.start_ns).result(10)
        text = ring.call(lambda: __import__("plclab.trace", fromlist=["csv_text"]).csv_text(
            ring.trace_for_download())).result(10)
    finally:
        ring.stop()
    assert window[1] >= 59.9 and window[1] - 25.0 <= window[0] <= window[1] - 19.9, window    # the last 20..25 s
    assert sim_start > 0                                               # the simulation's trace is trimmed too
    start_ns = round(window[0] * 1e9)
    for name in ("SA5", "SQ1", "SQ2", "L3"):
        kept = trace.changes(name)
        assert kept[0][0] == start_ns
        assert kept[0][1] == reference.value_at_ns(name, start_ns)
        assert kept[1:] == [c for c in reference.changes(name) if c[0] > start_ns], name
        assert len(kept) < len(reference.changes(name))
    times = {float(line.split(",")[0]) for line in text.splitlines()[1:]}
    assert min(times) == window[0]                # the download holds the window, nothing older


# --------------------------------------------------------------------------- the lab keeps a program running

def _deep_fbs(levels: int) -> str:
    """FB1 holds an FB0, FB2 an FB1, ...: nesting deeper than Python's recursion limit."""
    parts = ["FUNCTION_BLOCK FB0\nVAR x : INT; END_VAR\nx := x + 1;\nEND_FUNCTION_BLOCK\n"]
    parts += [f"FUNCTION_BLOCK FB{i}\nVAR inner : FB{i - 1}; END_VAR\ninner();\nEND_FUNCTION_BLOCK\n"
              for i in range(1, levels)]
    parts.append(f"PROGRAM Deep\nVAR top : FB{levels - 1}; END_VAR\ntop();\nEND_PROGRAM\n"
                 "CONFIGURATION Config0\n RESOURCE Res0 ON PLC\n  TASK t (INTERVAL := T#10ms, PRIORITY := 0);\n"
                 "  PROGRAM Main WITH t : Deep;\n END_RESOURCE\nEND_CONFIGURATION\n")
    return "".join(parts)


def test_an_upload_that_cannot_be_loaded_leaves_the_previous_program_running(running, tmp_path):
    server, url = running("mp9c")
    lab = server.lab
    deep = asyncio.run(_post(url + "api/program", _files(("deep.st", _deep_fbs(700).encode()))))
    assert deep["ok"] is False
    assert deep["errors"][0]["text"].startswith("deep.st:"), deep      # one located line (check or load)
    assert "Traceback" not in str(deep)
    assert lab.program_name == "baseline (shipped)"
    lab.call(lambda: lab.advance(0.1)).result(10)
    assert lab.session.plc.state == "RUN" and lab.session.plc.fault is None
    # Restart, Reload and a new upload all still work
    assert asyncio.run(_ws_exchange(url, [{"op": "restart", "id": 1}]))[0]["ok"] is True
    assert asyncio.run(_post(url + "api/reload", None))["ok"] is True
    assert main(["build", "mp9c", "baseline", "-o", str(tmp_path / "mp9c.st")]) == 0
    loaded = asyncio.run(_post(url + "api/program", _files(("mp9c.st", (tmp_path / "mp9c.st").read_bytes()))))
    assert loaded["ok"] is True and lab.program_name == "mp9c.st"


def test_a_load_that_fails_after_the_check_goes_back_to_the_previous_program(running, tmp_path, monkeypatch):
    """What the trial load cannot foresee (here: memory runs out while the PLC is built) still
    leaves a program running: the previous one, started again."""
    from plclab.scenario import Session

    server, url = running("mp9c")
    lab = server.lab
    assert main(["build", "mp9c", "baseline", "-o", str(tmp_path / "mp9c.st")]) == 0
    real = Session.load_program

    def out_of_memory(self, sources, checked=None):
        if sources[0][0] == "mp9c.st":
            self.plc.stop()                   # as the real load does before building the new PLC
            raise MemoryError()
        return real(self, sources, checked)
    monkeypatch.setattr(Session, "load_program", out_of_memory)
    answer = asyncio.run(_post(url + "api/program", _files(("mp9c.st", (tmp_path / "mp9c.st").read_bytes()))))
    assert answer["ok"] is False
    assert answer["message"] == ("the program could not be loaded (it needs more memory than the lab has: "
                                 "MemoryError); the PLC runs the previous program again (restarted)")
    assert lab.program_name == "baseline (shipped)"
    lab.call(lambda: lab.advance(0.1)).result(10)
    assert lab.session.plc.state == "RUN"
    assert "mp9c.st" not in [n for n, _ in lab.session.sources]
    assert any("Mp9cFull" in text or "PRG_Mp9c" in text for _n, text in lab.session.sources)


def test_cnc_lab_runs_a_task4_block_alone_and_loads_part_programs(tmp_path):
    """`plclab lab cnc --program FB_CncEvalLinear.st` (the block alone, as `plclab cnc` takes
    it); a part program that does not parse gets its G-code line; the table cuts a loaded one."""
    from pathlib import Path

    from plclab.stands.cnc import SQUARE

    block = Path(__file__).resolve().parents[2] / "solutions" / "POUs" / "FB_CncEvalLinear.st"
    server = open_lab("cnc", program=[str(block)], port=0, modbus_port=None)
    lab = server.lab
    try:
        assert "FB_CncEvalLinear.st" in lab.program_name
        with pytest.raises(Exception) as e:
            lab.load_part("G01 X10 Q\n", "bad.nc", "evalfn")
        assert str(e.value).startswith("bad.nc:1:"), e.value
        assert lab.load_part(SQUARE, "square.nc", "evalfn") == "4 frames of square.nc loaded (evalfn)"
        lab.press("SB1", True)
        lab.session.run(0.01)
        lab.press("SB1", False)
        lab.session.run(5.0)                                # F300: 5 mm/s along X
        m = lab.panel.mimic(lab.session)
        assert m["frame"] == 2 and m["x"] == 20.0 and m["missed"] == {"X": 0, "Y": 0, "Z": 0}, m
        assert m["bound_mm"] == 0.01 and m["error_mm"] <= m["bound_mm"]
    finally:
        lab.stop()


def test_two_snapshots_a_slow_page_has_not_received_merge_without_losing_what_is_sent_once():
    from plclab.lab.server import _merge

    old = {"t": 1.0, "events": [1], "actions": ["a"], "trends": {"SB1": [[0.5, 1]]}, "frames": {"rows": [["1"]]},
           "monitor": {"pou": "P", "instance": "Main", "values": {"n": 1, "d": 0}},
           "mimic": {"x": 1.0, "path": [[0.0, 0.0], [1.0, 0.0]]}}
    new = {"t": 2.0, "events": [2], "actions": ["b"], "trends": {"SB1": [[1.5, 0]]},
           "monitor": {"pou": "P", "instance": "Main", "values": {"n": 2}},
           "mimic": {"x": 2.0, "path": [[2.0, 0.0]]}}
    out = _merge(old, new)
    assert out["t"] == 2.0 and out["events"] == [1, 2] and out["actions"] == ["a", "b"]
    assert out["trends"] == {"SB1": [[0.5, 1], [1.5, 0]]}
    assert out["frames"] == {"rows": [["1"]]}                                 # sent when it changed: kept
    assert out["monitor"]["values"] == {"n": 2, "d": 0}                     # changes only: both
    assert out["mimic"] == {"x": 2.0, "path": [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]}
    other = _merge(old, dict(new, monitor={"pou": "Q", "instance": None, "values": {"x": 5}}))
    assert other["monitor"] == {"pou": "Q", "instance": None, "values": {"x": 5}}   # another POU: its own


def test_a_graded_moment_asked_wrongly_is_one_line(running):
    server, url = running("mp9c")

    async def go():
        async with aiohttp.ClientSession() as http:
            token = await _token(http, url)
            headers = {"X-PLCLab-Token": token}
            async with http.post(url + "api/grade", json={"task": "task1"}, headers=headers) as r:
                graded = await r.json()
            out = []
            for body in ({"run": "7-task1", "row": "G1"}, {"run": graded["run"], "row": "NOPE"}, ["G1"],
                         {"run": graded["run"]}):
                async with http.post(url + "api/graded", json=body, headers=headers) as r:
                    out.append((r.status, (await r.json())["message"]))
            return graded, out
    graded, answers = asyncio.run(go())
    assert graded["ok"] and graded["run"] == "1-task1"
    assert answers == [(200, "the lab no longer keeps that grade's program: grade again"),
                       (200, "row NOPE names no moment of a graded run"),
                       (200, 'graded: send {"run": "1-task1", "row": "G1"}'),
                       (200, 'graded: send {"run": "1-task1", "row": "G1"}')]


def test_a_setting_that_restarts_the_program_keeps_the_forces():
    """FINE_MS downloads PRG_CncStand again (a cold start): a force set before it is still in
    effect after it, as after any program download that still has the variable."""
    lab = Lab("cnc", speed=1.0).start()
    try:
        lab.call(lambda: lab.force("SB3", False)).result(10)            # emergency stop held, by force
        lab.call(lambda: lab.set_knob("FINE_MS", 5)).result(10)
        lab.call(lambda: lab.advance(0.05)).result(10)
        assert lab.call(lambda: lab.session.plc.read("SB3")).result(10) is False     # what the program reads
        assert lab.call(lambda: dict(lab.forces.values)).result(10) == {"SB3": False}
        assert lab.call(lambda: lab.session.tick).result(10) == 0.005     # the restart did happen
    finally:
        lab.stop()


class _SlowPage:
    """A WebSocket whose page reads only when let: what a loaded browser does to the lab."""

    closed = False

    def __init__(self):
        self.got: list[dict] = []
        self.reading = asyncio.Event()

    async def send_str(self, text: str) -> None:
        await self.reading.wait()
        self.got.append(json.loads(text))


def test_a_page_reading_slowly_gets_every_reply_after_the_states_made_before_it():
    """The lab made a state (watch list [A]), then did the page's command (watch [A, B]) and
    replied: the page must see that state before the reply, or it takes the old list for the
    lab's newest and drops B (the watch table lost a row under load). States queued side by
    side still merge into one; a page that does not read holds its commands back."""
    from plclab.lab.server import MAX_QUEUED, LabServer, _Client

    async def play() -> tuple[list[dict], int]:
        page = _SlowPage()
        client = _Client(page)
        sender = asyncio.ensure_future(LabServer._sender(client))
        client.put_state({"type": "state", "t": 1, "watch": [["A", 0, False]], "events": ["e1"]})
        await asyncio.sleep(0)                              # the sender waits on the socket
        client.put_state({"type": "state", "t": 2, "watch": [["A", 0, False]], "events": ["e2"]})
        client.put_state({"type": "state", "t": 3, "watch": [["A", 0, False]], "events": ["e3"]})
        client.put({"type": "reply", "id": 7, "op": "watch", "ok": True})
        client.put_state({"type": "state", "t": 4, "watch": [["A", 0, False], ["B", 1, False]], "events": []})
        for i in range(MAX_QUEUED + 10):                   # replies the page does not read yet
            client.put({"type": "reply", "id": 100 + i, "op": "run", "ok": True})
        waiting = asyncio.ensure_future(client.room())
        await asyncio.sleep(0.01)
        held = not waiting.done()
        page.reading.set()
        await asyncio.wait_for(waiting, 5)
        while client.outbox:
            await asyncio.sleep(0.001)
        sender.cancel()
        return page.got, held

    got, held = asyncio.run(play())
    assert [m.get("t", m.get("id")) for m in got[:5]] == [1, 3, 7, 4, 100], got[:5]
    assert got[1]["events"] == ["e2", "e3"]                   # two unsent states, one message, nothing lost
    assert [r[0] for r in got[3]["watch"]] == ["A", "B"]
    assert len(got) == 4 + MAX_QUEUED + 10
    assert held, "a page that does not read got its commands answered into an unbounded queue"
