"""The native scan path (plclab.runtime.native, its C from plclab.runtime.cgen) computes what
the Python path computes: every stand's scenarios in every variant give the same traces, and
random operator scripts give the same outputs, variables and retained values scan for scan.
(The semantics suite, tests/runtime/test_semantics_*.py, also runs every case natively.)
Also: what it does not cover runs on the Python path, PLCLAB_NATIVE=0 turns it off, faults
name the same kind, message and ST line, views by name read and write the C memory, and the
build cache holds up when processes build the same program at once."""
from __future__ import annotations

import json
import math
import os
import random
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

from plclab.frontend import check_sources
from plclab.runtime import native
from plclab.runtime.compiler import Ref, compile_unit
from plclab.runtime.plc import FAULT, PLC
from plclab.runtime.retain import MemoryRetainStore
from plclab.stands import stand_module
from plclab.stands.base import stand_spec

STANDS = ("mp9c", "tur10", "thermo", "cnc")
VARIANTS = [(s, v) for s in STANDS for v in stand_module(s).SPEC.stand.variants]


def _same(v: Any) -> Any:
    """A value as compared: NaN equals NaN."""
    return "nan" if isinstance(v, float) and math.isnan(v) else v


def _session(spec: Any, variant: str, on_native: bool, monkeypatch: pytest.MonkeyPatch, **kw: Any) -> Any:
    """A session of `variant` on the path asked for (native: built now, never a fallback)."""
    if on_native:
        monkeypatch.setenv(native.ENV, "1")
        s = spec.session(variant, **kw)
        assert s.plc.native is not None, "the native path did not take a shipped program"
    else:
        with native.python_only():
            s = spec.session(variant, **kw)
        assert s.plc.native is None
    monkeypatch.delenv(native.ENV, raising=False)
    return s


def _play(spec: Any, variant: str, scenario: str, on_native: bool, tmp_path: Path,
          monkeypatch: pytest.MonkeyPatch) -> dict:
    path = "native" if on_native else "python"
    s = _session(spec, variant, on_native, monkeypatch, retain_path=tmp_path / f"{path}-{scenario}.json")
    if on_native:
        monkeypatch.setenv(native.ENV, "1")         # a PLC restart in the scenario: native again
    ctx = native.python_only() if not on_native else _Nothing()
    with ctx:
        try:
            spec.scenario(scenario)(s)
            outcome = "passed"
        except AssertionError as e:
            outcome = f"failed: {e}"
    monkeypatch.delenv(native.ENV, raising=False)
    assert (s.plc.native is not None) == on_native
    return {"trace": {n: [(t, _same(v)) for t, v in s.trace.changes(n)] for n in s.trace.signals()},
            "outcome": outcome, "retain": s.plc.retain_snapshot(), "fault": str(s.plc.fault),
            "retain_file": (tmp_path / f"{path}-{scenario}.json").read_text()
            if (tmp_path / f"{path}-{scenario}.json").exists() else None}


class _Nothing:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: Any) -> None:
        return None


@pytest.mark.parametrize("stand,variant", VARIANTS, ids=[f"{s}-{v}" for s, v in VARIANTS])
def test_every_scenario_gives_the_same_trace_on_both_paths(stand, variant, tmp_path, monkeypatch):
    spec = stand_spec(stand)
    for scenario in spec.scenarios:
        py = _play(spec, variant, scenario, False, tmp_path, monkeypatch)
        na = _play(spec, variant, scenario, True, tmp_path, monkeypatch)
        assert na["outcome"] == py["outcome"], scenario
        assert na["fault"] == py["fault"], scenario
        for name, changes in py["trace"].items():
            assert na["trace"].get(name) == changes, f"{scenario}: {name} differs"
        assert na["trace"].keys() == py["trace"].keys(), scenario
        assert na["retain"] == py["retain"], scenario
        retain_py = py["retain_file"]
        assert (na["retain_file"] is None) == (retain_py is None), scenario
        if retain_py is not None:      # what was saved (the file also holds the wall-clock save time)
            assert json.loads(na["retain_file"])["values"] == json.loads(retain_py)["values"], scenario


