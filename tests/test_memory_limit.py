"""The process memory limit of a program run (plclab.limits; issue #25 item 1): `plclab sim`,
`grade` and `run --program` hold the student's program to a memory allowance, and a run past it
is one clear line (grade: a FAIL), exit 1, never a traceback or the machine's memory.

The allowance is made small here (PLCLAB_MEMORY_LIMIT_MB) so that a program the checker accepts
(4 MB declared as 4 million BOOLs: some 40 MiB of Python lists) crosses it,
while a small program still runs under the same allowance: the limit stops what grows, nothing else.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import plclab
from plclab.stands import bundle
from plclab.stands.mp9c import STAND

CONFIG = ("CONFIGURATION Config0 RESOURCE Res0 ON PLC TASK t(INTERVAL := T#10ms, PRIORITY := 0); "
          "PROGRAM i WITH t : Prog; END_RESOURCE END_CONFIGURATION\n")
BIG_DECLS = "".join(f"    big{i} : ARRAY[1..1000000] OF BOOL;\n" for i in range(4))   # 4 MB: accepted by check


def plclab_cli(args: list[str], cwd: Path, limit_mb: int) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(Path(plclab.__file__).resolve().parents[1]),
               PLCLAB_MEMORY_LIMIT_MB=str(limit_mb))
    env.pop("PLCLAB_DEBUG", None)
    return subprocess.run([sys.executable, "-m", "plclab.cli", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300)


def test_sim_past_the_limit_is_one_line_and_a_small_program_still_runs(tmp_path):
    big = tmp_path / "big.st"
    big.write_text(f"PROGRAM Prog\nVAR\n{BIG_DECLS}END_VAR\nbig0[1] := NOT big0[1];\nEND_PROGRAM\n{CONFIG}")
    small = tmp_path / "small.st"
    small.write_text(f"PROGRAM Prog\nVAR\n  x : BOOL;\nEND_VAR\nx := NOT x;\nEND_PROGRAM\n{CONFIG}")
    done = plclab_cli(["check", str(big)], tmp_path, 24)
    assert done.returncode == 0, done.stderr                 # within what a program may declare
    done = plclab_cli(["sim", str(big), "--duration", "0.05"], tmp_path, 24)
    assert done.returncode == 1
    assert done.stderr.splitlines() == ["plclab sim: out of memory: the run needed more than the 24 MiB memory limit "
                                        "of a program run (docs/reliability.md); nothing else was affected"]
    done = plclab_cli(["sim", str(small), "--duration", "0.05"], tmp_path, 24)
    assert done.returncode == 0 and done.stdout.startswith("simulated 0.05 s"), done.stdout + done.stderr
    done = plclab_cli(["sim", str(big), "--duration", "0.05"], tmp_path, 0)    # 0: no limit
    assert done.returncode == 0, done.stderr


def test_grade_past_the_limit_is_a_clear_fail(tmp_path):
    program = tmp_path / "task1.st"
    program.write_text(bundle(STAND, "task1").replace("VAR_GLOBAL\n", "VAR_GLOBAL\n" + BIG_DECLS, 1))
    done = plclab_cli(["grade", "mp9c", "task1", str(program), "--out", str(tmp_path / "g")], tmp_path, 32)
    assert done.returncode == 1
    assert done.stderr.splitlines() == ["plclab grade: FAIL: out of memory: the run needed more than the 32 MiB "
                                        "memory limit of a program run (docs/reliability.md); nothing else was "
                                        "affected"]
    assert "Traceback" not in done.stdout + done.stderr


def test_run_program_is_held_to_the_limit(tmp_path):
    program = tmp_path / "full.st"
    program.write_text(bundle(STAND, "full").replace("VAR_GLOBAL\n", "VAR_GLOBAL\n" + BIG_DECLS, 1))
    done = plclab_cli(["run", "mp9c", "--scenario", "step", "--program", str(program)], tmp_path, 32)
    assert done.returncode == 1
    assert done.stderr.splitlines()[-1].startswith("plclab run: out of memory: the run needed more than the 32 MiB")


PROBE = """
import resource
from plclab.limits import memory_limited
before = resource.getrlimit(resource.RLIMIT_AS)
with memory_limited(256 * 1024 * 1024):
    small = bytearray(16 * 1024 * 1024)
    try:
        bytearray(512 * 1024 * 1024)
        print("no limit")
    except MemoryError:
        print("limited")
after = resource.getrlimit(resource.RLIMIT_AS)
bytearray(512 * 1024 * 1024)
print("restored", after == before)
"""


def test_the_limit_holds_inside_and_is_lifted_after():
    env = dict(os.environ, PYTHONPATH=str(Path(plclab.__file__).resolve().parents[1]))
    done = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, timeout=60)
    assert done.stdout.split() == ["limited", "restored", "True"], done.stdout + done.stderr
