"""The thermo stand's SCADA tasks graded from the client's Modbus traffic (issue 12 part 5).

Two halves. From hand-written traffic logs (deterministic): a right client passes, each
realistic mistake (never reads %MW3, an offset off by one, input registers instead of holding
registers, reads that stop, 2500 written, a write in automatic mode, the fan written instead of
the heater) fails on the row that names it, with expected and observed values. Live, with a real
Modbus TCP client on loopback (pymodbus, and the project's HMI): the stand is served, the
traffic recorded and graded, and the replay answers every request as the live stand did.
"""
from __future__ import annotations

import struct
import sys
import threading
import time
from pathlib import Path

import pytest
from pymodbus.client import ModbusTcpClient

from plclab.cli import main
from plclab.errors import PlcLabError
from plclab.grader.thermo import grade_live, grade_log, grade_traffic, replay
from plclab.hmi import run_hmi
from plclab.modbus.traffic import Exchange, Traffic, parse_traffic, read_traffic

# --------------------------------------------------------------------------- traffic by hand


def read(start: int, count: int, function: int = 3) -> bytes:
    return struct.pack(">BHH", function, start, count)


def write(register: int, value: int) -> bytes:
    return struct.pack(">BHH", 6, register, value & 0xFFFF)


def write_many(start: int, *values: int) -> bytes:
    return struct.pack(f">BHHB{len(values)}H", 16, start, len(values), 2 * len(values),
                       *(v & 0xFFFF for v in values))


def traffic(duration: float, polls: bytes | None = read(0, 7), every: float = 1.0,
            extra: tuple[tuple[float, bytes], ...] = (), poll_until: float | None = None) -> Traffic:
    """A client polling `polls` every `every` s from t = 0.5 (a SCADA scanner) until
    `poll_until`, plus the `extra` requests at their times."""
    ex = []
    if polls is not None:
        t = 0.5
        while t <= (duration if poll_until is None else poll_until):
            ex.append(Exchange(round(t, 3), 1, polls, b""))
            t += every
    ex += [Exchange(t, 1, pdu, b"") for t, pdu in extra]
    ex.sort(key=lambda e: e.time_s)
    return Traffic(ex, duration)


def rows(report) -> dict[str, object]:
    return {r.id: r for r in report.rows}


def assert_only_failing(report, *rids: str) -> None:
    assert [r.id for r in report.failed()] == list(rids), report.text()
    for r in report.failed():
        assert r.expected and r.observed, r


# --------------------------------------------------------------------------- Task 1, from logs
def test_task1_a_client_polling_the_registers_passes(tmp_path):
    report = grade_traffic("scada1", traffic(60.0), "poll.csv", tmp_path)
    assert report.passed, report.text()
    assert [r.id for r in report.rows] == ["S1.1", "S1.2", "G1"]
    assert report.traces["replay"] == [tmp_path / "thermo-scada1-replay.csv", tmp_path / "thermo-scada1-replay.vcd"]
    assert (tmp_path / "thermo-scada1-replay.csv").read_text(encoding="utf-8").startswith("time_s,name,value\n")


def test_task1_reading_from_register_4_is_named_an_offset_off_by_one():
    report = grade_traffic("scada1", traffic(60.0, polls=read(4, 3)))
    assert_only_failing(report, "S1.1", "S1.2")
    row = rows(report)["S1.1"]
    assert row.expected == "a read of holding register 3 (%MW3, function 03)"
    assert row.observed == ("reads of %MW4..%MW6 only, never %MW3 (holding register 3 is offset 3 from start "
                            "address 0: an offset or start address off by one?)")
    assert row.time == 0.5


def test_task1_reading_input_registers_is_named():
    report = grade_traffic("scada1", traffic(30.0, polls=read(0, 7, function=4)))
    assert_only_failing(report, "S1.1", "S1.2", "G1")
    assert rows(report)["S1.1"].observed == (
        "the client reads input registers (function 04), e.g. read input registers 0..6 at t = 0.50 s: the "
        "Twido stand's %MW are holding registers (function 03)")
    assert rows(report)["G1"].observed.startswith(
        "30 of 30 requests refused: read input registers 0..6 at t = 0.50 s: exception 01 (illegal function")