def _state(obj: Any, twin: Any, path: str, out: list) -> None:
    """(path, value) of every variable of Python object `obj`, read from `twin` (the same
    variables on the other path), appended to `out` as pairs to compare."""
    if isinstance(obj, list):
        assert len(twin) == len(obj), path
        for i, (a, b) in enumerate(zip(obj, twin)):
            _state(a, b, f"{path}[{i}]", out)
        return
    if isinstance(obj, (bool, int, float, str)) or obj is None:
        out.append((path, _same(obj), _same(twin)))
        return
    names = list(obj.__dict__) if hasattr(obj, "__dict__") and not hasattr(type(obj), "__slots__") \
        else [n for c in type(obj).__mro__ for n in getattr(c, "__slots__", ()) if n != "__dict__"]
    if not names and hasattr(obj, "__dict__"):
        names = list(obj.__dict__)
    for n in names:
        if n.startswith("_") or not hasattr(obj, n):
            continue
        v = getattr(obj, n)
        if v is None or isinstance(v, Ref):        # a scalar VAR_IN_OUT: compared where it lives
            assert (getattr(twin, n) is None) == (v is None), f"{path}.{n}"
            continue
        _state(v, getattr(twin, n), f"{path}.{n}", out)


@pytest.mark.parametrize("stand", STANDS)
def test_random_operator_scripts_give_the_same_variables_scan_for_scan(stand, tmp_path, monkeypatch):
    """Console actions at random scans (and, now and then, a Modbus client's write into the
    memory and output image): after every scan both paths hold the same image, the same value
    in every variable of every program instance and block, and the same retained values."""
    spec = stand_spec(stand)
    variant = spec.stand.richest_variant
    rng = random.Random(f"native-{stand}")
    py = _session(spec, variant, False, monkeypatch, watch_internals=False)
    na = _session(spec, variant, True, monkeypatch, watch_internals=False)
    # the Python objects of the Python path's program, to enumerate every variable
    outputs = [b for b in py.plc.bindings if not b.is_input]
    console = [c for c in spec.console if c in (getattr(py.plant, "CONSOLE", None) or spec.console)]
    for scan in range(1500 if stand != "cnc" else 700):
        if console and rng.random() < 0.04:
            name = rng.choice(console)
            value = rng.random() < 0.5
            for s in (py, na):
                s.plant.set_switch(name, value)
        if outputs and rng.random() < 0.01:
            b = rng.choice(outputs)
            raw = rng.randrange(0, 2 if b.area[1] == "X" else 1 << 16)
            for s in (py, na):
                s.plc.image.queue_write(b.area, b.index, [raw])
        for s in (py, na):
            s.sim.step(1)
        assert na.plc.image.areas == py.plc.image.areas, f"scan {scan}: the image differs"
        assert str(na.plc.fault) == str(py.plc.fault), f"scan {scan}"
        if scan % 10 == 0 or scan < 50:
            pairs: list = []
            _state(py.plc.G, na.plc.G, "G", pairs)
            for a, b in zip(py.plc.instances, na.plc.instances):
                _state(a.obj, b.obj, a.name, pairs)
            diff = [(p, x, y) for p, x, y in pairs if x != y]
            assert not diff, f"scan {scan}: {diff[:5]}"
            assert len(pairs) > 20
        assert na.plc.retain_snapshot() == py.plc.retain_snapshot(), f"scan {scan}"


# --------------------------------------------------------------------------- single programs

def _pair(src: str, **kw: Any) -> tuple[PLC, PLC]:
    cu = check_sources([("t.st", textwrap.dedent(src))])
    py = PLC(compile_unit(cu), native=False, **kw)
    na = PLC(compile_unit(cu), native=True, **kw)
    assert py.native is None and na.native is not None
    return py, na


