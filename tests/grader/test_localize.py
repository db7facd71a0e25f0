"""Where the mistake most likely is (plclab.grader.localize, plclab.runtime.tracing): the dynamic
slice of an output on small programs, the diff against a starting program, the ranking; and the
figure on the project's one-mistake fixtures (tests/grader/localize_rates.py)."""
from __future__ import annotations

import pytest

from plclab.frontend import check_sources
from plclab.grader.report import GradeReport, Row
from plclab.grader.localize import (StateLog, backward_slice, changed_lines, ochiai, pou_lines, rank)
from plclab.runtime.compiler import compile_unit
from plclab.runtime.native import python_only
from plclab.runtime.plc import PLC
from plclab.runtime.sim import Simulation
from plclab.runtime.tracing import Tracer


def _sim(src: str, name: str = "t.st") -> Simulation:
    """A program on the Python path, whatever the native cache holds: the tracer follows the
    generated Python (as the grader's replays do, plclab.runtime.native.python_only)."""
    with python_only():
        return Simulation(PLC(compile_unit(check_sources([(name, src)]))), watch=[])


def _traced(sim: Simulation, scans: int, log: StateLog | None = None) -> Tracer:
    clock = lambda: sim.plc.now_ns / 1e9        # noqa: E731
    tr = Tracer(sim.plc.compiled, clock, sample=(lambda: log.record(clock(), sim.plc)) if log else None)
    tr.start()
    try:
        sim.step(scans)
    finally:
        tr.stop()
    return tr


def _key(sim: Simulation, path: str) -> tuple:
    owner, attr = sim.plc.resolve(path)
    return (id(owner), attr)


def _sliced_lines(sim: Simulation, tr: Tracer, path: str) -> set[int]:
    compiled = sim.plc.compiled
    sl = backward_slice(tr, [_key(sim, path)], lambda line: compiled.where(line) is not None)
    return {info.line for eid in sl.steps if (info := compiled.where(tr.events[eid].line)) is not None}


def _line(src: str, text: str) -> int:
    return next(n for n, line in enumerate(src.splitlines(), 1) if text in line)


CHAIN = """PROGRAM main
VAR
    n : INT;
    a : INT;
    b : INT;
    c : INT;
    unrelated : INT;
    out : BOOL;
END_VAR
n := n + 1;
unrelated := n * 2;
IF n > 2 THEN
    a := n;
END_IF;
b := a + 1;
c := 5;
c := b;
out := c > 3;
END_PROGRAM
"""


def test_the_slice_follows_data_and_control_back_through_the_scans():
    sim = _sim(CHAIN)
    tr = _traced(sim, 5)
    assert sim.plc.read("main.out") is True
    got = _sliced_lines(sim, tr, "main.out")
    want = {_line(CHAIN, s) for s in ("out := c > 3", "c := b", "b := a + 1", "a := n", "IF n > 2", "n := n + 1")}
    assert got == want                     # not `unrelated`, not `c := 5` (overwritten before use)


CALLS = """FUNCTION FC_Twice : INT
VAR_INPUT
    X : INT;
END_VAR
FC_Twice := X * 2;
END_FUNCTION

FUNCTION_BLOCK FB_Hold
VAR_INPUT
    Set : BOOL;
END_VAR
VAR_OUTPUT
    Q : BOOL;
END_VAR
IF Set THEN
    Q := TRUE;
END_IF;
END_FUNCTION_BLOCK

PROGRAM main
VAR
    n : INT;
    m : INT;
    other : INT;
    h : FB_Hold;
    out : BOOL;
END_VAR
n := n + 1;
other := FC_Twice(X := 7);
m := FC_Twice(X := n);
h(Set := m > 4);
out := h.Q;
END_PROGRAM
"""


def test_the_slice_goes_into_functions_and_function_blocks():
    sim = _sim(CALLS)
    tr = _traced(sim, 4)
    assert sim.plc.read("main.out") is True
    got = _sliced_lines(sim, tr, "main.out")
    for s in ("out := h.Q", "h(Set := m > 4)", "m := FC_Twice(X := n)", "FC_Twice := X * 2", "Q := TRUE",
              "IF Set THEN", "n := n + 1"):
        assert _line(CALLS, s) in got, s
    assert _line(CALLS, "other := FC_Twice(X := 7)") not in got


