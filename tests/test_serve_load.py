"""`plclab serve` keeps its scan period while the Modbus face is flooded (issue #25 item 9).

Before, a face answering ~35,000 requests/s took Python's interpreter (and a core) from the
10 ms scan of MP-9C, which skipped 1-150 ticks in a few seconds. Now the face is admitted at
most FACE_MAX_REQUESTS_PER_S (the scan first) and the scan thread claims the interpreter
often (plclab.runtime.realtime).

How the check stays robust on two busy cores: loopback only, bounded load (4 client processes,
pipelined reads, a few seconds, killed after); the window measured starts once every client is
connected and answered (starting Python processes is a burst of CPU no design can hide); the
verdict reads the runtime's own tick accounting (ticks missed, overruns), not the wall clock,
with a tolerance of 2 % of the ticks plus 3 for the machine's own hiccups (the old code lost
50-150 ticks of 300 in this window; the new one 0). The figure itself is `plclab bench`'s
"serve under Modbus load".
"""
from __future__ import annotations

import dataclasses
import subprocess
import sys
import time

from plclab import config
from plclab.modbus.rawclient import RawModbusClient
from plclab.modbus.server import ModbusTcpServer
from plclab.modbus.maps import OpenPlcMap
from plclab.plants import make_plant
from plclab.runtime.image import ProcessImage
from plclab.serve import FACE_MAX_REQUESTS_PER_S, ServeOptions, Service
from plclab.stands import get_stand, sources

LOADER = r"""
import socket, struct, sys, time
port, seconds, batch = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
s = socket.create_connection(("127.0.0.1", port), timeout=10)
s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
request = b"".join(struct.pack(">HHHBBHH", i, 0, 6, 1, 3, 0, 10) for i in range(batch))
reply = batch * (9 + 20)
end = time.monotonic() + seconds
while time.monotonic() < end:
    s.sendall(request)
    got = 0
    while got < reply:
        data = s.recv(65536)
        if not data:
            sys.exit(1)
        got += len(data)
"""
CLIENTS, BATCH, WINDOW_S = 4, 50, 3.0


def _service() -> Service:
    conf = config.defaults()
    stand = conf.stand("mp9c")
    modbus = dataclasses.replace(conf.modbus, port=0)
    return Service(ServeOptions(sources(get_stand("mp9c"), stand.variant), stand, modbus, make_plant("mp9c"),
                                stand.profile, None, None), report=lambda line: None)


def test_the_scan_keeps_its_period_while_the_modbus_face_is_flooded():
    svc = _service()
    svc.start()
    loaders = []
    try:
        loaders = [subprocess.Popen([sys.executable, "-c", LOADER, str(svc.server.port), str(WINDOW_S + 20), str(BATCH)])
                   for _ in range(CLIENTS)]
        give_up = time.monotonic() + 30
        while (svc.server.active_clients < CLIENTS or svc.server.stats["requests"] < 20 * BATCH * CLIENTS) \
                and time.monotonic() < give_up:
            time.sleep(0.05)
        assert svc.server.active_clients == CLIENTS, "the load clients did not connect"
        time.sleep(0.5)                                # past the start of the client processes
        before, served_before = dataclasses.replace(svc.runner.stats), svc.server.stats["requests"]
        time.sleep(WINDOW_S)
        after, served = svc.runner.stats, svc.server.stats["requests"] - served_before
        assert all(p.poll() is None for p in loaders), "a load client stopped early"
    finally:
        for p in loaders:
            p.kill()
            p.wait()
        svc.stop()
    scans = after.ticks - before.ticks
    missed = after.skipped_ticks - before.skipped_ticks
    expected = WINDOW_S / (svc.plc.tick_ns / 1e9)
    assert served > 1000                              # the face was busy all along
    assert served <= FACE_MAX_REQUESTS_PER_S * (WINDOW_S + 1)   # admitted at the face's rate, the rest waited
    assert missed <= 3 + 0.02 * expected, (scans, missed, after.overruns - before.overruns)
    assert svc.plc.state == "STOP" and svc.plc.fault is None


def test_admission_control_answers_every_request_at_the_rate():
    """A client pipelining more than the rate allows gets every answer, in order; the excess
    waited (counted), nothing was refused or dropped."""
    image = ProcessImage()
    for i in range(10):
        image.set("QW", i, 100 + i)
    with ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0, max_requests_per_s=200) as server:
        with RawModbusClient("127.0.0.1", server.port) as client:
            for _ in range(3):
                assert [client.read_holding_registers(0, 10) for _ in range(20)] == [list(range(100, 110))] * 20
        assert server.stats["requests"] == 60
        assert server.stats["throttled"] > 0          # 60 requests at 200/s with a burst of 4: most waited


def test_the_status_line_shows_overruns_and_missed_ticks():
    svc = _service()
    svc.runner.stats.overruns, svc.runner.stats.skipped_ticks, svc.runner.stats.max_lateness_s = 2, 5, 0.0312
    assert "overruns=2 (5 ticks missed, 31.2 ms latest)" in svc.status()
    svc.runner.stats.overruns = 0
    assert "overruns=0  clients=" in svc.status()
    svc.stop()