def _scan_both(py: PLC, na: PLC, n: int = 1) -> None:
    for _ in range(n):
        for plc in (py, na):
            plc.scan()
            plc.advance()


def test_a_fault_names_the_same_kind_message_and_line_natively():
    src = """
    PROGRAM main
    VAR i : DINT := 0; a : ARRAY[1..3] OF DINT; d : DINT := 7; z : DINT; q : DINT; END_VAR
    i := i + 1;
    q := d / (3 - i);
    a[i] := q;
    END_PROGRAM
    """
    py, na = _pair(src)
    _scan_both(py, na, 3)
    assert py.state == na.state == FAULT
    assert na.fault.kind == "division_by_zero" and str(na.fault) == str(py.fault)
    assert (na.fault.pou, na.fault.file, na.fault.line) == (py.fault.pou, py.fault.file, py.fault.line) == \
        ("main", "t.st", 5)
    src = src.replace("q := d / (3 - i);", "q := d;")
    py, na = _pair(src)
    _scan_both(py, na, 4)
    assert na.fault.kind == "index_out_of_range" and na.fault.message == "array index 4 outside 1..3"
    assert str(na.fault) == str(py.fault) and na.fault.line == py.fault.line == 6


def test_overflow_rounding_and_timers_scan_for_scan():
    """Wraparound per type, REAL rounding (double literals), TON/TOF/TP, counters, edges and
    bistables, checked value by value over many scans on both paths."""
    py, na = _pair("""
    PROGRAM main
    VAR
      n : DINT; s : SINT := 120; u : USINT := 250; w : WORD := 16#FFF0; ud : UDINT := 4294967290;
      r : REAL := 0.0; l : LREAL; q : INT; same : BOOL; m : DINT;
      t1 : TON; t2 : TOF; t3 : TP; c : CTU; e : R_TRIG; f : F_TRIG; b : SR; x : RS;
      tq1, tq2, tq3, cq : BOOL; et : TIME;
    END_VAR
    n := n + 1;
    s := s + 3; u := u + 3; w := w XOR SHL(w, 1); ud := ud + 3;
    r := r + 0.1; l := l + 0.1; same := r = 0.1 * DINT_TO_REAL(n);
    q := REAL_TO_INT(r * 2.5); m := (n * 7) MOD 5;
    t1(IN := (n MOD 50) > 10, PT := T#150ms); tq1 := t1.Q; et := t1.ET;
    t2(IN := (n MOD 40) < 5, PT := T#100ms); tq2 := t2.Q;
    t3(IN := (n MOD 30) = 3, PT := T#70ms); tq3 := t3.Q;
    c(CU := (n MOD 4) = 0, R := (n MOD 100) = 0, PV := 7); cq := c.Q;
    e(CLK := (n MOD 3) = 0); f(CLK := (n MOD 5) = 0);
    b(S1 := e.Q, R := f.Q); x(S := f.Q, R1 := e.Q);
    END_PROGRAM
    """, tick_ns=10_000_000)
    names = ["n", "s", "u", "w", "ud", "r", "l", "q", "same", "m", "tq1", "tq2", "tq3", "cq", "et",
             "c.CV", "b.Q1", "x.Q1", "t1.ET", "t2.ET", "t3.ET", "e.Q", "f.Q"]
    for scan in range(400):
        _scan_both(py, na)
        got = [_same(na.read(f"main.{k}")) for k in names]
        assert got == [_same(py.read(f"main.{k}")) for k in names], f"scan {scan}"
    assert na.read("main.s") != 120 and isinstance(na.read("main.r"), float)


