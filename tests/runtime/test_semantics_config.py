"""CONFIGURATION / RESOURCE / TASK scheduling, global variables, located I/O and runtime faults.

Execution model (docs/timing.md): the base tick is the GCD of the task intervals; each tick
samples the inputs, runs the due PROGRAM instances in RESOURCE declaration order (as OpenPLC's
generated Res0.c does: PRIORITY does not reorder) and publishes the outputs. Timing convention
(docs/timing.md): the first scan is at t = 0 and an input event at t is seen by the first scan at
or after t.
"""
from __future__ import annotations

import pytest

import struct

from plclab.runtime.sim import InputEvent
from st_helpers import MS, load

pytestmark = pytest.mark.usefixtures("compile_mode")


def config(programs: str, resource: str, globals_: str = "") -> str:
    return f"""{programs}
CONFIGURATION Config0
  {globals_}
  RESOURCE Res0 ON PLC
{resource}
  END_RESOURCE
END_CONFIGURATION
"""


# --------------------------------------------------------------------------- globals

def test_var_external_shares_a_global_between_programs():
    src = config("""
PROGRAM producer
VAR_EXTERNAL counter : INT; flag : BOOL; END_VAR
counter := counter + 1;
flag := counter >= 103;
END_PROGRAM
PROGRAM consumer
VAR_EXTERNAL counter : INT; flag : BOOL; END_VAR
VAR seen : INT; seen_flag : BOOL; END_VAR
seen := counter * 10;
seen_flag := flag;
END_PROGRAM
""", """
    TASK main_task(INTERVAL := T#20ms, PRIORITY := 0);
    PROGRAM p WITH main_task : producer;
    PROGRAM c WITH main_task : consumer;
""", "VAR_GLOBAL counter : INT := 100; flag : BOOL; END_VAR")
    sim = load(src)
    sim.step(1)
    assert sim.plc.read("counter") == 101           # initial value of the global, plus one
    assert sim.plc.read("c.seen") == 1010           # consumer sees the value of this tick
    assert sim.plc.read("c.seen_flag") is False
    sim.step(2)
    assert sim.plc.read("c.seen_flag") is True      # counter reached 103
    sim.plc.write("counter", 0)
    sim.step(3)
    assert sim.plc.read("c.seen") == 30
    assert sim.plc.read("c.seen_flag") is False


def test_global_constant_and_retained_initial_values():
    src = config("""
PROGRAM main
VAR_EXTERNAL CONSTANT lim_hi : INT; END_VAR
VAR_EXTERNAL level : REAL; END_VAR
VAR over : BOOL; END_VAR
level := level + 10.0;
over := REAL_TO_INT(level) > lim_hi;
END_PROGRAM
""", """
    TASK t(INTERVAL := T#100ms, PRIORITY := 0);
    PROGRAM inst WITH t : main;
""", "VAR_GLOBAL CONSTANT lim_hi : INT := 25; END_VAR VAR_GLOBAL level : REAL := 1.5; END_VAR")
    sim = load(src)
    sim.step(2)
    assert sim.plc.read("inst.over") is False       # 21.5 rounds to 22
    sim.step(1)
    assert sim.plc.read("inst.over") is True        # 31.5
    assert sim.plc.tick_ns == 100 * MS


# --------------------------------------------------------------------------- tasks

TWO_TASKS = config("""
PROGRAM fast
VAR_EXTERNAL trail : DINT; END_VAR
VAR n : INT; END_VAR
n := n + 1;
trail := trail * 10 + 1;
END_PROGRAM
PROGRAM slow
VAR_EXTERNAL trail : DINT; END_VAR
VAR n : INT; last_fast : INT; END_VAR
n := n + 1;
trail := trail * 10 + 2;
END_PROGRAM
""", """
    TASK t_slow(INTERVAL := T#50ms, PRIORITY := 1);
    TASK t_fast(INTERVAL := T#10ms, PRIORITY := 5);
    PROGRAM s WITH t_slow : slow;
    PROGRAM f WITH t_fast : fast;
""", "VAR_GLOBAL trail : DINT; END_VAR")


def test_two_tasks_base_tick_and_rates():
    sim = load(TWO_TASKS)
    assert sim.plc.tick_ns == 10 * MS               # GCD of 10 ms and 50 ms
    sim.run(1.0)                                    # 100 ticks: t = 0 .. 990 ms
    assert sim.plc.read("f.n") == 100
    assert sim.plc.read("s.n") == 20                # every 5th tick, starting at t = 0


def test_slow_program_runs_on_ticks_0_5_10():
    sim = load(TWO_TASKS)
    ran = []
    for tick in range(12):
        before = sim.plc.read("s.n")
        sim.step(1)
        if sim.plc.read("s.n") != before:
            ran.append(tick)
    assert ran == [0, 5, 10]


