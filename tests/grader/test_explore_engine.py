"""The exploration engine (issues 29 and 30): searching without recording and with the model
answer's side played once gives the same report as recording everything; `--jobs N` gives the
same report as one process; a class's graders share the model answer's plays; coverage-guided
exploration finds the mistakes a random script rarely shows within the default budget."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

import plclab.grader.explore as explore_module
from plclab.frontend import check_sources, read_sources
from plclab.grader.explore import Explorer, Program, explore, model_answer, script_stream, states_of
from plclab.grader.registry import requirement_set
from plclab.stands.base import stand_spec

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import make_explore_fixtures as mf  # noqa: E402
from explored import explored  # noqa: E402


def _fixture(name: str) -> Path:
    return mf.path(next(f for f in mf.ALL if f"{f.stand}/{f.name}" == name))


def _program(path: Path) -> Program:
    srcs = read_sources([path])
    return Program(srcs, check_sources(srcs))


def _finding(result) -> tuple:
    f = result.finding
    return (result.episodes, round(result.plant_seconds, 6), result.inconclusive, result.seed,
            f and f.steps, f and f.first_difference, f and f.line, f and f.script.csv_text())


def test_the_report_is_the_same_recorded_or_not_and_on_one_or_two_processes(tmp_path, capsys, monkeypatch):
    """`plclab grade` of a one-mistake program: searching without recording (the default), with
    every play recorded in full and nothing reused (as before issue 30), and with --jobs 2: the
    same report byte for byte, and the same script file."""
    from plclab.cli import main
    path = _fixture("mp9c/task2_resume_after_power_cycle")
    texts, scripts = [], []
    for how in ("search", "recorded", "jobs2"):
        out = tmp_path / how
        if how == "recorded":
            original = explore_module.Explorer.__init__

            def recorded(self, *args, **kwargs):
                kwargs["record"] = True
                original(self, *args, **kwargs)
            monkeypatch.setattr(explore_module.Explorer, "__init__", recorded)
        argv = ["grade", "mp9c", "task2", str(path), "--out", str(out)] + (["--jobs", "2"] if how == "jobs2" else [])
        code = main(argv)
        monkeypatch.undo()
        texts.append(capsys.readouterr().out.replace(str(out), "OUT"))
        scripts.append((out / "mp9c-task2-explore.csv").read_text())
        assert code == 1
    assert "E1" in texts[0] and "FAIL" in texts[0]
    assert texts[0] == texts[1] == texts[2]
    assert scripts[0] == scripts[1] == scripts[2]


def test_a_passing_exploration_is_the_same_on_two_processes():
    """A correct alternative: every script of the budget played, on one process and on two."""
    path = _fixture("mp9c/task2_alt_pause_if")
    model, _ = model_answer("mp9c", "task2", None)
    expl = stand_spec("mp9c").explore
    runs = [explore(expl, "mp9c", "task2", requirement_set("mp9c", "task2").make_session, _program(path), model, 10,
                    jobs=jobs) for jobs in (1, 2)]
    assert runs[0].finding is None and runs[0].episodes == 10
    assert _finding(runs[0]) == _finding(runs[1])


def test_a_class_plays_the_model_answer_once_per_script(tmp_path):
    """Two students under the class's seed with a shared folder of model-answer plays: the
    second plays none of the model answer's side, and its result is what it is alone."""
    model, _ = model_answer("mp9c", "task2", None)
    expl = stand_spec("mp9c").explore
    make = requirement_set("mp9c", "task2").make_session
    first = explore(expl, "mp9c", "task2", make, _program(_fixture("mp9c/task2_alt_pause_if")), model, 6, seed=7,
                    model_plays=tmp_path)
    student = _program(_fixture("mp9c/task2_alt_counter_debounce"))
    second = explore(expl, "mp9c", "task2", make, student, model, 6, seed=7, model_plays=tmp_path)
    alone = explore(expl, "mp9c", "task2", make, student, model, 6, seed=7)
    assert first.model_plays >= 5 and second.model_plays == 0 and alone.model_plays == first.model_plays
    assert _finding(second) == _finding(alone)
    assert len(list(tmp_path.glob("*.play"))) == 6


def test_the_scripts_depend_on_the_seed_and_the_model_answer_never_on_the_student(tmp_path):
    """Coverage guidance reads the model answer's states only: two students get the same
    stream, and after the first round some scripts are kept scripts mutated."""
    model, _ = model_answer("mp9c", "task2", None)
    expl = stand_spec("mp9c").explore
    make = requirement_set("mp9c", "task2").make_session
    streams = []
    for name in ("mp9c/task2_alt_pause_if", "mp9c/task2_full_memory_wraps"):
        ex = Explorer(expl, "task2", make, _program(_fixture(name)), model)
        streams.append(list(script_stream(ex, 3, 16)))
    assert streams[0] == streams[1]
    ex = Explorer(expl, "task2", make, _program(_fixture("mp9c/task2_alt_pause_if")), model)
    plain = list(script_stream(ex, 3, 16, coverage=False))
    assert plain[:8] == streams[0][:8] and plain[8:] != streams[0][8:]
    states = states_of(ex, streams[0][0])
    assert states and all(len(s) == 2 + len(expl.state_paths) for s in states)


