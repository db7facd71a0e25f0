"""plclab.fileio: every output refuses what is not a regular file, is written atomically, and
destroys nothing the user did not name; the CLI writers (build, sim, run) follow it."""
from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

import pytest

from plclab.cli import main
from plclab.fileio import (OutputError, check_output, open_atomic, remove_stale_temporaries, temporary_name,
                           write_bytes, write_text)

PROGRAM = """
PROGRAM main
VAR lamp AT %QX0.0 : BOOL; END_VAR
lamp := NOT lamp;
END_PROGRAM
"""


def snapshot(directory: Path) -> dict[str, tuple]:
    """Every entry under `directory`: kind, and content / link target."""
    out = {}
    for p in sorted(directory.rglob("*")):
        st = os.lstat(p)
        if stat.S_ISLNK(st.st_mode):
            out[str(p)] = ("link", os.readlink(p))
        elif stat.S_ISREG(st.st_mode):
            out[str(p)] = ("file", p.read_bytes(), stat.S_IMODE(st.st_mode))
        else:
            out[str(p)] = ("other", stat.S_IFMT(st.st_mode))
    return out


def test_writes_a_new_file_making_its_directories_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "a" / "b" / "out.csv"
    write_text(target, "x\n")
    assert target.read_text() == "x\n"
    assert [p.name for p in target.parent.iterdir()] == ["out.csv"]


def test_replacing_a_file_keeps_its_permissions(tmp_path):
    target = tmp_path / "out.st"
    target.write_text("old")
    target.chmod(0o640)
    write_bytes(target, b"new")
    assert target.read_bytes() == b"new" and stat.S_IMODE(target.stat().st_mode) == 0o640


def make_nonregular(tmp_path: Path) -> dict[str, Path]:
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    link = tmp_path / "link.csv"
    link.symlink_to(victim)
    dangling = tmp_path / "dangling.csv"
    dangling.symlink_to(tmp_path / "nowhere")
    directory = tmp_path / "dir.csv"
    directory.mkdir()
    (directory / "inside").write_text("mine")
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    return {"symlink": link, "dangling symlink": dangling, "directory": directory, "fifo": fifo}


@pytest.mark.parametrize("kind", ["symlink", "dangling symlink", "directory", "fifo"])
def test_an_existing_target_that_is_not_a_regular_file_is_refused_and_untouched(tmp_path, kind):
    target = make_nonregular(tmp_path)[kind]
    before = snapshot(tmp_path)
    with pytest.raises(OutputError, match="exists and is .*refusing to replace it") as e:
        write_text(target, "data")
    assert "\n" not in str(e.value)
    assert snapshot(tmp_path) == before


def test_a_device_is_refused_and_never_opened():
    with pytest.raises(OutputError, match=r"^/dev/full: exists and is a character device"):
        write_bytes("/dev/full", b"x")


def test_a_path_under_a_file_is_one_line(tmp_path):
    (tmp_path / "plain").write_text("keep")
    for target in (tmp_path / "plain" / "out.csv", tmp_path / "plain" / "sub" / "out.csv"):
        with pytest.raises(OutputError, match="is a file, not a directory") as e:
            write_text(target, "x")
        assert "\n" not in str(e.value)
    assert (tmp_path / "plain").read_text() == "keep"


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "out.csv"
    target.write_text("old")
    with pytest.raises(OutputError, match="out.csv: cannot write: No space left on device"):
        with open_atomic(target) as f:
            f.write("half")
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    assert target.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_an_error_of_the_writer_itself_passes_through_and_writes_nothing(tmp_path):
    target = tmp_path / "out.csv"
    with pytest.raises(ValueError):
        with open_atomic(target) as f:
            f.write("half")
            raise ValueError("writer bug")
    assert list(tmp_path.iterdir()) == []


def test_a_missing_directory_can_be_required(tmp_path):
    with pytest.raises(OutputError, match="no such directory"):
        check_output(tmp_path / "missing" / "x.st", parents=False)
    assert not (tmp_path / "missing").exists()


def test_stale_temporaries_of_dead_processes_are_removed_and_nothing_else(tmp_path):
    target = tmp_path / "plc.retain"
    target.write_text("{}")
    dead = tmp_path / f".plc.retain.{2**22 + 12345}-0badc0de.tmp"     # above Linux's pid_max
    dead.write_text("partial")
    mine = temporary_name(target)
    mine.write_text("in progress")
    live = tmp_path / f".plc.retain.{os.getppid()}-00c0ffee.tmp"        # our parent is alive
    live.write_text("in progress")
    other = tmp_path / f".other.retain.{2**22 + 12345}-0badc0de.tmp"  # another file's temporary
    other.write_text("not ours")
    fake = tmp_path / f".plc.retain.{2**22 + 1}-0badc0de.tmp"
    fake.mkdir()                                                      # not a regular file
    assert remove_stale_temporaries(target) == [dead]
    assert {p.name for p in tmp_path.iterdir()} == {"plc.retain", mine.name, live.name, other.name, fake.name}


# ------------------------------------------------------------------ the CLI writers

def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("plclab: error:") and "internal error" not in err[0]
    return err[0]


def bad_targets(tmp_path: Path) -> dict[str, str]:
    made = make_nonregular(tmp_path)
    (tmp_path / "plain").write_text("keep")
    return {"symlink": str(made["symlink"]), "directory": str(made["directory"]), "device": "/dev/full",
            "under a file": str(tmp_path / "plain" / "out.x"), "proc": "/proc/plclab-nowhere/out.x"}


BAD = ["symlink", "directory", "device", "under a file", "proc"]


@pytest.mark.parametrize("where", BAD)
def test_build_output_to_a_bad_target_is_one_line_and_destroys_nothing(tmp_path, capsys, where):
    target = bad_targets(tmp_path)[where]
    before = snapshot(tmp_path)
    assert main(["build", "mp9c", "baseline", "-o", target]) == 1
    assert target.split("/")[-1] in one_error_line(capsys)
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("option", ["--csv", "--vcd", "--plot"])
@pytest.mark.parametrize("where", BAD)
def test_sim_output_to_a_bad_target_is_one_line_and_destroys_nothing(tmp_path, capsys, option, where):
    st = tmp_path / "prog.st"
    st.write_text(PROGRAM)
    target = bad_targets(tmp_path)[where]
    before = snapshot(tmp_path)
    assert main(["sim", str(st), "--duration", "0.1", option, target]) == 1
    one_error_line(capsys)
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("option", ["--csv", "--vcd", "--plot"])
@pytest.mark.parametrize("where", ["directory", "device", "under a file"])
def test_run_output_to_a_bad_target_is_one_line_and_destroys_nothing(tmp_path, capsys, monkeypatch, option, where):
    monkeypatch.chdir(tmp_path)
    target = bad_targets(tmp_path)[where]
    before = snapshot(tmp_path)
    assert main(["run", "mp9c", "--scenario", "step", option, target]) == 1
    one_error_line(capsys)
    assert snapshot(tmp_path) == before
