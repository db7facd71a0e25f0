"""A graded run's state at a row's moment (plclab.grader.replayed): the row's scenario played
again on the graded program, stopped before the first scan after that time, also after a PLC
restart in the scenario; a moment the replay does not reach is one line, never another
moment's state."""
from __future__ import annotations

import pytest

from plclab.errors import PlcLabError
from plclab.grader import Requirement, RequirementSet, Scenario, grade_sources, registry, replayed
from plclab.grader.mp9c import make_session

COUNTER = """PROGRAM Counter
VAR sa5 AT %IX1.4 : BOOL; END_VAR
VAR n : INT; seen : BOOL; END_VAR
n := n + 1;
IF sa5 THEN seen := TRUE; END_IF;
END_PROGRAM
CONFIGURATION Config0
    RESOURCE Res0 ON PLC
        TASK t (INTERVAL := T#10ms, PRIORITY := 0);
        PROGRAM Main WITH t : Counter;
    END_RESOURCE
END_CONFIGURATION
"""
SOURCES = [("counter.st", COUNTER)]


@pytest.fixture
def restarting():
    """One scenario: 1 s, SA5 on, 0.5 s, a PLC restart (the count starts again), 1 s."""
    def run(s, c):
        s.run(1.0)
        s.console.set(SA5=1)
        s.run(0.5)
        s.restart_plc()
        s.run(1.0)
        with c.requirement("X1"):
            c.check("X1", False, "n = 0", str(s.value("Main.n")), s.now)

    req = RequirementSet(stand="mp9c", task="replaytest", title="replay test",
                         requirements=(Requirement("X1", "the count is 0 at the end", "s1"),),
                         scenarios=(Scenario("s1", run),), make_session=make_session)
    registry.register(req)
    yield
    del registry._REGISTRY[("mp9c", "replaytest")]


def state(s):
    return s.now, s.value("Main.n"), s.value("Main.seen")


def test_the_state_is_the_last_scans_at_or_before_the_moment(restarting):
    t, n, seen = replayed("mp9c", "replaytest", SOURCES, "s1", 0.505, state)
    assert n == 51 and not seen                     # scans at 0, 0.01 .. 0.50
    assert t == pytest.approx(0.51)                 # stopped before the scan at 0.51 ran
    _t, n, seen = replayed("mp9c", "replaytest", SOURCES, "s1", 1.2, state)
    assert n == 121 and seen


def test_a_moment_after_a_plc_restart_is_reached_too(restarting):
    report = grade_sources("mp9c", "replaytest", SOURCES)
    row = report.row("X1")
    assert not row.passed and row.observed == str(100)    # the count after the restart: 1 s of scans
    _t, n, seen = replayed("mp9c", "replaytest", SOURCES, "s1", 1.5 + 0.3, state)
    assert 30 <= n <= 31 and seen                         # counted again from the restart (cold), SA5 still on


def test_a_moment_past_the_run_or_an_unknown_scenario_is_one_line(restarting):
    with pytest.raises(PlcLabError, match=r"^the replay of scenario s1 ended at t = 2\.\d\d s, before t = 9\.00 s$"):
        replayed("mp9c", "replaytest", SOURCES, "s1", 9.0, state)
    with pytest.raises(PlcLabError, match="has no scenario 'nope'"):
        replayed("mp9c", "replaytest", SOURCES, "nope", 1.0, state)