def test_typed_literals_keep_their_type_and_abs_of_the_least_value_wraps_on_both_paths():
    """matiec writes `DWORD#5` as the cast `(DWORD)5`, so an expression of typed 32- and
    64-bit literals computes in that C type (`NOT DWORD#5` is 4294967290, not -6); ABS of a
    type's least value is that value again (two's complement, as the Python path wraps), also
    where gcc would take its abs as never negative; and `-INT#-5` builds (it was C's `--5`, a
    build error, so the program ran on the Python path). All found by random programs
    (tests/runtime/test_native_random_programs.py); each assertion failed before."""
    py, na = _pair("""
    PROGRAM main
    VAR r : ARRAY[1..3] OF BOOL; least : LINT := LINT#-9223372036854775808; a : LINT; neg : BOOL; m : INT; END_VAR
    m := -INT#-5;
    a := ABS(least);
    neg := ABS(least) < 0;
    r[1] := NOT LWORD#2 > LWORD#1;
    r[2] := NOT DWORD#5 > DWORD#0;
    r[3] := LINT#2147483647 + 1 > 0;
    END_PROGRAM
    """)
    _scan_both(py, na)
    assert py.read("main.r") == na.read("main.r") == [True] * 3
    assert py.read("main.a") == na.read("main.a") == -(1 << 63) and py.read("main.neg") == na.read("main.neg") is True
    assert py.read("main.m") == na.read("main.m") == 5      # C's `- -5`, not the decrement `--5`
    # the shape the fuzz found (gcc's folding depends on it): ABS(1) > ABS(least) is 1 > least
    py, na = _pair("""
    PROGRAM main
    VAR
      least : LINT := LINT#-9223372036854775808; one : LINT := LINT#-9223372036854775808;
      b0 : BOOL := TRUE; b1 : BOOL := FALSE; b2 : BOOL := TRUE;
    END_VAR
    IF (NOT b0) XOR b0 THEN one := LINT#1; END_IF;
    b0 := SEL(SEL(b1 AND b2, b1, b0), ABS(one) > ABS(least), SEL(FALSE, b2, DINT#7 < DINT#1));
    END_PROGRAM
    """)
    _scan_both(py, na)
    assert py.read("main.b0") is na.read("main.b0") is True


def test_writes_by_name_and_retain_go_through_the_c_memory(tmp_path):
    """Writing a variable (as forcing and the lab do) changes what the C computes with; a
    retained variable saved by the native path is restored into the Python path and back."""
    from plclab.runtime.retain import RetainStore
    src = """
    PROGRAM main
    VAR RETAIN keep : DINT; frames : ARRAY[1..3] OF INT; END_VAR
    VAR inc : DINT := 1; END_VAR
    VAR out AT %QW0 : INT; END_VAR
    keep := keep + inc;
    frames[2] := DINT_TO_INT(keep);
    out := frames[2];
    END_PROGRAM
    """
    cu = check_sources([("t.st", textwrap.dedent(src))])
    store = RetainStore(tmp_path / "r.json")
    na = PLC(compile_unit(cu), native=True, retain=store, retain_period_ns=0)
    assert na.native is not None
    na.scan()
    na.write("main.inc", 10)
    na.write("main.frames[1]", -5)
    na.scan()
    assert na.read("main.keep") == 11 and na.image.areas["QW"][0] == 11
    assert na.read("main.frames[1]") == -5
    na.stop()
    py = PLC(compile_unit(cu), native=False, retain=RetainStore(tmp_path / "r.json"))
    assert py.read("main.keep") == 11 and py.read("main.frames") == [-5, 11, 0]
    back = PLC(compile_unit(cu), native=True, retain=RetainStore(tmp_path / "r.json"))
    assert back.read("main.keep") == 11 and back.read("main.frames") == [-5, 11, 0]


def test_what_the_backend_does_not_cover_runs_on_the_python_path(monkeypatch, capsys):
    src = "PROGRAM main\nVAR s : STRING; n : INT; END_VAR\ns := CONCAT(s, 'a'); n := LEN(s);\nEND_PROGRAM\n"
    cu = check_sources([("t.st", src)])
    plc = PLC(compile_unit(cu), native=True)
    assert plc.native is None
    plc.scan()
    assert plc.read("main.n") == 1
    assert capsys.readouterr().err == ""            # nobody asked for native: silent
    monkeypatch.setenv(native.ENV, "1")
    native._told.clear()
    PLC(compile_unit(cu))
    PLC(compile_unit(cu))
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "does not cover STRING variables" in err and "Python path" in err


