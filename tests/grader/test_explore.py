"""Exploration (issue 21): the student's program against the task's model answer under seeded
random operator scripts. Mistakes that only an unscripted console history shows are caught,
with a minimal script a student can replay and the student's ST line; the same file gives
the same report; the budget is what it says. (That a mistake is found by many scripts:
test_explore_rates.py; that correct programs written differently pass:
test_explore_alternatives.py.)"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from plclab.grader import engine
from plclab.grader.explore import explore, model_answer
from plclab.stands.scripts import read_script
from plclab.grader.registry import requirement_set
from plclab.runner import run_scenario
from plclab.stands import get_stand
from plclab.stands.base import stand_spec

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import make_explore_fixtures as mf  # noqa: E402
from explore_cases import FIXTURES, MISTAKES, explore_fixture, program  # noqa: E402

# the scripted scenarios' own fixtures of the same kind: exploration finds them too
WATCHDOG_WHOLE_RUN = [("mp9c", FIXTURES / "mp9c" / "task2_watchdog_whole_run.st"),
                      ("tur10", FIXTURES / "tur10" / "task2_watchdog_whole_run.st")]


def test_fixture_generator_check_finds_every_fixture_current():
    r = subprocess.run([sys.executable, str(HERE / "make_explore_fixtures.py"), "--check"], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr


@pytest.mark.parametrize("fixture", MISTAKES, ids=lambda f: f"{f.stand}-{f.name}")
def test_a_mistake_only_a_console_history_shows_is_found_with_its_script_and_line(fixture):
    path = mf.path(fixture)
    result = explore_fixture(fixture.stand, fixture.task, path)
    f = result.finding
    assert f is not None, f"{fixture.name}: no divergence in {result.episodes} scripts"
    # shrunk: a handful of console steps, not the random script's dozens
    assert 1 <= len(f.script.events) <= fixture.max_steps, f.steps
    assert f.steps[0].startswith("1. ") and " s " in f.steps[0]
    assert "the model answer has" in f.first_difference and "your program" in f.first_difference
    # the student's line: in the student's file, a statement writing the differing output
    assert f.line is not None, f.first_difference
    file, line, stmt = f.line
    assert Path(file).name == path.name and line > 1
    assert stmt.replace(" ", "").startswith(f"{f.output}:=") or f.output in stmt, (f.output, stmt)
    assert path.read_text().splitlines()[line - 1].strip() == stmt


@pytest.mark.parametrize("stand,path", WATCHDOG_WHOLE_RUN, ids=lambda x: str(x).split("/")[-1])
def test_a_watchdog_that_times_the_whole_run_is_found_with_a_one_minimal_script(stand, path, tmp_path):
    from plclab.grader.explore import Explorer
    from plclab.stands.scripts import without
    model, _ = model_answer(stand, "task2", None)
    student = program(path)
    expl = stand_spec(stand).explore
    result = explore(expl, stand, "task2", requirement_set(stand, "task2").make_session, student, model)
    f = result.finding
    assert f is not None
    assert f.divergence.signal.name == "HL1"          # the fault's blinking: a stop the model answer has not
    assert Path(f.line[0]).name == path.name
    # shrunk to 1-minimal: without any one of its steps the script shows no difference
    ex = Explorer(expl, "task2", requirement_set(stand, "task2").make_session, student, model)
    assert ex.diverges(f.script) is not None
    for k in range(len(f.script.events)):
        assert ex.diverges(without(f.script, {k})) is None, f"step {k + 1} of {f.steps} is not needed"


def test_a_lamp_is_compared_as_it_is_seen_on_off_or_blinking():
    from plclab.stands.operators import BLINKING, lamp_pattern, lamp_timing
    steady = [(0.0, True), (2.0, False), (5.0, True)]
    assert lamp_pattern(steady) == steady                       # changes far apart: as they are
    blink = [(0.0, False)] + [(1.0 + 0.5 * k, k % 2 == 0) for k in range(4)] + [(9.0, True)]
    # on at 1.0, off 1.5, on 2.0, off 2.5: a blink from 1.0, off from 2.5 (as the last toggle left it)
    assert lamp_pattern(blink) == [(0.0, False), (1.0, BLINKING), (2.5, False), (9.0, True)]
    off_first = [(0.0, False)] + [(1.5 + 0.5 * k, k % 2 == 0) for k in range(4)]
    assert lamp_pattern(off_first)[1] == (1.5, BLINKING)        # the other phase: 0.5 s later,
    assert lamp_timing(False, BLINKING) >= 0.5                  # within the freedom of the phase
    assert lamp_timing(True, False) is None                     # a steady change: the stand's timing
    two = [(0.0, False), (1.0, True), (1.4, False)]             # one short pulse is no blink
    assert lamp_pattern(two) == two


def _compare_lamp(model_changes, student_changes, script_rows, stand="mp9c", task="task2"):
    from plclab.grader.explore import compare
    from plclab.stands.scripts import Event, Script
    expl = stand_spec(stand).explore
    observed = [o for o in expl.compared(task) if o.name == "HL1"]
    events = tuple(Event(t, n, v) for t, n, v in script_rows)
    return compare({"HL1": model_changes}, {"HL1": student_changes}, observed, expl, Script(events, 30.0), 30.0)


def test_how_the_full_memory_blink_answers_more_presses_is_free_in_manual_mode_only():
    # the model answer blinks 2 s from the first refused press; the student's restarts the
    # blink at each press, so its lamp stays on while presses come, then blinks 2 s more
    model = [(0.0, False)] + [(5.0 + 0.5 * k, k % 2 == 0) for k in range(4)]
    student = [(0.0, False), (5.0, True), (6.6, False), (6.9, True), (7.4, False), (7.9, True), (8.4, False)]
    assert _compare_lamp(model, student, []) is None                           # manual mode: free
    auto = [(0.5, "SA1", "1")]
    d = _compare_lamp(model, student, auto)                                    # automatic mode: compared
    assert d is not None and d.signal.name == "HL1"
    # a lamp that never blinks where the model answer's does is a difference in automatic mode
    d = _compare_lamp(model, [(0.0, False)], auto)
    assert d is not None and d.kind == "missing"


def test_every_task_explores_its_model_answer_without_a_difference():
    for stand in ("mp9c", "tur10"):
        for task in ("task1", "task2", "task3"):
            model, _ = model_answer(stand, task, None)
            r = explore(stand_spec(stand).explore, stand, task, requirement_set(stand, task).make_session,
                        model, model, 1)
            assert r.finding is None and r.episodes == 1 and r.plant_seconds > 20


def _grade(path: Path, out: Path, explore_n):
    return engine.grade("mp9c", "task3", [str(path)], out_dir=str(out), explore=explore_n)


def test_the_report_is_the_same_byte_for_byte_and_the_script_replays_the_difference(tmp_path, capsys):
    path = mf.path(next(f for f in MISTAKES if f.stand == "mp9c" and f.name == "task3_stop_needs_enable"))
    first = _grade(path, tmp_path / "out", None)          # the default budget: found whatever the seed
    script_file = tmp_path / "out" / "mp9c-task3-explore.csv"
    first_script = script_file.read_text()
    second = _grade(path, tmp_path / "out", None)
    assert first.text() == second.text()
    assert script_file.read_text() == first_script
    row = first.row("E1")
    assert not row.passed and row.steps and row.expected and row.observed
    assert "timing +/- 0.06 s" in row.expected                   # the tolerance
    assert any(line.startswith(f"{path.name}:") for line in row.lines)   # the student's lines, ranked
    assert f"last written by {path.name}:" in row.written
    assert any(n.startswith("replay: plclab run mp9c --program") for n in first.notes)
    # the script file is the input-CSV format and replays the same difference
    assert first_script.splitlines()[0] == "time_s,name,value"
    r = run_scenario("mp9c", program=[str(path)], inputs=str(script_file), against="task3", out_dir=str(tmp_path))
    assert r.failure is not None and r.failure == row.steps[-1].removeprefix("-> ")
    # and through the command line, as a student types it
    from plclab.cli import main
    code = main(["run", "mp9c", "--program", str(path), "--inputs", str(script_file), "--against", "task3"])
    assert code == 1
    assert f"difference from the task3 model answer: {r.failure}" in capsys.readouterr().out


def test_the_budget_is_a_number_of_scripts_and_the_report_says_how_much_was_explored(tmp_path):
    model_file = tmp_path / "model.st"
    from plclab.stands import bundle
    model_file.write_text(bundle(get_stand("mp9c"), "task3"))
    report = _grade(model_file, tmp_path / "out", 3)
    assert report.row("E1").passed
    note = next(n for n in report.notes if n.startswith("exploration:"))
    assert "3 random operator scripts" in note and "s of plant time" in note and "no difference" in note
    assert report.exit_code == 0


def test_without_a_model_answer_the_scenarios_run_and_one_line_says_why(tmp_path, monkeypatch):
    from plclab import stands
    model_file = tmp_path / "model.st"
    model_file.write_text(stands.bundle(get_stand("mp9c"), "task3"))
    monkeypatch.setattr(stands, "SOLUTIONS_DIR", None)          # as in the installed wheel
    report = engine.grade("mp9c", "task3", [str(model_file)], explore=None)
    assert all(r.id != "E1" for r in report.rows) and report.rows
    assert [n for n in report.notes if n.startswith("exploration not run:")] == \
        ["exploration not run: no model answer here (the installed package carries none): run the grade in the "
         "instructor's checkout of PLC Lab, or give the course's model answer with --reference FILE.st..."]
    # a course's own model answer given with --reference: exploration runs
    ref = tmp_path / "ours.st"
    ref.write_text(model_file.read_text())
    report = engine.grade("mp9c", "task3", [str(model_file)], reference=[str(ref)], explore=2)
    assert report.row("E1").passed


def test_an_operator_script_file_round_trips(tmp_path):
    import random
    expl = stand_spec("mp9c").explore
    script = expl.generate(random.Random(7), "task2", 30.0)
    f = tmp_path / "s.csv"
    f.write_text(script.csv_text())
    again = read_script(str(f), stand_spec("mp9c"))
    assert again.csv_text() == script.csv_text()
    kinds = {e.name for e in script.events}
    assert "SB1" in kinds and "SA1" in kinds


def test_a_retain_function_block_with_external_variables_survives_a_power_cycle(tmp_path):
    """A student may declare a block instance RETAIN (a 'resume after power failure' idea):
    its VAR_EXTERNAL names are the globals', not variables of the instance, and a restart
    must neither fail nor lose the instance's own retained values."""
    from plclab.scenario import Session
    from plclab.stands import bundle
    from plclab.stands.mp9c import STAND, labels
    text = bundle(STAND, "task2").replace(
        "VAR RETAIN\n    Cp : ST_ControlProgram;", "VAR RETAIN\n    Robot : FB_Mp9cAutomatic;\n    Cp : ST_ControlProgram;", 1)
    text = text.replace("    Robot : FB_Mp9cAutomatic;       (* automatic work mode subroutine *)\n", "", 1)
    s = Session([("robot.st", text)], STAND.make_plant(), labels(), retain_path=tmp_path / "r.json")
    s.run(0.2)
    s.plc.write("Main.Robot.Valves", 77)
    s.restart_plc(off_time=0.5)
    s.run(0.05)
    assert s.fault is None
    assert s.value("Main.Robot.Valves") == 77


