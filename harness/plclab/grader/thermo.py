"""The thermo stand's SCADA exercises graded (textbook section 5.3; docs/grading.md).

Task 1 (`scada1`): the student's SCADA client reads and displays the heat-sink temperature
%MW3. Task 2 (`scada2`): it displays and sets the heater power %MW2 (0..2000). The student's
work is the client's configuration (ClearSCADA, FUXA, mbpoll, the project's HMI...), so the
grader judges what the client did on the wire, from a Modbus traffic log (modbus.traffic):

1. `record_session` serves the stand in real time (its shipped program, the Twido face)
   and records every request the client sends, with the PLC's time;
2. the grading engine (`grade`, as for the robots) reads the log as the task's submission
   (`TRAFFIC_LOG`) and runs its one scenario, `replay`: each logged request is answered by
   the same Twido map at the same plant time on a fresh stand in virtual time, so the verdict
   is reproducible from the log alone (an instructor grades it again later, `grade-class`
   grades a folder of logs, tests are deterministic), and the plant's answer (does the
   heater follow?) is in the replay's trace;
3. each requirement is judged over the replayed exchanges and the trace, and a failing row
   names the mistake (the register actually read, the value refused, the mode it was
   written in) with expected and observed values.

Requirements are declared once below (`Requirement`s registered per task like the robots'),
each sentence built from the module constants its judge uses.
"""
from __future__ import annotations

import dataclasses
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

from plclab import fileio
from plclab.errors import PlcLabError
from plclab.modbus.maps import TwidoMap
from plclab.modbus.profiles import MANUAL, THERMO_MODES, THERMO_RULES, valid_range
from plclab.modbus.protocol import ModbusException, Request, Table
from plclab.modbus.server import answer_pdu
from plclab.modbus.traffic import Exchange, Traffic, TrafficRecorder, describe, exception_name, parse_traffic
from plclab.scenario import Session
from plclab.stands import twido_profile

from .engine import grade, grade_sources
from .registry import Checks, Failure, Requirement, RequirementSet, Scenario, Submission, register
from .report import GradeReport

STAND = "thermo"
SCENARIO = "replay"                 # the one "scenario": the recorded traffic replayed
TEMPERATURE, HEATER, MODE = 3, 2, 0          # %MWn of the register contract
HEATER_RANGE = valid_range(THERMO_RULES, "HEATER_CTRL")     # what the stand accepts in %MW2
READ_PERIOD_S = 10.0                # a display that shows the value reads it at least this often
NAMED_REFUSALS = 3                  # refused requests named one by one in a row; the rest counted


@dataclass(frozen=True)
class Replayed:
    """One exchange of the log as the replayed stand answered it."""

    exchange: Exchange
    request: Optional[Request]      # decoded (None: malformed)
    refusal: Optional[ModbusException]
    mode: int                       # %MW0 when the request arrived
    response: bytes = b""           # the replayed stand's answer (PDU)

    @property
    def time(self) -> float:
        return self.exchange.time_s

    def what(self) -> str:
        return describe(self.exchange.request)

    def refused_text(self) -> str:
        """`write %MW2 = 2500 at t = 12.00 s: exception 03 (illegal data value: %MW2 = 2500 outside 0..2000)`"""
        e = self.refusal
        reason = f": {e.reason}" if e is not None and e.reason else ""
        code = int(e.code) if e is not None else 0
        return (f"{self.what()} at t = {self.time:.2f} s: exception {code:02d} "
                f"({exception_name(code)}{reason})")

    def reads(self, register: int) -> bool:
        r = self.request.read if self.request is not None else None
        return r is not None and r.table is Table.HOLDING_REGISTERS and r.start <= register < r.start + r.count

    def written(self, register: int) -> Optional[int]:
        """The value this request writes to holding register `register` (signed), or None."""
        w = self.request.write if self.request is not None else None
        if w is None or w.table is not Table.HOLDING_REGISTERS or not w.start <= register < w.start + len(w.values):
            return None
        raw = w.values[register - w.start]
        return raw - 0x10000 if raw >= 0x8000 else raw


@dataclass
class Replay:
    """The stand as the client drove it: what the grading engine runs a scenario on (it reads
    `now` and `trace`, like a Session's), with the exchanges the requirements judge."""

    traffic: Traffic
    session: Session
    exchanges: list[Replayed]

    @property
    def now(self) -> float:
        return self.session.now

    @property
    def trace(self):
        return self.session.trace

    @property
    def span(self) -> tuple[float, float]:
        """From the client's first request to its last (a client may connect late or leave early)."""
        return (self.exchanges[0].time, self.exchanges[-1].time) if self.exchanges else (0.0, 0.0)


