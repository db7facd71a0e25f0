"""Golden-trace diff: the first diverging signal and time, and the one-scan tolerance."""
from __future__ import annotations

import pytest

from plclab.trace import Difference, Trace, diff, parse_csv

MS = 1_000_000
SCAN = 10 * MS


def make(edges: dict[str, list[tuple[int, object]]], kinds: dict[str, str] | None = None) -> Trace:
    t = Trace()
    for name, changes in edges.items():
        kind = (kinds or {}).get(name, "bool")
        t.declare(name, kind, changes[0][1])
        for time_ns, value in changes[1:]:
            t.change(time_ns, name, value)
    return t


def golden() -> Trace:
    return make({"%QX0.1": [(0, 0), (1_230 * MS, 1), (2_000 * MS, 0)],
                 "%QX0.2": [(0, 0), (3_000 * MS, 1)]})


def test_identical_traces_have_no_difference():
    assert diff(golden(), golden()) is None


def test_first_difference_names_signal_time_and_values():
    actual = make({"%QX0.1": [(0, 0), (2_000 * MS, 1)],          # late: should be 1 at 1.23
                   "%QX0.2": [(0, 0), (2_500 * MS, 1)]})
    d = diff(golden(), actual)
    assert d == Difference("%QX0.1", 1_230 * MS, True, False, "bool")
    assert str(d) == "first difference at t=1.230 s: %QX0.1 expected 1, got 0"
    assert d.time_s == 1.23


def test_earliest_signal_wins_over_name_order():
    actual = make({"%QX0.1": [(0, 0), (1_230 * MS, 1), (2_000 * MS, 0)],
                   "%QX0.2": [(0, 0), (1_000 * MS, 1)]})
    assert str(diff(golden(), actual)) == \
        "first difference at t=1.000 s: %QX0.2 expected 0, got 1"


def test_ties_in_time_are_broken_by_name():
    a = make({"b": [(0, 0), (5 * MS, 1)], "a": [(0, 0), (5 * MS, 1)]})
    b = make({"b": [(0, 0)], "a": [(0, 0)]})
    assert diff(a, b).name == "a"


def test_edges_within_tolerance_are_not_differences():
    actual = make({"%QX0.1": [(0, 0), (1_230 * MS + SCAN, 1), (2_000 * MS - SCAN, 0)],
                   "%QX0.2": [(0, 0), (3_000 * MS + SCAN, 1)]})
    assert diff(golden(), actual, tolerance_ns=SCAN) is None
    d = diff(golden(), actual)               # without tolerance the first shift is reported
    assert (d.name, d.time_ns) == ("%QX0.1", 1_230 * MS)


def test_shift_beyond_tolerance_is_reported_with_sequence_values():
    actual = make({"%QX0.1": [(0, 0), (1_230 * MS, 1), (2_000 * MS + 2 * SCAN, 0)],
                   "%QX0.2": [(0, 0), (3_000 * MS, 1)]})
    d = diff(golden(), actual, tolerance_ns=SCAN)
    assert str(d) == "first difference at t=2.000 s: %QX0.1 expected 0, got 1"


def test_an_extra_short_pulse_is_a_difference_even_with_tolerance():
    actual = make({"%QX0.1": [(0, 0), (1_230 * MS, 1), (2_000 * MS, 0),
                              (2_500 * MS, 1), (2_500 * MS + SCAN, 0)],
                   "%QX0.2": [(0, 0), (3_000 * MS, 1)]})
    assert str(diff(golden(), actual, tolerance_ns=SCAN)) == \
        "first difference at t=2.500 s: %QX0.1 expected 0, got 1"


def test_wrong_value_at_the_right_time_is_reported():
    a = make({"PRG.speed": [(0, 0), (1 * MS, 500)]}, {"PRG.speed": "int"})
    b = make({"PRG.speed": [(0, 0), (1 * MS, 1500)]}, {"PRG.speed": "int"})
    assert str(diff(a, b, tolerance_ns=SCAN)) == \
        "first difference at t=0.001 s: PRG.speed expected 500, got 1500"


def test_missing_signal_and_name_filter():
    actual = make({"%QX0.1": [(0, 0), (1_230 * MS, 1), (2_000 * MS, 0)]})
    d = diff(golden(), actual)
    assert str(d) == "first difference at t=0.000 s: %QX0.2 expected 0, got no such signal"
    assert diff(golden(), actual, names=["%QX0.1"]) is None


def test_strings_are_quoted_and_sub_ms_times_shown_exactly():
    a = make({"PRG.mode": [(0, "IDLE"), (1_000_500, "RUN")]}, {"PRG.mode": "str"})
    b = make({"PRG.mode": [(0, "IDLE"), (1_000_500, "STOP")]}, {"PRG.mode": "str"})
    assert str(diff(a, b)) == \
        "first difference at t=0.0010005 s: PRG.mode expected 'RUN', got 'STOP'"


def test_golden_csv_against_a_run():
    golden_csv = "time_s,name,value\n0,%QX0.1,0\n0,%QX0.2,0\n1.23,%QX0.1,1\n2,%QX0.1,0\n3,%QX0.2,1\n"
    assert diff(parse_csv(golden_csv), golden()) is None
    with pytest.raises(ValueError):
        diff(golden(), golden(), tolerance_ns=-1)
