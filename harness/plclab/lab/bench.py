"""`plclab bench`'s figures of the virtual lab: how often a page gets the stand's state, how
far behind the plant it is when it gets it, and what each connected page costs the server.

The lab runs as a user runs it (`plclab lab STAND --port 0`, its own process); pages are
WebSocket clients that read every state message. Lag of a message = the plant time the wall
clock says it is when the message arrives (the server's pacing, carried in the message) minus
the time of the scan it shows, in scans. CPU is the server process's, from /proc (Linux).
"""
from __future__ import annotations

import asyncio
import json
import os
import re
import signal
import subprocess
import sys
import time
from typing import Optional


def _cpu_s(pid: int) -> Optional[float]:
    """User + system CPU seconds of a process so far (None where /proc is not there)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return None


async def _pages(url: str, n: int, seconds: float) -> list[dict]:
    import aiohttp

    async def page() -> dict:
        lags, count = [], 0
        async with aiohttp.ClientSession() as http:
            async with http.get(url + "api/session") as r:          # the page's token (docs/lab.md)
                token = (await r.json())["token"]
            async with http.ws_connect(url + "ws", params={"token": token}, max_msg_size=0) as ws:
                end = time.monotonic() + seconds
                start = None
                while time.monotonic() < end:
                    try:
                        msg = await asyncio.wait_for(ws.receive(), max(0.01, end - time.monotonic()))
                    except asyncio.TimeoutError:
                        break
                    if msg.type != aiohttp.WSMsgType.TEXT:
                        break
                    m = json.loads(msg.data)
                    if m.get("type") != "state":
                        continue
                    if start is None:              # the first is the full history: not counted
                        start = time.monotonic()
                        continue
                    count += 1
                    arrived = time.monotonic()
                    lags.append((m["paced"] + (arrived - m["wall"]) * m["speed"] - m["t"]) / m["tick"])
                took = time.monotonic() - (start or time.monotonic())
        return {"updates_per_s": count / took if took > 0 else 0.0, "lags": lags}
    return await asyncio.gather(*(page() for _ in range(n)))


def bench_lab(stand: str = "mp9c", speeds: tuple[float, ...] = (1, 10), seconds: float = 3.0,
              pages: int = 4) -> list[dict]:
    """For each speed: updates per second a page gets, its lag in scans (p50, p99, max), and
    the server's CPU (share of one core) with no page, with one and with `pages` pages."""
    results = []
    for speed in speeds:
        from plclab.stands import get_stand
        proc = subprocess.Popen([sys.executable, "-m", "plclab.cli", "lab", stand, "--port", "0",
                                 "--variant", get_stand(stand).richest_variant,      # the most complete program
                                 "--speed", str(speed), "--modbus-port", "0"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            url = None
            for _ in range(2):
                line = proc.stdout.readline()
                found = re.search(r"open (http://\S+/) in a browser", line)
                url = found.group(1) if found else url
            if url is None:
                raise RuntimeError(f"plclab lab did not start: {proc.stderr.read()[:300]}")
            time.sleep(0.5)                        # past the start-up

            def cpu_share(n: int) -> tuple[float, list[dict]]:
                c0, w0 = _cpu_s(proc.pid), time.monotonic()
                got = asyncio.run(_pages(url, n, seconds)) if n else (time.sleep(seconds) or [])
                c1, w1 = _cpu_s(proc.pid), time.monotonic()
                return ((c1 - c0) / (w1 - w0) if c0 is not None and c1 is not None else float("nan")), got
            idle, _ = cpu_share(0)
            one, got = cpu_share(1)
            many, _ = cpu_share(pages)
        finally:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.communicate(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
        lags = sorted(got[0]["lags"]) or [float("nan")]
        results.append({
            "stand": stand, "speed": speed, "updates_per_s": got[0]["updates_per_s"],
            "lag_p50_scans": lags[len(lags) // 2], "lag_p99_scans": lags[min(len(lags) - 1, int(len(lags) * 0.99))],
            "lag_max_scans": lags[-1], "cpu_idle": idle, "cpu_per_page": (many - idle) / pages,
            "cpu_one_page": one - idle, "pages": pages,
        })
    return results


def report_lab(report, quick: bool = False) -> list[dict]:
    """The bench lines of the lab (goal on every stand: >= 20 updates/s, <= 1 scan of lag at
    x1), and the trace the lab keeps after a long run (bounded: a ring, engine.TRACE_KEEP_S)."""
    seconds = 1.5 if quick else 4.0
    results = bench_lab("mp9c", (1, 10), seconds=seconds)
    for stand in ("tur10", "thermo", "cnc"):
        results += bench_lab(stand, (1,), seconds=seconds, pages=2)
    for r in results:
        goal = "  (goal >= 20/s, <= 1 scan)" if r["speed"] == 1 else ""
        if r["stand"] == "cnc":            # 1-ms cycles, a state every 10 ms: the lag goal is 10 cycles
            goal = "  (goal >= 20/s, <= 10 of its 1-ms cycles)"
        report(f"lab: {r['stand']} x{r['speed']:g}: {r['updates_per_s']:.0f} updates/s per page, lag p50 "
               f"{r['lag_p50_scans']:.2f} / p99 {r['lag_p99_scans']:.2f} / max {r['lag_max_scans']:.2f} scans{goal}; "
               f"server CPU {r['cpu_idle'] * 100:.0f}% with no page, +{r['cpu_per_page'] * 100:.1f}% per page "
               f"({r['pages']} pages)")
    kept = trace_kept("mp9c", hours=1.0 if quick else 2.0)
    report(f"lab: mp9c trace after {kept['hours']:g} h of plant time: {kept['changes']} changes kept from "
           f"t = {kept['from_s']:.0f} s (a ring of {kept['keep_s'] / 60:.0f} min; "
           f"{kept['changes_per_min']:.0f} changes per plant minute)")
    return results


def trace_kept(stand: str, hours: float = 2.0) -> dict:
    """Run the lab's engine for `hours` of plant time, a console change every 5 s: how much
    trace it keeps (the ring bounds it whatever the run's length)."""
    from plclab.lab.engine import TRACE_KEEP_S, Lab
    from plclab.stands import get_stand

    lab = Lab(stand, variant=get_stand(stand).richest_variant)   # the most complete program
    try:
        lab.session.run(lab.session.tick)
        control = next(c for c in lab.panel.controls if c.kind == "switch")
        for k in range(int(hours * 3600 / 5)):
            lab.set_control(control.label, k % 2)
            lab._run_scans(round(5.0 / lab.session.tick))
        trace = lab.session.trace
        changes = sum(len(trace.changes(n)) for n in trace.signals())
        changes += sum(len(lab.session.sim.trace.changes(n)) for n in lab.session.sim.trace.signals())
        return {"hours": hours, "changes": changes, "from_s": trace.start_ns / 1e9, "keep_s": TRACE_KEEP_S,
                "changes_per_min": changes / (TRACE_KEEP_S / 60)}
    finally:
        lab.stop()