def test_task1_reading_past_the_register_table_is_refused_and_named():
    report = grade_traffic("scada1", traffic(20.0, polls=read(0, 10)))
    assert_only_failing(report, "S1.1", "S1.2", "G1")
    assert rows(report)["S1.1"].observed == (
        "every read of %MW3 was refused: read %MW0..%MW9 at t = 0.50 s: exception 02 (illegal data address: "
        "holding registers 0..9: %MW7 is not a register of thermo)")


def test_task1_reads_that_stop_are_not_periodic():
    report = grade_traffic("scada1", traffic(60.0, poll_until=20.0,
                                             extra=((45.0, read(6, 1)), (50.0, read(6, 1)))))
    assert_only_failing(report, "S1.2")
    row = rows(report)["S1.2"]
    assert row.expected == "a read of %MW3 at least every 10 s (+/- one scan, 0.1 s)"
    assert row.observed == ("no read of %MW3 for 30.5 s after the last read, from t = 19.50 s to t = 50.00 s "
                            "(20 reads in 49.5 s)")
    assert row.time == 19.5


def test_task1_a_single_read_is_not_a_display():
    report = grade_traffic("scada1", traffic(30.0, polls=None, extra=((2.0, read(3, 1)), (3.0, read(6, 1)))))
    assert_only_failing(report, "S1.2")
    assert rows(report)["S1.2"].observed == ("one read of %MW3 (t = 2.00 s) in the 1.0 s the client talked to the "
                                             "stand: a display read once never updates")


def test_no_traffic_fails_every_row_saying_the_client_never_connected():
    report = grade_traffic("scada2", Traffic([], 120.0))
    assert [r.passed for r in report.rows] == [False] * 5
    for r in report.rows:
        assert "no Modbus request in the 120.0 s recorded: the client never talked to the stand" in r.observed


# --------------------------------------------------------------------------- Task 2, from logs
RIGHT_TASK2 = ((5.0, write(0, 0)), (5.5, write(2, 1500)), (20.0, write(2, 800)))


def test_task2_a_right_client_passes_and_the_plants_heater_follows():
    t = traffic(40.0, extra=RIGHT_TASK2)
    report = grade_traffic("scada2", t)
    assert report.passed, report.text()
    r = replay(t)
    assert r.session.trace.value_at("HEATER", 5.5) == 0
    assert r.session.trace.value_at("HEATER", 5.6) == 1500          # one scan after the write
    assert r.session.trace.value_at("HEATER", 20.1) == 800
    assert r.session.trace.value_at("TEMP_ADC", 40.0) > r.session.trace.value_at("TEMP_ADC", 5.0)


def test_task2_writing_2500_fails_the_range_row_and_is_named_among_the_refused():
    t = traffic(40.0, extra=RIGHT_TASK2 + ((25.0, write(2, 2500)),))
    report = grade_traffic("scada2", t)
    assert_only_failing(report, "S2.3", "G1")
    row = rows(report)["S2.3"]
    assert row.expected == "%MW2 within 0..2000 (2000 is full power, 40 W)"
    assert row.observed == ("%MW2 = 2500 written at t = 25.00 s, refused with exception 03; 1 of 3 writes of %MW2 "
                            "out of range")
    assert row.time == 25.0
    assert rows(report)["G1"].observed == (
        "1 of 44 requests refused: write %MW2 = 2500 at t = 25.00 s: exception 03 (illegal data value: "
        "%MW2 = 2500 outside 0..2000)")
    assert replay(t).session.trace.value_at("HEATER", 30.0) == 800      # refused: nothing changed


def test_task2_a_negative_power_is_out_of_range_too():
    report = grade_traffic("scada2", traffic(40.0, extra=RIGHT_TASK2 + ((25.0, write(2, -100)),)))
    assert_only_failing(report, "S2.3", "G1")
    assert rows(report)["S2.3"].observed.startswith("%MW2 = -100 written at t = 25.00 s, refused")


def test_task2_writing_in_automatic_mode_fails_the_manual_mode_row():
    t = traffic(40.0, extra=((5.0, write(0, 1)), (6.0, write(2, 1500)), (10.0, write(0, 0)),
                             (11.0, write(2, 1500))))
    report = grade_traffic("scada2", t)
    assert_only_failing(report, "S2.4", "G1")
    row = rows(report)["S2.4"]
    assert row.expected == "%MW0 = 0 (manual mode) set before %MW2 is written"
    assert row.observed == ("%MW2 = 1500 written at t = 6.00 s while %MW0 = 1 (automatic-1): refused with "
                            "exception 03; 1 such write")
    assert "%MW2 is writable only when %MW0 = 0" in rows(report)["G1"].observed


