"""The grade engine reads, checks and compiles a submission once per grade, each scenario
still starting a fresh PLC; its trace files go through plclab.fileio (a bad --out is one
line, refused before any scenario runs)."""
from __future__ import annotations

import pytest

import plclab.grader.engine as engine
import plclab.scenario as scenario_module
from plclab.errors import PlcLabError
from plclab.grader import Requirement, RequirementSet, Scenario, grade_sources, registry
from plclab.grader.mp9c import make_session
from plclab.stands import sources
from plclab.stands.mp9c import STAND
from plclab.trace import csv_text


@pytest.fixture
def selftest(monkeypatch):
    """A three-scenario task on mp9c whose scenarios record what each fresh stand did, with
    counters on the front end and the compiler."""
    runs: list[str] = []
    calls = {"check": 0, "compile": 0}

    def counted(fn, key):
        def wrapper(*args, **kwargs):
            calls[key] += 1
            return fn(*args, **kwargs)
        return wrapper

    monkeypatch.setattr(engine, "check_sources", counted(engine.check_sources, "check"))
    monkeypatch.setattr(scenario_module, "check_sources", counted(scenario_module.check_sources, "check"))
    monkeypatch.setattr(scenario_module, "compile_unit", counted(scenario_module.compile_unit, "compile"))

    def run(s, c):
        assert s.plc.ticks == 0
        s.console.set(SA1=True)
        s.run(0.3)
        s.restart_plc()                   # a cold restart in the scenario: still no new compile
        s.run(0.2)
        runs.append(csv_text(s.trace))
        with c.requirement(f"X{len(runs)}"):
            pass

    req = RequirementSet(stand="mp9c", task="selftest", title="self test",
                         requirements=tuple(Requirement(f"X{i}", f"scenario {i} runs", f"s{i}") for i in (1, 2, 3)),
                         scenarios=tuple(Scenario(f"s{i}", run, needs_retain=i == 2) for i in (1, 2, 3)),
                         make_session=make_session)
    registry.register(req)
    yield runs, calls
    del registry._REGISTRY[("mp9c", "selftest")]


def test_a_submission_is_checked_and_compiled_once_per_grade(selftest, tmp_path):
    runs, calls = selftest
    report = grade_sources("mp9c", "selftest", sources(STAND, "task1"), out_dir=str(tmp_path / "out"))
    assert report.passed, report.text()
    assert calls == {"check": 1, "compile": 1}
    assert len(runs) == 3 and runs[0] == runs[1] == runs[2]     # each scenario a fresh PLC, same story
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == \
        sorted(f"mp9c-selftest-s{i}.{ext}" for i in (1, 2, 3) for ext in ("csv", "vcd"))
    assert calls["compile"] == 1
    grade_sources("mp9c", "selftest", sources(STAND, "task1"))
    assert calls == {"check": 2, "compile": 2}                     # the next grade compiles anew


@pytest.mark.parametrize("block", ["dir_at_trace", "file_as_dir"])
def test_a_bad_out_is_one_line_before_any_scenario_runs(selftest, tmp_path, block):
    runs, _calls = selftest
    if block == "dir_at_trace":
        out = tmp_path / "out"
        (out / "mp9c-selftest-s2.vcd").mkdir(parents=True)
        message = "mp9c-selftest-s2.vcd: exists and is a directory; refusing to replace it"
    else:
        out = tmp_path / "taken"
        out.write_text("the user's notes\n")
        message = "is a file, not a directory"
    with pytest.raises(PlcLabError, match=message) as e:
        grade_sources("mp9c", "selftest", sources(STAND, "task1"), out_dir=str(out))
    assert "\n" not in str(e.value) and runs == []
    if block == "file_as_dir":
        assert out.read_text() == "the user's notes\n"


def test_plclab_grade_with_an_out_that_is_a_file_is_one_line_and_leaves_it(tmp_path, capsys):
    from plclab.cli import main
    from plclab.stands import get_stand

    taken = tmp_path / "notes.txt"
    taken.write_text("keep me\n")
    files = [str(p) for p in get_stand("mp9c").files("task1")]
    assert main(["grade", "mp9c", "task1", *files, "--out", str(taken)]) == 1
    err = capsys.readouterr().err.strip()
    assert "is a file, not a directory" in err and len(err.splitlines()) == 1
    assert taken.read_text() == "keep me\n"


def _native_library(text: str):
    """The native library of program `text` if it has been built (in this process, or in the
    cache folder $XDG_CACHE_HOME names), once every background build is over; else None."""
    import threading

    from plclab.frontend import check_sources
    from plclab.runtime import native
    from plclab.runtime.cgen import emit_c
    from plclab.runtime.compiler import compile_unit
    for t in list(threading.enumerate()):
        if t.name == "plclab-native-build":
            t.join(120)
    return native.build(emit_c(compile_unit(check_sources([("robot.st", text)])).checked), wait=False, later=False)


def _unique_task1() -> str:
    """The MP-9C Task 1 bundle with a variable of its own: C that no test has built."""
    import uuid

    from plclab.stands import bundle
    text = bundle(STAND, "task1")
    at = text.index("\n", text.index("\nPROGRAM ") + 1)
    return text[:at] + f"\nVAR\n    unique_{uuid.uuid4().hex} : INT;\nEND_VAR" + text[at:]


def test_a_grading_that_does_not_explore_builds_no_native_library(tmp_path, monkeypatch):
    """Scenarios alone (no exploration) run on the Python path and build nothing: a few
    seconds of plant time cost less than compiling the program's C. PLCLAB_NATIVE=1 asks for
    native in such a grading too; a program graded with an exploration starts its build in
    the scenarios (the search plays it many times)."""
    from plclab.runtime import native
    monkeypatch.delenv(native.ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    alone = _unique_task1()
    report = grade_sources("mp9c", "task1", [("robot.st", alone)])
    assert report.passed and not report.errors
    assert _native_library(alone) is None
    monkeypatch.setenv(native.ENV, "1")
    assert grade_sources("mp9c", "task1", [("robot.st", alone)]).passed
    assert _native_library(alone) is not None
    monkeypatch.delenv(native.ENV)
    explored = _unique_task1()
    assert grade_sources("mp9c", "task1", [("robot.st", explored)], explore=1).passed
    assert _native_library(explored) is not None
