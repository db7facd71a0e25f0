"""Modbus throughput figures for `plclab bench`: requests/s and latency of the server face.

Loopback only, an ephemeral port, the OpenPLC map over a fresh ProcessImage; clients are
RawModbusClient threads (cheap, so the figures describe the server more than the client).
"""
from __future__ import annotations

import threading
import time

from plclab.runtime.image import ProcessImage

from .maps import OpenPlcMap
from .rawclient import RawModbusClient
from .server import ModbusTcpServer

REGISTERS = 10


def _percentile(sorted_values: list[float], q: float) -> float:
    if not sorted_values:
        return 0.0
    index = min(len(sorted_values) - 1, max(0, round(q * (len(sorted_values) - 1))))
    return sorted_values[index]


def _run(port: int, clients: int, duration_s: float) -> dict:
    latencies: list[list[float]] = [[] for _ in range(clients)]
    errors: list[str] = []
    gate = threading.Barrier(clients + 1)
    stop = threading.Event()

    def worker(out: list[float]) -> None:
        try:
            with RawModbusClient("127.0.0.1", port, timeout=5.0) as client:
                gate.wait(timeout=10.0)
                while not stop.is_set():
                    t0 = time.perf_counter()
                    client.read_holding_registers(0, REGISTERS)
                    out.append(time.perf_counter() - t0)
        except (OSError, ConnectionError, threading.BrokenBarrierError) as exc:
            errors.append(str(exc))

    threads = [threading.Thread(target=worker, args=(lat,), daemon=True) for lat in latencies]
    for t in threads:
        t.start()
    try:
        gate.wait(timeout=10.0)
    except threading.BrokenBarrierError:
        errors.append("clients did not connect")
    began = time.perf_counter()
    time.sleep(duration_s)
    stop.set()
    for t in threads:
        t.join(10.0)
    elapsed = time.perf_counter() - began
    merged = sorted(x for lat in latencies for x in lat)
    return {
        "clients": clients,
        "requests": len(merged),
        "requests_per_s": len(merged) / elapsed if elapsed > 0 else 0.0,
        "p50_ms": 1000.0 * _percentile(merged, 0.50),
        "p99_ms": 1000.0 * _percentile(merged, 0.99),
        "errors": len(errors),
    }


def bench_modbus(duration_s: float = 2.0) -> dict:
    """Read 10 holding registers in a loop with 1 and then 10 clients, duration_s/2 each.

    Returns {"registers": 10, "clients_1": {...}, "clients_10": {...}} where each entry has
    clients, requests, requests_per_s, p50_ms, p99_ms and errors.
    """
    image = ProcessImage()
    for i in range(REGISTERS):
        image.set("QW", i, i)
    server = ModbusTcpServer(OpenPlcMap(image), "127.0.0.1", 0, name="bench").start()
    try:
        half = max(duration_s / 2.0, 0.05)
        return {"registers": REGISTERS,
                "clients_1": _run(server.port, 1, half),
                "clients_10": _run(server.port, 10, half)}
    finally:
        server.stop()
