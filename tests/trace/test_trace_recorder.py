"""The per-scan recorder: only changes go into the trace, and it agrees with every snapshot."""
from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from plclab.trace import Recorder, Trace

SCAN = 10_000_000


def test_recorder_records_only_what_changed_and_counts_it():
    t = Trace()
    for name in ("%QX0.0", "%QX0.1", "PRG.n"):
        t.declare(name, "bool" if name.startswith("%") else "int", 0)
    snap = {"%QX0.0": False, "%QX0.1": False, "PRG.n": 0}
    rec = Recorder(t, lambda: snap)
    assert rec.sample(0) == 0
    snap["%QX0.1"] = True
    assert rec.sample(SCAN) == 1
    assert rec.sample(2 * SCAN) == 0
    snap["PRG.n"] = 5
    snap["%QX0.1"] = False
    assert rec.sample(3 * SCAN) == 2
    assert t.changes("%QX0.1") == [(0, False), (SCAN, True), (3 * SCAN, False)]
    assert t.changes("%QX0.0") == [(0, False)]
    assert t.end_ns == 3 * SCAN


def test_first_scan_at_zero_replaces_the_declared_initial_value():
    t = Trace()
    t.declare("%QX0.0", "bool", False)
    rec = Recorder(t, names=["%QX0.0"])
    rec.record(0, [True])
    assert t.changes("%QX0.0") == [(0, True)]


def test_recorder_accepts_image_bits_as_ints_for_bool_signals():
    t = Trace()
    t.declare("%IX0.0", "bool", False)
    rec = Recorder(t, names=["%IX0.0"])
    rec.record_mapping(SCAN, {"%IX0.0": 1, "other": 42})
    rec.record_mapping(2 * SCAN, {"%IX0.0": True})      # 1 == True: not a change
    assert t.changes("%IX0.0") == [(0, False), (SCAN, True)]


def test_recorder_ignores_nan_staying_nan():
    t = Trace()
    t.declare("r", "real", 0.0)
    rec = Recorder(t, names=["r"])
    assert rec.record(SCAN, [math.nan]) == 1
    assert rec.record(2 * SCAN, [float("nan")]) == 0   # a different NaN object, same value
    assert len(t.changes("r")) == 2


@settings(max_examples=60, deadline=None)
@given(st.lists(st.lists(st.integers(-3, 3), min_size=4, max_size=4), min_size=1, max_size=40))
def test_trace_reproduces_every_snapshot(snapshots):
    names = [f"v{i}" for i in range(4)]
    t = Trace()
    for n in names:
        t.declare(n, "int", 0)
    rec = Recorder(t, names=names)
    for k, values in enumerate(snapshots):
        rec.record(k * SCAN, values)
    for k, values in enumerate(snapshots):
        assert [t.value_at_ns(n, k * SCAN) for n in names] == values
    for n in names:   # changes only: consecutive entries always differ
        vals = [v for _t, v in t.changes(n)]
        assert all(a != b for a, b in zip(vals, vals[1:]))
