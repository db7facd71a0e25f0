"""CSV writer/reader: exact text, exact round trip, one `FILE:LINE: error:` line per bad row."""
from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plclab.errors import PlcLabError
from plclab.trace import (
    Trace, TraceFormatError, csv_text, diff, format_seconds, parse_csv, parse_seconds,
    read_csv, write_csv)

MS = 1_000_000


def sample() -> Trace:
    t = Trace()
    t.declare("%QX0.1", "bool", False)
    t.declare("%IW2", "int", 0, width=16)
    t.declare("PRG_Main.temp", "real", 20.0)
    t.declare("PRG_Main.state", "str", "IDLE")
    t.change(0, "%IW2", 100)                  # first scan at t=0
    t.change(10 * MS, "PRG_Main.temp", 0.1 + 0.2)
    t.change(1_250 * MS, "%QX0.1", True)
    t.change(1_250 * MS, "PRG_Main.state", "RUN, fast")
    t.change(1_230 * MS, "%IW2", 7)
    return t


def test_csv_text_is_exact():
    assert csv_text(sample()) == (
        "time_s,name,value\n"
        "0,%QX0.1,0\n"
        "0,%IW2,100\n"
        "0,PRG_Main.temp,20.0\n"
        '0,PRG_Main.state,"IDLE"\n'
        "0.01,PRG_Main.temp,0.30000000000000004\n"
        "1.23,%IW2,7\n"
        "1.25,%QX0.1,1\n"
        '1.25,PRG_Main.state,"RUN, fast"\n')


def test_every_signal_has_its_initial_value_at_time_zero():
    t = sample()
    t.declare("PRG_Main.late", "int", 5)
    rows = csv_text(t).splitlines()[1:]
    at_zero = [r.split(",")[1] for r in rows if r.startswith("0,")]
    assert at_zero == t.signals()


@pytest.mark.parametrize("ns,text", [(0, "0"), (10 * MS, "0.01"), (1_250 * MS, "1.25"),
                                     (3_000_000_000, "3"), (300_000_000, "0.3"), (1, "0.000000001")])
def test_times_are_printed_exactly_and_parsed_back(ns, text):
    assert format_seconds(ns) == text
    assert parse_seconds(text) == ns


def test_round_trip_is_exact(tmp_path):
    t = sample()
    path = tmp_path / "run.csv"
    write_csv(t, path)
    back = read_csv(path)
    assert back.signals() == t.signals()
    for name in t.signals():
        assert back.changes(name) == t.changes(name)
        assert back.info(name).kind == t.info(name).kind
    assert back.info("%IW2").width == 16       # the address gives the width back
    assert diff(t, back) is None


def test_a_quoted_digit_string_stays_a_string_and_real_stays_real():
    t = Trace()
    t.declare("s", "str", "1")
    t.declare("r", "real", 1.0)
    t.declare("q", "str", 'say "hi"\nbye')
    back = parse_csv(csv_text(t))
    assert back.changes("s") == [(0, "1")] and back.info("s").kind == "str"
    assert back.changes("r") == [(0, 1.0)] and back.info("r").kind == "real"
    assert back.changes("q") == [(0, 'say "hi"\nbye')]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(1, 5_000_000_000), st.integers(0, 2),
                          st.one_of(st.integers(-2**31, 2**31), st.floats(allow_nan=False),
                                    st.text(max_size=5))),
                max_size=30))
def test_round_trip_random_traces(events):
    t = Trace()
    t.declare("i", "int", 0)
    t.declare("r", "real", 0.5)
    t.declare("s", "str", "")
    for time_ns, which, value in sorted(events, key=lambda e: e[0]):
        name = "irs"[which]
        if name == "i" and isinstance(value, int) and not isinstance(value, bool):
            t.change(time_ns, name, value)
        elif name == "r" and isinstance(value, float):
            t.change(time_ns, name, value)
        elif name == "s" and isinstance(value, str):
            t.change(time_ns, name, value)
    back = parse_csv(csv_text(t), kinds={"i": "int", "r": "real", "s": "str"})
    for name in "irs":
        assert back.changes(name) == t.changes(name)


def test_kinds_inferred_when_not_given():
    back = parse_csv("time_s,name,value\n0,a,0\n0,b,0\n0,c,0.5\n0,d,OPEN\n0,%MW3,1\n"
                     "1,a,TRUE\n1,b,-2\n")
    assert [back.info(n).kind for n in "abcd"] == ["bool", "int", "real", "str"]
    assert back.info("%MW3").kind == "int" and back.info("%MW3").width == 16
    assert back.value_at("a", 1.0) is True


def test_input_scripts_may_start_a_signal_later():
    text = "time_s,name,value\n0.5,%IX0.0,1\n0.8,%IX0.0,0\n"
    script = parse_csv(text, require_initial=False)
    assert script.changes("%IX0.0") == [(500 * MS, True), (800 * MS, False)]
    with pytest.raises(TraceFormatError, match="has no initial value at time 0"):
        parse_csv(text, filename="in.csv")


@pytest.mark.parametrize("body,line,message", [
    ("time,name,value\n", 1, "expected the header `time_s,name,value`, got `time,name,value`"),
    ("", 1, "empty file"),
    ("time_s,name,value\n0,a,1\n0.5,b\n", 3, "expected 3 fields (time_s,name,value), got 2"),
    ("time_s,name,value\n0,a,1\nsoon,a,0\n", 3, "bad time 'soon'"),
    ("time_s,name,value\n0,a,1\n-1,a,0\n", 3, "bad time '-1'"),
    ("time_s,name,value\n0,a,1\n0.0000000001,a,0\n", 3, "finer than 1 ns"),
    ("time_s,name,value\n0,a,1\n\n2,a,0\n1,a,1\n", 5,
     "time 1 s is before the previous row's 2 s (line 4)"),
    ("time_s,name,value\n0,a,1\n0,a,0\n", 3, "second value for a at t=0 s (first on line 2)"),
    ("time_s,name,value\n0,%QX0.0,0\n1,%QX0.0,2\n", 3, "bad value '2' for BOOL %QX0.0"),
    ("time_s,name,value\n0,,1\n", 2, "empty signal name"),
])
def test_bad_rows_give_one_file_line_error(tmp_path, body, line, message):
    path = tmp_path / "bad.csv"
    path.write_text(body)
    with pytest.raises(TraceFormatError) as info:
        read_csv(path)
    text = str(info.value)
    assert text.startswith(f"{path}:{line}: error: ")
    assert message in text
    assert "\n" not in text


def test_format_error_is_a_value_error_and_a_user_error():
    with pytest.raises(ValueError):
        parse_csv("nope\n")
    assert issubclass(TraceFormatError, PlcLabError)


def test_kinds_argument_validates_values():
    with pytest.raises(TraceFormatError, match=r"<csv>:3: error: bad value '1.5' for integer n"):
        parse_csv("time_s,name,value\n0,n,1\n1,n,1.5\n", kinds={"n": "int"})


def test_reader_accepts_a_bom_and_crlf(tmp_path):
    path = tmp_path / "excel.csv"
    path.write_bytes(b"\xef\xbb\xbftime_s,name,value\r\n0,x,1\r\n0.25,x,0\r\n")
    t = read_csv(path)
    assert t.changes("x") == [(0, True), (250 * MS, False)]
    assert not math.isnan(t.end_s) and t.end_s == 0.25
