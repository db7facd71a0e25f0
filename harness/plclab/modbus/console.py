"""The console face: a stand's operator console on Modbus TCP, the same in every real-time mode.

Why: inside OpenPLC the PSM layer overwrites every %IX from the plant each scan, and OpenPLC's
own Modbus server cannot write %IX, so a switch or SB1 can only be operated through the plant.
This face serves a PlantHost (plclab.plants.host) with the stand's FACE table
(plclab.plants.<stand>.FACE, documented in docs/openplc.md):

  coils             0..  the console switches, in FACE.switches order (read and write):
                         what the operator did, 1 = on / pressed; for a normally closed
                         button (the CNC stand's emergency stop SB3) the PLC then reads 0
  discrete inputs   0..  the lamps (PLC outputs) in FACE.lamps order, then PLANT_FAULT
  input registers   0..  the plant readouts in FACE.readouts order (raw 16-bit)
  holding registers none (exception 01), but for a stand with a tape reader (FACE.tape: the
                         CNC stand): 0 the frame count, 1 the method, 2.. the frames'
                         values (FACE.tape registers); writing register 0 puts the tape
                         written so far on the reader (`plclab console cnc --part`)

It is served by the PSM script inside OpenPLC, by `plclab plant --psm` and by `plclab serve`
(default 127.0.0.1:2606). `ConsoleClient` is the project's client (`plclab console`); any
Modbus client works too. Standard library only (it runs inside OpenPLC's Python).
"""
from __future__ import annotations

import time
import importlib
from typing import Any, Callable, Iterable

from plclab.errors import PlcLabError

from .maps import RegisterMap
from .protocol import (MAX_WRITE_REGISTERS, READ_COILS, READ_DISCRETE_INPUTS, READ_HOLDING_REGISTERS,
                       READ_INPUT_REGISTERS, WRITE_MULTIPLE_COILS, WRITE_MULTIPLE_REGISTERS, WRITE_SINGLE_COIL,
                       WRITE_SINGLE_REGISTER, ExceptionCode, ModbusException, Table)
from .rawclient import RawModbusClient, RawModbusError
from .server import DEFAULT_HOST, ModbusTcpServer, ServerError

CONSOLE_PORT = 2606
FAULT_LAMP = "PLANT_FAULT"
DEFAULT_PRESS_S = 0.3          # long enough for any scan, short of TUR-10's 3 s reset hold


class ConsoleMap(RegisterMap):
    """The console face of one PlantHost; what the operator set is remembered per coil."""

    functions = frozenset({READ_COILS, READ_DISCRETE_INPUTS, READ_INPUT_REGISTERS,
                           WRITE_SINGLE_COIL, WRITE_MULTIPLE_COILS})
    tape_functions = frozenset({READ_HOLDING_REGISTERS, WRITE_SINGLE_REGISTER, WRITE_MULTIPLE_REGISTERS})

    def __init__(self, host: Any):
        self.host = host
        self.switches = tuple(host.face.switches)
        self.coils = [0] * len(self.switches)
        self.tape = [0] * getattr(host.face, "tape", 0)     # the tape being written (holding registers)
        if self.tape:
            self.functions = self.functions | self.tape_functions

    def read(self, table: Table, start: int, count: int) -> list[int]:
        if table is Table.COILS:
            values = list(self.coils)
        elif table is Table.DISCRETE_INPUTS:
            values = self.host.lamps()
        elif table is Table.INPUT_REGISTERS:
            values = self.host.readouts()
        elif table is Table.HOLDING_REGISTERS and self.tape:
            values = self.tape
        else:
            raise ModbusException(ExceptionCode.ILLEGAL_FUNCTION, f"the console face has no {table.value}")
        _check(table, start, count, len(values))
        return values[start:start + count]

    def write(self, table: Table, start: int, values: tuple[int, ...]) -> None:
        if table is Table.HOLDING_REGISTERS and self.tape:
            self._write_tape(start, values)
            return
        if table is not Table.COILS:
            raise ModbusException(ExceptionCode.ILLEGAL_FUNCTION, f"writing {table.value}")
        _check(table, start, len(values), len(self.switches))
        for i, value in enumerate(values, start):
            self.coils[i] = 1 if value else 0
            name = self.switches[i]        # the contact: a pressed normally closed button opens
            self.host.set_switch(name, self.coils[i] ^ (name in self.host.normally_closed))

    def _write_tape(self, start: int, values: tuple[int, ...]) -> None:
        """Tape registers; writing register 0 (the frame count) loads the tape onto the
        reader, refused whole (exception 03) if the plant refuses it."""
        _check(Table.HOLDING_REGISTERS, start, len(values), len(self.tape))
        tape = list(self.tape)
        tape[start:start + len(values)] = [v & 0xFFFF for v in values]
        if start == 0:
            count, method, n = tape[0], tape[1], self.host.face.tape_fields
            most = (len(tape) - 2) // n
            if not 1 <= count <= most:
                raise ModbusException(ExceptionCode.ILLEGAL_DATA_VALUE,
                                      f"tape: frame count {count} outside 1..{most}")
            words = [v - 0x10000 if v & 0x8000 else v for v in tape[2:2 + n * count]]
            try:
                self.host.load_tape(method, [tuple(words[k:k + n]) for k in range(0, len(words), n)])
            except ValueError as exc:
                raise ModbusException(ExceptionCode.ILLEGAL_DATA_VALUE, f"tape: {exc}") from None
        self.tape = tape


