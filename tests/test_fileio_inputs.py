"""Issue 25 item 6: what a user names as input (`check`, `grade`, `run --program`) is read only
if it is a regular file within the size limit, refused in one line before reading otherwise:
`grade /dev/zero` exited 70, `check` on a FIFO hung, a 3 GB file was read whole."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from plclab import fileio
from plclab.cli import main
from plclab.frontend.parser import MAX_SOURCE_BYTES

HARNESS = Path(__file__).resolve().parents[1] / "harness"


def test_a_regular_file_is_read_and_a_link_given_by_the_user_is_followed(tmp_path):
    (tmp_path / "a.st").write_bytes(b"PROGRAM p END_PROGRAM\n")
    (tmp_path / "link.st").symlink_to(tmp_path / "a.st")
    assert fileio.read_input(tmp_path / "a.st", 100) == b"PROGRAM p END_PROGRAM\n"
    assert fileio.read_input(tmp_path / "link.st", 100) == b"PROGRAM p END_PROGRAM\n"
    with pytest.raises(fileio.InputError, match=r"^not a regular file \(a symbolic link\)"):
        fileio.read_input(tmp_path / "link.st", 100, follow_symlinks=False)


def test_a_fifo_a_device_and_a_large_file_are_refused_before_reading(tmp_path):
    fifo = tmp_path / "p.st"
    os.mkfifo(fifo)
    with pytest.raises(fileio.InputError, match=r"^not a regular file \(a FIFO\); refused without reading it$"):
        fileio.read_input(fifo, 100)           # would block forever if it were opened for reading
    with pytest.raises(fileio.InputError, match=r"^not a regular file \(a character device\)"):
        fileio.read_input("/dev/zero", 100)
    big = tmp_path / "big.st"
    with open(big, "wb") as f:
        f.truncate(3 * 1024 ** 3)            # sparse: 3 GB that take no disk and must not be read
    with pytest.raises(fileio.InputError, match=r"^file too large \(3221225472 bytes; the limit is 100\)$"):
        fileio.read_input(big, 100)


def test_a_proc_file_whose_size_says_zero_is_read_no_further_than_the_limit():
    with pytest.raises(fileio.InputError, match=r"^file too large \(more than \d+ bytes; the limit is 10\)$"):
        fileio.read_input("/proc/self/status", 10)


@pytest.mark.parametrize("command", [["check"], ["grade", "mp9c", "task1"]])
@pytest.mark.parametrize("kind", ["fifo", "device", "large"])
def test_check_and_grade_refuse_non_regular_or_large_files_in_one_line(command, kind, tmp_path):
    if kind == "fifo":
        path = tmp_path / "p.st"
        os.mkfifo(path)
        reason = "not a regular file (a FIFO); refused without reading it"
    elif kind == "device":
        path, reason = Path("/dev/zero"), "not a regular file (a character device); refused without reading it"
    else:
        path = tmp_path / "big.st"
        with open(path, "wb") as f:
            f.truncate(MAX_SOURCE_BYTES + 1)
        reason = f"file too large ({MAX_SOURCE_BYTES + 1} bytes; the limit is {MAX_SOURCE_BYTES})"
    # a child process with a timeout: today's `check` on a FIFO blocks forever
    run = subprocess.run([sys.executable, "-m", "plclab.cli", *command, str(path), *(
        ["--out", str(tmp_path / "out")] if command[0] == "grade" else [])],
        env={**os.environ, "PYTHONPATH": str(HARNESS)}, capture_output=True, text=True, timeout=60)
    assert run.returncode == 1, run.stderr
    line = f"{path}:1:1: error: {reason}"
    assert line in (run.stderr + run.stdout).splitlines(), (run.stdout, run.stderr)
    assert "Traceback" not in run.stderr


@pytest.mark.parametrize("command", [["cnc"], ["grade", "thermo", "scada1", "--traffic"]])
def test_a_part_program_and_a_traffic_log_that_are_a_fifo_are_refused_in_one_line(command, tmp_path):
    """The other files a user names: a G-code part program and a recorded SCADA traffic log
    (a student's hand-in) go through the same check; a FIFO used to hang the command."""
    fifo = tmp_path / "part.nc"
    os.mkfifo(fifo)
    run = subprocess.run([sys.executable, "-m", "plclab.cli", *command, str(fifo)],
                         env={**os.environ, "PYTHONPATH": str(HARNESS)}, capture_output=True, text=True,
                         timeout=60, cwd=tmp_path)
    assert run.returncode != 0 and "Traceback" not in run.stderr
    out = run.stdout + run.stderr
    assert f"{fifo}" in out and "not a regular file (a FIFO); refused without reading it" in out, out
