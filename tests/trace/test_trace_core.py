"""Trace recording and the query helpers scenarios use (docs/contributing.md: read like the lab plan)."""
from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plclab.trace import NotFound, Trace, UnknownSignal

MS = 1_000_000
S = 1_000_000_000


def mp9c_like() -> Trace:
    """SQ2 (arm at lower stop) at 1.0 s, L2 moves 3 s later, L3 at 6.5 s; HL1 blinks."""
    t = Trace()
    t.declare("%IX0.2", "bool", False)
    t.declare("%QX0.2", "bool", False)
    t.declare("%QX0.3", "bool", False)
    t.declare("%QX0.5", "bool", False)
    t.declare("PRG_Main.fbPause.ET", "int", 0)
    for name, alias in [("%IX0.2", "SQ2"), ("%QX0.2", "L2"), ("%QX0.3", "L3"), ("%QX0.5", "HL1")]:
        t.alias(alias, name)
    t.change(1 * S, "SQ2", True)
    t.change(4 * S, "L2", True)
    t.change(6_500 * MS, "L3", True)
    t.change(2 * S, "HL1", True)
    t.change(2_250 * MS, "HL1", False)
    t.change(3 * S, "HL1", True)
    t.change(3_500 * MS, "HL1", False)
    t.change(9 * S, "HL1", True)
    t.advance(10 * S)
    return t


def test_change_records_only_differences_and_keeps_the_initial_value():
    t = Trace()
    t.declare("%QX0.1", "bool", False)
    assert t.change(10 * MS, "%QX0.1", False) is False
    assert t.change(20 * MS, "%QX0.1", True) is True
    assert t.change(30 * MS, "%QX0.1", True) is False
    assert t.changes("%QX0.1") == [(0, False), (20 * MS, True)]


def test_values_are_normalised_to_the_declared_kind():
    t = Trace()
    t.declare("b", "bool", 0)
    t.declare("r", "real", 1)
    t.change(5, "b", 1)
    t.change(5, "r", 2)
    assert t.changes("b") == [(0, False), (5, True)] and type(t.changes("b")[1][1]) is bool
    assert type(t.changes("r")[1][1]) is float
    t.declare("i", "int", 0)
    with pytest.raises(TypeError):       # an int signal never silently truncates a REAL
        t.change(6, "i", 1.5)


def test_value_at_is_the_value_after_the_changes_at_that_instant():
    t = Trace()
    t.declare("cnt", "int", 0)
    t.change(1_230 * MS, "cnt", 7)
    assert t.value_at("cnt", 0.0) == 0
    assert t.value_at("cnt", 1.229999999) == 0
    assert t.value_at("cnt", 1.23) == 7
    assert t.value_at("cnt", 99.0) == 7


def test_second_change_at_same_instant_replaces_and_a_glitch_cancels():
    t = Trace()
    t.declare("x", "int", 0)
    t.change(5, "x", 1)
    t.change(5, "x", 2)
    assert t.changes("x") == [(0, 0), (5, 2)]
    t.change(5, "x", 0)          # back to the value before t=5: no event at all
    assert t.changes("x") == [(0, 0)]
    t.change(0, "x", 3)          # the first scan at t=0 sets the value seen at start
    assert t.changes("x") == [(0, 3)]


def test_time_going_backwards_is_refused():
    t = Trace()
    t.declare("x", "int", 0)
    t.change(10, "x", 1)
    with pytest.raises(ValueError, match="before its last change"):
        t.change(9, "x", 2)


def test_nan_to_nan_is_not_a_change():
    t = Trace()
    t.declare("r", "real", math.nan)
    assert t.change(1, "r", float("nan")) is False
    assert t.change(2, "r", 1.0) is True


def test_declaration_errors_are_clear():
    t = Trace()
    t.declare("x", "int", 0)
    with pytest.raises(ValueError, match="declared twice"):
        t.declare("x", "int", 0)
    with pytest.raises(ValueError, match="kind 'word'"):
        t.declare("y", "word", 0)
    with pytest.raises(ValueError, match="width"):
        t.declare("z", "bool", 0, width=8)


def test_unknown_name_suggests_close_names():
    t = mp9c_like()
    with pytest.raises(UnknownSignal, match=r"no signal 'SQ3'.*did you mean SQ2"):
        t.value_at("SQ3", 1.0)


def test_the_style_guide_scenario_reads_as_written():
    trace = mp9c_like()
    start = 0.5
    done = trace.first(lambda io: io.SQ2, after=start)
    moved = trace.next_change(["L2", "L3"], after=done)
    assert done == 1.0
    assert moved - done == pytest.approx(3.0, abs=0.01)