def test_a_plc_says_at_which_ticks_a_program_runs():
    """A stand ticks every 10 ms; a task of 50 ms (and one of 20 ms) runs only at some of the
    ticks. `runs_a_task_now` says whether the scan about to run enters any program: it is what
    a grader's sampler of the program's state looks at (plclab.grader.localize)."""
    src = config("""
PROGRAM slow
VAR n : INT; END_VAR
n := n + 1;
END_PROGRAM
PROGRAM middle
VAR n : INT; END_VAR
n := n + 1;
END_PROGRAM
""", """
    TASK t_slow(INTERVAL := T#50ms, PRIORITY := 1);
    TASK t_mid(INTERVAL := T#20ms, PRIORITY := 2);
    PROGRAM s WITH t_slow : slow;
    PROGRAM m WITH t_mid : middle;
""")
    sim = load(src, tick_ms=10)
    said, ran = [], []
    for tick in range(12):
        said.append(sim.plc.runs_a_task_now())
        before = (sim.plc.read("s.n"), sim.plc.read("m.n"))
        sim.step(1)
        ran.append((sim.plc.read("s.n"), sim.plc.read("m.n")) != before)
    assert said == ran
    assert ran == [t % 5 == 0 or t % 2 == 0 for t in range(12)] and not all(ran)


def test_programs_run_in_resource_declaration_order():
    # `s` is declared first, so on a tick where both run the slow one runs first, even
    # though its PRIORITY number is different (OpenPLC keeps declaration order)
    sim = load(TWO_TASKS)
    sim.step(1)                                     # tick 0: s then f
    assert sim.plc.read("trail") == 21
    sim.plc.write("trail", 0)
    sim.step(4)                                     # ticks 1..4: only f
    assert sim.plc.read("trail") == 1111
    sim.plc.write("trail", 0)
    sim.step(1)                                     # tick 5: s then f again
    assert sim.plc.read("trail") == 21


def test_declaration_order_not_priority_within_one_task():
    src = config("""
PROGRAM a
VAR_EXTERNAL trail : DINT; END_VAR
trail := trail * 10 + 1;
END_PROGRAM
PROGRAM b
VAR_EXTERNAL trail : DINT; END_VAR
trail := trail * 10 + 2;
END_PROGRAM
""", """
    TASK t1(INTERVAL := T#20ms, PRIORITY := 9);
    TASK t0(INTERVAL := T#20ms, PRIORITY := 0);
    PROGRAM pb WITH t1 : b;
    PROGRAM pa WITH t0 : a;
""", "VAR_GLOBAL trail : DINT; END_VAR")
    sim = load(src)
    sim.step(2)
    assert sim.plc.read("trail") == 2121


# --------------------------------------------------------------------------- located variables

LOCATED = """
PROGRAM main
VAR
  start AT %IX0.0 : BOOL;
  stop AT %IX1.7 : BOOL;
  level AT %IW3 : INT;
END_VAR
VAR
  motor AT %QX0.1 : BOOL;
  lamp AT %QX2.0 : BOOL;
  setpoint AT %QW1 : INT;
  raw AT %QW2 : WORD;
END_VAR
VAR
  counter AT %MW10 : UINT;
  gain AT %MD4 : REAL;
END_VAR
IF start THEN motor := TRUE; END_IF;
IF stop THEN motor := FALSE; END_IF;
lamp := NOT motor;
setpoint := level * 2;
raw := INT_TO_WORD(level);
counter := counter + 1;
gain := gain + 0.5;
END_PROGRAM
"""


def test_located_bits_and_words_in_the_process_image():
    sim = load(LOCATED, tick_ms=10)
    img = sim.plc.image.areas
    sim.set("%IW3", -300)
    sim.step(1)
    assert img["QX"][0 * 8 + 1] == 0 and img["QX"][2 * 8 + 0] == 1
    assert img["QW"][1] == (-600) & 0xFFFF          # INT stored as a 16-bit word
    assert img["QW"][2] == 0xFED4
    sim.set("%IX0.0", True)
    sim.step(1)
    assert img["QX"][1] == 1 and img["QX"][16] == 0
    sim.set("%IX0.0", False)
    sim.set("%IX1.7", True)                         # bit 7 of byte 1 is index 15
    sim.step(1)
    assert img["QX"][1] == 0
    assert sim.plc.read("main.stop") is True


def test_located_memory_words_and_real_doublewords():
    sim = load(LOCATED, tick_ms=10)
    img = sim.plc.image.areas
    sim.step(3)
    assert img["MW"][10] == 3
    assert struct.unpack("<f", struct.pack("<I", img["MD"][4]))[0] == 1.5   # IEEE-754 bits
    assert sim.plc.read("%MD4") == 1.5


def test_input_event_seen_by_first_scan_at_or_after_its_time():
    sim = load(LOCATED, tick_ms=10)
    sim.schedule([InputEvent(25 * MS, "%IX0.0", 1)])
    sim.step(3)                                     # scans at 0, 10, 20 ms
    assert sim.plc.image.areas["QX"][1] == 0
    sim.step(1)                                     # scan at 30 ms sees it
    assert sim.plc.image.areas["QX"][1] == 1
    # the trace stamps the change with the time of the scan that made it
    assert [(t, int(v)) for t, v in sim.trace.changes("%QX0.1")] == [(0, 0), (30 * MS, 1)]