def test_plclab_native_0_turns_it_off(monkeypatch):
    cu = check_sources([("t.st", "PROGRAM main\nVAR n : INT; END_VAR\nn := n + 1;\nEND_PROGRAM\n")])
    monkeypatch.setenv(native.ENV, "0")
    assert PLC(compile_unit(cu), native=None).native is None
    monkeypatch.setenv(native.ENV, "1")
    assert PLC(compile_unit(cu), native=None).native is not None


def test_concurrent_builds_of_one_program_share_one_cache_entry(tmp_path):
    """Three processes build the same new program at once into one cache: all three run it
    natively, and the cache holds one library and no half-written file."""
    st = tmp_path / "p.st"
    st.write_text(f"PROGRAM main\nVAR n : DINT; END_VAR\nn := n + {random.randrange(1 << 30)};\nEND_PROGRAM\n")
    code = textwrap.dedent(f"""
        from plclab.frontend import load_files
        from plclab.runtime.compiler import Ref, compile_unit
        from plclab.runtime.plc import PLC
        plc = PLC(compile_unit(load_files([{str(st)!r}])), native=True)
        plc.scan(); plc.advance(); plc.scan()
        print(plc.native is not None, plc.read("main.n"))
    """)
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "cache"))
    procs = [subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE, text=True)
             for _ in range(3)]
    outs = [p.communicate(timeout=120)[0].split() for p in procs]
    assert all(p.returncode == 0 for p in procs)
    assert len({tuple(o) for o in outs}) == 1 and outs[0][0] == "True"
    files = sorted(os.listdir(tmp_path / "cache" / "plclab" / "native"))
    assert len(files) == 1 and files[0].startswith("_plclab_native_"), files


def test_the_cache_stays_within_its_bound_dropping_the_libraries_loaded_least_recently(tmp_path, monkeypatch):
    """Every new program adds a library (a class graded term after term, a test suite run
    day after day): past CACHE_MAX_BYTES the one loaded least recently goes, never the one
    just built; a program whose library went is built again; a dead build's folder goes."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(native, "PREFER_API", False)
    monkeypatch.setattr(native, "_LOADED", {})
    cache = tmp_path / "plclab" / "native"
    units = [check_sources([("t.st", f"PROGRAM main\nVAR n : DINT; END_VAR\nn := n + {k};\nEND_PROGRAM\n")])
             for k in (101, 202, 303)]

    def run(cu: Any) -> Path:
        """Run the program natively; its library's path."""
        plc = PLC(compile_unit(cu), native=True)
        assert plc.native is not None
        plc.scan()
        modname, _api, _include, ext = native._key(native._emitted(cu), native.c_compiler())
        return cache / f"{modname}{ext}"

    a, b = run(units[0]), run(units[1])
    os.utime(a, (1_000_000, 1_000_000))           # A loaded long ago...
    native._LOADED.clear()
    run(units[0])                                 # ...and now again: it is the recent one
    assert a.stat().st_mtime > 2_000_000
    os.utime(b, (1_500_000, 1_500_000))
    dead, live = cache / "build-dead", cache / "build-live"
    dead.mkdir(), live.mkdir()
    os.utime(dead, (1_000_000, 1_000_000))
    monkeypatch.setattr(native, "CACHE_MAX_BYTES", a.stat().st_size + b.stat().st_size + 100)
    c = run(units[2])                             # a third library: over the bound
    assert sorted(p.name for p in cache.iterdir()) == sorted([a.name, c.name, live.name])
    native._LOADED.clear()
    assert run(units[1]) == b and b.exists()      # B is built again when needed
    assert not a.exists() and c.exists()          # A was the least recent now


