"""The requirement-declaration API (plclab.grader.registry): a requirement checked in a
`with c.requirement(...)` block passes on a normal exit unless a failure was recorded, is
"not checked" when its scenario stops, and a bug of the grader itself is never charged to
the student (an ERROR row, exit code 2)."""
from __future__ import annotations

import pytest

from plclab.grader import Checks, Requirement, RequirementSet, Scenario, grade_sources
from plclab.grader import registry
from plclab.grader.mp9c import make_session
from plclab.scenario import ScenarioFailure
from plclab.stands import sources
from plclab.stands.mp9c import STAND

R1, R2, R3 = (Requirement(f"R{i}", f"requirement {i}", "s") for i in (1, 2, 3))


def test_a_block_passes_on_exit_fails_on_a_recorded_failure_and_leaves_unreached_ones_unchecked():
    c = Checks((R1, R2, R3))

    def scenario() -> None:
        with c.requirement(R1) as rid:
            assert rid == "R1"
            c.check(rid, True, "x", "x", 0.0)
            return                                  # a return inside the block completes R1
    scenario()
    with c.requirement(R2) as rid:
        c.check(rid, False, "expected", "observed", 1.5)
    with pytest.raises(ScenarioFailure):
        with c.requirement(R3):
            raise ScenarioFailure("the stand could not go on")
    assert "R1" in c.passed and "R1" not in c.failures
    assert c.failures["R2"][0].observed == "observed"
    assert "R3" not in c.passed and "R3" not in c.failures


def test_an_unknown_requirement_is_refused():
    with pytest.raises(KeyError, match="no requirement 'R9'"):
        with Checks((R1,)).requirement("R9"):
            pass


def test_a_grader_bug_is_an_error_row_never_the_students_failure():
    def buggy(s, c):
        with c.requirement("X1"):
            s.run(0.1)
            raise TypeError("a bug in the grader")

    def fine(s, c):
        with c.requirement("X2"):
            s.run(0.1)

    req = RequirementSet(stand="mp9c", task="selftest", title="self test",
                         requirements=(Requirement("X1", "checked by a buggy scenario", "buggy"),
                                       Requirement("X2", "checked by a sound scenario", "fine")),
                         scenarios=(Scenario("buggy", buggy), Scenario("fine", fine)), make_session=make_session)
    registry.register(req)
    try:
        report = grade_sources("mp9c", "selftest", sources(STAND, "task1"))
    finally:
        del registry._REGISTRY[("mp9c", "selftest")]
    x1, x2 = report.row("X1"), report.row("X2")
    assert x2.passed and not x1.passed and x1.internal and x1.result == "ERROR"
    assert "bug of the grader, not of your program" in x1.observed and "TypeError" in x1.observed
    assert report.exit_code == 2 and "not a mistake of your program" in report.text()


def test_a_requirement_repeated_in_step_mode_passes_only_if_checked_to_the_end_in_both():
    """`repeats`: continuous mode passes R1, step mode stops before reaching it: R1 is not
    passed, and its row names the step-mode scenario and why it stopped."""
    def continuous(s, c):
        with c.requirement("X1"):
            s.run(0.1)

    def step(s, c):
        s.run(0.2)
        raise ScenarioFailure("step mode: the first press started nothing")

    x1 = Requirement("X1", "checked in both modes", "continuous")
    req = RequirementSet(stand="mp9c", task="selftest", title="self test", requirements=(x1,),
                         scenarios=(Scenario("continuous", continuous), Scenario("step", step, repeats="continuous")),
                         make_session=make_session)
    assert req.checked_in(x1) == ["continuous", "step"]
    registry.register(req)
    try:
        report = grade_sources("mp9c", "selftest", sources(STAND, "task1"))
    finally:
        del registry._REGISTRY[("mp9c", "selftest")]
    row = report.row("X1")
    assert not row.passed and not row.internal and row.scenario == "step"
    assert row.observed == ("not checked in scenario step: the scenario stopped first: step mode: the first "
                            "press started nothing")
    assert row.time == pytest.approx(0.2, abs=0.011)


def test_a_scenario_repeating_an_unknown_one_is_refused():
    with pytest.raises(ValueError, match="repeats unknown scenario 'nope'"):
        RequirementSet(stand="mp9c", task="selftest", title="t", requirements=(R1,),
                       scenarios=(Scenario("s", lambda s, c: None), Scenario("t", lambda s, c: None, repeats="nope")),
                       make_session=make_session)


@pytest.mark.parametrize("stand,task", [("mp9c", "task2"), ("tur10", "task3"), ("thermo", "scada1"), ("cnc", "task4")])
def test_grade_requirements_lists_the_rows_a_grade_gives_before_grading(stand, task, capsys, tmp_path, monkeypatch):
    from plclab.cli import main
    from plclab.grader import requirement_table

    monkeypatch.chdir(tmp_path)
    assert main(["grade", stand, task, "--requirements"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0].startswith(("MP-9C", "TUR-10", "Thermo", "CNC")) and lines[2].split() == ["id", "requirement"]
    listed = [line.split()[0] for line in lines[4:] if line[:1].strip()]
    table = requirement_table(stand, task, exploration=True)
    assert listed == [rid for rid, _ in table]
    assert (listed[-1] == "E1") == (stand in ("mp9c", "tur10"))                 # the robots are explored too
    joined = " ".join(" ".join(line.split()[1:] if line[:1].strip() else line.split()) for line in lines[4:])
    assert all(text in joined for _, text in table)                               # each sentence, whole
    assert list(tmp_path.iterdir()) == []                                         # graded nothing, wrote nothing


def test_grade_requirements_ids_are_the_rows_of_a_real_grade(capsys):
    from plclab.cli import main

    assert main(["grade", "mp9c", "task1", "--requirements"]) == 0
    listed = [line.split()[0] for line in capsys.readouterr().out.splitlines()[4:] if line[:1].strip()]
    report = grade_sources("mp9c", "task1", sources(STAND, "baseline"))      # the scenarios' rows, then E1
    assert [row.id for row in report.rows] + ["E1"] == listed
    assert main(["grade", "mp9c", "task1", "x.st", "--requirements"]) == 1
    assert "grades nothing" in capsys.readouterr().err
