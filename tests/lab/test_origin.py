"""Only the lab's own page drives the lab (issue 25, item 3): another site's page, a
DNS-rebinding host name, a request without this run's token are refused, each with one line;
the lab's own page (and a client that reads the token) still works."""
from __future__ import annotations

import asyncio

import aiohttp
import pytest

from plclab.lab import LabServer, LabThread, open_lab
from plclab.lab.engine import Lab

EVIL = "http://evil.example"
PROGRAM = """PROGRAM Blinker
VAR x : BOOL; END_VAR
x := NOT x;
END_PROGRAM
CONFIGURATION Config0
    RESOURCE Res0 ON PLC
        TASK t (INTERVAL := T#10ms, PRIORITY := 0);
        PROGRAM Main WITH t : Blinker;
    END_RESOURCE
END_CONFIGURATION
"""


@pytest.fixture(scope="module")
def lab():
    thread = LabThread(open_lab("mp9c", port=0, speed=1.0, modbus_port=0))
    url = thread.start()
    yield thread.server, url
    thread.stop()


def _form() -> aiohttp.FormData:
    form = aiohttp.FormData()
    form.add_field("files", PROGRAM.encode(), filename="evil.st", content_type="text/plain")
    return form


async def _token(http: aiohttp.ClientSession, url: str) -> str:
    async with http.get(url + "api/session") as r:
        assert r.status == 200
        return (await r.json())["token"]


async def _status(http, method: str, url: str, **kw) -> tuple[int, str]:
    async with http.request(method, url, **kw) as r:
        body = await r.json(content_type=None) if r.content_type == "application/json" else {"message": await r.text()}
        return r.status, body.get("message", "")


def test_a_websocket_from_another_site_or_without_the_token_is_refused(lab):
    server, url = lab

    async def go():
        async with aiohttp.ClientSession() as http:
            token = await _token(http, url)
            refused = []
            for kw in ({"origin": EVIL, "params": {"token": token}},           # another site's page
                       {"params": {"token": "guess"}}, {}):                     # no / a wrong token
                with pytest.raises(aiohttp.WSServerHandshakeError) as e:
                    await http.ws_connect(url + "ws", **kw)
                refused.append(e.value.status)
            # the lab's own page: its own origin and the token
            own = url.rstrip("/")
            async with http.ws_connect(url + "ws", origin=own, params={"token": token}) as ws:
                hello = await asyncio.wait_for(ws.receive_json(), 10)
            return refused, hello
    refused, hello = asyncio.run(go())
    assert refused == [403, 403, 403]
    assert hello["type"] == "hello" and hello["stand"] == "mp9c"


def test_a_cross_site_upload_or_grade_changes_nothing(lab):
    server, url = lab

    async def go():
        async with aiohttp.ClientSession() as http:
            token = await _token(http, url)
            return [
                # a form another site's page posts (multipart: no preflight in a browser)
                await _status(http, "POST", url + "api/program", data=_form(), headers={"Origin": EVIL}),
                await _status(http, "POST", url + "api/program", data=_form(),
                              headers={"Origin": EVIL, "X-PLCLab-Token": token}),
                await _status(http, "POST", url + "api/program", data=_form(), headers={"Sec-Fetch-Site": "cross-site",
                                                                                   "X-PLCLab-Token": token}),
                await _status(http, "POST", url + "api/program", data=_form()),              # no token
                # text/plain: the body a cross-site form or sendBeacon can send
                await _status(http, "POST", url + "api/grade", data='{"task": "task1"}',
                              headers={"Content-Type": "text/plain", "Origin": EVIL}),
                await _status(http, "POST", url + "api/grade", data='{"task": "task1"}',
                              headers={"Content-Type": "text/plain"}),
                await _status(http, "POST", url + "api/grade", data='{"task": "task1"}',
                              headers={"Content-Type": "text/plain", "X-PLCLab-Token": token}),
                await _status(http, "POST", url + "api/reload", headers={"Origin": EVIL}),
                await _status(http, "POST", url + "api/graded", data='{"run": "1-task1", "row": "G1"}',
                              headers={"Content-Type": "text/plain", "Origin": EVIL}),
                await _status(http, "POST", url + "api/graded", data='{"run": "1-task1", "row": "G1"}',
                              headers={"Content-Type": "text/plain", "X-PLCLab-Token": token}),
            ]
    answers = asyncio.run(go())
    assert [status for status, _ in answers] == [403, 403, 403, 403, 403, 403, 415, 403, 403, 415], answers
    assert answers[9][1] == 'graded: send {"run": "1-task1", "row": "G1"} as application/json'
    assert answers[0][1].startswith("refused: a request from another site's page (http://evil.example)")
    assert answers[2][1].startswith("refused: a request from another site's page")
    assert answers[3][1].startswith("refused: the lab's session token is missing or stale")
    assert answers[6][1] == 'grade: send {"task": "task1"} as application/json'
    assert server.lab.program_name == "baseline (shipped)"          # nothing was loaded
    assert server._grade_runs == 0                              # nothing was graded


def test_a_dns_rebinding_host_is_refused_and_the_lab_s_own_names_are_served(lab):
    server, url = lab
    port = server.port

    async def go():
        async with aiohttp.ClientSession() as http:
            out = {}
            for host in (f"attacker.example:{port}", "attacker.example", f"127.0.0.1.attacker.example:{port}",
                         f"127.0.0.1:{port + 1}", f"localhost:{port}", f"127.0.0.1:{port}", f"[::1]:{port}"):
                out[host] = [(await _status(http, "GET", url + path, headers={"Host": host}))[0]
                             for path in ("", "api/session", "trace.csv")]
            # a rebinding page: its own origin, the attacker's host name, as a browser sends them
            out["ws"] = None
            try:
                await http.ws_connect(url + "ws", origin=f"http://attacker.example:{port}",
                                      headers={"Host": f"attacker.example:{port}"})
            except aiohttp.WSServerHandshakeError as e:
                out["ws"] = e.status
            out["message"] = (await _status(http, "GET", url + "api/session",
                                            headers={"Host": f"attacker.example:{port}"}))[1]
            return out
    out = asyncio.run(go())
    for host in (f"attacker.example:{port}", "attacker.example", f"127.0.0.1.attacker.example:{port}",
                 f"127.0.0.1:{port + 1}"):
        assert out[host] == [403, 403, 403], (host, out[host])
    assert out[f"localhost:{port}"] == out[f"127.0.0.1:{port}"] == out[f"[::1]:{port}"] == [200, 200, 200]
    assert out["ws"] == 403
    assert out["message"] == (f"refused: this lab answers to localhost or an IP address on port {port}, not to the "
                              f"host 'attacker.example:{port}' (open the address `plclab lab` printed)")


def test_the_name_given_to_bind_is_a_host_of_the_lab():
    server = LabServer(Lab("mp9c"), bind="labpc.example", port=8080)
    try:
        assert server.host_ok("labpc.example:8080") and server.host_ok("LABPC.example:8080")
        assert server.host_ok("localhost:8080") and server.host_ok("192.168.1.20:8080")
        assert not server.host_ok("labpc.example:8081")
        assert not server.host_ok("evil.example:8080") and not server.host_ok("labpc.example.evil:8080")
        assert not server.host_ok("user@labpc.example:8080") and not server.host_ok("")
    finally:
        server.lab.stop()


def test_each_run_of_the_lab_has_its_own_token():
    a, b = LabServer(Lab("mp9c"), port=0), LabServer(Lab("mp9c"), port=0)
    try:
        assert a.token != b.token and len(a.token) >= 32
    finally:
        a.lab.stop()
        b.lab.stop()
