"""Issue 21 item 6: a requirement never checked because an earlier failure stopped its
scenario is NOT CHECKED (not a pass, not a second mistake) in `plclab grade`'s table; with no
failure to explain the stop, the stop itself stays that row's FAIL. grade exits 1 either way
(NOT CHECKED rows only occur after a FAIL). The class outputs: tests/grader/test_class_untrusted.py."""
from __future__ import annotations

import pytest

from plclab.cli import main
from plclab.grader import Requirement, RequirementSet, Scenario, grade, grade_sources
from plclab.grader import registry
from plclab.grader.mp9c import make_session
from plclab.scenario import ScenarioFailure
from plclab.stands import sources
from plclab.stands.mp9c import STAND
from grader_helpers import FIXTURES_DIR


def _selftest(*scenarios: Scenario, requirements: tuple[Requirement, ...]):
    req = RequirementSet(stand="mp9c", task="selftest", title="self test", requirements=requirements,
                         scenarios=scenarios, make_session=make_session)
    registry.register(req)
    try:
        return grade_sources("mp9c", "selftest", sources(STAND, "task1"))
    finally:
        del registry._REGISTRY[("mp9c", "selftest")]


def test_rows_after_a_failure_that_stopped_the_scenario_are_not_checked():
    def flow(s, c):
        with c.requirement("X1"):
            s.run(0.1)
            c.check("X1", False, "L1 = 1", "L1 = 0", s.now)
        with c.requirement("X2"):
            raise ScenarioFailure("the gripper never closed")

    def other(s, c):
        s.run(0.1)
        raise ScenarioFailure("the rotation never started")     # no failure explains this stop

    report = _selftest(Scenario("a", flow), Scenario("b", other),
                       requirements=(Requirement("X1", "one", "a"), Requirement("X2", "two", "a"),
                                     Requirement("X3", "three", "b")))
    x1, x2, x3 = report.row("X1"), report.row("X2"), report.row("X3")
    assert (x1.result, x2.result, x3.result) == ("FAIL", "NOT CHECKED", "FAIL")
    assert x2.observed == "not checked: the scenario stopped first: the gripper never closed"
    assert x3.observed == "not checked: the scenario stopped first: the rotation never started"
    assert not report.passed and report.exit_code == 1
    text = report.text()
    assert any(line.startswith("X2 ") and line.endswith("  NOT CHECKED") for line in text.splitlines())
    assert "0 of 3 requirements passed: FAIL" in text
    assert "1 requirement(s) NOT CHECKED: an earlier failure stopped their scenario" in text
    assert max(len(line) for line in text.splitlines() if line.startswith("X")) <= 100


def test_a_check_made_impossible_by_an_earlier_failure_is_not_checked_even_if_its_block_ends():
    def flow(s, c):
        with c.requirement("X1"):
            c.check("X1", False, "HL1 = 1", "HL1 = 0", 0.0)
        with c.requirement("X2"):
            c.not_checked("X2", "HL1 is 0 (see X1)", 0.0)

    report = _selftest(Scenario("a", flow), requirements=(Requirement("X1", "one", "a"),
                                                            Requirement("X2", "two", "a")))
    assert [r.result for r in report.rows] == ["FAIL", "NOT CHECKED"]
    assert report.row("X2").observed == "not checked: HL1 is 0 (see X1)"


def test_a_real_program_stopping_early_gets_not_checked_rows_and_exit_code_1(capsys, tmp_path):
    fixture = FIXTURES_DIR / "mp9c" / "task3_stops_at_once.st"
    report = grade("mp9c", "task3", [str(fixture)])
    results = {r.id: r.result for r in report.rows}
    assert results["T3.4"] == "FAIL"
    assert results["T3.5"] == results["T3.6"] == "NOT CHECKED"
    assert report.row("T3.5").observed == "not checked: the scenario could not go on after T3.4 failed"
    # the command line prints them so (its scenarios only: the rows are theirs)
    assert main(["grade", "mp9c", "task3", str(fixture), "--out", str(tmp_path), "--explore", "0"]) == 1
    out = capsys.readouterr().out
    assert [line.split()[0] for line in out.splitlines() if line.endswith("NOT CHECKED")] == ["T3.5", "T3.6"]


@pytest.mark.parametrize("fixture, rid, after", [("task3_wrap_not_suppressed", "T3.6", "T3.5")])
def test_a_row_that_says_it_cannot_be_checked_names_the_failure_before_it(fixture, rid, after):
    report = grade("mp9c", "task3", [str(FIXTURES_DIR / "mp9c" / f"{fixture}.st")])
    assert report.row(after).result == "FAIL"
    assert report.row(rid).result == "NOT CHECKED" and f"see {after}" in report.row(rid).observed
