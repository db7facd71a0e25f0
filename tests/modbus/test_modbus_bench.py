"""`plclab bench`'s Modbus figures: the function runs, reports what it promises, and stays
above a recorded floor: a tenth of the throughput this project's 2-core CI machine measured
with the whole suite running beside it (2026-12-01), so only a tenfold regression fails."""
from __future__ import annotations

from plclab.modbus.bench import bench_modbus

# recorded: 549 requests/s with 1 client, 771 with 10
REQUESTS_PER_S_FLOOR = {1: 55.0, 10: 77.0}


def test_bench_modbus_reports_both_client_counts():
    result = bench_modbus(0.4)
    assert result["registers"] == 10
    for key, clients in (("clients_1", 1), ("clients_10", 10)):
        figures = result[key]
        assert figures["clients"] == clients
        assert figures["errors"] == 0
        assert figures["requests"] > 0 and figures["requests_per_s"] >= REQUESTS_PER_S_FLOOR[clients], figures
        assert 0 < figures["p50_ms"] <= figures["p99_ms"]