RARE = ["mp9c/task2_full_memory_wraps", "mp9c/task2_restart_needs_two_presses"]


@pytest.mark.parametrize("name", RARE)
def test_coverage_guided_exploration_finds_a_rare_mistake_within_the_default_budget(name):
    """Memory full then a refused press; a restart that needs two presses: found within the
    stand's default budget, under the submission's own seed, with the script that shows it."""
    path = _fixture(name)
    expl = stand_spec("mp9c").explore
    result = explored("mp9c", "task2", path)       # as `plclab grade` explores (once per session)
    assert result.finding is not None, f"{name}: no difference in {result.episodes} scripts"
    assert result.episodes <= expl.episodes


@pytest.mark.parametrize("record", [True, False], ids=["recorded", "searching"])
@pytest.mark.parametrize("stand", ["mp9c", "tur10"])
def test_a_play_through_idle_scans_shows_what_stepping_every_scan_shows(stand, record, monkeypatch):
    """Where a robot stands idle under unchanged outputs, the closed loop does not step it, write
    its inputs again or look at it (issue 30); while searching (nothing recorded) it runs such
    quiet stretches in one native call, up to the scan that changes an output or the model
    answer's inner state (PLC.run_quiet). The TUR-10 is stepped on values in order (no dicts),
    and where no link or lamp changed, the probe does not look and its trace records nothing.
    Over generated scripts with faults and power cycles, each played with those shortcuts and
    with every scan stepped in full through the plant's dict step, looked at and recorded:
    the same recorded trace, the same changes the probe saw and the model answer's states,
    the same plant, plant events and PLC at the end; and the shortcuts were taken."""
    import dataclasses
    import random

    from plclab.grader.explore import play
    from plclab.plants.tur10 import Tur10
    from plclab.runtime.plantio import PlantBinding
    from plclab.runtime.plc import PLC
    from plclab.runtime.retain import MemoryRetainStore
    expl = stand_spec(stand).explore
    model, _why = model_answer(stand, "task3", None)
    req = requirement_set(stand, "task3")
    idle_scans = quiet_scans = unchanged_looks = 0
    if expl.unchanged is not None:
        last_seen: list = [None]

        def counting_unchanged(plant):
            nonlocal unchanged_looks
            seen_now = expl.unchanged(plant)
            unchanged_looks += seen_now == last_seen[0]
            last_seen[0] = seen_now
            return seen_now
        expl_short = dataclasses.replace(expl, unchanged=counting_unchanged)
    else:
        expl_short = expl
    for seed in range(3):
        script = expl.generate(random.Random(seed), "task3", expl.episode_s)
        inner = expl.state_paths if seed != 1 else ()      # the model answer's side, and a student's
        seen = []
        for shortcut in (True, False):
            s = req.make_session(list(model.sources), MemoryRetainStore(), model.checked)
            if not shortcut:                 # every step in full, the plant's own shortcut too
                monkeypatch.setattr(PlantBinding, "step_idle", lambda self, dt: False)
                monkeypatch.setattr(type(s.plant), "idle", lambda self, outputs, dt: False)
                # the plant's step on names (a dict each way), and a TUR-10 whose every step
                # counts as a change: looked at and recorded at every scan
                monkeypatch.setattr(PlantBinding, "step",
                                    lambda self, dt: self.write_inputs(self.plant.step(self.read_outputs(), dt)))
                every_values = Tur10.step_values

                def every_step_a_change(self, outputs, dt):
                    values = every_values(self, outputs, dt)
                    self.state_changes += 1
                    return values
                monkeypatch.setattr(Tur10, "step_values", every_step_a_change)
            else:
                original, original_quiet = PlantBinding.step_idle, PLC.run_quiet

                def counting(self, dt):
                    nonlocal idle_scans
                    idle = original(self, dt)
                    idle_scans += idle
                    return idle

                def counting_quiet(self, n, watch=None):
                    nonlocal quiet_scans
                    k = original_quiet(self, n, watch)
                    quiet_scans += k
                    return k
                monkeypatch.setattr(PlantBinding, "step_idle", counting)
                monkeypatch.setattr(PLC, "run_quiet", counting_quiet)
            probe = play(s, script, expl_short if shortcut else dataclasses.replace(expl, unchanged=None),
                         record=record, inner=inner)
            monkeypatch.undo()
            plc = s.plc
            seen.append(({n: s.trace.changes(n) for n in s.trace.signals()}, probe.changes, probe.states,
                         s.plant.snapshot(), list(s.plant.events), plc.ticks, plc.state, plc.fault,
                         plc.retain_snapshot(), {a: list(v) for a, v in plc.image.areas.items()}))
        assert seen[0] == seen[1]
    if record:                          # a recorded play samples every scan: no quiet stretch
        assert idle_scans > 1000 and quiet_scans == 0
    else:                               # the quiet stretches take most idle scans
        assert quiet_scans > 1000 and idle_scans > 0
    if stand == "tur10":                # scans where only the sensor bus changed: not looked at
        assert unchanged_looks > 1000
