"""`plclab bench`'s Modbus figures: the function runs and reports what it promises."""
from __future__ import annotations

from plclab.modbus.bench import bench_modbus


def test_bench_modbus_reports_both_client_counts():
    result = bench_modbus(0.4)
    assert result["registers"] == 10
    for key, clients in (("clients_1", 1), ("clients_10", 10)):
        figures = result[key]
        assert figures["clients"] == clients
        assert figures["errors"] == 0
        assert figures["requests"] > 0 and figures["requests_per_s"] > 0
        assert 0 < figures["p50_ms"] <= figures["p99_ms"]
