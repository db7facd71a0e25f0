"""`plclab hmi thermo`: the reference HMI of the thermostabilization stand's SCADA exercises.

It does what the textbook's ClearSCADA project does, as a terminal program: a Modbus TCP
channel to the stand (one run by `plclab serve thermo`, or a real Twido), a scanner reading
the holding registers from start address 0, and points at offset = register - start address.
Task 1 shows the heat-sink temperature (%MW3); Task 2 shows and sets the heater power (%MW2,
0..2000). It is only a Modbus client (pymodbus), so it works against anything that honours
the register contract (plclab.stands.twido_profile("thermo")). A refused write shows the exception
the stand answered with and the rule of the contract that explains it.

Output is one line per change of the registers, so it reads the same in a terminal, a log
or a test; commands come one per line on standard input (`help` lists them).
"""
from __future__ import annotations

import logging
import queue
import threading
import time
from dataclasses import dataclass
from typing import Callable, Optional, TextIO

from plclab.errors import PlcLabError
from plclab.modbus.profiles import THERMO_RULES, Access, Register, TwidoProfile
from plclab.stands import twido_profile

MODE_NAMES = {0: "manual", 1: "auto-1", 2: "auto-2"}
MODE_WORDS = {"manual": 0, "auto1": 1, "auto-1": 1, "automatic-1": 1, "auto2": 2, "auto-2": 2,
              "automatic-2": 2}
EXCEPTION_NAMES = {1: "illegal function", 2: "illegal data address", 3: "illegal data value",
                   4: "server device failure"}
UNITS = {"temperature": " C", "setpoint": " C", "fan_speed": "/s"}

_VALID = {rule.name: rule.valid for rule in THERMO_RULES}       # the contract's ranges, not a copy
_HELP_ROWS = (
    ("heater N", f"heater power {_VALID['heater']} (manual mode)", "fan N", f"fan {_VALID['fan']} (manual mode)"),
    ("setpoint N", f"temperature setpoint {_VALID['setpoint']} C", "mode M",
     f"manual | auto1 | auto2 (or {_VALID['mode']})"),
    ("%MWn N", "write any register", "show", "every register with its meaning"),
    ("help", "this text", "quit", "stop (also end of input, Ctrl-C)"),
)
HELP = "\n".join(["commands (one per line):"] + [f"  {a:<16}{b:<41}{c:<11}{d}" for a, b, c, d in _HELP_ROWS])


class HmiError(PlcLabError):
    """The HMI cannot do what was asked (no connection, a command it does not know)."""


class Refused(PlcLabError):
    """The stand answered a write with a Modbus exception."""

    def __init__(self, code: int, message: str):
        super().__init__(message)
        self.code = code


class ModbusChannel:
    """One Modbus TCP channel to one device: holding registers read and written as SCADA does."""

    def __init__(self, host: str, port: int, device_id: int = 1, timeout: float = 3.0):
        from pymodbus.client import ModbusTcpClient

        # the HMI says what went wrong in its own words, once; pymodbus's log would repeat it
        logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
        self.where = f"{host}:{port}"
        self.device_id = device_id
        self.client = ModbusTcpClient(host, port=port, timeout=timeout, retries=0)

    def connect(self) -> "ModbusChannel":
        if not self.client.connect():
            raise HmiError(f"cannot reach the stand at {self.where} (is `plclab serve thermo` running?)")
        return self

    def read(self, start: int, count: int) -> list[int]:
        from pymodbus.exceptions import ModbusException

        try:
            result = self.client.read_holding_registers(start, count=count, device_id=self.device_id)
        except ModbusException:
            raise HmiError(f"no answer from the stand at {self.where}") from None
        if result.isError():
            raise Refused(result.exception_code, f"reading %MW{start}..%MW{start + count - 1}: "
                                                 f"{_exception(result.exception_code)}")
        return list(result.registers)

    def write(self, address: int, raw: int) -> None:
        from pymodbus.exceptions import ModbusException

        try:
            result = self.client.write_register(address, raw, device_id=self.device_id)
        except ModbusException:
            raise HmiError(f"no answer from the stand at {self.where}") from None
        if result.isError():
            raise Refused(result.exception_code, _exception(result.exception_code))

    def close(self) -> None:
        self.client.close()


def _exception(code: int) -> str:
    return f"exception {code:02d} ({EXCEPTION_NAMES.get(code, 'unknown')})"


@dataclass
class Point:
    """A register shown on the HMI: offset = address - the scanner's start address."""

    register: Register
    offset: int