@pytest.mark.parametrize("rows,says", [
    ("0.1,SA9,1", "'SA9' is no console input of mp9c"),
    ("0.1,SA5,2", "SA5 takes 0 or 1"),
    ("0.1,PLC,soon", "PLC takes the seconds the PLC stays off"),
    ("0.1,FAULT,nope x=1", "unknown fault 'nope'"),
    ("0.1,FAULT,jammed mechanism=foo", "unknown mechanism 'foo'"),
])
def test_a_bad_operator_script_is_one_clear_line(tmp_path, capsys, rows, says):
    from plclab.cli import main
    script = tmp_path / "s.csv"
    script.write_text(f"time_s,name,value\n{rows}\n1.0,END,0\n")
    assert main(["run", "mp9c", "--variant", "task2", "--inputs", str(script), "--csv", str(tmp_path / "t.csv")]) != 0
    err = capsys.readouterr().err
    assert says in err and str(script) in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_a_script_names_a_console_input_by_its_label_plant_name_or_address(tmp_path):
    from plclab.stands.scripts import read_script
    rows = "time_s,name,value\n0.5,I0.7,1\n0.6,i07,0\n0.7,%IX0.7,1\n1.0,SB1,1\n1.2,sb1,0\n2.0,END,0\n"
    f = tmp_path / "s.csv"
    f.write_text(rows)
    from plclab.stands import stand_module
    labels = stand_module("mp9c").session("baseline", watch_internals=False, retain_path=tmp_path / "r.json").labels
    script = read_script(str(f), stand_spec("mp9c"), labels)
    assert [(e.name, e.value, e.hold) for e in script.events] == [("I07", "1", 0.0), ("I07", "0", 0.0),
                                                                   ("I07", "1", 0.0), ("SB1", "1", 0.2)]
    assert script.duration == 2.0


