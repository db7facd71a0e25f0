"""A program checked again is the unit checked before (a stand's sessions, a test's, the lab's
reloads check one shipped program over and over): the same CheckedUnit for the same files
under the same limits, a new check for anything else, and two sessions of one program that
share it still keep their own state."""
from __future__ import annotations

import pytest

import plclab.frontend as F
from plclab.errors import CompileError
from plclab.frontend import check_limits, check_sources
from plclab.runtime import native
from plclab.stands import bundle, cnc, get_stand
from plclab.stands.base import stand_spec

SMALL = ("PROGRAM PCount\nVAR n : INT; END_VAR\nn := n + 1;\nEND_PROGRAM\n"
         "CONFIGURATION Config0 RESOURCE Res0 ON PLC TASK t(INTERVAL := T#10ms, PRIORITY := 1); "
         "PROGRAM i WITH t : PCount; END_RESOURCE END_CONFIGURATION\n")


def test_the_same_files_give_the_same_unit_and_any_difference_a_new_check():
    text = bundle(get_stand("mp9c"), "task3")
    first = check_sources([("robot.st", text)])
    assert check_sources([("robot.st", text)]) is first
    assert check_sources(iter([("robot.st", text)])) is first            # any iterable of the pairs
    renamed = check_sources([("other.st", text)])                          # a name is in every diagnostic
    assert renamed is not first and renamed.unit.pous[0].file == "other.st"
    edited = check_sources([("robot.st", text.replace("T#3s", "T#4s", 1))])
    assert edited is not first
    assert check_sources([("robot.st", text)]) is first


def test_a_program_that_fails_is_checked_each_time_and_a_lowered_limit_is_obeyed(monkeypatch):
    bad = SMALL.replace("n := n + 1;", "n := n + ;")
    for _ in range(2):
        with pytest.raises(CompileError) as info:
            check_sources([("bad.st", bad)])
        assert info.value.diagnostics[0].line == 3
    nested = SMALL.replace("n := n + 1;", "IF n > 0 THEN IF n > 1 THEN n := 2; END_IF; END_IF;")
    ok = check_sources([("nested.st", nested)])
    assert check_sources([("nested.st", nested)]) is ok
    monkeypatch.setattr(check_limits, "MAX_STATEMENT_NESTING", 1)
    with pytest.raises(CompileError) as info:                      # not the unit checked under the old limit
        check_sources([("nested.st", nested)])
    assert "nest" in str(info.value)


def test_the_units_kept_stay_within_their_bound(monkeypatch):
    monkeypatch.setattr(F, "_CHECKED", type(F._CHECKED)())
    monkeypatch.setattr(F, "CHECKED_CHARS", 3 * len(SMALL) + 10)
    units = [check_sources([(f"p{n}.st", SMALL)]) for n in range(6)]
    assert len(F._CHECKED) == 3 and sum(n for _unit, n in F._CHECKED.values()) == 3 * len(SMALL)
    assert check_sources([("p5.st", SMALL)]) is units[5]               # the last ones kept
    assert check_sources([("p0.st", SMALL)]) is not units[0]           # the first dropped: checked anew
    big = SMALL + "(*" + "x" * F.CHECKED_MAX_CHARS + "*)\n"
    assert check_sources([("big.st", big)]) is not check_sources([("big.st", big)])
    assert sum(n for _unit, n in F._CHECKED.values()) <= F.CHECKED_CHARS


def test_a_drawn_program_is_checked_each_time():
    """ST made from a plc.xml (a GeneratedSource) names the drawing in its diagnostics and
    carries it in the unit (`drawings`): each check keeps its own."""
    from plclab.frontend.graphical.places import GeneratedSource
    drawn = GeneratedSource(SMALL, {}, "drawn.st")
    first = check_sources([("drawn.st", drawn)])
    assert first.drawings == {"drawn.st": drawn}
    assert check_sources([("drawn.st", drawn)]) is not first


def test_two_sessions_of_one_program_share_its_unit_and_keep_their_own_state():
    spec = stand_spec("mp9c")
    a, b = spec.session("full"), spec.session("full")
    assert a.checked is b.checked and a.plc is not b.plc
    a.console.set(SA1=0, SA5=1)                  # manual mode, arm down: only on stand a
    a.run(2.0)
    b.run(2.0)
    fresh = spec.session("full")
    fresh.run(2.0)
    labels = sorted(a.labels)

    def story(s):
        return {k: s.trace.changes(k) for k in labels if k in s.trace}
    assert story(a) != story(b)
    assert story(b) == story(fresh)


def test_the_c_of_a_program_is_made_once_per_checked_unit(monkeypatch):
    made = []
    emit = native.emit_c
    monkeypatch.setattr(native, "emit_c", lambda checked: made.append(checked) or emit(checked))
    monkeypatch.setattr(native, "_EMITTED", {})
    sessions = [cnc.session() for _ in range(3)]
    assert sessions[0].checked is sessions[2].checked
    assert sessions[0].plc.compiled is not sessions[2].plc.compiled        # each its own compiled state
    assert len(made) == 1
    cnc.session(fine_ms=5)                                                  # another program: its own C
    assert len(made) == 2