def test_a_timer_carries_its_inputs_to_its_output():
    src = """PROGRAM main
VAR
    go : BOOL;
    t : TON;
    out : BOOL;
END_VAR
go := TRUE;
t(IN := go, PT := T#50ms);
out := t.Q;
END_PROGRAM
"""
    sim = _sim(src)
    tr = _traced(sim, 10)
    assert sim.plc.read("main.out") is True
    got = _sliced_lines(sim, tr, "main.out")
    assert {_line(src, "go := TRUE"), _line(src, "t(IN := go"), _line(src, "out := t.Q")} <= got


IN_OUT = """TYPE Pair :
STRUCT
    a : INT;
    b : INT;
END_STRUCT;
END_TYPE

FUNCTION_BLOCK FB_Bump
VAR_IN_OUT
    P : Pair;
    K : INT;
END_VAR
VAR_INPUT
    Amount : INT;
END_VAR
VAR
    calls : INT;
END_VAR
calls := calls + 1;
P.a := P.a + Amount;
K := K + P.a;
END_FUNCTION_BLOCK

PROGRAM main
VAR
    x : Pair;
    y : Pair;
    kx : INT;
    ky : INT;
    bump : FB_Bump;
    n : INT;
    out : INT;
END_VAR
n := n + 1;
IF n MOD 2 = 0 THEN
    bump(P := x, K := kx, Amount := 1);
ELSE
    bump(P := y, K := ky, Amount := 2);
END_IF;
out := x.a + ky;
END_PROGRAM
"""


@pytest.mark.parametrize("src", [CHAIN, CALLS, IN_OUT], ids=["chain", "calls", "in_out"])
def test_a_lines_storage_worked_out_once_is_what_working_it_out_each_time_gives(src, monkeypatch):
    """The tracer reuses a line's storage keys for the same instance (IEC storage is fixed), but
    never across a VAR_IN_OUT, which each call binds to another variable (`bump` works on x,
    then on y): every event is the same as the tracer working each one out anew gives."""
    def named(tr: Tracer) -> list:
        """The events with each object's id replaced by its class (two runs have two sets of
        objects, and a call's reference cells come and go); which object is which shows in
        the slice, compared too."""
        def key(k: tuple) -> tuple:
            return (tr.types[k[0]].__name__, *k[1:]) if isinstance(k[0], int) else k
        return [(e.line, e.scan, [key(k) for k in e.reads], [(key(k), strong) for k, strong in e.writes], e.parent,
                 e.call) for e in (tr.events[i] for i in tr.order)]

    runs = []
    for cache in (False, True):
        monkeypatch.setattr(Tracer, "CACHE_LINES", cache)
        sim = _sim(src)
        tr = _traced(sim, 6)
        runs.append((named(tr), _sliced_lines(sim, tr, "main.out")))
    assert runs[0] == runs[1]
    if src is IN_OUT:      # the slice of out reaches the call on x, and not the one on y
        assert _line(src, "bump(P := x") in runs[1][1] and _line(src, "P.a := P.a + Amount") in runs[1][1]



def test_the_state_log_records_each_scans_changes_as_reading_every_variable_by_name_gives():
    """StateLog reads hundreds of values per scan through a reader generated for the objects
    it walked; what it records is what reading each variable by name (getattr, every scan)
    records, through a whole struct assigned (other objects), a VAR_IN_OUT rebound at each
    call and a cold restart (a new set of objects)."""
    from plclab.runtime.tracing import StateReader, _get

    class ByName(StateReader):
        def _walk(self, plc):
            super()._walk(plc)
            self._same = lambda: all(_get(c, k) is o for c, k, o in self.edges)
            self._get_all = lambda: [_get(c, k) for c, k, _path in self.leaves]

    sim = _sim(IN_OUT)
    log, by_name = StateLog(), StateLog()
    by_name._reader = ByName()
    for n in range(12):
        if n == 6:
            sim.plc.restart()
        if n == 8:
            sim.plc.write("main.x", sim.plc.read("main.y"))      # a whole struct assigned
        for one in (log, by_name):
            one.record(n * 0.01, sim.plc)
        sim.step(1)
    assert log._reader.walks >= 2                   # the restart's objects were walked anew
    assert log.changes == by_name.changes
    assert sum(len(ch) for ch in log.changes.values()) > 2 * len(log.changes)   # values changed over the scans