def test_first_by_name_alias_address_and_qualified_parts():
    t = mp9c_like()
    t.change(7 * S, "PRG_Main.fbPause.ET", 500)
    assert t.first("SQ2") == 1.0
    assert t.first("%IX0.2") == 1.0
    assert t.first(lambda io: io["%QX0.3"] and io.L2) == 6.5
    assert t.first(lambda io: io.PRG_Main.fbPause.ET >= 500) == 7.0


def test_first_returns_after_itself_when_already_true():
    t = mp9c_like()
    assert t.first("SQ2", after=2.0) == 2.0


def test_first_raises_with_the_window_or_returns_default():
    t = mp9c_like()
    with pytest.raises(NotFound, match=r"never held between t=0 s and t=10 s"):
        t.first(lambda io: io.L2 and not io.SQ2)
    assert t.first(lambda io: io.L2 and not io.SQ2, default=None) is None
    with pytest.raises(NotFound, match="L3 was never true between t=0 s and t=5 s"):
        t.first("L3", until=5.0)


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_first_values_answers_as_first_does(data):
    """`first_values` (one pass over the changes of the signals its predicate reads) is `first`
    for such a predicate: the same instant, or the same NotFound line, over any window; a
    signal declared later reads None before (the TUR-10's contention check uses it)."""
    t = Trace()
    names = ["a", "b", "c"]
    for n in names:
        t.declare(n, "bool", data.draw(st.booleans()), time_ns=data.draw(st.sampled_from([0, 0, 3 * MS])))
    for when in sorted(data.draw(st.lists(st.integers(3 * MS, 2 * S), max_size=30))):
        t.change(when, data.draw(st.sampled_from(names)), data.draw(st.booleans()))
    t.advance(2 * S)
    need = data.draw(st.integers(1, 3))
    chosen = data.draw(st.lists(st.sampled_from(names), min_size=1, max_size=3, unique=True))
    after = data.draw(st.sampled_from([0.0, 0.001, 0.5, 1.0, 3.0]))
    until = data.draw(st.sampled_from([None, 0.0, 0.7, 1.5]))

    def by_state(io):
        return sum(not io[n] for n in chosen) >= need

    def by_values(values):
        return sum(not v for v in values) >= need
    by_values.__name__ = by_state.__name__ = "two_off"
    try:
        expected = t.first(by_state, after=after, until=until)
    except NotFound as e:
        with pytest.raises(NotFound) as got:
            t.first_values(chosen, by_values, after=after, until=until)
        assert str(got.value) == str(e)
        assert t.first_values(chosen, by_values, after=after, until=until, default=None) is None
    else:
        assert t.first_values(chosen, by_values, after=after, until=until) == expected


def test_first_only_evaluates_where_a_read_signal_changes():
    t = Trace()
    t.declare("a", "bool", False)
    t.declare("busy", "int", 0)
    for k in range(1, 1001):
        t.change(k * MS, "busy", k)        # a noisy signal the predicate never reads
    t.change(2 * S, "a", True)
    calls = []

    def pred(io):
        calls.append(io.time_s)
        return io.a

    assert t.first(pred) == 2.0
    assert calls == [0.0, 2.0]


def test_next_change_is_inclusive_and_ignores_initial_values():
    t = mp9c_like()
    assert t.next_change("SQ2") == 1.0
    assert t.next_change("SQ2", after=1.0) == 1.0
    assert t.next_change(["L2", "L3"], after=4.001) == 6.5
    with pytest.raises(NotFound, match="L2, L3 did not change"):
        t.next_change(["L2", "L3"], after=7.0)
    assert t.next_change("L2", after=7.0, default=-1) == -1


def test_edges_pulses_and_durations_high():
    t = mp9c_like()
    assert t.edges("HL1") == [2.0, 3.0, 9.0]
    assert t.edges("HL1", "falling") == [2.25, 3.5]
    assert t.edges("HL1", "any", after=2.5, until=3.6) == [3.0, 3.5]
    assert t.pulses("HL1") == [(2.0, 2.25), (3.0, 3.5), (9.0, 10.0)]   # last closed at trace end
    assert t.durations_high("HL1") == [0.25, 0.5, 1.0]
    assert t.durations_high("HL1", after=2.5, until=5.0) == [0.5]


def test_state_at_reads_values_at_one_instant():
    t = mp9c_like()
    io = t.state_at(4.0)
    assert io.SQ2 is True and io.L2 is True and io["%QX0.3"] is False
    with pytest.raises(AttributeError, match="no signal 'L9'"):
        io.L9