def _check(table: Table, start: int, count: int, size: int) -> None:
    if start + count > size:
        raise ModbusException(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                              f"console face {table.value} {start}..{start + count - 1} outside 0..{size - 1}")


CONSOLE_MAX_REQUESTS_PER_S = 1000
"""Admission control of the console face (a panel operated by hand, polled by a page or a
`plclab console`): a flood of requests waits instead of taking the interpreter from the scan
of `plclab serve`, which runs in the same process (docs/reliability.md, "The scan first")."""


def start_console_face(host: Any, address: tuple[str, int],
                       warn: Callable[[str], None]) -> ModbusTcpServer | None:
    """Serve the console face of `host` at (HOST, PORT), or warn once and return None: the
    PLC's I/O matters more than the console, so a busy port does not stop the plant."""
    try:
        return ModbusTcpServer(ConsoleMap(host), address[0], address[1], max_clients=16,   # idle ones closed after 60 s
                               name="console", max_requests_per_s=CONSOLE_MAX_REQUESTS_PER_S).start()
    except ServerError as exc:
        warn(f"warning: no console face: {exc}")
        return None


def console_lines(face: Any, coils: list[int], lamps: list[int], readouts: list[int]) -> list[str]:
    """What `plclab console` prints: one line per table, NAME=value in address order."""
    lamp_names = [label for label, _loc in face.lamps] + [FAULT_LAMP]
    return ["switches: " + " ".join(f"{n}={v}" for n, v in zip(face.switches, coils)),
            "lamps:    " + " ".join(f"{n}={v}" for n, v in zip(lamp_names, lamps)),
            "readouts: " + " ".join(f"{n}={v}" for (n, _unit), v in zip(face.readouts, readouts))]


class ConsoleError(PlcLabError):
    """A console name or value the stand does not have: one line for the user."""


class ConsoleClient:
    """The project's client of a console face: switches by name, presses, the whole state."""

    def __init__(self, face: Any, host: str = DEFAULT_HOST, port: int = CONSOLE_PORT,
                 timeout: float = 2.0, sleep: Callable[[float], None] = time.sleep):
        self.face = face
        try:
            self.client = RawModbusClient(host, port, timeout=timeout)
        except OSError as exc:
            raise ConsoleError(f"cannot reach the console face at {host}:{port}: "
                               f"{exc.strerror or exc}") from None
        self.sleep = sleep

    def __enter__(self) -> "ConsoleClient":
        self.client.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        self.client.__exit__(*exc)

    def coil(self, name: str) -> int:
        """The coil address of a console switch (case-insensitive)."""
        names = [n.upper() for n in self.face.switches]
        key = name.strip().upper()
        if key not in names:
            raise ConsoleError(f"no console switch {name!r}; this stand has {', '.join(self.face.switches)}")
        return names.index(key)

    def set(self, name: str, value: int) -> None:
        self.client.write_coil(self.coil(name), bool(value))

    def press(self, name: str, seconds: float = DEFAULT_PRESS_S) -> None:
        """Switch on, hold `seconds`, switch off (a push button, or a held jog switch)."""
        address = self.coil(name)
        self.client.write_coil(address, True)
        self.sleep(seconds)
        self.client.write_coil(address, False)

    def load_tape(self, method: int, frames: list[tuple[int, ...]]) -> None:
        """Write a part program's frames to the face's tape registers, then the count, which
        puts it on the reader (the PLC stores the frames while idle)."""
        words = [v & 0xFFFF for frame in frames for v in frame]
        self.client.write_register(1, method)
        for k in range(0, len(words), MAX_WRITE_REGISTERS):
            self.client.write_registers(2 + k, words[k:k + MAX_WRITE_REGISTERS])
        self.client.write_register(0, len(frames))

    def state(self) -> tuple[list[int], list[int], list[int]]:
        """(coils, lamps, readouts) as the face serves them now."""
        face = self.face
        coils = self.client.read_coils(0, len(face.switches))
        lamps = self.client.read_discrete_inputs(0, len(face.lamps) + 1)
        readouts = self.client.read_input_registers(0, len(face.readouts)) if face.readouts else []
        return coils, lamps, readouts