def test_the_tracer_leaves_the_garbage_collector_as_it_found_it():
    """The collector is off while a trace is recorded (it would walk the growing trace again
    and again) and on again after, whether or not it was on before."""
    import gc
    assert gc.isenabled()
    sim = _sim(CHAIN)
    tr = Tracer(sim.plc.compiled, lambda: sim.plc.now_ns / 1e9)
    tr.start()
    try:
        off_while_tracing = not gc.isenabled()
        sim.step(3)
    finally:
        tr.stop()
    assert off_while_tracing and gc.isenabled()
    assert len(tr.scan_times) == 3 and tr.events
    gc.disable()
    try:
        _traced(sim, 1)
        assert not gc.isenabled()
    finally:
        gc.enable()


def test_a_dropped_trace_is_freed_at_once_without_the_cyclic_collector():
    """A trace is hundreds of thousands of events; a grading that localizes several rows, or
    a process that grades many programs (grade-class, the lab), must get them back as each
    replay is dropped. The line tracer of a traced call once named itself (a reference cycle
    holding the whole trace): every trace then waited for a full collection, and a process
    grading one program after another grew by about 85 MB per program."""
    import gc
    import weakref

    sim = _sim(CALLS)                       # calls of an FC and an FB: a line tracer per call
    gc.disable()
    try:
        tr = _traced(sim, 3)
        assert len(tr.events) > 10
        gone = weakref.ref(tr)
        del tr
        assert gone() is None, "the trace is held by a reference cycle"
    finally:
        gc.enable()


def test_a_trace_stopped_in_kept_out_of_gc_is_not_walked_and_the_block_gives_everything_back():
    """A row's localization keeps its traces out of the collector's walks (issue 30: the
    first collection after a replay walked every event): a tracer stopped in the block leaves
    the collector on with the trace frozen out of it, and the block's end gives back what is
    alive, so cyclic garbage made while tracing is still collected."""
    import gc
    import weakref

    from plclab.runtime.tracing import kept_out_of_gc

    class Cycle:
        me: object = None

    sim = _sim(CHAIN)
    with kept_out_of_gc():
        tr = Tracer(sim.plc.compiled, lambda: sim.plc.now_ns / 1e9)
        tr.start()
        sim.step(3)
        garbage = Cycle()
        garbage.me = garbage
        gone = weakref.ref(garbage)
        del garbage
        tr.stop()
        assert gc.isenabled() and gc.get_freeze_count() > 0
        event = next(iter(tr.events.values()))
        assert not any(o is event for o in gc.get_objects()), "the trace is walked by the collector"
        del tr, event
    assert gc.get_freeze_count() == 0 and gc.isenabled()
    gc.collect()
    assert gone() is None, "cyclic garbage made while tracing was never collected"


START = """FUNCTION_BLOCK FB_Pulse
VAR_INPUT
    Go : BOOL;
END_VAR
VAR_OUTPUT
    Q : BOOL;
END_VAR
Q := Go;
END_FUNCTION_BLOCK

PROGRAM main
VAR
    n : INT;
    p : FB_Pulse;
    out : BOOL;
END_VAR
n := n + 1;
p(Go := n > 2);
out := p.Q;
END_PROGRAM
"""


def test_what_the_student_changed_is_a_line_diff_per_pou_matched_by_name():
    student = START.replace("p(Go := n > 2);", "p(Go := n > 3);").replace(
        "END_PROGRAM", "END_PROGRAM\n\nFUNCTION_BLOCK FB_New\nVAR\n    x : INT;\nEND_VAR\nx := 1;\nEND_FUNCTION_BLOCK")
    # the POUs in another order, a comment and indentation changed: not changes
    moved = student.split("\n\nPROGRAM main")
    student = "PROGRAM main" + moved[1] + "\n\n" + moved[0].replace("Q := Go;", "  Q := Go;   (* copy *)")
    changed, kept = changed_lines([("s.st", student)], [("start.st", START)])
    lines = student.splitlines()
    named = {lines[n - 1].strip() for _f, n in changed}
    assert "p(Go := n > 3);" in named
    assert {"FUNCTION_BLOCK FB_New", "x := 1;"} <= named
    assert not {"Q := Go;   (* copy *)", "n := n + 1;", "out := p.Q;"} & named
    assert kept > 0.9
    assert set(pou_lines(START)) == {"FB_Pulse", "main"}