def test_task2_manual_mode_and_power_in_one_request_is_right():
    report = grade_traffic("scada2", traffic(30.0, extra=((5.0, write(0, 2)), (8.0, write_many(0, 0, 0, 1200)))))
    assert report.passed, report.text()


def test_task2_only_automatic_mode_writes_mean_the_heater_was_never_set():
    report = grade_traffic("scada2", traffic(30.0, extra=((5.0, write(0, 1)), (6.0, write(2, 1500)))))
    assert_only_failing(report, "S2.2", "S2.4", "G1")
    assert rows(report)["S2.2"].observed == (
        "every write of %MW2 was refused, the first: write %MW2 = 1500 at t = 6.00 s: exception 03 (illegal data "
        "value: %MW2 is writable only when %MW0 = 0)")


def test_task2_writing_the_fan_instead_of_the_heater_is_named():
    report = grade_traffic("scada2", traffic(30.0, extra=((5.0, write(1, 1500)), (6.0, write(1, 900)))))
    assert_only_failing(report, "S2.2", "S2.3", "S2.4", "G1")
    assert rows(report)["S2.2"].observed == ("writes to %MW1 only, never %MW2 (holding register 2 is offset 2 from "
                                             "start address 0: an offset off by one?)")
    assert rows(report)["S2.3"].observed.startswith("not checked: writes to %MW1 only")


def test_task2_a_client_that_only_reads_never_set_the_heater():
    report = grade_traffic("scada2", traffic(30.0))
    assert_only_failing(report, "S2.2", "S2.3", "S2.4")
    assert rows(report)["S2.2"].observed == "the client wrote nothing (only reads): the heater power was never set"


def test_task2_reading_only_the_temperature_does_not_display_the_heater():
    report = grade_traffic("scada2", traffic(30.0, polls=read(3, 1), extra=((5.0, write(2, 1000)),)))
    assert_only_failing(report, "S2.1")
    assert rows(report)["S2.1"].observed == ("reads of %MW3 only, never %MW2 (holding register 2 is offset 2 from "
                                             "start address 0: an offset or start address off by one?)")


# --------------------------------------------------------------------------- the log file
def test_traffic_log_round_trips_and_grades_the_same(tmp_path):
    t = traffic(40.0, extra=RIGHT_TASK2 + ((25.0, write(2, 2500)),))
    path = tmp_path / "log.csv"
    path.write_text(t.csv_text(), encoding="utf-8")
    back = read_traffic(path)
    assert back.duration_s == 40.0 and back.exchanges == t.exchanges
    assert "25.000,1,06000209c4,,write %MW2 = 2500" in path.read_text(encoding="utf-8")
    assert [(r.id, r.passed, r.observed) for r in grade_log("scada2", path).rows] == \
           [(r.id, r.passed, r.observed) for r in grade_traffic("scada2", t).rows]


@pytest.mark.parametrize("text, message", [
    ("hello\n", "log.csv:1: error: not a plclab traffic log: the header must be time_s,unit,request,response,what"),
    ("time_s,unit,request,response\nabc,1,0300000001,\n", "log.csv:2: error: time_s 'abc' is not a number"),
    ("time_s,unit,request,response\n1.0,1,zz,\n", "log.csv:2: error: unit must be a whole number and "
                                                  "request/response hexadecimal PDUs"),
    ("time_s,unit,request,response\n1.0,1\n", "log.csv:2: error: expected time_s,unit,request,response[,what]"),
    ("# plclab modbus traffic; duration_s=1e8\ntime_s,unit,request,response\n", "log.csv:1: error: duration_s "
     "1e+08 is not a time in seconds within 0..86400 (a lab session of at most a day)"),
])
def test_a_bad_traffic_log_is_one_line(text, message):
    with pytest.raises(PlcLabError) as e:
        parse_traffic(text, "log.csv")
    assert str(e.value) == message


