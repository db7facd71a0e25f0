"""The virtual lab's web server (aiohttp): the page, its WebSocket and a few HTTP endpoints.

    GET  /                 the page (static/index.html, shipped in the package; no CDN)
    GET  /api/session      {"token", "session"}: what the page needs to send commands
    GET  /ws?token=T       WebSocket: state pushed after every batch of scans; commands in
    POST /api/program      load ST files and/or a plc.xml (multipart), checked first: `file:line:col: ...`
                           (a drawing's errors name its POU, rung and element)
    POST /api/script?name=F  replay an input script (the CSV as the body): the stand reset, its steps
                           applied at their plant times (plclab.lab.script)
    POST /api/reload       load the program again (the last upload, else the files it came from)
    POST /api/grade        {"task": "task1"}: the grader on the loaded program, as a table
    GET  /grade/RUN/FILE   a grade run's trace files
    GET  /trace.csv|.vcd   the recorded trace (the last TRACE_KEEP_S of plant time)

Every page sees the same stand: a console change from any of them is applied in arrival
order (last writer wins) and every page shows the result. A page that goes away releases
the push buttons it was holding. Bad requests get one line back; the server keeps running.

Who may drive the lab (docs/reliability.md, "The virtual lab's origin rules"): the lab
listens on loopback while its student browses the web, so any page the browser shows could
send it requests. Every request must name the lab itself in its Host header (localhost, an
IP address, or the name given to --bind, with the lab's port: a DNS-rebinding name is
refused); a request a browser marks with another Origin, or as cross-site, is refused; and
every request that changes state (the WebSocket, every POST) carries the per-run token the
page reads from /api/session, which another site's script cannot read.
"""
from __future__ import annotations

import asyncio
import hmac
import io
import ipaddress
import json
import math
import secrets
import threading
from urllib.parse import urlsplit
from pathlib import Path
from typing import Any, Optional

from aiohttp import BodyPartReader, WSMsgType, web

from plclab.errors import PlcLabError
from plclab.frontend import is_project_file
from plclab.lab.engine import SPEEDS, Lab, LabError, check_program, read_upload

STATIC = Path(__file__).resolve().parent / "static"
MAX_UPLOAD = 4 * 1024 * 1024      # bytes per upload: a lab program is a few tens of kB of ST (a plc.xml, ten times that)
MAX_FILES = 32
LAB_OVERHEAD = 512 * 1024 * 1024  # bytes the lab process may grow by beyond one program run's allowance:
                                  # its threads' malloc arenas, the page's traces, a grade beside the running PLC
MAX_MESSAGE = 64 * 1024           # bytes of one WebSocket message from a page
MAX_QUEUED = 64                   # messages waiting for a page before its commands wait too


class _Client:
    """One connected page: what it has not been sent yet, in the order the lab made it, and
    the buttons it holds.

    Everything for a page (states, replies, notices) goes through one queue and one sender.
    A reply written beside the sender overtook, for a page reading slowly (the sender waiting
    for its socket), a state the lab had made before the command: the page took that older
    state for news and dropped a variable it had just asked to watch."""

    def __init__(self, ws: web.WebSocketResponse):
        self.ws = ws
        self.outbox: list = []           # JSON texts, and states (dicts) merged while unsent
        self.ready = asyncio.Event()     # something to send
        self.sent = asyncio.Event()      # something was sent (or the page is gone)
        self.gone = False                # its sender has stopped: nothing more is queued
        self.held: set[str] = set()

    def put_state(self, snap: dict) -> None:
        """A state: merged into the one waiting at the end of the queue, if any (a slow page
        gets the newest state with every event and trend point), else queued."""
        if self.gone:
            return
        if self.outbox and isinstance(self.outbox[-1], dict):
            self.outbox[-1] = _merge(self.outbox[-1], snap)
        else:
            self.outbox.append(snap)
        self.ready.set()

    def put(self, message: dict) -> None:
        """A message sent once (a reply, a notice), after everything queued before it."""
        if self.gone:
            return
        self.outbox.append(json.dumps(message))
        self.ready.set()

    async def room(self) -> None:
        """Until the queue is short again: a page that sends commands faster than it reads
        the replies is read from no faster than it reads (its queue stays bounded)."""
        while len(self.outbox) > MAX_QUEUED and not self.gone:
            self.sent.clear()
            await self.sent.wait()


