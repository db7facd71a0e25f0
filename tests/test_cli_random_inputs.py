"""Every CLI entry point, given random bytes as any of its input files, ends with exit 0, 1 or 2
and one line per problem naming the file: never exit 70 (internal error), never a traceback.

Bounded for CI on 2 cores: a few dozen examples per input, no deadline per example (the
machine may be loaded), and each run is in-process (no interpreter start-up)."""
from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from plclab.cli import main

GOOD_ST = """
PROGRAM main
VAR x AT %IX0.0 : BOOL; q AT %QX0.0 : BOOL; END_VAR
VAR r : REAL; n : INT; END_VAR
VAR RETAIN kept : DINT; END_VAR
q := x; kept := kept + 1;
END_PROGRAM
CONFIGURATION Config0 RESOURCE Res0 ON PLC
TASK t (INTERVAL := T#10ms, PRIORITY := 0);
PROGRAM inst WITH t : main;
END_RESOURCE END_CONFIGURATION
"""

# Bytes that look like the real thing half the time: random bytes, or a valid file mutated.
CSV_SEED = b"time_s,name,value\n0,%IX0.0,1\n0.05,inst.r,2.5\n0.1,inst.n,-7\n"
CONF_SEED = b"[runtime]\nstart_in_run_mode = true\n[modbus]\nport = 5020\n[mp9c]\nvariant = baseline\n"
RETAIN_SEED = b'{"format":"plclab-retain-1","signature":"x","values":{"INST.KEPT":3}}'


def mutated(seed: bytes) -> st.SearchStrategy[bytes]:
    def mutate(args: tuple[int, bytes, int]) -> bytes:
        at, insert, cut = args
        at %= len(seed) + 1
        return seed[:at] + insert + seed[at + cut:]
    return st.tuples(st.integers(0, 10_000), st.binary(max_size=12), st.integers(0, 6)).map(mutate)


def inputs(seed: bytes) -> st.SearchStrategy[bytes]:
    return st.one_of(st.binary(max_size=300), mutated(seed))


SETTINGS = settings(max_examples=20, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
ST_DIAGNOSTIC = re.compile(r"^.+:\d+:\d+: error: .+$")


def run(argv: list[str]) -> tuple[int, list[str]]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    assert "Traceback" not in out.getvalue() and "internal error" not in out.getvalue()
    return code, err.getvalue().splitlines()


def assert_clean(code: int, lines: list[str], named: str, st_file: bool = False) -> None:
    text = "\n".join(lines)
    assert code in (0, 1, 2), f"exit {code}: {text}"
    assert "Traceback" not in text and "internal error" not in text, text
    if code == 0:
        return
    assert lines, "an error exit without a message"
    if st_file and all(ST_DIAGNOSTIC.match(x) for x in lines):
        assert all(x.startswith(named) for x in lines), text          # every diagnostic names the file
        return
    assert len(lines) == 1, text
    assert named in lines[0], text


@pytest.fixture
def files(tmp_path: Path) -> Path:
    (tmp_path / "good.st").write_text(GOOD_ST)
    return tmp_path


@SETTINGS
@given(data=st.one_of(st.binary(max_size=300), mutated(GOOD_ST.encode())))
def test_check_and_sim_with_random_st(files, data):
    path = files / "random.st"
    path.write_bytes(data)
    for argv in (["check", str(path)], ["sim", str(path), "--duration", "0.05"]):
        assert_clean(*run(argv), named=str(path), st_file=True)


@SETTINGS
@given(data=inputs(CSV_SEED))
def test_sim_with_a_random_input_script(files, data):
    path = files / "in.csv"
    path.write_bytes(data)
    assert_clean(*run(["sim", str(files / "good.st"), "--duration", "0.2", "--inputs", str(path)]), named=str(path))


@SETTINGS
@given(data=st.one_of(st.binary(max_size=300), mutated(GOOD_ST.encode())))
def test_grade_with_a_random_program(files, data):
    path = files / "random.st"
    path.write_bytes(data)
    code, lines = run(["grade", "mp9c", "task1", str(path), "--out", str(files / "grade")])
    if code == 1 and not lines:
        return                  # the program ran and failed requirements: the grade report says which
    assert_clean(code, lines, named=str(path), st_file=True)


@SETTINGS
@given(data=inputs(CONF_SEED))
def test_serve_with_a_random_config(files, data):
    path = files / "openplc.conf"
    path.write_bytes(data)
    code, lines = run(["serve", "mp9c", "--config", str(path), "--program", str(files / "good.st"),
                       "--port", "0", "--console", "127.0.0.1:0", "--duration", "0"])
    assert_clean(code, lines, named=path.name)


@SETTINGS
@given(data=inputs(RETAIN_SEED))
def test_serve_with_a_random_retain_file(files, data):
    retain = files / "kept.retain"
    retain.write_bytes(data)
    conf = files / "openplc.conf"
    conf.write_text(f"[mp9c]\nretain_file = {retain.name}\n")
    code, lines = run(["serve", "mp9c", "--config", str(conf), "--program", str(files / "good.st"),
                       "--port", "0", "--console", "127.0.0.1:0", "--duration", "0"])
    assert_clean(code, lines, named=retain.name)
    assert code == 0                         # a bad retain file is set aside; the PLC still runs
    for p in files.iterdir():
        p.unlink() if p.name.startswith("kept.retain") else None


@pytest.mark.parametrize("argv", [["run", "mp9c", "--scenario", "step"], ["run", "mp9c", "--scenario", "step", "--csv", "-"]])
def test_output_piped_into_a_reader_that_stops_early_ends_quietly(argv):
    """`plclab run ... | head -1`: the reader closes the pipe; plclab stops without an internal
    error or a traceback and says so by its exit status, as a Unix tool ended by SIGPIPE (141)."""
    import subprocess
    import sys
    proc = subprocess.Popen([sys.executable, "-c", "import sys; from plclab.cli import main; sys.exit(main())", *argv],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()                               # the reader has gone before the first line
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141, err
    assert err == ""
