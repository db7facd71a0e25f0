"""Retain: persisted atomically, restored on start, a bad file is reported and set aside."""
from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest


from plclab.frontend import check_sources
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.runtime.retain import RetainStore

TASK_CONFIG = """CONFIGURATION Config0 RESOURCE Res0 ON PLC
TASK t (INTERVAL := T#10ms, PRIORITY := 0);
PROGRAM inst WITH t : main;
END_RESOURCE END_CONFIGURATION
"""

COUNTER = """
PROGRAM main
VAR RETAIN count : DINT; frames : ARRAY[1..4] OF INT; END_VAR
VAR scratch : INT; END_VAR
count := count + 1;
frames[1] := DINT_TO_INT(count MOD 1000);
scratch := scratch + 1;
END_PROGRAM
""" + TASK_CONFIG


def make_plc(src: str, path: Path, **kw) -> PLC:
    return PLC(compile_unit(check_sources([("retain.st", src)])), retain=RetainStore(path), **kw)


def run_scans(plc: PLC, n: int) -> None:
    for _ in range(n):
        plc.scan()
        plc.advance()


def test_retained_values_survive_a_restart_and_plain_ones_do_not(tmp_path):
    path = tmp_path / "retain.json"
    plc = make_plc(COUNTER, path)
    run_scans(plc, 25)
    plc.stop()                                   # stop flushes
    again = make_plc(COUNTER, path)
    assert again.read("inst.count") == 25
    assert again.read("inst.frames")[0] == 25
    assert again.read("inst.scratch") == 0       # not RETAIN: back to its initial value


def test_values_are_persisted_every_period_without_a_stop(tmp_path):
    path = tmp_path / "retain.json"
    plc = make_plc(COUNTER, path, retain_period_ns=100_000_000)   # every 100 ms of PLC time
    run_scans(plc, 35)                                            # t = 0 .. 340 ms
    saved = json.loads(path.read_text())["values"]["INST.COUNT"]
    assert saved == 31        # last persisted at the scan of t = 300 ms (the 31st scan)


def test_corrupt_file_is_reported_and_set_aside(tmp_path):
    path = tmp_path / "retain.json"
    path.write_text('{"format": "plclab-retain-1", "signature": "x", "values": {')   # truncated JSON
    problems = []
    plc = PLC(compile_unit(check_sources([("retain.st", COUNTER)])), retain=RetainStore(path, report=problems.append))
    assert plc.read("inst.count") == 0
    assert len(problems) == 1 and "corrupt" in problems[0] and "set aside" in problems[0]
    assert not path.exists()
    assert len(list(tmp_path.glob("retain.json.bad-*"))) == 1


def test_file_of_another_program_is_not_used(tmp_path):
    path = tmp_path / "retain.json"
    plc = make_plc(COUNTER, path)
    run_scans(plc, 5)
    plc.stop()
    other = COUNTER.replace("count : DINT", "count : INT").replace("count := count + 1", "count := count + 2") \
        .replace("DINT_TO_INT(count MOD 1000)", "count MOD 1000")
    problems = []
    plc2 = PLC(compile_unit(check_sources([("retain.st", other)])), retain=RetainStore(path, report=problems.append))
    assert plc2.read("inst.count") == 0
    assert problems and "different program" in problems[0]


CHILD = textwrap.dedent("""
    import sys
    from plclab.frontend import check_sources
    from plclab.runtime.compiler import compile_unit
    from plclab.runtime.plc import PLC
    from plclab.runtime.retain import RetainStore
    src = open(sys.argv[1]).read()
    store = RetainStore(sys.argv[2])
    plc = PLC(compile_unit(check_sources([("retain.st", src)])), retain=store, retain_period_ns=10_000_000)
    print("start", plc.read("inst.count"), flush=True)
    while True:
        plc.scan(); saved = plc.now_ns > 0; plc.advance()      # the scan at t = 0 saves nothing
        if saved:
            print(plc.read("inst.count"), flush=True)   # after the save of this scan completed
""")


def test_kill_9_at_random_moments_never_corrupts_the_file(tmp_path):
    """Repeatedly kill a PLC that persists every scan; each time the file must load and hold
    the last persisted state or the one being persisted at the kill."""
    src = tmp_path / "retain.st"
    src.write_text(COUNTER)
    child = tmp_path / "child.py"
    child.write_text(CHILD)
    store_path = tmp_path / "retain.json"
    rng = random.Random(1234)
    sig = make_plc(COUNTER, tmp_path / "probe.json").retain_signature()
    previous = 0
    for _round in range(12):
        proc = subprocess.Popen([sys.executable, str(child), str(src), str(store_path)],
                                stdout=subprocess.PIPE, text=True)
        first = proc.stdout.readline().split()
        assert first[0] == "start" and int(first[1]) == previous      # restored what was persisted
        time.sleep(rng.uniform(0.02, 0.25))
        os.kill(proc.pid, signal.SIGKILL)
        out = proc.stdout.read()       # not communicate(timeout=): it skips lines readline() buffered
        proc.wait(timeout=10)
        printed = [int(x) for x in out.split()]           # values known to be saved
        values = RetainStore(store_path).load(sig)
        if values is None and previous == 0 and not printed and not store_path.exists():
            continue                                      # killed before its first save: no file yet
        assert values is not None, "retain file unreadable after kill -9"
        if printed:                                       # the last saved one, or the save under way
            assert values["INST.COUNT"] in (printed[-1], printed[-1] + 1)
        else:                                             # killed before or during the first save
            assert values["INST.COUNT"] in (previous, previous + 2)
        assert not list(tmp_path.glob("retain.json.bad-*"))
        previous = values["INST.COUNT"]
    assert previous > 0
    RetainStore(store_path)                        # a start removes what the kills left
    assert sorted(p.name for p in tmp_path.iterdir()) == ["child.py", "retain.json", "retain.st"]