class ThermoHmi:
    """The HMI's logic, apart from the terminal: scan, show, and write with explanations."""

    def __init__(self, channel: ModbusChannel, profile: Optional[TwidoProfile] = None, start: int = 0):
        self.channel = channel
        self.profile = profile = profile or twido_profile("thermo")
        self.start = start
        self.length = max(r.address for r in profile.registers) + 1 - start
        self.points = {r.name: Point(r, r.address - start) for r in profile.registers}
        self.values: dict[str, int] = {}

    # ------------------------------------------------------------------ scanning
    def scan(self) -> dict[str, int]:
        """One poll of the scanner: every register of the profile, as the program sees it."""
        raw = self.channel.read(self.start, self.length)
        self.values = {name: p.register.as_value(raw[p.offset]) for name, p in self.points.items()}
        return self.values

    def status_line(self, values: dict[str, int]) -> str:
        """The operator's display: one line with every point."""
        parts = []
        for name, p in self.points.items():
            if p.register.name == "reserved":
                continue
            v = values[name]
            shown = MODE_NAMES.get(v, str(v)) if name == "mode" else f"{v}{UNITS.get(name, '')}"
            parts.append(f"{name}={shown}")
        return " ".join(parts)

    def table(self, values: dict[str, int]) -> str:
        rows = []
        for name, p in self.points.items():
            r = p.register
            rule = f"{r.access.value}" + (f", {r.valid}" if r.valid is not None else "") + \
                (f", writable while {r.writable_when}" if r.writable_when is not None else "")
            rows.append(f"  %MW{r.address:<2} {name:<12} {values[name]:>6}   {r.description} [{rule}]")
        return "\n".join(rows)

    # ------------------------------------------------------------------ control
    def write(self, target: str, value_text: str) -> str:
        """Write one register by point name (`heater`) or address (`%MW2`); returns what to
        show. A refusal raises Refused with the stand's exception and the contract's reason."""
        reg = self._register(target)
        value = self._value(reg, value_text)
        try:
            self.channel.write(reg.address, value & 0xFFFF)
        except Refused as e:
            raise Refused(e.code, f"%MW{reg.address} ({reg.name}) := {value} refused: {e}"
                                  f"{self._why(reg, value)}") from None
        return f"%MW{reg.address} ({reg.name}) := {value}"

    def _register(self, target: str) -> Register:
        t = target.strip().lower()
        if t.startswith("%mw") and t[3:].isdigit():
            reg = self.profile.register(int(t[3:]))
            if reg is None:         # not in the contract: still sent, the stand decides
                return Register(int(t[3:]), f"%MW{t[3:]}")
            return reg
        if t in self.points:
            return self.points[t].register
        raise HmiError(f"unknown point '{target}'; one of {', '.join(self.points)} or %MWn")

    @staticmethod
    def _value(reg: Register, text: str) -> int:
        t = text.strip().lower()
        if reg.name == "mode" and t in MODE_WORDS:
            return MODE_WORDS[t]
        try:
            value = int(t, 0)
        except ValueError:
            raise HmiError(f"'{text}' is not a whole number") from None
        if not -0x8000 <= value <= 0xFFFF:
            raise HmiError(f"{value} does not fit in a 16-bit register")
        return value

    def _why(self, reg: Register, value: int) -> str:
        """The contract's reason for a refusal, from the values of the last scan."""
        if reg.access is Access.RO:
            return ": the register is read only"
        if reg.valid is not None and value not in reg.valid:
            return f": valid values are {reg.valid}"
        rule = reg.writable_when
        if rule is not None and self.values.get(self._name_at(rule.address)) != rule.value:
            return f": writable only while {rule} (manual mode)"
        return ""

    def _name_at(self, address: int) -> str:
        reg = self.profile.register(address)
        return reg.name if reg is not None else ""

    def execute(self, line: str) -> Optional[str]:
        """One command line; returns the text to show. `quit` raises StopIteration."""
        words = line.split()
        if not words:
            return None
        cmd = words[0].lower()
        if cmd in ("quit", "exit", "q"):
            raise StopIteration
        if cmd == "help":
            return HELP
        if cmd == "show":
            return self.table(self.scan())
        if len(words) == 2:
            return self.write(words[0], words[1])
        raise HmiError(f"cannot read '{line.strip()}' (try: heater 1500, mode manual, help)")


def run_hmi(host: str, port: int, *, period: float = 1.0, once: bool = False, sets: tuple[str, ...] = (),
            commands: Optional[TextIO] = None, out: Callable[[str], None] = print,
            clock: Callable[[], float] = time.monotonic) -> int:
    """Connect and run the `sets` commands (`heater=1500`); then, with `once`, show one status
    line and stop, else show a status line whenever the registers change (polled every
    `period` s) while running the commands read from `commands`, until `quit`, the end of
    the input or Ctrl-C. Exit status 1 if a command failed, else 0."""
    channel = ModbusChannel(host, port).connect()
    hmi = ThermoHmi(channel)
    failed = False

    def do(line: str) -> bool:
        """Run one command; False when it asks to stop."""
        nonlocal failed
        try:
            text = hmi.execute(line)
        except StopIteration:
            return False
        except (Refused, HmiError) as e:
            failed = True
            text = f"! {e}"
        if text:
            out(text)
        return True

    try:
        out(f"thermo HMI: Modbus TCP {host}:{port}, holding registers %MW{hmi.start}..%MW{hmi.start + hmi.length - 1}"
            f" (start address {hmi.start}); type 'help' for commands")
        hmi.scan()
        for assignment in sets:
            name, _, value = assignment.partition("=")
            do(f"{name} {value}")
        if once:
            out(hmi.status_line(hmi.scan()))
            return 1 if failed else 0
        lines: queue.Queue[Optional[str]] = queue.Queue()
        if commands is not None:
            threading.Thread(target=_read_lines, args=(commands, lines), daemon=True).start()
        shown: Optional[dict[str, int]] = None
        lost = False
        started = clock()
        while True:
            if hmi.values != shown:
                out(f"t={clock() - started:6.1f}s  {hmi.status_line(hmi.values)}")
                shown = dict(hmi.values)
            try:
                line = lines.get(timeout=period)
            except queue.Empty:
                line = ""
            if line is None or (line and not do(line)):
                break
            lost = _rescan(hmi, lost, out)
    except KeyboardInterrupt:
        pass
    finally:
        channel.close()
    return 1 if failed else 0


def _rescan(hmi: ThermoHmi, lost: bool, out: Callable[[str], None]) -> bool:
    """Poll again; a lost channel is said once and retried at every period, as SCADA does.
    Returns whether the channel is (still) lost."""
    try:
        hmi.scan()
    except HmiError as e:
        if not lost:
            out(f"! {e}; retrying")
        return True
    if lost:
        out("communication restored")
    return False


def _read_lines(stream: TextIO, lines: "queue.Queue[Optional[str]]") -> None:
    for line in stream:
        lines.put(line.strip())
    lines.put(None)              # end of input