# --------------------------------------------------------------------------- the grading engine's path
def test_the_tasks_are_registered_requirements_graded_by_grade_like_the_robots(tmp_path):
    from plclab.grader import grade, requirement_table, tasks

    assert tasks("thermo", None) == ["scada1", "scada2"]
    assert tasks("thermo") == []                          # none grades an ST program (the lab page's list)
    assert [rid for rid, _ in requirement_table("thermo", "scada1")] == ["S1.1", "S1.2", "G1"]
    assert dict(requirement_table("thermo", "scada1"))["S1.2"].startswith("It reads %MW3 periodically, at least "
                                                                         "every 10 s")
    assert [rid for rid, _ in requirement_table("thermo", "scada2")] == ["S2.1", "S2.2", "S2.3", "S2.4", "G1"]
    right, wrong = tmp_path / "right.csv", tmp_path / "wrong.csv"
    right.write_text(traffic(40.0, extra=RIGHT_TASK2).csv_text(), encoding="utf-8")
    wrong.write_text(traffic(40.0, extra=RIGHT_TASK2 + ((25.0, write(2, 2500)),)).csv_text(), encoding="utf-8")
    passed = grade("thermo", "scada2", [str(right)], out_dir=str(tmp_path / "out"))
    assert passed.passed and passed.exit_code == 0, passed.text()
    assert passed.text().splitlines()[1] == f"traffic log: {right}"
    failed = grade("thermo", "scada2", [str(wrong)])
    assert failed.exit_code == 1
    row = failed.row("S2.3")
    assert (row.result, row.expected, row.time, row.scenario) == (
        "FAIL", "%MW2 within 0..2000 (2000 is full power, 40 W)", 25.0, "replay")


@pytest.mark.parametrize("data, message", [
    (b"\x00\x01binary\xff", "log.csv:1: error: not a text file (a plclab traffic log is UTF-8 CSV)"),
    (b"time_s,unit,request,response\n1.0,1\n", "log.csv:2: error: expected time_s,unit,request,response[,what]"),
])
def test_an_unreadable_log_is_a_failing_report_with_one_line(data, message, tmp_path, monkeypatch, capsys):
    from plclab.grader import grade

    monkeypatch.chdir(tmp_path)
    (tmp_path / "log.csv").write_bytes(data)
    report = grade("thermo", "scada1", ["log.csv"])
    assert report.errors == [message] and report.exit_code == 1
    assert report.text().splitlines()[2:] == ["the traffic log cannot be read:", message, "FAIL"]
    assert main(["grade", "thermo", "scada1", "--traffic", "log.csv", "--out", "o"]) == 1
    assert message in capsys.readouterr().out


def test_a_grader_bug_is_an_error_row_and_exit_code_2_never_the_students_fault(monkeypatch):
    from plclab.grader import thermo

    def broken(self, register):
        raise ZeroDivisionError("bug in a judge")
    monkeypatch.setattr(thermo.Replayed, "written", broken)
    report = grade_traffic("scada2", traffic(40.0, extra=RIGHT_TASK2))
    assert report.exit_code == 2
    assert rows(report)["S2.1"].result == "PASS"            # judged before the bug
    assert rows(report)["S2.2"].result == "ERROR"
    assert "the grader failed (ZeroDivisionError: bug in a judge)" in rows(report)["S2.2"].observed


def test_the_committed_class_of_logs_is_what_the_generator_makes():
    from make_scada_fixtures import main as make

    assert make(["--check"]) == 0


# --------------------------------------------------------------------------- live, real clients
class Live:
    """`grade_live` in a thread on an ephemeral loopback port; the test's client talks to it,
    then `finish()` ends the recording and returns (report, traffic)."""

    def __init__(self, task: str, out: Path):
        self.ready = threading.Event()
        self.done = threading.Event()
        self.result: tuple | None = None
        self.error: BaseException | None = None

        def listening(host: str, port: int) -> None:
            self.port = port
            self.ready.set()

        def run() -> None:
            try:
                self.result = grade_live(task, "127.0.0.1", 0, 60.0, out, on_listening=listening,
                                         stop=self.done.is_set)
            except BaseException as e:      # reported by finish()
                self.error = e
                self.ready.set()
        self.thread = threading.Thread(target=run, daemon=True)
        self.thread.start()
        assert self.ready.wait(30), "the stand did not start listening"
        assert self.error is None, self.error

    def client(self) -> ModbusTcpClient:
        c = ModbusTcpClient("127.0.0.1", port=self.port, timeout=5, retries=0)
        assert c.connect()
        return c

    def finish(self):
        self.done.set()
        self.thread.join(30)
        assert not self.thread.is_alive()
        if self.error is not None:
            raise self.error
        return self.result