def test_inputs_are_copied_in_at_the_start_of_each_tick():
    # the program works on a copy of the input image taken when the tick starts: an image
    # change between scans shows in the variable only at the next scan
    src = """
PROGRAM main
VAR x AT %IX0.0 : BOOL; END_VAR
VAR seen : INT; END_VAR
IF x THEN seen := seen + 1; END_IF;
END_PROGRAM
"""
    sim = load(src)
    plc = sim.plc
    plc.image.areas["IX"][0] = 1
    sim.step(1)
    plc.image.areas["IX"][0] = 0
    assert plc.read("main.x") is True and plc.read("main.seen") == 1
    sim.step(1)
    assert plc.read("main.x") is False and plc.read("main.seen") == 1


# --------------------------------------------------------------------------- faults

FAULTY = """
PROGRAM main
VAR
  out AT %QX0.0 : BOOL;
  aout AT %QW0 : INT;
END_VAR
VAR
  d : INT := 5;
  z : INT;
  r : INT;
  i : INT;
  a : ARRAY[1..4] OF INT;
  mode : INT;
END_VAR
out := TRUE;
aout := 1234;
IF mode = 1 THEN
  r := d / z;
ELSIF mode = 2 THEN
  i := i + 5;
  a[i] := 1;
ELSIF mode = 3 THEN
  WHILE TRUE DO
    r := r + 1;
  END_WHILE;
END_IF;
END_PROGRAM
"""


def _fault_run(mode: int, **kw):
    sim = load(FAULTY, name="faulty.st", tick_ms=10, **kw)
    sim.step(2)
    assert sim.plc.state == "RUN"
    assert sim.plc.image.areas["QX"][0] == 1 and sim.plc.image.areas["QW"][0] == 1234
    sim.set("main.mode", mode)
    sim.step(1)
    return sim


def _assert_faulted(sim, kind: str, line: int):
    plc = sim.plc
    assert plc.state == "FAULT"
    assert plc.fault.kind == kind
    assert plc.fault.pou.upper() == "MAIN"
    assert plc.fault.file == "faulty.st"
    assert plc.fault.line == line
    assert plc.fault.time_ns == 20 * MS
    # outputs in the image go to their safe state
    assert plc.image.areas["QX"][0] == 0
    assert plc.image.areas["QW"][0] == 0
    # and the PLC stays stopped: further ticks do not run the program
    sim.step(3)
    assert plc.state == "FAULT" and plc.image.areas["QX"][0] == 0


def test_integer_division_by_zero_faults():
    sim = _fault_run(1)
    _assert_faulted(sim, "division_by_zero", 18)


def test_array_index_out_of_range_faults():
    sim = _fault_run(2)
    _assert_faulted(sim, "index_out_of_range", 21)
    assert "5" in sim.plc.fault.message


def test_endless_while_loop_trips_the_watchdog():
    sim = _fault_run(3, watchdog_s=0.2)
    _assert_faulted(sim, "watchdog", 23)       # the WHILE line


def test_restart_after_fault_reinitialises():
    sim = _fault_run(1)
    assert sim.plc.state == "FAULT"
    sim.plc.restart()
    assert sim.plc.state == "RUN"
    assert sim.plc.read("main.mode") == 0          # variables back to their initial values
    sim.step(1)
    assert sim.plc.state == "RUN" and sim.plc.image.areas["QX"][0] == 1


def test_fault_inside_function_names_the_function():
    src = """
FUNCTION Ratio : INT
VAR_INPUT a : INT; b : INT; END_VAR
Ratio := a / b;
END_FUNCTION
PROGRAM main
VAR r : INT; z : INT; END_VAR
r := Ratio(10, z);
END_PROGRAM
"""
    sim = load(src, name="fn.st")
    sim.step(1)
    f = sim.plc.fault
    assert sim.plc.state == "FAULT"
    assert (f.kind, f.pou.upper(), f.file, f.line) == ("division_by_zero", "RATIO", "fn.st", 4)


def test_for_loop_up_to_the_type_maximum_never_ends():
    # `k := k + 1` is stored back into the USINT, so after 255 comes 0 and `k <= 255` holds
    # forever (the C matiec generates loops forever too): the watchdog stops it
    src = """
PROGRAM main
VAR k : USINT; n : DINT; END_VAR
FOR k := 250 TO 255 DO
  n := n + 1;
END_FOR;
END_PROGRAM
"""
    sim = load(src, name="loop.st", watchdog_s=0.1)
    sim.step(1)
    f = sim.plc.fault
    assert sim.plc.state == "FAULT"
    assert (f.kind, f.file, f.line) == ("watchdog", "loop.st", 4)
    assert sim.plc.read("main.n") > 256          # it went round more than once