def _merge(old: dict, new: dict) -> dict:
    """Two snapshots a slow page has not received yet, as one: the newest state with the
    events, actions and trend points of both."""
    if old.get("epoch") != new.get("epoch"):  # the stand was reset (an input script): the new one only
        return new
    out = dict(new)
    for key in ("events", "actions"):
        out[key] = old.get(key, []) + new.get(key, [])
    trends = {k: list(v) for k, v in old.get("trends", {}).items()}
    for name, points in new.get("trends", {}).items():
        trends.setdefault(name, []).extend(points)
    out["trends"] = trends
    old_path, new_mimic = old.get("mimic", {}).get("path"), new.get("mimic")
    if old_path and isinstance(new_mimic, dict) and "path" in new_mimic:   # the CNC's tool path: new points only
        out["mimic"] = dict(new_mimic, path=old_path + new_mimic["path"])
    for key in ("frames",):                  # sent only when changed: the older one still counts
        if key not in new and key in old:
            out[key] = old[key]
    if "monitor" in old:                     # values sent only when changed: keep the older ones
        if "monitor" not in new:
            out["monitor"] = old["monitor"]
        elif (old["monitor"]["pou"], old["monitor"]["instance"]) == (new["monitor"]["pou"], new["monitor"]["instance"]):
            out["monitor"] = dict(new["monitor"], values={**old["monitor"]["values"], **new["monitor"]["values"]})
    return out


