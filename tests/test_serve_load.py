"""`plclab serve` keeps its scan period while the Modbus face is flooded (issue #25 item 9).

Before, a face answering ~35,000 requests/s took Python's interpreter (and a core) from the
10 ms scan of MP-9C, which skipped 1-150 ticks in a few seconds. Now the face is admitted at
most FACE_MAX_REQUESTS_PER_S (the scan first) and the scan thread claims the interpreter
often (plclab.runtime.realtime).

How the check stays robust on two busy cores: loopback only, bounded load (4 client processes,
pipelined reads, a few seconds, killed after: plclab.bench.bench_serve_load, the bench's own
figure); the window measured starts once every client is connected and answered (starting
Python processes is a burst of CPU no design can hide); the
verdict reads the runtime's own tick accounting (ticks missed, overruns), not the wall clock,
with a tolerance of 2 % of the ticks plus 3 for the machine's own hiccups (the old code lost
50-150 ticks of 300 in this window; the new one 0). The figure itself is `plclab bench`'s
"serve under Modbus load".
"""
from __future__ import annotations

import dataclasses

from plclab import config
from plclab.bench import bench_serve_load
from plclab.modbus.maps import OpenPlcMap
from plclab.modbus.rawclient import RawModbusClient
from plclab.modbus.server import ModbusTcpServer
from plclab.plants import make_plant
from plclab.runtime.image import ProcessImage
from plclab.serve import FACE_MAX_REQUESTS_PER_S, ServeOptions, Service
from plclab.stands import get_stand, sources


def test_the_scan_keeps_its_period_while_the_modbus_face_is_flooded():
    r = bench_serve_load(seconds=3.0, clients=4, batch=50)
    assert r["clients"] == 4 and r["clients_at_end"] == 4, r       # the load was there all along
    assert r["requests_per_s"] > 300, r                             # and the face busy answering it
    assert r["requests_per_s"] <= FACE_MAX_REQUESTS_PER_S * 1.3, r  # at the face's rate: the rest waited
    assert r["missed_ticks"] <= 3 + 0.02 * r["expected_scans"], r
    assert r["fault"] is None


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
    conf = config.defaults()
    stand = conf.stand("mp9c")
    svc = Service(ServeOptions(sources(get_stand("mp9c"), stand.variant), stand,
                               dataclasses.replace(conf.modbus, enabled=False), make_plant("mp9c"), stand.profile,
                               None, None), report=lambda line: None)
    svc.runner.stats.overruns, svc.runner.stats.skipped_ticks, svc.runner.stats.max_lateness_s = 2, 5, 0.0312
    assert "overruns=2 (5 ticks missed, 31.2 ms latest)" in svc.status()
    svc.runner.stats.overruns = 0
    assert "overruns=0  clients=" in svc.status()
    svc.stop()