def test_a_difference_is_named_by_the_requirement_it_plainly_breaks():
    from plclab.grader.explore import Divergence, Finding, requirement_of
    from plclab.stands.scripts import Event, Script
    expl = stand_spec("mp9c").explore
    rotation = next(o for o in expl.compared("task1") if o.name == "rotation")
    div = Divergence(0.5, rotation, 1, 0, "missing", 0.0, 0.0)

    def finding(*events):
        return Finding(Script(tuple(events), 3.0), div, [], "", None, None, 0.5)
    # manual mode from power-up: the rotation not following SA3 is Task 1's rotation row
    assert requirement_of("mp9c", "task1", finding(Event(0.3, "SA3", "1")), expl) == "T1.2"
    # after automatic mode the same difference has other causes: E1's own
    assert requirement_of("mp9c", "task1", finding(Event(0.1, "SA1", "1"), Event(0.2, "SA1", "0"),
                                                   Event(0.3, "SA3", "1")), expl) is None
    assert requirement_of("mp9c", "task2", finding(Event(0.3, "SA3", "1")), expl) is None


def test_a_too_long_pause_is_measured_not_only_missed(tmp_path):
    """Issue 21's poor message: a too-long pause was "every reference stayed 0" without the
    pause measured. The row now says when the next frame came."""
    from plclab.stands import bundle
    path = tmp_path / "long_pause.st"
    path.write_text(bundle(get_stand("tur10"), "task2").replace("LONG_PAUSE : TIME := T#3s;",
                                                                  "LONG_PAUSE : TIME := T#6s;", 1))
    row = engine.grade("tur10", "task2", [str(path)]).row("T2.2")
    assert not row.passed
    assert "every reference stayed 0" in row.observed and "the next nonzero reference came at t = " in row.observed
    assert "6.0" in row.observed.split("came at t = ")[1]           # 6.0x s after the frame was reached