class LabServer:
    """Serves one `Lab` on bind:port (0: any free port); for thermo also the Twido Modbus
    face on bind:modbus_port, on the same process image the page edits."""

    def __init__(self, lab: Lab, bind: str = "127.0.0.1", port: int = 8080,
                 modbus_port: Optional[int] = None):
        self.lab = lab
        self.bind = bind
        self.port = port
        self.modbus_port = modbus_port
        self.modbus = None
        self.clients: set[_Client] = set()
        self.loop: Optional[asyncio.AbstractEventLoop] = None
        self._runner: Optional[web.AppRunner] = None
        self._grade_lock: Optional[asyncio.Lock] = None
        self._grade_runs = 0
        self.grade_files: dict[str, Path] = {}
        self.last_grade: Optional[dict] = None       # the last grade's table (a reloaded page shows it)
        self.graded_runs: dict[str, dict] = {}       # run -> what a row's replay needs (the last GRADED_KEPT)
        self.token = secrets.token_urlsafe(24)       # what a state-changing request must carry
        self.session_id = secrets.token_hex(6)       # a page that sees it change knows the lab restarted

    # ------------------------------------------------------------------ life cycle
    def app(self) -> web.Application:
        @web.middleware
        async def guard(request: web.Request, handler):
            why = self.refusal(request)
            if why is not None:
                return _refuse(why, status=403)
            return await handler(request)

        app = web.Application(client_max_size=MAX_UPLOAD + 64 * 1024, middlewares=[guard, _one_line_errors])
        app.router.add_get("/", self.index)
        app.router.add_get("/api/session", self.session_info)
        app.router.add_get("/ws", self.websocket)
        app.router.add_post("/api/program", self.upload)
        app.router.add_post("/api/reload", self.reload)
        app.router.add_post("/api/script", self.script)
        app.router.add_post("/api/grade", self.grade)
        app.router.add_post("/api/graded", self.graded_moment)
        app.router.add_get("/grade/{run}/{file}", self.grade_file)
        app.router.add_get("/trace.csv", self.trace_csv)
        app.router.add_get("/trace.vcd", self.trace_vcd)
        app.router.add_static("/static/", STATIC, show_index=False)
        return app

    async def start(self) -> str:
        """Listen; returns the page's URL. The engine starts too."""
        self.loop = asyncio.get_running_loop()
        self._grade_lock = asyncio.Lock()
        if self.lab.stand == "thermo" and self.modbus_port is not None:
            self._start_modbus()
        self._runner = web.AppRunner(self.app(), access_log=None, handle_signals=False)
        await self._runner.setup()
        site = web.TCPSite(self._runner, self.bind, self.port)
        try:
            await site.start()
        except OSError as e:
            await self._runner.cleanup()
            self._stop_modbus()
            raise LabError(f"lab: cannot listen on {self.bind}:{self.port} ({e.strerror or e})") from None
        self.port = site._server.sockets[0].getsockname()[1]     # the real port when 0 was asked
        self.lab.listen(self._on_snapshot)
        if self.lab._thread is None:
            self.lab.start()
        return self.url

    @property
    def url(self) -> str:
        host = f"[{self.bind}]" if ":" in self.bind else self.bind
        return f"http://{host}:{self.port}/"

    def _start_modbus(self) -> None:
        from plclab.modbus.server import ModbusTcpServer
        try:
            self.modbus = ModbusTcpServer(self.lab.twido_map(external=True), self.bind, self.modbus_port, name="twido").start()
        except (OSError, PlcLabError) as e:
            raise LabError(f"lab: the Twido Modbus face cannot listen on {self.bind}:{self.modbus_port} "
                           f"({getattr(e, 'strerror', None) or e}); choose another --modbus-port") from None

    def _stop_modbus(self) -> None:
        if self.modbus is not None:
            self.modbus.stop()
            self.modbus = None

    async def stop(self) -> None:
        for c in list(self.clients):
            await c.ws.close()
        if self._runner is not None:
            await self._runner.cleanup()
        self._stop_modbus()
        self.lab.stop()

    # ------------------------------------------------------------------ who may drive the lab
    def host_ok(self, host: str) -> bool:
        """Whether a Host header names this lab: its port, and localhost, an IP address or
        the --bind name (a DNS name an attacker controls never is one of them)."""
        try:
            parts = urlsplit("//" + host)
            name, port = parts.hostname, parts.port
        except ValueError:
            return False
        if not name or parts.username is not None or parts.path or parts.query or (port or 80) != self.port:
            return False
        if name in ("localhost", self.bind.lower().strip("[]")):
            return True
        try:
            ipaddress.ip_address(name)
        except ValueError:
            return False
        return True

    def refusal(self, request: web.Request) -> Optional[str]:
        """Why `request` is refused (one line), or None. Host first (DNS rebinding), then a
        browser's Origin / Sec-Fetch-Site, then the token of state-changing requests."""
        host = request.headers.get("Host", "")
        if not self.host_ok(host):
            named = not _is_ip(self.bind) and self.bind.lower() != "localhost"
            names = "localhost or an IP address" + (f" or {self.bind}" if named else "")
            return (f"refused: this lab answers to {names} on port {self.port}, not to the host "
                    f"'{host[:80]}' (open the address `plclab lab` printed)")
        origin = request.headers.get("Origin")
        if origin is not None and not _same_origin(origin, host):
            return f"refused: a request from another site's page ({origin[:80]}); only the lab's own page drives it"
        changes = request.method not in ("GET", "HEAD") or request.path == "/ws"
        if changes or request.path == "/api/session":
            if request.headers.get("Sec-Fetch-Site", "same-origin") not in ("same-origin", "none"):
                return "refused: a request from another site's page; only the lab's own page drives it"
        if changes:
            token = request.query.get("token") if request.path == "/ws" else request.headers.get("X-PLCLab-Token")
            if not token or not hmac.compare_digest(token.encode(), self.token.encode()):
                return ("refused: the lab's session token is missing or stale (reload the page; a script "
                        "reads it from /api/session)")
        return None

    async def session_info(self, request: web.Request) -> web.Response:
        return web.json_response({"token": self.token, "session": self.session_id},
                                 headers={"Cache-Control": "no-store"})

    # ------------------------------------------------------------------ pushing state
    def _on_snapshot(self, snap: dict) -> None:
        """Engine thread: hand the snapshot to the event loop."""
        loop = self.loop
        if loop is not None and not loop.is_closed():
            try:
                loop.call_soon_threadsafe(self._fanout, snap)
            except RuntimeError:          # the loop is closing
                pass

    def _fanout(self, snap: dict) -> None:
        for c in self.clients:
            c.put_state(snap)

    def _broadcast(self, message: dict) -> None:
        for c in self.clients:
            if not c.ws.closed:
                c.put(message)

    @staticmethod
    async def _sender(c: _Client) -> None:
        """The page's one writer: the queue in order, each message sent before the next."""
        try:
            while not c.ws.closed:
                await c.ready.wait()
                c.ready.clear()
                while c.outbox and not c.ws.closed:
                    item = c.outbox.pop(0)
                    await c.ws.send_str(item if isinstance(item, str) else json.dumps(item))
                    c.sent.set()
        except (ConnectionError, RuntimeError):
            pass
        finally:
            c.gone = True
            c.outbox.clear()
            c.sent.set()

    # ------------------------------------------------------------------ the page
    async def index(self, request: web.Request) -> web.StreamResponse:
        return web.FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-cache"})

    def hello(self) -> dict:
        from plclab.grader import requirement_table, tasks
        lab = self.lab
        try:
            grade_tasks = tasks(lab.stand)
        except PlcLabError:
            grade_tasks = []
        checks = {task: requirement_table(lab.stand, task) for task in grade_tasks}   # what each grade checks
        twido = None
        if self.modbus is not None:
            twido = f"{self.bind}:{self.modbus.port}"
        return {"type": "hello", "stand": lab.stand, "title": lab.module.STAND.title, "panel": lab.panel.describe(),
                "speeds": list(SPEEDS), "tasks": grade_tasks, "checks": checks, "twido": twido, "pages": len(self.clients) + 1,
                "trend_names": lab.trend_names, "trend_window": lab.panel.trend_window, "can_reload": True, "session": self.session_id,
                "grade": self.last_grade}

    async def websocket(self, request: web.Request) -> web.StreamResponse:
        ws = web.WebSocketResponse(heartbeat=20.0, max_msg_size=MAX_MESSAGE)
        await ws.prepare(request)
        client = _Client(ws)
        await ws.send_str(json.dumps(self.hello()))
        loop = asyncio.get_running_loop()

        def first_state() -> None:
            # in the engine thread: the full snapshot, then register the page for what follows
            # (both through the event loop, in this order: no change is lost or doubled)
            snap = self.lab.snapshot(full=True)
            loop.call_soon_threadsafe(self._join, client, snap)
        await asyncio.wrap_future(self.lab.call(first_state))
        sender = asyncio.ensure_future(self._sender(client))
        try:
            async for msg in ws:
                if msg.type == WSMsgType.TEXT:
                    reply = await self._command(client, msg.data)
                    if reply is not None and not ws.closed:
                        client.put(reply)
                        await client.room()
                elif msg.type == WSMsgType.ERROR:
                    break
        finally:
            self.clients.discard(client)
            self.lab.viewers = len(self.clients)
            client.ready.set()
            sender.cancel()
            for label in list(client.held):          # a page that goes away lets go of its buttons
                self.lab.call(lambda label=label: self.lab.press(label, False), console=True)
            self._broadcast({"type": "pages", "pages": len(self.clients)})
        return ws

    def _join(self, client: _Client, snap: dict) -> None:
        self.clients.add(client)
        self.lab.viewers = len(self.clients)
        client.put_state(snap)
        self._broadcast({"type": "pages", "pages": len(self.clients)})

    async def _command(self, client: _Client, text: str) -> Optional[dict]:
        """One command from a page; the reply says whether it was done, or why not."""
        try:
            msg = json.loads(text)
            if not isinstance(msg, dict):
                raise ValueError
        except ValueError:
            return {"type": "reply", "ok": False, "message": "not a command (a JSON object was expected)"}
        op, mid = msg.get("op"), msg.get("id")
        if not isinstance(mid, (int, str)) or isinstance(mid, bool):
            mid = None
        lab = self.lab
        try:
            if op not in lab.ops():
                if op in ALL_OPS:
                    raise LabError(f"{lab.stand} has no '{op}' command (that is another stand's)")
                raise LabError(f"unknown command '{str(op)[:40]}'")
            if op == "set":
                label, value = str(msg["label"]), _bit(msg.get("value"))
                await asyncio.wrap_future(lab.call(lambda: lab.set_control(label, value), console=True))
            elif op in ("press", "release"):
                label = str(msg["label"])
                await asyncio.wrap_future(lab.call(lambda: lab.press(label, op == "press"), console=True))
                if not lab.panel.control(label).latching:     # a latched button stays when the page goes
                    (client.held.add if op == "press" else client.held.discard)(label)
            elif op == "speed":
                await asyncio.wrap_future(lab.call(lambda: lab.set_speed(msg["value"])))
            elif op == "unscript":
                await asyncio.wrap_future(lab.call(lab.stop_script))
            elif op in ("pause", "run"):
                await asyncio.wrap_future(lab.call(lambda: lab.set_paused(op == "pause")))
            elif op == "scan":
                await asyncio.wrap_future(lab.call(lab.single_scan))
            elif op == "restart":
                await asyncio.wrap_future(lab.call(lab.restart_plc))
                self._broadcast({"type": "notice", "text": "PLC restarted (power cycle, retained variables kept)"})
            elif op == "inject":
                params = msg.get("params") or {}
                if not isinstance(params, dict):
                    raise LabError("fault parameters must be name: value pairs")
                await asyncio.wrap_future(lab.call(lambda: lab.inject(str(msg["fault"]), params)))
            elif op == "clear":
                await asyncio.wrap_future(lab.call(lab.clear_faults))
            elif op == "trends":
                names = msg.get("names")
                if not isinstance(names, list):
                    raise LabError("trends: a list of signal names was expected")
                chosen = await asyncio.wrap_future(lab.call(lambda: lab.set_trends(names)))
                full = await asyncio.wrap_future(lab.call(lambda: lab.snapshot(full=True)))
                self._broadcast({"type": "trends", "names": chosen, "trends": full["trends"]})
            elif op == "tree":
                tree = await asyncio.wrap_future(lab.call(lab.variable_tree))
                return {"type": "reply", "id": mid, "op": op, "ok": True, "tree": tree}
            elif op == "watch":
                paths = msg.get("paths")
                if not isinstance(paths, list):
                    raise LabError("watch: a list of variable paths was expected")
                await asyncio.wrap_future(lab.call(lambda: lab.set_watch(paths)))
            elif op == "force":
                path, value = str(msg["path"]), msg.get("value")
                if not isinstance(value, (str, int, float, bool)):
                    raise LabError("force: a value (TRUE, 12, 1.5, T#2s) was expected")
                await asyncio.wrap_future(lab.call(lambda: lab.force(path, value)))
            elif op == "unforce":
                path = msg.get("path")
                await asyncio.wrap_future(lab.call(lambda: lab.unforce(None if path is None else str(path))))
            elif op == "source":
                pous = await asyncio.wrap_future(lab.call(lab.listing))
                return {"type": "reply", "id": mid, "op": op, "ok": True, "pous": pous}
            elif op == "monitor":
                pou, instance = str(msg["pou"]), msg.get("instance")
                await asyncio.wrap_future(lab.call(lambda: lab.select_monitor(pou, instance)))
            elif op == "knob":
                label, value = str(msg["label"]), _whole(msg.get("value"), "value", -(1 << 31), 1 << 31)
                await asyncio.wrap_future(lab.call(lambda: lab.set_knob(label, value), console=True))
            elif op == "part":
                text, name, method = msg.get("text"), str(msg.get("name") or "part.nc")[:80], str(msg.get("method") or "evalfn")
                if not isinstance(text, str) or len(text) > MAX_MESSAGE:
                    raise LabError("part: the part program's text was expected (at most 64 KiB)")
                done = await asyncio.wrap_future(lab.call(lambda: lab.load_part(text, name, method)))
                self._broadcast({"type": "notice", "text": done})
            elif op == "contour":
                contour = await asyncio.wrap_future(lab.call(lab.contour))
                return {"type": "reply", "id": mid, "op": op, "ok": True, **contour}
            elif op == "register":
                address = _whole(msg.get("address"), "address", 0, 65535)
                value = _whole(msg.get("value"), "value", -32768, 65535)
                await asyncio.wrap_future(lab.call(lambda: lab.write_register(address, value)))
        except (LabError, PlcLabError) as e:
            return {"type": "reply", "id": mid, "op": op, "ok": False, "message": str(e)}
        except (KeyError, TypeError, ValueError, OverflowError) as e:
            return {"type": "reply", "id": mid, "op": op, "ok": False,
                    "message": f"{op}: bad or missing value ({type(e).__name__}: {str(e)[:80]})"}
        except Exception as e:      # noqa: BLE001 - a bug of ours: one line to the page, the page stays
            import logging
            logging.getLogger("plclab.lab").exception("command %s failed", op)
            return {"type": "reply", "id": mid, "op": op, "ok": False,
                    "message": f"internal error of the lab ({type(e).__name__}); please report it"}
        return {"type": "reply", "id": mid, "op": op, "ok": True}

    # ------------------------------------------------------------------ program
    async def upload(self, request: web.Request) -> web.Response:
        if request.content_length is not None and request.content_length > MAX_UPLOAD + 64 * 1024:
            return _refuse(f"upload too large ({request.content_length} bytes): at most {MAX_UPLOAD // 1024} KiB")
        try:
            reader = await request.multipart()
        except Exception:            # noqa: BLE001 - not multipart, or a broken header
            return _refuse("upload: send the ST files as multipart/form-data (the page's file picker does)")
        files: list[tuple[str, str]] = []
        total = 0
        try:
            while True:
                part = await reader.next()
                if part is None:
                    break
                if not isinstance(part, BodyPartReader) or not part.filename:
                    continue
                name = Path(part.filename.replace("\\", "/")).name or "program.st"
                data = bytearray()
                while True:
                    chunk = await part.read_chunk(65536)
                    if not chunk:
                        break
                    total += len(chunk)
                    if total > MAX_UPLOAD:
                        return _refuse(f"upload too large: at most {MAX_UPLOAD // 1024} KiB in one load")
                    data += chunk
                if len(files) >= MAX_FILES:
                    return _refuse(f"upload: at most {MAX_FILES} files in one load")
                files.append((name, bytes(data) if is_project_file(name) else _decode(name, bytes(data))))
        except _NotText as e:
            return _refuse(str(e), errors=[{"text": str(e), "line": None, "source": None}])
        except (asyncio.CancelledError, MemoryError):
            raise
        except Exception as e:       # noqa: BLE001 - any malformed body (aiohttp raises many kinds)
            why = " ".join(str(e).split())[:120] or type(e).__name__
            return _refuse(f"upload: the request could not be read as multipart/form-data ({why})", status=400)
        if not files:
            return _refuse("upload: no file in the request (choose one or more .st files or a plc.xml)")
        if sum(is_project_file(n) for n, _ in files) > 1:
            return _refuse("upload: one OpenPLC Editor project (plc.xml) at a time (with .st files if you like)")
        loop = asyncio.get_running_loop()
        try:
            sources, errors = await loop.run_in_executor(None, read_upload, files)
        except MemoryError:
            return _refuse("upload: reading it needs more memory than the lab has; the PLC keeps the program it runs")
        if errors:
            return _refuse(f"the program does not pass the check ({len(errors)} error(s)); the PLC keeps the "
                           f"program it runs", errors=[_located(e, sources) for e in errors])
        return await self._load(sources, ", ".join(n for n, _ in files), upload=True)

    async def _load(self, files: list[tuple[str, str]], name: str, upload: bool = False) -> web.Response:
        loop = asyncio.get_running_loop()
        checked, errors = await loop.run_in_executor(None, lambda: check_program(files, trial=True))
        if errors:
            return _refuse(f"the program does not pass the check ({len(errors)} error(s)); the PLC keeps the "
                           f"program it runs", errors=[_located(e, files) for e in errors])
        try:
            await asyncio.wrap_future(self.lab.call(lambda: self.lab.load_program(files, checked, name, upload)))
        except LabError as e:
            self._broadcast({"type": "notice", "text": str(e)})
            return _refuse(str(e), errors=[{"text": str(e), "file": None, "line": None, "source": None}])
        self._broadcast({"type": "notice", "text": f"program loaded: {name}"})
        return web.json_response({"ok": True, "message": f"program loaded: {name}", "errors": []})

    async def script(self, request: web.Request) -> web.Response:
        """Replay an input script: every row checked first (`FILE:LINE: error: ...`), then the
        stand reset and the steps applied at their plant times."""
        from plclab.lab.script import MAX_SCRIPT_BYTES, parse_script
        name = Path(request.query.get("name", "script.csv").replace("\\", "/")).name[:120] or "script.csv"
        if request.content_length is not None and request.content_length > MAX_SCRIPT_BYTES:
            return _refuse(f"{name}: larger than {MAX_SCRIPT_BYTES // 1024} KiB: not an input script")
        data = await request.content.read(MAX_SCRIPT_BYTES + 1)
        lab = self.lab
        try:
            steps = parse_script(data, name, lab.panel, lab.session.labels)
            await asyncio.wrap_future(lab.call(lambda: lab.start_script(steps, name)))
        except PlcLabError as e:
            return _refuse(str(e), errors=[{"text": str(e), "file": name, "line": None, "source": None}])
        self._broadcast({"type": "notice", "text": f"input script {name}: the stand reset, replaying {len(steps)} step(s)"})
        return web.json_response({"ok": True, "message": f"replaying {name}: {len(steps)} step(s)", "errors": []})

    async def reload(self, request: web.Request) -> web.Response:
        """The program again: the last upload (the page's files are not on disk), else the
        --program files read again, else the shipped variant read again."""
        lab = self.lab
        if lab.uploaded is not None:
            files = list(lab.uploaded)
            name = ", ".join(Path(n).name for n, _ in files)
            return await self._load(files, name, upload=True)
        if lab.program_files:
            from plclab.frontend import read_sources
            try:
                files = read_sources(lab.program_files)
            except PlcLabError as e:
                return _refuse(str(e))
            name = ", ".join(Path(n).name for n, _ in files)
        else:
            files = list(lab.session.sources)
            if any(n.startswith("<") for n, _t in files):     # a shipped variant: read plc/ again
                from plclab.stands import sources
                files = sources(lab.module.STAND, lab.variant)
            name = lab.program_name
        return await self._load(files, name)

    # ------------------------------------------------------------------ grade
    async def grade(self, request: web.Request) -> web.Response:
        from plclab.grader import grade_sources
        if request.content_type != "application/json":
            return _refuse('grade: send {"task": "task1"} as application/json', status=415)
        try:
            body = await request.json()
            task = str(body["task"])
        except (ValueError, KeyError, TypeError):
            return _refuse('grade: send {"task": "task1"}')
        assert self._grade_lock is not None
        if self._grade_lock.locked():
            return _refuse("grade: a grade (or a graded run's replay) is already running; wait for it")
        async with self._grade_lock:
            sources, program = await asyncio.wrap_future(self.lab.call(
                lambda: (list(self.lab.session.sources), self.lab.program_name)))
            self._grade_runs += 1
            run = f"{self._grade_runs}-{task}"
            out_dir = self.lab.work_dir / "grade" / run
            loop = asyncio.get_running_loop()
            try:
                report = await loop.run_in_executor(None, grade_sources, self.lab.stand, task, sources, str(out_dir))
            except PlcLabError as e:
                return _refuse(str(e))
        links: dict[str, list[dict]] = {}
        for scenario, paths in report.traces.items():
            links[scenario] = []
            for p in paths:
                self.grade_files[f"{run}/{p.name}"] = p
                links[scenario].append({"name": p.name, "url": f"/grade/{run}/{p.name}"})
        graded = await loop.run_in_executor(None, self._graded_values, report)
        rows = [{"id": r.id, "text": r.text, "result": r.result, "expected": r.expected, "observed": r.observed,
                 "time": r.time, "scenario": r.scenario, "traces": links.get(r.scenario, []),
                 "graded": graded.get(r.id)} for r in report.rows]
        n_pass = sum(r.passed for r in report.rows)
        summary = (f"{n_pass} of {len(report.rows)} requirements passed: {'PASS' if report.passed else 'FAIL'}"
                   if not report.errors else "the program does not compile: FAIL")
        result = {"ok": True, "title": report.title, "task": task, "passed": report.passed,
                  "errors": report.errors, "rows": rows, "summary": summary, "program": program, "run": run}
        self.graded_runs[run] = {"task": task, "sources": sources, "replays": {},
                            "rows": {r.id: (r.scenario, r.time) for r in report.rows
                                     if not r.passed and r.time is not None and r.scenario}}
        for old in list(self.graded_runs)[:-GRADED_KEPT]:
            del self.graded_runs[old]
        self.last_grade = result                 # a reloaded page shows it again
        return web.json_response(result)

    async def graded_moment(self, request: web.Request) -> web.Response:
        """The program's values in a graded run at a row's time, for Program online: the
        row's scenario played again on the graded program to that time (plclab.grader.
        replayed), every POU instance read as the live view reads it (monitor.every_value).
        Refused, in one line, where they cannot be had: the page then says so and shows none."""
        from plclab.grader import replayed
        from plclab.lab.monitor import every_value
        if request.content_type != "application/json":
            return _refuse('graded: send {"run": "1-task1", "row": "G1"} as application/json', status=415)
        try:
            body = await request.json()
            run, rid = str(body["run"]), str(body["row"])
        except (ValueError, KeyError, TypeError):
            return _refuse('graded: send {"run": "1-task1", "row": "G1"}')
        graded = self.graded_runs.get(run)
        if graded is None:
            return _refuse("the lab no longer keeps that grade's program: grade again")
        where = graded["rows"].get(rid)
        if where is None:
            return _refuse(f"row {rid[:20]} names no moment of a graded run")
        running = await asyncio.wrap_future(self.lab.call(lambda: list(self.lab.session.sources)))
        if running != graded["sources"]:
            return _refuse("the lab runs another program than the one graded: grade again to see its run")
        scenario, t = where
        assert self._grade_lock is not None
        async with self._grade_lock:              # one replay or grade at a time (2 s each, or so)
            if where not in graded["replays"]:
                loop = asyncio.get_running_loop()
                try:
                    values = await loop.run_in_executor(None, replayed, self.lab.stand, graded["task"], graded["sources"],
                                                        scenario, t, lambda s: every_value(s.plc, s.sources))
                    graded["replays"][where] = {"ok": True, "values": values}
                except PlcLabError as e:
                    graded["replays"][where] = {"ok": False, "message": str(e)}
        answer = graded["replays"][where]
        return web.json_response({**answer, "message": answer.get("message", ""), "errors": [],
                                  "row": rid, "scenario": scenario, "time": t})

    def _graded_values(self, report: Any) -> dict[str, str]:
        """For each row that did not pass at a known time: the console and the outputs as the
        graded run had them then (read from its trace), in console labels; what a student
        compares with the lab's live values when the row opens the program."""
        from plclab.trace import read_csv
        lab = self.lab
        names = [c.label for c in lab.panel.controls] + [lamp.label for lamp in lab.panel.lamps]
        labels = lab.session.labels
        traces: dict[str, Any] = {}
        out: dict[str, str] = {}
        for r in report.rows:
            if r.passed or r.time is None:
                continue
            csv = next((p for p in report.traces.get(r.scenario, []) if p.suffix == ".csv"), None)
            if csv is None:
                continue
            try:
                if csv not in traces:
                    traces[csv] = read_csv(csv)
                trace = traces[csv]
                shown = []
                for label in names:
                    signal = next((c.signal for c in lab.panel.controls if c.label == label), label)
                    address = labels.get(signal, signal)
                    if address in trace:
                        shown.append(f"{label}={_plain_value(trace.value_at(address, r.time))}")
            except (PlcLabError, OSError, ValueError, LookupError):
                continue
            if shown:
                out[r.id] = f"the graded run ({r.scenario}) at t = {r.time:.2f} s: " + " ".join(shown)
        return out

    async def grade_file(self, request: web.Request) -> web.StreamResponse:
        key = f"{request.match_info['run']}/{request.match_info['file']}"
        path = self.grade_files.get(key)
        if path is None or not path.exists():
            raise web.HTTPNotFound(text=f"no grade trace {key}")
        return web.FileResponse(path, headers={"Content-Disposition": f'attachment; filename="{path.name}"'})

    # ------------------------------------------------------------------ traces
    async def trace_csv(self, request: web.Request) -> web.Response:
        from plclab.trace import csv_text
        text, window = await asyncio.wrap_future(self.lab.call(
            lambda: (csv_text(self.lab.trace_for_download()), self.lab.trace_window())))
        return _attachment(text, self._trace_name(window, "csv"), "text/csv")

    def _trace_name(self, window: tuple[float, float], ext: str) -> str:
        """The download's name says which plant times it holds (the trace is a ring)."""
        return f"{self.lab.stand}-lab-t{window[0]:.0f}-{window[1]:.0f}s.{ext}"

    async def trace_vcd(self, request: web.Request) -> web.Response:
        from plclab.trace import write_vcd

        def vcd() -> tuple[str, tuple[float, float]]:
            buf = io.StringIO()
            write_vcd(self.lab.trace_for_download(), buf)
            return buf.getvalue(), self.lab.trace_window()
        text, window = await asyncio.wrap_future(self.lab.call(vcd))
        return _attachment(text, self._trace_name(window, "vcd"), "text/plain")