def test_a_changed_line_on_the_path_ranks_first_and_one_off_it_is_not_named():
    # the starting program pulses when n > 2; the task asks n > 4 (the model answer); the
    # student changed two lines: one on the output's path (n > 3, the mistake), one off it
    student = START.replace("p(Go := n > 2);", "p(Go := n > 3);").replace(
        "    out : BOOL;\nEND_VAR", "    out : BOOL;\n    spare : INT;\nEND_VAR").replace(
        "out := p.Q;", "out := p.Q;\nspare := 7;")
    model = START.replace("p(Go := n > 2);", "p(Go := n > 4);")
    s, m = _sim(student, "s.st"), _sim(model, "m.st")
    slog, mlog = StateLog(), StateLog()
    tr = _traced(s, 4, slog)
    _traced(m, 4, mlog)
    assert s.plc.read("main.out") != m.plc.read("main.out")
    compiled = s.plc.compiled
    sl = backward_slice(tr, [_key(s, "main.out")], lambda line: compiled.where(line) is not None)
    changed, _kept = changed_lines([("s.st", student)], [("start.st", START)])
    cands = rank(tr, sl, set(), [("s.st", student)], changed, slog, mlog)
    assert cands and cands[0].line == _line(student, "p(Go := n > 3)")
    assert all(c.line != _line(student, "spare := 7") for c in cands)
    assert "s.st:" in cands[0].where() and "`p(Go := n > 3);`" in cands[0].where()


def test_a_line_left_as_the_starting_program_had_it_is_named_where_values_first_depart():
    # the task needs `p(Go := n > 4)`; the student never changed that line (still n > 2) but
    # changed another one the output depends on in a way that departs later
    student = START.replace("out := p.Q;", "out := p.Q AND n > 0;")
    model = START.replace("p(Go := n > 2);", "p(Go := n > 4);")
    s, m = _sim(student, "s.st"), _sim(model, "m.st")
    slog, mlog = StateLog(), StateLog()
    tr = _traced(s, 4, slog)
    _traced(m, 4, mlog)
    compiled = s.plc.compiled
    sl = backward_slice(tr, [_key(s, "main.out")], lambda line: compiled.where(line) is not None)
    changed, _kept = changed_lines([("s.st", student)], [("start.st", START)])
    cands = rank(tr, sl, set(), [("s.st", student)], changed, slog, mlog)
    lines = [c.line for c in cands]
    assert _line(student, "Q := Go;") in lines[:1] or _line(student, "p(Go := n > 2)") in lines[:1], cands
    assert _line(student, "out := p.Q AND n > 0") in lines


def test_a_program_written_from_scratch_is_ranked_by_its_spectrum():
    assert ochiai(0, 5, 3) == 0.0
    assert ochiai(3, 0, 3) == 1.0
    assert ochiai(2, 2, 4) == pytest.approx(2 / (4 * 4) ** 0.5)
    src = """PROGRAM main
VAR
    n : INT;
    late : BOOL;
    out : BOOL;
END_VAR
n := n + 1;
late := FALSE;
IF n > 3 THEN
    late := TRUE;
END_IF;
out := late;
END_PROGRAM
"""
    sim = _sim(src)
    tr = _traced(sim, 6)
    compiled = sim.plc.compiled
    sl = backward_slice(tr, [_key(sim, "main.out")], lambda line: compiled.where(line) is not None)
    # the output differs from the model answer's in the scans where it is TRUE (n > 3)
    failing = {k for k in range(len(tr.scan_times)) if k + 1 > 3}
    cands = rank(tr, sl, failing, [("t.st", src)], None, limit=3)
    assert cands[0].line == _line(src, "late := TRUE")      # runs only in the failing scans
    assert cands[0].suspicion == 1.0