def test_a_program_loaded_again_is_built_in_the_background(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv(native.ENV, raising=False)
    cu = check_sources([("t.st", f"PROGRAM main\nVAR n : DINT; END_VAR\nn := n + {random.randrange(1 << 30)};\n"
                                 "END_PROGRAM\n")])
    assert PLC(compile_unit(cu)).native is None          # loaded once: no build
    assert not (tmp_path / "plclab" / "native").exists()
    assert PLC(compile_unit(cu)).native is None          # again: built in the background
    for t in list(native.threading.enumerate()):
        if t.name == "plclab-native-build":
            t.join(60)
    assert PLC(compile_unit(cu)).native is not None       # once built: native


def test_check_emit_c_prints_the_c_or_says_what_it_does_not_cover(tmp_path):
    ok = tmp_path / "ok.st"
    ok.write_text("PROGRAM main\nVAR n : INT; END_VAR\nn := n + 1;\nEND_PROGRAM\n")
    r = subprocess.run([sys.executable, "-m", "plclab.cli", "check", "--emit-c", str(ok)],
                       capture_output=True, text=True)
    if r.returncode != 0 and "No module named" in r.stderr:
        r = subprocess.run([str(Path(sys.executable).parent / "plclab"), "check", "--emit-c", str(ok)],
                           capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "self->f_N = (self->f_N + 1);" in r.stdout and "int scan(State *st" in r.stdout
    bad = tmp_path / "bad.st"
    bad.write_text("PROGRAM main\nVAR s : STRING; END_VAR\ns := 'a';\nEND_PROGRAM\n")
    r = subprocess.run([str(Path(sys.executable).parent / "plclab"), "check", "--emit-c", str(bad)],
                       capture_output=True, text=True)
    assert r.returncode != 0 and r.stdout == ""
    assert r.stderr.strip().splitlines() == [
        "plclab: error: the native scan path does not cover STRING variables: this program runs on the "
        "Python path (docs/runtime.md)"]


class CountingMemory(MemoryRetainStore):
    """A grading's retain memory that counts its writes (values made now or when loaded)."""

    flushes = 0

    def flush(self, sig, values):
        self.flushes += 1
        return super().flush(sig, values)

    def flush_later(self, sig, snapshot):
        self.flushes += 1
        return super().flush_later(sig, snapshot)

    def saved(self):
        """(signature, values) that a restart would load (None: nothing saved)."""
        return None if self._saved is None else (self._saved[0], self.load(self._saved[0]))


def test_a_gradings_retain_memory_is_written_when_a_retained_value_changed_and_holds_each_periods_values():
    """A grading saves the retained variables every second of plant time, thousands of times;
    on the native path a save of what the memory already holds is skipped (the C memory
    compared). Skipped or not, a power cut that loses the stop's flush restores exactly the
    values of the last periodic save, as on the Python path, which writes every time; a
    change anywhere in a retained FB (a field, a nested array element) is written."""
    src = """
    FUNCTION_BLOCK FB_Store
    VAR_INPUT put : BOOL; slot : INT; value : INT; END_VAR
    VAR frames : ARRAY[1..8] OF INT; count : INT; END_VAR
    IF put THEN frames[slot] := value; count := count + 1; END_IF;
    END_FUNCTION_BLOCK
    PROGRAM main
    VAR RETAIN store : FB_Store; END_VAR
    VAR put : BOOL; slot : INT := 1; value : INT; END_VAR
    store(put := put, slot := slot, value := value);
    put := FALSE;
    END_PROGRAM
    CONFIGURATION Config0 RESOURCE Res0 ON PLC
    TASK t (INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM inst WITH t : main;
    END_RESOURCE END_CONFIGURATION
    """
    unit = compile_unit(check_sources([("t.st", textwrap.dedent(src))]))
    stores = {"native": CountingMemory(), "python": CountingMemory()}
    plcs = {how: PLC(unit, native=how == "native", retain=stores[how], retain_period_ns=100_000_000)
            for how in stores}
    assert plcs["native"].native is not None and plcs["python"].native is None
    puts = {12: (3, 7), 47: (8, -2), 48: (3, 9)}          # scan -> (slot, value)
    for tick in range(100):                                 # 1 s of PLC time: saves at 0.1 .. 0.9 s
        for plc in plcs.values():
            if tick in puts:
                plc.write("inst.put", True)
                plc.write("inst.slot", puts[tick][0])
                plc.write("inst.value", puts[tick][1])
            plc.scan()
            plc.advance()
    assert stores["python"].flushes == 9
    # written at the first save (nothing held yet) and at the first save after each change
    assert stores["native"].flushes == 3
    for plc in plcs.values():
        plc.scan()                                          # t = 1 s: a save
        plc.advance()
        plc.write("inst.put", True)
        plc.write("inst.value", 100)
        plc.scan()                                          # changed after the last save
        plc.enter_fault("internal", "power cut: no flush at stop")
    back = {how: PLC(unit, native=how == "native", retain=stores[how]) for how in stores}
    for plc in back.values():
        assert plc.read("inst.store.frames") == [0, 0, 9, 0, 0, 0, 0, -2]
        assert plc.read("inst.store.count") == 3


QUIET = """
PROGRAM main
VAR
    q AT %QX0.0 : BOOL;
    w AT %QW0 : INT;
    x AT %IX0.0 : BOOL;
    level AT %IW0 : INT;
END_VAR
VAR
    n : INT;
    t : TON;
    pulses : INT;
END_VAR
VAR RETAIN
    kept : INT;
END_VAR
n := n + 1;
t(IN := NOT t.Q, PT := T#250ms);
IF t.Q THEN pulses := pulses + 1; END_IF;
q := x AND pulses MOD 2 = 1;
w := pulses * 10 + level;
IF n MOD 37 = 0 THEN kept := kept + 1; END_IF;
END_PROGRAM

PROGRAM slow
VAR
    n : INT;
    t : TON;
    pulses : INT;
END_VAR
n := n + 1;
t(IN := NOT t.Q, PT := T#90ms);
IF t.Q THEN pulses := pulses + 1; END_IF;
IF n = 120 THEN n := n / (n - 120); END_IF;
END_PROGRAM

CONFIGURATION Config0 RESOURCE Res0 ON PLC
TASK fast (INTERVAL := T#10ms, PRIORITY := 0);
TASK slow_task (INTERVAL := T#30ms, PRIORITY := 1);
PROGRAM a WITH fast : main;
PROGRAM b WITH slow_task : slow;
END_RESOURCE END_CONFIGURATION
"""


def test_a_quiet_run_leaves_the_plc_where_as_many_scans_would():
    """PLC.run_quiet (the closed loop's stretches where the plant stands idle) runs scans in
    one native call until an output or a watched variable changes or a scan faults. Played
    against scanning tick by tick, with inputs changed between runs, two tasks of different
    periods, a retain save every 0.1 s and a division by zero at the 120th scan of the slow
    one: after each run, the same time, outputs, variables, retained store and fault; a run
    stops at the scan that changed an output or the watched variable; and most ticks ran in
    runs of many scans."""
    unit = compile_unit(check_sources([("t.st", QUIET)]))
    stores = {"quiet": CountingMemory(), "scans": CountingMemory()}
    plcs = {how: PLC(unit, native=True, retain=stores[how], retain_period_ns=100_000_000) for how in stores}
    quiet, scans = plcs["quiet"], plcs["scans"]
    assert quiet.native is not None
    inputs = {0: (1, 5), 63: (0, 7), 64: (1, 7), 140: (1, -3)}     # tick -> (%IX0.0, %IW0)

    def state(plc: PLC) -> tuple:
        return (plc.ticks, plc.now_ns, plc.state, plc.fault, {a: list(v) for a, v in plc.image.areas.items()},
                plc.read("a.n"), plc.read("b.n"), plc.read("a.pulses"), plc.read("b.t.ET"), plc.read("a.kept"),
                plc.retain_snapshot())

    def put(plc: PLC, tick: int) -> None:
        if tick in inputs:
            plc.image.areas["IX"][0], plc.image.areas["IW"][0] = inputs[tick][0], inputs[tick][1] & 0xFFFF

    history = []
    for tick in range(400):
        put(scans, tick)
        scans.scan()
        scans.advance()
        history.append(state(scans))
    runs = []
    watch_pairs = [quiet.resolve("b.pulses")]
    while quiet.ticks < 400:
        tick = quiet.ticks
        put(quiet, tick)
        later = [t for t in inputs if t > tick]
        n = min(400, *later) - tick if later else 400 - tick
        outputs = list(quiet.image.areas["QX"][:1]) + list(quiet.image.areas["QW"][:1])
        watched = quiet.read("b.pulses")
        k = ran = quiet.run_quiet(n, native.Watch.of(quiet, watch_pairs))
        if k == 0:                               # a retain save due, or faulted: scan as usual
            quiet.scan()
            quiet.advance()
            k = 1
        runs.append(k)
        assert state(quiet) == history[quiet.ticks - 1], f"after the run of {k} from tick {tick}"
        # stopped before n, not at a save's scan nor by a fault: it changed something
        if ran and k < n and quiet.state != FAULT and quiet.ticks % 10 != 0:
            assert ([quiet.image.areas["QX"][0], quiet.image.areas["QW"][0]] != outputs
                    or quiet.read("b.pulses") != watched), tick
    assert quiet.fault is not None and quiet.fault.kind == "division_by_zero"
    assert stores["quiet"].flushes == stores["scans"].flushes and stores["quiet"].saved() == stores["scans"].saved()
    assert max(runs) >= 8 and len(runs) < 400 / 2, runs      # runs up to each save (every 10 ticks)


def test_no_quiet_run_where_it_could_differ_from_scanning():
    """The Python path, a PLC not running, a Modbus write waiting and replaced I/O stages (the
    lab's forces) all scan tick by tick (run_quiet answers 0)."""
    unit = compile_unit(check_sources([("t.st", QUIET)]))
    with native.python_only():
        assert PLC(unit).run_quiet(10) == 0
    plc = PLC(unit, native=True)
    plc.image.queue_write("QW", 0, [3])
    assert plc.run_quiet(10) == 0
    plc.image.apply_pending()
    plc.read_inputs = plc.read_inputs            # an instance's own stage, as the lab sets it
    assert plc.run_quiet(10) == 0
    del plc.read_inputs
    assert plc.run_quiet(10) > 0
    plc.stop()
    assert plc.run_quiet(10) == 0


def test_a_build_in_the_background_leaves_the_main_threads_output_alone(tmp_path, monkeypatch):
    """A program loaded again is built in a background thread (program_for); the build writes
    nothing and never redirects sys.stdout, so every line the main thread prints meanwhile (a
    command's report) reaches its stream."""
    import io
    import threading

    from plclab.runtime.cgen import emit_c
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    import uuid
    # a program no test of this process has loaded yet (a loaded one is not built again)
    src = QUIET.replace("    kept : INT;", f"    kept : INT;\n    unique_{uuid.uuid4().hex} : INT;")
    cprog = emit_c(compile_unit(check_sources([("t.st", src)])).checked)
    ours = io.StringIO()
    monkeypatch.setattr(sys, "stdout", ours)
    before = set(threading.enumerate())
    assert native.build(cprog, wait=False, later=True) is None          # not built yet: later
    builders = [t for t in threading.enumerate() if t not in before]
    assert builders
    n = 0
    while any(t.is_alive() for t in builders) and n < 2_000_000:
        print(f"line {n}")
        n += 1
    for t in builders:
        t.join(timeout=120)
    printed = ours.getvalue().splitlines()
    assert sys.stdout is ours and n > 0 and printed == [f"line {k}" for k in range(n)]
    assert native.build(cprog, wait=False) is not None                   # and it was built