def parse_value(text: str, what: str) -> int:
    """0/1/on/off for a switch."""
    key = text.strip().lower()
    if key in ("1", "on", "true"):
        return 1
    if key in ("0", "off", "false"):
        return 0
    raise ConsoleError(f"{what}: {text!r} is not a switch value (0/1, on/off)")


def _press(text: str) -> tuple[str, float]:
    name, sep, seconds = text.partition("=")
    if not sep:
        return name, DEFAULT_PRESS_S
    try:
        value = float(seconds)
    except ValueError:
        value = -1.0
    if not 0 < value <= 60:
        raise ConsoleError(f"--press {text}: the hold time must be 0..60 seconds")
    return name, value


def run_console(stand: str, where: tuple[str, int], sets: Iterable[str] = (),
                presses: Iterable[str] = (), tape: tuple[int, list[tuple[int, ...]]] | None = None,
                tape_wait: float = 10.0) -> list[str]:
    """`plclab console`: put a part program on the tape reader (`tape`: method, frames) and
    wait up to `tape_wait` s for the PLC to store it, set switches (NAME=V), then press
    buttons (NAME[=SECONDS]) one after the other, then read the face; the lines to print.
    Bad names fail before anything is sent."""
    face = importlib.import_module(f"plclab.plants.{stand}").FACE
    if tape is not None and not face.tape:
        raise ConsoleError(f"the {stand} stand has no tape reader (--part is for the cnc stand)")
    with ConsoleClient(face, where[0], where[1]) as client:
        writes = []
        for text in sets:
            name, sep, value = text.partition("=")
            if not sep:
                raise ConsoleError(f"--set {text}: expected NAME=VALUE, e.g. SA5=1")
            writes.append((client.coil(name), parse_value(value, f"--set {text}")))
        holds = [(client.coil(name), name, seconds) for name, seconds in map(_press, presses)]
        lines = []
        try:
            if tape is not None:
                lines.append(_send_tape(client, face, *tape, tape_wait))
            for address, value in writes:
                client.client.write_coil(address, bool(value))
            for _address, name, seconds in holds:
                client.press(name, seconds)
            return lines + console_lines(face, *client.state())
        except (OSError, RawModbusError) as exc:
            raise ConsoleError(f"console face at {where[0]}:{where[1]}: {exc}") from None


def _send_tape(client: ConsoleClient, face: Any, method: int, frames: list[tuple[int, ...]], wait: float) -> str:
    """Load the tape and wait up to `wait` s for the PLC to store and acknowledge every frame
    (the `tape` readout); the line to print, or ConsoleError (one line: how many frames were
    stored and why not the rest). Refused, nothing sent, while a part program runs or is held
    (HL1 lit): the PLC stores a tape only while no program runs."""
    lamps = [label for label, _loc in face.lamps]
    running = "HL1" in lamps and (lambda: client.client.read_discrete_inputs(lamps.index("HL1"), 1)[0] == 1)
    if running and running():
        raise ConsoleError("tape: not loaded: a part program is running or held (HL1 lit), and the PLC stores "
                           "a tape only while no program runs; load it when the part has ended (or after SB3)")
    try:
        client.load_tape(method, frames)
    except RawModbusError as exc:
        raise ConsoleError(f"the stand refused the part program: {exc}") from None
    where = [name for name, _unit in face.readouts].index("tape")
    n = len(frames)
    deadline = time.monotonic() + wait
    while True:               # the readout counts this tape from its load on (0 at first)
        stored = client.client.read_input_registers(where, 1)[0]
        if stored == n or time.monotonic() >= deadline:
            break
        client.sleep(0.05)
    if stored == n:
        return f"tape: {n} frames stored and acknowledged by the PLC; SB1 runs them"
    if running and running():
        why = f"the PLC stored {stored} of {n} frames: a part program started before it had stored them all (HL1 lit)"
    elif stored == 0:
        why = (f"the PLC stored 0 of {n} frames in {wait:g} s: it acknowledged none (TAPE_ACK, %QW4; the cnc "
               f"program must run in OpenPLC, idle, with this PSM script)")
    else:
        why = f"the PLC stored {stored} of {n} frames in {wait:g} s: it stopped acknowledging (TAPE_ACK, %QW4)"
    raise ConsoleError(f"tape: {why}; SB1 runs nothing until every frame is stored (the tape stays on the reader)")