GRADED_KEPT = 4         # grades whose program the lab keeps for their rows' replays

ALL_OPS = ("set", "press", "release", "speed", "pause", "run", "scan", "restart", "inject", "clear", "trends",
           "tree", "watch", "force", "unforce", "source", "monitor", "unscript", "register", "knob", "part", "contour")


def _plain_value(value: Any) -> str:
    if isinstance(value, bool):
        return str(int(value))
    return str(value)


def _bit(value: Any) -> int:
    """A switch position from a page: 0 or 1 (also false / true), nothing else."""
    if isinstance(value, bool) or (isinstance(value, int) and value in (0, 1)):
        return int(value)
    raise LabError(f"set: a switch is 0 or 1, not {str(value)[:40]}")


def _whole(value: Any, what: str, lo: int, hi: int) -> int:
    """A whole number in lo..hi from a page (1e400, 1.5, "x" and 70000 are refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or \
            (isinstance(value, float) and not (math.isfinite(value) and value.is_integer())):
        raise LabError(f"{what} must be a whole number, not {str(value)[:40]}")
    if not lo <= value <= hi:
        raise LabError(f"{what} {value:g} is outside {lo}..{hi}")
    return int(value)


@web.middleware
async def _one_line_errors(request: web.Request, handler):
    """A bug of ours in a request: one line back to the page (the server goes on)."""
    try:
        return await handler(request)
    except web.HTTPException:
        raise
    except Exception as e:      # noqa: BLE001 - the page gets a line, the log the traceback
        import logging
        logging.getLogger("plclab.lab").exception("request %s failed", request.path)
        why = " ".join(str(e).split())[:200]
        return _refuse(f"internal error of the lab ({type(e).__name__}: {why}); please report it", status=500)


def _is_ip(name: str) -> bool:
    try:
        ipaddress.ip_address(name.strip("[]"))
    except ValueError:
        return False
    return True


def _same_origin(origin: str, host: str) -> bool:
    """Whether a browser's Origin header is the page served under `host` (http or https)."""
    try:
        o, h = urlsplit(origin), urlsplit("//" + host)
        if o.scheme not in ("http", "https") or not o.hostname or o.path:
            return False
        default = 443 if o.scheme == "https" else 80
        return (o.hostname, o.port or default) == (h.hostname, h.port or 80)
    except ValueError:
        return False