def test_a_pause_stored_on_every_manual_scan_is_named_as_a_possible_cause(tmp_path):
    """Issue 21's poor message: a pause stored on every manual scan was reported only as "off
    by one". The row names that cause beside the index one."""
    from plclab.stands import bundle
    text = bundle(get_stand("mp9c"), "task2")
    store = "        Cp.Frames[Cp.Count].Pause := SEL(G := I07, IN0 := SHORT_PAUSE, IN1 := LONG_PAUSE);\n"
    text = text.replace(store, "").replace(
        "(* SB1: CP frame saving, program reset *)\n",
        "(* SB1: CP frame saving, program reset *)\nIF Cp.Count > 0 THEN\n    Cp.Frames[Cp.Count].Pause := "
        "SEL(G := I07, IN0 := SHORT_PAUSE, IN1 := LONG_PAUSE);\nEND_IF;\n", 1)
    path = tmp_path / "every_scan.st"
    path.write_text(text)
    row = engine.grade("mp9c", "task2", [str(path)]).row("T2.2")
    assert not row.passed and "stored on every manual scan instead of at the SB1 press" in row.observed


def test_an_extension_interlocked_with_the_lift_fails_its_own_row(tmp_path):
    """Issue 21's poor message: an extension interlocked with the lift was reported only as a
    playback difference of frame 3. The manual row checks each switch with the others at 1 too."""
    from plclab.stands import bundle
    text = bundle(get_stand("mp9c"), "task1").replace(
        "L6 := SA4;                          (* arm forward *)\nL7 := NOT SA4;                      (* arm backward *)\n",
        "L6 := SA4 AND NOT SA5;              (* arm forward, only while the arm is up *)\nL7 := NOT L6;\n", 1)
    path = tmp_path / "interlock.st"
    path.write_text(text)
    row = engine.grade("mp9c", "task1", [str(path)]).row("T1.3")
    assert not row.passed
    assert "after SA4 := 1 (with SA2=1 SA3=1 SA5=1): L6=1 L7=0" in row.expected and row.observed == "L6=0 L7=1"
