"""Retain errors (issue 15): a save that fails never stops the scan (or, if configured, is a
visible FAULT); a bad file is set aside naming why, and only a regular file is ever set aside;
values out of their variable's range are refused, not wrapped; stale temporaries are removed."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

from plclab.frontend import check_sources
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.runtime.retain import RetainStore

COUNTER = """
PROGRAM main
VAR RETAIN count : DINT; frames : ARRAY[1..4] OF INT; END_VAR
VAR lamp AT %QX0.0 : BOOL; END_VAR
count := count + 1;
frames[1] := DINT_TO_INT(count MOD 1000);
lamp := TRUE;
END_PROGRAM
CONFIGURATION Config0 RESOURCE Res0 ON PLC
TASK t (INTERVAL := T#10ms, PRIORITY := 0);
PROGRAM inst WITH t : main;
END_RESOURCE END_CONFIGURATION
"""


def make(path: Path, **kw) -> tuple[PLC, list[str]]:
    problems: list[str] = []
    plc = PLC(compile_unit(check_sources([("retain.st", COUNTER)])), retain=RetainStore(path, report=problems.append),
              retain_period_ns=100_000_000, **kw)
    return plc, problems


def run_scans(plc: PLC, n: int) -> None:
    for _ in range(n):
        plc.scan()
        plc.advance()


def saved_file(path: Path, **values) -> None:
    """A retain file of COUNTER as the PLC writes it, with `values` changed as a person would."""
    plc, _ = make(path)
    run_scans(plc, 3)
    plc.stop()
    data = json.loads(path.read_text())
    data["values"].update(values)
    path.write_text(json.dumps(data))


def test_a_save_that_fails_is_reported_once_and_the_scan_goes_on_then_recovers(tmp_path):
    blocker = tmp_path / "state"
    blocker.write_text("a file where the retain directory should be")
    path = blocker / "retain.json"                         # can never be written: a file is in the way
    plc, problems = make(path)
    run_scans(plc, 50)                                     # 0.5 s of PLC time: four flushes
    assert plc.state == "RUN" and plc.read("inst.count") == 50
    assert len(problems) == 1 and "retain.json" in problems[0] and "retrying" in problems[0]
    assert plc.retain_store.failed_saves == 4
    assert blocker.read_text().startswith("a file")        # nothing of the user's touched
    blocker.unlink()
    blocker.mkdir()
    run_scans(plc, 10)                                     # the next flush succeeds
    assert "saved again" in problems[-1] and len(problems) == 2
    assert json.loads(path.read_text())["values"]["INST.COUNT"] == 51


def test_a_failed_save_can_be_configured_to_fault_visibly(tmp_path):
    (tmp_path / "state").write_text("x")
    plc, problems = make(tmp_path / "state" / "retain.json", retain_fault=True)
    run_scans(plc, 12)                                     # the flush at t = 100 ms fails
    assert plc.state == "FAULT" and plc.fault.kind == "retain"
    assert "cannot save the retained variables" in str(plc.fault)
    assert plc.image.areas["QX"][0] == 0                   # outputs in their safe state


FULL_DISK_CHILD = textwrap.dedent("""
    import resource, signal, sys
    from plclab.frontend import check_sources
    from plclab.runtime.compiler import compile_unit
    from plclab.runtime.plc import PLC
    from plclab.runtime.retain import RetainStore
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)      # a write past the limit fails with EFBIG
    src = open(sys.argv[1]).read()
    plc = PLC(compile_unit(check_sources([("retain.st", src)])),
              retain=RetainStore(sys.argv[2], report=lambda m: print("REPORT", m)), retain_period_ns=10_000_000)
    resource.setrlimit(resource.RLIMIT_FSIZE, (20, 20))  # the disk is "full" after 20 bytes
    for _ in range(30):
        plc.scan(); plc.advance()
    print("STATE", plc.state, plc.read("inst.count"))