def poll(c: ModbusTcpClient, times: int, start: int = 0, count: int = 7) -> None:
    for _ in range(times):
        assert not c.read_holding_registers(start, count=count, device_id=1).isError()
        time.sleep(0.1)


def assert_replay_answers_as_live(traffic: Traffic) -> None:
    """The grader's replay answers every recorded request exactly as the live stand did
    (the live plant steps in wall-clock time, the replay on the scan grid: the heater powers
    below are low, so %MW3 stays at 22 C in these short sessions and the answers match)."""
    r = replay(traffic)
    assert [x.response for x in r.exchanges] == [e.response for e in traffic.exchanges]


def test_live_task2_done_right_with_pymodbus_passes(tmp_path):
    live = Live("scada2", tmp_path)
    c = live.client()
    poll(c, 3)
    assert not c.write_register(2, 300, device_id=1).isError()
    poll(c, 3)
    c.close()
    report, traffic, log = live.finish()
    assert report.passed, report.text()
    assert log == tmp_path / "thermo-scada2-traffic.csv" and read_traffic(log).exchanges == traffic.exchanges
    assert len(traffic.exchanges) == 7
    assert_replay_answers_as_live(traffic)


def test_live_task2_writing_2500_fails_on_the_range_row(tmp_path):
    live = Live("scada2", tmp_path)
    c = live.client()
    poll(c, 2)
    assert c.write_register(2, 2500, device_id=1).isError()          # the stand refuses it (03)
    assert not c.write_register(2, 200, device_id=1).isError()
    poll(c, 2)
    c.close()
    report, traffic, _ = live.finish()
    assert_only_failing(report, "S2.3", "G1")
    assert rows(report)["S2.3"].observed.startswith("%MW2 = 2500 written at t = ")
    assert rows(report)["S2.3"].observed.endswith(", refused with exception 03; 1 of 2 writes of %MW2 out of range")
    assert_replay_answers_as_live(traffic)


def test_live_task2_writing_in_automatic_mode_fails_on_the_manual_mode_row(tmp_path):
    live = Live("scada2", tmp_path)
    c = live.client()
    poll(c, 2)
    assert not c.write_register(0, 1, device_id=1).isError()          # automatic-1
    assert c.write_register(2, 1500, device_id=1).isError()
    assert not c.write_register(0, 0, device_id=1).isError()
    assert not c.write_register(2, 200, device_id=1).isError()
    poll(c, 2)
    c.close()
    report, traffic, _ = live.finish()
    assert_only_failing(report, "S2.4", "G1")
    assert " while %MW0 = 1 (automatic-1): refused with exception 03; 1 such write" in rows(report)["S2.4"].observed
    assert_replay_answers_as_live(traffic)


def test_live_task1_never_reading_mw3_fails_on_the_read_row(tmp_path):
    live = Live("scada1", tmp_path)
    c = live.client()
    poll(c, 4, start=4, count=3)
    c.close()
    report, _, _ = live.finish()
    assert_only_failing(report, "S1.1", "S1.2")
    assert rows(report)["S1.1"].observed.startswith("reads of %MW4..%MW6 only, never %MW3")


def test_live_task2_with_the_project_hmi_passes(tmp_path):
    live = Live("scada2", tmp_path)

    def commands():
        yield "heater 300\n"
        time.sleep(0.6)                      # the HMI keeps polling every 0.1 s meanwhile
        yield "quit\n"
    lines: list[str] = []
    assert run_hmi("127.0.0.1", live.port, period=0.1, commands=commands(), out=lines.append) == 0
    report, traffic, _ = live.finish()
    assert "%MW2 (heater) := 300" in lines
    assert report.passed, report.text()
    assert_replay_answers_as_live(traffic)