def replay(traffic: Traffic) -> Replay:
    """Answer each logged request on a fresh stand at its time, after the scan of that time
    (as the live stand did), and run the plant to the end of the recording."""
    from plclab.stands.thermo import session

    s = session()
    rmap = TwidoMap(s.plc.image, twido_profile(STAND))
    tick_ns = s.plc.tick_ns
    out = []
    for e in traffic.exchanges:
        _run_through(s, round(e.time_s * 1e9), tick_ns)
        mode = rmap.read(Table.HOLDING_REGISTERS, MODE, 1)[0]     # as the client sees it (queued writes too)
        response, refusal = answer_pdu(rmap, e.request)
        out.append(Replayed(e, e.decoded(), refusal, mode, response))
    _run_through(s, round(traffic.duration_s * 1e9) + tick_ns, tick_ns)   # the last write takes effect
    return Replay(traffic, s, out)


def _run_through(s: Session, t_ns: int, tick_ns: int) -> None:
    """Scan until the scan at time `t_ns` has run."""
    if s.plc.now_ns <= t_ns:
        s.run(((t_ns - s.plc.now_ns) // tick_ns + 1) * tick_ns / 1e9)


# --------------------------------------------------------------------------- checks
Judge = Callable[[Replay], Optional[Failure]]      # None: the requirement is met


def _no_traffic(r: Replay) -> Optional[str]:
    if not r.exchanges:
        return (f"no Modbus request in the {r.traffic.duration_s:.1f} s recorded: the client never talked to the "
                f"stand (check its address, port and that it uses Modbus TCP)")
    return None


def _why_not_read(r: Replay, register: int, name: str) -> tuple[str, Optional[float]]:
    """The mistake behind 'never read `register`', as precisely as the traffic shows it."""
    nothing = _no_traffic(r)
    if nothing:
        return nothing, None
    refused = [x for x in r.exchanges if x.reads(register) and x.refusal is not None]
    if refused:
        return f"every read of {name} was refused: {refused[0].refused_text()}", refused[0].time
    inputs = [x for x in r.exchanges if x.request is not None and x.request.read is not None
              and x.request.read.table is Table.INPUT_REGISTERS]
    if inputs:
        return (f"the client reads input registers (function 04), e.g. {inputs[0].what()} at t = "
                f"{inputs[0].time:.2f} s: the Twido stand's %MW are holding registers (function 03)"), inputs[0].time
    reads = [x for x in r.exchanges if x.request is not None and x.request.read is not None and x.refusal is None]
    if not reads:
        return "the client never reads a register", None
    seen = sorted({a for x in reads for a in range(x.request.read.start, x.request.read.start + x.request.read.count)})
    hint = ""
    if register - 1 in seen or register + 1 in seen:
        hint = (f" (holding register {register} is offset {register} from start address 0: an offset or start "
                f"address off by one?)")
    return (f"reads of {_registers(seen)} only, never {name}{hint}"), reads[0].time


def _registers(addresses: list[int]) -> str:
    runs, start = [], None
    for i, a in enumerate(addresses):
        if start is None:
            start = a
        if i + 1 == len(addresses) or addresses[i + 1] != a + 1:
            runs.append(f"%MW{start}" if start == a else f"%MW{start}..%MW{a}")
            start = None
    return ", ".join(runs)


def reads_register(register: int, name: str) -> Judge:
    def check(r: Replay) -> Optional[Failure]:
        if any(x.reads(register) and x.refusal is None for x in r.exchanges):
            return None
        observed, t = _why_not_read(r, register, name)
        return Failure(f"a read of holding register {register} ({name}, function 03)", observed, t)
    return check


def reads_periodically(register: int, name: str, period_s: float = READ_PERIOD_S) -> Judge:
    def check(r: Replay) -> Optional[Failure]:
        tick = r.session.tick
        expected = f"a read of {name} at least every {period_s:g} s (+/- one scan, {tick:g} s)"
        times = [x.time for x in r.exchanges if x.reads(register) and x.refusal is None]
        if not times:
            observed, t = _why_not_read(r, register, name)
            return Failure(expected, observed, t)
        first, last = r.span
        if len(times) < 2:
            return Failure(expected, f"one read of {name} (t = {times[0]:.2f} s) in the {last - first:.1f} s "
                           f"the client talked to the stand: a display read once never updates", times[0])
        points = [first] + times + [last]
        gap, at = max((b - a, a) for a, b in zip(points, points[1:]))
        if gap > period_s + tick + 1e-9:
            what = "before the first read" if at == first and times[0] != first else \
                   "after the last read" if at == times[-1] and at != last else "between two reads"
            return Failure(expected, f"no read of {name} for {gap:.1f} s {what}, from t = {at:.2f} s "
                           f"to t = {at + gap:.2f} s ({len(times)} reads in {last - first:.1f} s)", at)
        return None
    return check


def every_request_accepted(r: Replay) -> Optional[Failure]:
    nothing = _no_traffic(r)
    if nothing:
        return Failure("requests the stand accepts", nothing, None)
    refused = [x for x in r.exchanges if x.refusal is not None]
    if not refused:
        return None
    named = "; ".join(x.refused_text() for x in refused[:NAMED_REFUSALS])
    more = f"; and {len(refused) - NAMED_REFUSALS} more" if len(refused) > NAMED_REFUSALS else ""
    return Failure("every request accepted (no Modbus exception)",
                   f"{len(refused)} of {len(r.exchanges)} requests refused: {named}{more}", refused[0].time)


def sets_heater(r: Replay) -> Optional[Failure]:
    """An accepted write of %MW2 and the plant's heater output at that value one scan later."""
    expected = "a write of %MW2 (holding register 2) that the stand accepts; the heater output %QW1 takes it"
    accepted = [x for x in r.exchanges if x.written(HEATER) is not None and x.refusal is None]
    if not accepted:
        observed, t = _why_not_written(r)
        return Failure(expected, observed, t)
    tick = r.session.tick
    trace = r.session.trace
    writes = [x for x in r.exchanges if x.refusal is None and
              (x.written(HEATER) is not None or x.written(MODE) is not None)]
    for x in accepted:
        later = [y.time for y in writes if y.time > x.time]
        if later and later[0] < x.time + tick + 1e-9:
            continue                    # overtaken within the scan: nothing to follow
        value = x.written(HEATER)
        heater = trace.value_at("HEATER", x.time + tick)
        if heater != value:
            return Failure(f"heater output %QW1 = {value} one scan ({tick:g} s) after %MW2 = {value}",
                           f"%QW1 = {heater} at t = {x.time + tick:.2f} s after %MW2 = {value} was accepted at "
                           f"t = {x.time:.2f} s", x.time + tick)
    return None


def _why_not_written(r: Replay) -> tuple[str, Optional[float]]:
    nothing = _no_traffic(r)
    if nothing:
        return nothing, None
    refused = [x for x in r.exchanges if x.written(HEATER) is not None]
    if refused:
        return f"every write of %MW2 was refused, the first: {refused[0].refused_text()}", refused[0].time
    writes = [x for x in r.exchanges if x.request is not None and x.request.write is not None]
    if not writes:
        return "the client wrote nothing (only reads): the heater power was never set", None
    targets = sorted({a for x in writes if x.request.write.table is Table.HOLDING_REGISTERS
                      for a in range(x.request.write.start, x.request.write.start + len(x.request.write.values))})
    if not targets:
        return (f"the client writes {writes[0].what()} (t = {writes[0].time:.2f} s), not holding register 2: "
                f"the Twido stand's %MW are holding registers (function 06 or 16)"), writes[0].time
    hint = " (holding register 2 is offset 2 from start address 0: an offset off by one?)" \
        if 1 in targets or 3 in targets else ""
    return f"writes to {_registers(targets)} only, never %MW2{hint}", writes[0].time


def _not_checked(r: Replay) -> Failure:
    """A rule about the writes of %MW2 when there is none: not passed for free."""
    why, t = _why_not_written(r)
    return Failure("writes of %MW2 to check", f"not checked: {why}", t)


def heater_in_range(r: Replay) -> Optional[Failure]:
    writes = [x for x in r.exchanges if x.written(HEATER) is not None]
    if not writes:
        return _not_checked(r)
    bad = [x for x in writes if x.written(HEATER) not in HEATER_RANGE]
    if not bad:
        return None
    x = bad[0]
    fate = f"refused with exception {int(x.refusal.code):02d}" if x.refusal is not None else "accepted"
    return Failure(f"%MW2 within {HEATER_RANGE} ({HEATER_RANGE.high} is full power, 40 W)",
                   f"%MW2 = {x.written(HEATER)} written at t = {x.time:.2f} s, {fate}; {len(bad)} of {len(writes)} "
                   f"writes of %MW2 out of range", x.time)


def heater_in_manual(r: Replay) -> Optional[Failure]:
    if not any(x.written(HEATER) is not None for x in r.exchanges):
        return _not_checked(r)
    bad = [x for x in r.exchanges if x.written(HEATER) in HEATER_RANGE and x.refusal is not None
           and (x.written(MODE) if x.written(MODE) is not None else x.mode) != MANUAL]
    if not bad:
        return None
    x = bad[0]
    return Failure("%MW0 = 0 (manual mode) set before %MW2 is written",
                   f"%MW2 = {x.written(HEATER)} written at t = {x.time:.2f} s while %MW0 = {x.mode} "
                   f"({THERMO_MODES.get(x.mode, 'unknown mode')}): refused with exception "
                   f"{int(x.refusal.code):02d}; {len(bad)} such write{'s' if len(bad) > 1 else ''}", x.time)


# --------------------------------------------------------------------------- the tasks
def _judged(judges: tuple[tuple[Requirement, Judge], ...]) -> Callable[[Replay, Checks], None]:
    """The replay scenario: each requirement judged over the replayed exchanges and trace."""
    def run(r: Replay, c: Checks) -> None:
        for req, judge in judges:
            with c.requirement(req) as rid:
                miss = judge(r)
                if miss is not None:
                    c.fail(rid, miss.expected, miss.observed, miss.time)
    return run


def read_log(sources: list[tuple[str, str]]) -> Traffic:
    """The submission of a SCADA task: one traffic log (the engine has read it as text)."""
    if len(sources) != 1:
        raise PlcLabError(f"grade: a SCADA task grades one traffic log, got {len(sources)}: "
                          + ", ".join(name for name, _ in sources))
    name, text = sources[0]
    return parse_traffic(text, name)


def _make_session(sources: list[tuple[str, str]], retain_path: Optional[Path], traffic: Traffic) -> Replay:
    """The stand as the student's client drove it: the log replayed (the engine's "session":
    it reads `now` and `trace`)."""
    return replay(traffic)


TRAFFIC_LOG = Submission("traffic log", ".csv", "the traffic log cannot be read:", read_log)
TRACE_NAMES = ["MODE", "HEATER_CTRL", "TEMPERATURE", "SETPOINT", "HEATER", "FAN", "TEMP_ADC"]

G1 = Requirement("G1", "Every request the client sends is accepted (no Modbus exception); refused ones are "
                 "counted and named.", SCENARIO)
S1_1 = Requirement("S1.1", f"The client reads the heat-sink temperature %MW3 (holding register {TEMPERATURE}, "
                   f"offset {TEMPERATURE} from start address 0).", SCENARIO)
S1_2 = Requirement("S1.2", f"It reads %MW3 periodically, at least every {READ_PERIOD_S:g} s, as long as it is "
                   "connected (the display follows the temperature).", SCENARIO)
S2_1 = Requirement("S2.1", f"The client displays the heater power: it reads %MW2 at least every "
                   f"{READ_PERIOD_S:g} s.", SCENARIO)
S2_2 = Requirement("S2.2", "It sets the heater power: the stand accepts a write of %MW2 and the plant's heater "
                   "follows (heater output %QW1 = the value, one scan later).", SCENARIO)
S2_3 = Requirement("S2.3", f"Every heater power it writes is within {HEATER_RANGE}.",
                   SCENARIO)
S2_4 = Requirement("S2.4", "It writes %MW2 in manual mode only (%MW0 = 0): in an automatic mode the regulator "
                   "owns the heater and the stand refuses the write.", SCENARIO)

JUDGES = {
    "scada1": ("Thermostabilization stand, SCADA Task 1: read and display the heat-sink temperature (%MW3).", (
        (S1_1, reads_register(TEMPERATURE, "%MW3")),
        (S1_2, reads_periodically(TEMPERATURE, "%MW3")),
        (G1, every_request_accepted),
    )),
    "scada2": ("Thermostabilization stand, SCADA Task 2: display and control the heater power (%MW2, 0..2000).", (
        (S2_1, reads_periodically(HEATER, "%MW2")),
        (S2_2, sets_heater),
        (S2_3, heater_in_range),
        (S2_4, heater_in_manual),
        (G1, every_request_accepted),
    )),
}
TASKS = {task: register(RequirementSet(
    stand=STAND, task=task, title=title, requirements=tuple(req for req, _ in judges),
    scenarios=(Scenario(SCENARIO, _judged(judges)),), make_session=_make_session,
    trace_names=lambda s: TRACE_NAMES, submission=TRAFFIC_LOG)) for task, (title, judges) in JUDGES.items()}


def scada_task(task: str) -> RequirementSet:
    """The task's requirement set; an unknown task is one line that says what the SCADA tasks are."""
    found = TASKS.get(task)
    if found is None:
        raise PlcLabError(f"grade: stand '{STAND}' has no task '{task}' (one of {', '.join(TASKS)}: the SCADA "
                          f"exercises, graded from the Modbus traffic of the student's client)")
    return found


def grade_traffic(task: str, traffic: Traffic, source: str = "<traffic>",
                  out_dir: Optional[str | Path] = None) -> GradeReport:
    """Grade a SCADA task from a traffic log in memory (as `grade` grades it from the file);
    the replay's trace goes to `out_dir`."""
    scada_task(task)
    return grade_sources(STAND, task, [(source, traffic.csv_text())], None if out_dir is None else str(out_dir))


# --------------------------------------------------------------------------- live
def record_session(host: str = "127.0.0.1", port: int = 5020, duration_s: Optional[float] = None,
                   on_listening: Optional[Callable[[str, int], None]] = None,
                   stop: Optional[Callable[[], bool]] = None) -> Traffic:
    """Serve the thermo stand (its shipped program, the Twido face) in real time and record
    every request until `duration_s` has passed, `stop()` says so, or Ctrl-C; returns the log.
    `on_listening(host, port)` is called once the face accepts clients."""
    import time

    from plclab import config
    from plclab.plants import make_plant
    from plclab.serve import ServeOptions, Service
    from plclab.stands import get_stand, sources

    conf = config.defaults()
    with tempfile.TemporaryDirectory(prefix="plclab-scada-") as tmp:
        stand_cfg = dataclasses.replace(conf.stand(STAND), retain_file=Path(tmp) / "thermo.retain")
        modbus = dataclasses.replace(conf.modbus, bind=host, port=port)
        opts = ServeOptions(sources(get_stand(STAND), "full"), stand_cfg, modbus, make_plant(STAND), "twido", twido_profile(STAND))
        service = Service(opts, report=lambda line: None)
        # stamped with the scan whose outputs the answer read (the replay answers after that scan)
        recorder = TrafficRecorder(lambda: (service.runner.scanned_ns or 0) / 1e9)
        service.server.on_request = recorder
        service.start()
        try:
            if on_listening is not None:
                on_listening(host, service.server.port)
            end = None if duration_s is None else time.monotonic() + duration_s
            while (end is None or time.monotonic() < end) and not (stop is not None and stop()):
                time.sleep(0.05)
        except KeyboardInterrupt:
            pass                                   # Ctrl-C ends the recording; grading follows
        finally:
            service.stop()
        return recorder.traffic(service.plc.now_ns / 1e9)


def traffic_log_path(task: str, out_dir: str | Path) -> Path:
    return Path(out_dir) / f"{STAND}-{task}-traffic.csv"


def grade_live(task: str, host: str, port: int, duration_s: Optional[float], out_dir: str | Path,
               on_listening: Optional[Callable[[str, int], None]] = None,
               stop: Optional[Callable[[], bool]] = None) -> tuple[GradeReport, Traffic, Path]:
    """`plclab grade thermo TASK --listen`: serve and record (see `record_session`), keep the
    traffic log in `out_dir` (to grade again later with `grade_log`), grade it."""
    scada_task(task)
    log = fileio.check_output(traffic_log_path(task, out_dir))     # refused before the session, not after
    traffic = record_session(host, port, duration_s, on_listening, stop)
    fileio.write_text(log, traffic.csv_text())
    return grade_log(task, log, out_dir), traffic, log          # the file as it will be graded again


def grade_log(task: str, path: str | Path, out_dir: Optional[str | Path] = None) -> GradeReport:
    """`plclab grade thermo TASK --traffic FILE`: grade a recorded traffic log."""
    scada_task(task)
    return grade(STAND, task, [str(path)], None if out_dir is None else str(out_dir))


__all__ = ["READ_PERIOD_S", "TASKS", "TRAFFIC_LOG", "Replay", "grade_live", "grade_log", "grade_traffic",
           "read_log", "record_session", "replay", "scada_task", "traffic_log_path"]