class _NotText(LabError):
    pass


def _decode(name: str, data: bytes) -> str:
    """UTF-8 text (a BOM is dropped), or one line saying where the first bad byte is."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        before = data[:e.start]
        line = before.count(b"\n") + 1
        col = e.start - (before.rfind(b"\n") + 1) + 1
        raise _NotText(f"{name}:{line}:{col}: error: not UTF-8 text (byte 0x{data[e.start]:02X}); save the file "
                       f"as UTF-8") from None
    if "\x00" in text:
        raise _NotText(f"{name}:1:1: error: a binary file, not ST text")
    return text.lstrip("\ufeff")


def _located(error: str, files: list[tuple[str, str]]) -> dict[str, Any]:
    """A diagnostic with the source line it points at (for the page to show)."""
    texts = dict(files)
    name, _, rest = error.partition(":")
    line_no, _, _rest = rest.partition(":")
    source = None
    line: Optional[int] = None
    if line_no.isdigit() and name in texts:
        line = int(line_no)
        lines = texts[name].splitlines()
        if 1 <= line <= len(lines):
            source = lines[line - 1]
    return {"text": error, "file": name if name in texts else None, "line": line, "source": source}


def _refuse(message: str, errors: Optional[list] = None, status: int = 200) -> web.Response:
    return web.json_response({"ok": False, "message": message, "errors": errors or []}, status=status)


def _attachment(text: str, filename: str, content_type: str) -> web.Response:
    return web.Response(text=text, content_type=content_type,
                        headers={"Content-Disposition": f'attachment; filename="{filename}"'})


class LabThread:
    """The server on an event loop of its own thread (tests, `plclab bench`): `start()` returns
    the URL once it listens; `stop()` ends it."""

    def __init__(self, server: LabServer):
        self.server = server
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="lab-web", daemon=True)

    def start(self) -> str:
        self._thread.start()
        return asyncio.run_coroutine_threadsafe(self.server.start(), self._loop).result(30)

    def stop(self) -> None:
        try:
            asyncio.run_coroutine_threadsafe(self.server.stop(), self._loop).result(30)
        finally:
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(10)
            self._loop.close()


def serve_lab(server: LabServer, report=print) -> int:
    """The CLI's `plclab lab`: serve until Ctrl-C / SIGTERM. The process is held to the memory
    allowance of a program run (plclab.limits) for its life: a student's program, loaded or
    uploaded, never takes the machine's memory (a scan past it is the PLC's out_of_memory
    fault; an upload past it is refused in one line; the lab goes on)."""
    import signal

    from plclab.limits import limit_memory, memory_allowance
    allowance = memory_allowance()
    limit_memory(None if allowance is None else allowance + LAB_OVERHEAD)

    async def main() -> None:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):      # before the URL is out: a stop then is clean
            try:
                loop.add_signal_handler(sig, stop.set)
            except (NotImplementedError, RuntimeError):
                pass
        url = await server.start()
        lab = server.lab
        twido = f"; Twido Modbus face on {server.bind}:{server.modbus.port}" if server.modbus else ""
        report(f"virtual lab: {lab.module.STAND.title}, program {lab.program_name}, x{lab.speed:g}{twido}")
        report(f"open {url} in a browser; Ctrl-C stops")
        try:
            await stop.wait()
        finally:
            await server.stop()
    asyncio.run(main())
    report("lab stopped")
    return 0