""")


def test_a_full_disk_does_not_stop_the_scan_and_leaves_no_partial_file(tmp_path):
    src = tmp_path / "retain.st"
    src.write_text(COUNTER)
    child = tmp_path / "child.py"
    child.write_text(FULL_DISK_CHILD)
    out = subprocess.run([sys.executable, str(child), str(src), str(tmp_path / "retain.json")],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[-1] == "STATE RUN 30"
    reports = [x for x in lines if x.startswith("REPORT")]
    assert len(reports) == 1 and "File too large" in reports[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["child.py", "retain.st"]   # no half file, no temp


def test_a_retain_file_naming_a_directory_is_never_renamed(tmp_path):
    directory = tmp_path / "retain.json"
    directory.mkdir()
    (directory / "notes.txt").write_text("mine")
    plc, problems = make(directory)
    run_scans(plc, 30)
    assert plc.state == "RUN"
    assert directory.is_dir() and (directory / "notes.txt").read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["retain.json"]
    assert "is a directory" in problems[0] and "not touched" in problems[0]
    assert len(problems) == 2 and "retrying" in problems[1]          # the saves: reported once


def test_a_retain_file_that_is_a_symlink_is_not_followed_or_renamed(tmp_path):
    target = tmp_path / "elsewhere.json"
    target.write_text("precious")
    link = tmp_path / "retain.json"
    link.symlink_to(target)
    plc, problems = make(link)
    run_scans(plc, 20)
    plc.stop()
    assert link.is_symlink() and target.read_text() == "precious"
    assert "symbolic link" in problems[0]


def test_a_file_nested_100000_deep_is_set_aside(tmp_path):
    path = tmp_path / "retain.json"
    path.write_text('{"format": "plclab-retain-1", "values": ' + "[" * 100_000 + "]" * 100_000 + "}")
    plc, problems = make(path)
    assert plc.state == "RUN" and plc.read("inst.count") == 0
    assert len(problems) == 1 and "corrupt" in problems[0] and "set aside" in problems[0]
    assert len(list(tmp_path.glob("retain.json.bad-*"))) == 1


def test_a_5000_digit_number_is_set_aside(tmp_path):
    path = tmp_path / "retain.json"
    saved_file(path)
    path.write_text(path.read_text().replace('"INST.COUNT": 3', '"INST.COUNT": ' + "7" * 5000))
    plc, problems = make(path)
    assert plc.read("inst.count") == 0 and len(problems) == 1 and "set aside" in problems[0]


def test_a_retained_dint_out_of_range_is_refused_naming_the_variable(tmp_path):
    path = tmp_path / "retain.json"
    saved_file(path, **{"INST.COUNT": 2**80 + 5})
    plc, problems = make(path)
    assert plc.read("inst.count") == 0                      # not 5
    assert len(problems) == 1 and "INST.COUNT" in problems[0] and "out of range for DINT" in problems[0]
    assert "set aside" in problems[0]


def test_a_retained_int_array_element_out_of_range_is_refused(tmp_path):
    path = tmp_path / "retain.json"
    saved_file(path, **{"INST.FRAMES": [40000, 0, 0, 0]})
    plc, problems = make(path)
    assert plc.read("inst.frames[1]") == 0                  # not -25536
    assert "INST.FRAMES" in problems[0] and "out of range for INT (-32768..32767)" in problems[0]


def test_stale_temporaries_of_a_killed_save_are_removed_at_start(tmp_path):
    path = tmp_path / "retain.json"
    saved_file(path)
    dead = 2**22 + 7                                         # above Linux's pid_max: no such process
    stale = [tmp_path / f".retain.json.{dead}-0123abcd.tmp", tmp_path / f"retain.json.tmp{dead}"]
    for p in stale:
        p.write_text('{"format": "plclab-re')
    keep = tmp_path / "retain.json.notes"
    keep.write_text("not a temporary")
    plc, problems = make(path)
    assert plc.read("inst.count") == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["retain.json", "retain.json.notes"]
    assert "removed 2 temporary file(s)" in problems[0]