def test_a_failing_row_lists_the_lines_most_likely_first_and_the_last_writer_last():
    row = Row("T2.2", "The pause recorded with a frame is held after it.", False, "3.00 s", "1.00 s", 12.5, "pauses",
              lines=("robot.st:308 `Pause(Start := TRUE, Duration := T#1s, Cancel := FALSE);`",
                     "robot.st:265 `Cp.Frames[Cp.Count].Pause := SEL(G := I07, IN0 := T#1s, IN1 := T#3s);`"),
              written="L2 last written by robot.st:463 `L2 := FC_BitOf(Valves, 1);`")
    text = GradeReport("mp9c", "task2", "MP-9C, Task 2", ["robot.st"], rows=[row]).text().splitlines()
    at = next(n for n, line in enumerate(text) if "where to look, most likely first:" in line)
    assert text[at + 1].strip().startswith("1. robot.st:308 `Pause(")
    assert any(line.strip().startswith("2. robot.st:265") for line in text[at + 2:at + 4])
    detail_end = next(n for n in range(at, len(text)) if not text[n].strip())
    assert text[detail_end - 1].strip() == "L2 last written by robot.st:463 `L2 := FC_BitOf(Valves, 1);`"
    assert all(len(line) <= 100 for line in text)


def test_the_changed_line_is_named_by_most_failing_reports_of_the_one_mistake_fixtures(capsys):
    """The issue's figure: at least 80 % of the failing reports of the one-mistake fixtures
    name the changed line among their ranked candidates. Slow: one grading per fixture."""
    import localize_rates
    with capsys.disabled():
        rate = localize_rates.main([])
    assert rate >= 0.8


def test_the_model_answers_state_is_sampled_at_each_scan_through_a_power_cycle_and_not_past_the_failure():
    """A row's lines compare the student's state with the model answer's, sampled as each scan
    of the model answer's replay begins (its inputs read). The TUR-10 `restart` scenario power
    cycles the PLC (another PLC object after it): the model answer is sampled once at every
    scan before the restart and after it, in time order, from the window's start on, and the
    replay stops at the first scan past the failure. (The line tracer that sampled it before
    issue 30 took the restarted program's start-up for a scan: one sample out of time order,
    which left the state log's changes unsorted.)"""
    from plclab.grader.explore import model_answer
    from plclab.grader.localize import _sampled
    from plclab.grader.registry import Checks, requirement_set
    from plclab.runtime.retain import MemoryRetainStore
    from plclab.scenario import ScenarioFailure, compiled_once

    req = requirement_set("tur10", "task2")
    scenario = next(s for s in req.scenarios if s.name == "restart")
    model, why = model_answer("tur10", "task2", None)
    assert model is not None, why
    with python_only(), compiled_once(model.checked, share=model.cache):
        session = req.make_session(list(model.sources), MemoryRetainStore(), model.checked)
        seen: list[tuple[float, int, int]] = []         # (time, PLC object, scans it ran before)
        since, stop_at = 0.5, 6.0

        def replay(sess, begin):
            begin()
            try:
                scenario.run(sess, Checks(req.requirements))
            except ScenarioFailure:
                pass

        _sampled(session, lambda: seen.append((session.now, id(session.plc), session.plc.ticks)), since, stop_at,
                 replay)
    times = [t for t, _plc, _ticks in seen]
    plcs = list(dict.fromkeys(p for _t, p, _ticks in seen))
    assert len(plcs) >= 2, "the PLC of the restart was not sampled"
    assert times == sorted(set(times)) and since - 1e-9 <= times[0] < since + 0.011
    assert stop_at - 0.011 < times[-1] <= stop_at + 1e-9          # the scan at the failure, none after it
    tick = session.plc.tick_ns / 1e9
    for plc in plcs:                    # every scan of each PLC in the window, none skipped
        ticks = [k for _t, p, k in seen if p == plc]
        assert ticks == list(range(ticks[0], ticks[0] + len(ticks))), "a scan was not sampled"
    off = [(a, b) for (a, _p, _k), (b, _q, _l) in zip(seen, seen[1:]) if b - a > tick + 1e-9]
    assert len(off) <= 1                # the power-off gap, if the restart turned it off for a while