# --------------------------------------------------------------------------- the command
def test_cli_grades_a_recorded_log(tmp_path, capsys):
    path = tmp_path / "log.csv"
    path.write_text(traffic(40.0, extra=RIGHT_TASK2 + ((25.0, write(2, 2500)),)).csv_text(), encoding="utf-8")
    assert main(["grade", "thermo", "scada2", "--traffic", str(path), "--out", str(tmp_path / "out")]) == 1
    out = capsys.readouterr().out
    assert "S2.3    Every heater power it writes is within 0..2000." in out
    assert "observed: %MW2 = 2500 written at t = 25.00 s, refused with exception 03" in out
    assert "3 of 5 requirements passed: FAIL" in out
    assert (tmp_path / "out" / "thermo-scada2-replay.vcd").exists()


@pytest.mark.parametrize("argv, message", [
    (["thermo", "task1", "a.st"], "grade: stand 'thermo' has no task 'task1' (one of scada1, scada2: the SCADA "
                                  "exercises, graded from the Modbus traffic of the student's client)"),
    (["thermo", "scada1", "a.st"], "grade: thermo scada1 grades the Modbus traffic of the student's SCADA client, "
                                   "not ST files: serve the stand with --listen HOST:PORT [--duration T], or grade "
                                   "a recording with --traffic FILE"),
    (["thermo", "scada1", "--traffic", "x.csv", "--duration", "5"],
     "grade: --traffic grades a recording, --listen/--duration make one: give one or the other"),
    (["mp9c", "task1", "--traffic", "x.csv"], "grade: --listen, --duration and --traffic are for the thermo SCADA "
                                              "tasks (plclab grade thermo scada1|scada2)"),
    (["thermo", "scada1", "--listen", "nowhere"], "--listen 'nowhere': expected HOST:PORT, e.g. 127.0.0.1:5020"),
])
def test_cli_misuse_is_one_line(argv, message, capsys):
    assert main(["grade"] + argv) == 1
    assert capsys.readouterr().err == f"plclab: error: {message}\n"


def test_cli_serves_records_and_grades(tmp_path):
    """`plclab grade thermo scada1 --listen 127.0.0.1:0 --duration 4` as a user runs it, with a
    client that polls the registers meanwhile."""
    import subprocess

    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "plclab.cli", "grade", "thermo", "scada1", "--listen",
                             "127.0.0.1:0", "--duration", "4", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        first = proc.stdout.readline()
        assert first.startswith("thermo stand on 127.0.0.1:"), first + proc.stderr.read()
        port = int(first.split()[3].rsplit(":", 1)[1])
        c = ModbusTcpClient("127.0.0.1", port=port, timeout=5, retries=0)
        assert c.connect()
        poll(c, 5)
        c.close()
        rest, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, rest + err
    assert rest.startswith(f"recorded 5 requests in ")
    assert "3 of 3 requirements passed: PASS" in rest
    assert len(read_traffic(out / "thermo-scada1-traffic.csv").exchanges) == 5


def test_a_failing_traffic_observer_costs_the_client_nothing():
    """The recording hook runs in the server's thread: its failure must not cost the answer."""
    from plclab.modbus.maps import TwidoMap
    from plclab.stands import twido_profile
    THERMO = twido_profile("thermo")
    from plclab.modbus.server import ModbusTcpServer
    from plclab.stands.thermo import session

    calls = []

    def observer(unit: int, request: bytes, response: bytes) -> None:
        calls.append((unit, request, response))
        raise RuntimeError("observer bug")
    with ModbusTcpServer(TwidoMap(session().plc.image, THERMO), port=0, on_request=observer) as server:
        c = ModbusTcpClient("127.0.0.1", port=server.port, timeout=5, retries=0)
        assert c.connect()
        assert c.read_holding_registers(6, count=1, device_id=1).registers == [40]
        c.close()
    assert calls == [(1, read(6, 1), bytes.fromhex("0302") + struct.pack(">H", 40))]


def test_cli_a_port_in_use_is_one_line_and_nothing_is_recorded(tmp_path, capsys):
    import socket

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        assert main(["grade", "thermo", "scada1", "--listen", f"127.0.0.1:{port}", "--duration", "1",
                     "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"plclab: error: modbus: cannot listen on 127.0.0.1:{port}: ") and err.count("\n") == 1
    assert not (tmp_path / "thermo-scada1-traffic.csv").exists()