def edit_saved_file(src: str, path: Path, scans: int, edit) -> None:
    """Run `scans` scans and stop (the file is written), then let `edit` change the saved
    values as a person editing the file would."""
    plc = make_plc(src, path)
    run_scans(plc, scans)
    plc.stop()
    saved = json.loads(path.read_text())
    edit(saved["values"])
    path.write_text(json.dumps(saved))


def load_reporting(src: str, path: Path) -> tuple[PLC, list[str]]:
    problems: list[str] = []
    plc = PLC(compile_unit(check_sources([("retain.st", src)])), retain=RetainStore(path, report=problems.append))
    return plc, problems


def test_a_value_not_of_its_type_sets_the_whole_file_aside(tmp_path):
    path = tmp_path / "retain.json"
    edit_saved_file(COUNTER, path, 5, lambda v: v["INST.FRAMES"].__setitem__(2, "lots"))
    plc, problems = load_reporting(COUNTER, path)
    assert (plc.read("inst.count"), plc.read("inst.frames[1]")) == (0, 0)    # none restored
    assert len(problems) == 1 and "INST.FRAMES: 'lots' is not of type INT" in problems[0] and "set aside" in problems[0]
    run_scans(plc, 1)
    assert plc.state == "RUN"


def test_an_out_of_range_value_sets_the_file_aside_instead_of_wrapping(tmp_path):
    path = tmp_path / "retain.json"
    edit_saved_file(COUNTER, path, 1, lambda v: v["INST.FRAMES"].__setitem__(0, 40000))   # an INT
    plc, problems = load_reporting(COUNTER, path)
    assert plc.read("inst.frames[1]") == 0                  # not 40000 - 65536
    assert len(problems) == 1 and "INST.FRAMES: 40000 is out of range for INT" in problems[0]


HOLD = """
FUNCTION_BLOCK FB_Hold
VAR_INPUT go : BOOL; END_VAR
VAR_OUTPUT n : INT; END_VAR
n := n + 1;
END_FUNCTION_BLOCK
PROGRAM main
VAR RETAIN h : FB_Hold; END_VAR
h(go := TRUE);
END_PROGRAM
""" + TASK_CONFIG


def test_retained_fb_instance_is_restored_and_checked(tmp_path):
    path = tmp_path / "retain.json"
    edit_saved_file(HOLD, path, 4, lambda v: None)
    assert make_plc(HOLD, path).read("inst.h.n") == 4
    edit_saved_file(HOLD, path, 0, lambda v: v["INST.H"]["fb"].__setitem__("N", "four"))
    plc, problems = load_reporting(HOLD, path)
    assert plc.read("inst.h.n") == 0 and len(problems) == 1 and "INST.H.N" in problems[0]


RECORDER = """
TYPE ST_Frame : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK FB_Recorder
VAR_INPUT put : BOOL; END_VAR
VAR frames : ARRAY[1..4] OF ST_Frame; last : ST_Frame; count : INT; END_VAR
IF put AND count < 4 THEN
    count := count + 1;
    frames[count].x := count * 10; frames[count].y := -count;
    last := frames[count];
END_IF;
END_FUNCTION_BLOCK
PROGRAM main
VAR RETAIN rec : FB_Recorder; END_VAR
rec(put := TRUE);
END_PROGRAM
""" + TASK_CONFIG


@pytest.mark.parametrize("native", [False, True], ids=["python", "native"])
def test_a_retained_blocks_arrays_and_structures_survive_a_restart_whole(tmp_path, native):
    """A student who declares the block that records the taught frames RETAIN finds them after
    a power cycle: every variable of the block, its arrays of structures and its structures
    too, not only its elementary variables (and a bad element names its variable)."""
    unit = compile_unit(check_sources([("retain.st", RECORDER)]))
    path = tmp_path / "retain.json"
    plc = PLC(unit, retain=RetainStore(path), native=native)
    assert (plc.native is not None) == native
    run_scans(plc, 3)
    plc.stop()
    back = PLC(unit, retain=RetainStore(path), native=native)
    assert back.read("inst.rec.count") == 3
    assert [(f.X, f.Y) for f in back.read("inst.rec.frames")] == [(10, -1), (20, -2), (30, -3), (0, 0)]
    assert (back.read("inst.rec.last").X, back.read("inst.rec.last").Y) == (30, -3)
    run_scans(back, 1)
    assert back.read("inst.rec.frames[4].x") == 40
    edit_saved_file(RECORDER, path, 2, lambda v: v["INST.REC"]["fb"]["FRAMES"][1].__setitem__("Y", 1 << 20))
    plc, problems = load_reporting(RECORDER, path)
    assert plc.read("inst.rec.count") == 0 and len(problems) == 1 and "INST.REC.FRAMES" in problems[0]


def test_a_memory_store_keeps_what_a_file_would_across_restarts_and_no_file_is_written(tmp_path, monkeypatch):
    """The grader's sessions keep retained values in memory: the same values after a restart as
    the file store gives (saved at the same moments), another program's values refused, and
    nothing written to disk."""
    from plclab.runtime.retain import MemoryRetainStore
    monkeypatch.chdir(tmp_path)
    memory = MemoryRetainStore()
    unit = compile_unit(check_sources([("retain.st", COUNTER)]))
    plc = PLC(unit, retain=memory, retain_period_ns=100_000_000)
    on_file = make_plc(COUNTER, tmp_path / "retain.json", retain_period_ns=100_000_000)
    run_scans(plc, 35)
    run_scans(on_file, 35)
    plc.enter_fault("internal", "power cut: no flush at stop")        # only the periodic save is kept
    on_file.enter_fault("internal", "power cut: no flush at stop")
    again = PLC(unit, retain=memory)
    from_file = make_plc(COUNTER, tmp_path / "retain.json")
    assert again.read("inst.count") == from_file.read("inst.count") == 31
    assert again.read("inst.frames") == from_file.read("inst.frames")
    assert again.read("inst.scratch") == 0
    run_scans(again, 4)
    again.stop()                                                      # stop flushes
    assert PLC(unit, retain=memory).read("inst.count") == 35
    other = COUNTER.replace("count : DINT", "count : INT").replace("count := count + 1", "count := count + 2") \
                   .replace("DINT_TO_INT(count MOD 1000)", "count MOD 1000")
    refused = PLC(compile_unit(check_sources([("retain.st", other)])), retain=memory)
    assert refused.read("inst.count") == 0 and "different program" in memory.last_problem
    assert sorted(p.name for p in tmp_path.iterdir()) == ["retain.json"]   # the file store's own only


@pytest.mark.parametrize("native", [False, True], ids=["python", "native"])
def test_a_restart_finds_the_last_save_of_a_memory_store_not_what_the_plc_held_at_the_end(native):
    """A grading's memory store gives a restart what the last periodic save held (the native
    path keeps the retained variables' memory then and makes the values of it only when a
    restart asks), not the values the PLC went on to hold; the same where the PLC restarted
    is the very one that saved (the lab's Restart PLC builds its variables anew in place)."""
    from plclab.runtime.retain import MemoryRetainStore
    unit = compile_unit(check_sources([("retain.st", COUNTER)]))
    memory = MemoryRetainStore()
    plc = PLC(unit, retain=memory, retain_period_ns=100_000_000, native=native)
    assert (plc.native is not None) == native
    run_scans(plc, 35)
    plc.enter_fault("internal", "power cut: no flush at stop")
    plc.restart()
    assert plc.read("inst.count") == 31 and plc.read("inst.frames")[0] == 31
    run_scans(plc, 12)                     # saved again at 37, 100 ms of PLC time after the last
    assert PLC(unit, retain=memory, native=native).read("inst.count") == 37
    assert plc.read("inst.count") == 43    # reading the store changed nothing the PLC holds


def test_a_memory_store_keeps_what_it_saved_after_the_plc_that_saved_it_is_gone():
    """The native path's save keeps the retained variables' C memory in the store, not a
    copy of their values: the store keeps that memory alive after its PLC is dropped and other
    PLCs have taken memory of their own (perhaps where the first one's was)."""
    import gc
    import weakref

    from plclab.runtime.retain import MemoryRetainStore
    unit = compile_unit(check_sources([("retain.st", COUNTER)]))
    memory = MemoryRetainStore()
    plc = PLC(unit, retain=memory, retain_period_ns=100_000_000, native=True)
    assert plc.native is not None
    run_scans(plc, 35)
    plc.enter_fault("internal", "power cut: no flush at stop")
    state = weakref.ref(plc._native_state)
    del plc
    others = [PLC(unit, native=True) for _ in range(50)]
    for other in others:
        run_scans(other, 3)
    gc.collect()
    assert state() is not None                 # what the store will read is still there
    back = PLC(unit, retain=memory, native=True)
    assert back.read("inst.count") == 31 and back.read("inst.frames")[0] == 31
    gc.collect()
    assert state() is None                     # read: the store holds the values, not the memory

