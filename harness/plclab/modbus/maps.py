"""Register maps: what a Modbus address means in the process image.

A map never touches the PLC's variables and never blocks the scan: reads are consistent
snapshots of the image, writes are validated whole and then queued with `queue_write`, which
the scan thread applies at the start of its next tick. A refused request raises
ModbusException before anything is queued, so a refused write changes nothing.
"""
from __future__ import annotations

import abc
from collections.abc import Iterator
from typing import Protocol

from plclab.runtime.image import AREAS, WORD_AREA_SIZE

from .profiles import Access, TwidoProfile
from .protocol import ALL_FUNCTIONS, ExceptionCode, ModbusException, Table


class ImageLike(Protocol):
    """The part of ProcessImage a Modbus face uses (safe from any thread)."""

    def snapshot(self, area: str, start: int, count: int) -> list[int]: ...

    def queue_write(self, area: str, start: int, values: list[int]) -> None: ...


def _address_error(table: Table, start: int, count: int, why: str) -> ModbusException:
    return ModbusException(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                           f"{table.value} {start}..{start + count - 1}: {why}")


def _unsupported(table: Table, what: str) -> ModbusException:
    return ModbusException(ExceptionCode.ILLEGAL_FUNCTION, f"{what} {table.value} not supported")


class RegisterMap(abc.ABC):
    """Address semantics of one Modbus face. Subclasses raise ModbusException to refuse."""

    functions: frozenset[int] = ALL_FUNCTIONS

    @abc.abstractmethod
    def read(self, table: Table, start: int, count: int) -> list[int]:
        """Values of `count` items from `start` (bits as 0/1, registers as 0..65535)."""

    @abc.abstractmethod
    def write(self, table: Table, start: int, values: tuple[int, ...]) -> None:
        """Validate the whole write, then queue it; raise before queuing anything."""


# --------------------------------------------------------------------------- OpenPLC

_BITS = AREAS["QX"][0]                         # 800: %QX0.0 .. %QX99.7
_WORDS = WORD_AREA_SIZE                         # 1024
# Holding-register segments: (first register, area, registers per element).
_HOLDING = (
    (0, "QW", 1),
    (_WORDS, "MW", 1),
    (2 * _WORDS, "MD", 2),
    (4 * _WORDS, "ML", 4),
)
_HOLDING_END = 8 * _WORDS                       # 8192, as OpenPLC's MAX_HOLD_REGS


def _split(value: int, words: int) -> list[int]:
    """An element as registers, most significant word first (OpenPLC's modbus.cpp order)."""
    return [(value >> (16 * (words - 1 - i))) & 0xFFFF for i in range(words)]


def _join(regs: list[int]) -> int:
    value = 0
    for reg in regs:
        value = (value << 16) | reg
    return value


class OpenPlcMap(RegisterMap):
    """OpenPLC v3's slave map (webserver/core/modbus.cpp), sized to this project's image.

    coils = %QX, discrete inputs = %IX (address = 8*byte + bit), input registers = %IW,
    holding 0..1023 = %QW, 1024..2047 = %MW, 2048..4095 = %MD (2 registers each, high word
    first), 4096..8191 = %ML (4 each, most significant first). Every address inside an area
    is backed by the image, so one no variable is located at reads what was last written
    there (0 at start) and accepts writes, as OpenPLC's mapUnusedIO buffers do. Outside every
    area: exception 02.

    A write to part of a %MD/%ML merges into the element's current value (read from a
    snapshot); two clients writing different halves of one element within the same tick can
    lose one half. A request spanning two areas (e.g. holding 1020..1030) is read and queued
    per area, so it is consistent within each area, not across them.
    """

    def __init__(self, image: ImageLike):
        self.image = image

    def read(self, table: Table, start: int, count: int) -> list[int]:
        if table is Table.HOLDING_REGISTERS:
            self._check(table, start, count, _HOLDING_END)
            out: list[int] = []
            for seg_start, area, words, lo, hi in self._segments(start, count):
                first, last = (lo - seg_start) // words, (hi - 1 - seg_start) // words
                regs: list[int] = []
                for value in self.image.snapshot(area, first, last - first + 1):
                    regs.extend(_split(value, words))
                offset = lo - (seg_start + first * words)
                out.extend(regs[offset:offset + hi - lo])
            return out
        area, size = {Table.COILS: ("QX", _BITS), Table.DISCRETE_INPUTS: ("IX", _BITS),
                      Table.INPUT_REGISTERS: ("IW", _WORDS)}[table]
        self._check(table, start, count, size)
        return self.image.snapshot(area, start, count)

    def write(self, table: Table, start: int, values: tuple[int, ...]) -> None:
        count = len(values)
        if table is Table.COILS:
            self._check(table, start, count, _BITS)
            self.image.queue_write("QX", start, [1 if v else 0 for v in values])
            return
        if table is not Table.HOLDING_REGISTERS:
            raise _unsupported(table, "writing")
        self._check(table, start, count, _HOLDING_END)
        for seg_start, area, words, lo, hi in self._segments(start, count):
            chunk = list(values[lo - start:hi - start])
            if words == 1:
                self.image.queue_write(area, lo - seg_start, chunk)
                continue
            first, last = (lo - seg_start) // words, (hi - 1 - seg_start) // words
            regs: list[int] = []
            for value in self.image.snapshot(area, first, last - first + 1):
                regs.extend(_split(value, words))
            offset = lo - (seg_start + first * words)
            regs[offset:offset + len(chunk)] = chunk
            elements = [_join(regs[i:i + words]) for i in range(0, len(regs), words)]
            self.image.queue_write(area, first, elements)

    @staticmethod
    def _check(table: Table, start: int, count: int, size: int) -> None:
        if start + count > size:
            raise _address_error(table, start, count, f"outside 0..{size - 1}")

    @staticmethod
    def _segments(start: int, count: int) -> Iterator[tuple[int, str, int, int, int]]:
        """(segment start, area, words per element, lo, hi) for each area the span touches."""
        end = start + count
        bounds = [s for s, _a, _w in _HOLDING[1:]] + [_HOLDING_END]
        for (seg_start, area, words), seg_end in zip(_HOLDING, bounds):
            lo, hi = max(start, seg_start), min(end, seg_end)
            if lo < hi:
                yield seg_start, area, words, lo, hi


# --------------------------------------------------------------------------- Twido

class TwidoMap(RegisterMap):
    """Twido-style map: holding register n = %MWn, only the profile's registers exist.

    Unknown address -> 02; read-only register, value outside its valid values, or a rule such
    as "writable only in manual mode" not met -> 03. A multi-register write is checked whole
    (addresses first, then values) and queued in one piece, or not at all.
    """

    def __init__(self, image: ImageLike, profile: TwidoProfile):
        for reg in profile.registers:
            if not 0 <= reg.address < WORD_AREA_SIZE:
                raise ValueError(f"profile {profile.name}: %MW{reg.address} outside %MW0..%MW{WORD_AREA_SIZE - 1}")
        self.image = image
        self.profile = profile
        self.functions = profile.functions

    def read(self, table: Table, start: int, count: int) -> list[int]:
        if table is not Table.HOLDING_REGISTERS:
            raise _unsupported(table, "reading")
        self._check_addresses(start, count)
        return self.image.snapshot("MW", start, count)

    def write(self, table: Table, start: int, values: tuple[int, ...]) -> None:
        if table is not Table.HOLDING_REGISTERS:
            raise _unsupported(table, "writing")
        self._check_addresses(start, len(values))
        after = self._view_after(start, values)
        for offset, raw in enumerate(values):
            reg = self.profile.register(start + offset)
            assert reg is not None
            name = f"%MW{reg.address}"
            if reg.access is Access.RO:
                raise ModbusException(ExceptionCode.ILLEGAL_DATA_VALUE, f"{name} is read only")
            value = reg.as_value(raw)
            if reg.valid is not None and value not in reg.valid:
                raise ModbusException(ExceptionCode.ILLEGAL_DATA_VALUE,
                                      f"{name} = {value} outside {reg.valid}")
            rule = reg.writable_when
            if rule is not None:
                cond = self.profile.register(rule.address)
                current = after.get(rule.address, 0)
                if cond is not None:
                    current = cond.as_value(current)
                if current != rule.value:
                    raise ModbusException(ExceptionCode.ILLEGAL_DATA_VALUE,
                                          f"{name} is writable only when {rule}")
        self.image.queue_write("MW", start, list(values))

    def _check_addresses(self, start: int, count: int) -> None:
        for address in range(start, start + count):
            if self.profile.register(address) is None:
                raise _address_error(Table.HOLDING_REGISTERS, start, count,
                                     f"%MW{address} is not a register of {self.profile.name}")

    def _view_after(self, start: int, values: tuple[int, ...]) -> dict[int, int]:
        """Condition registers as they would read once this write is applied."""
        view: dict[int, int] = {}
        for reg in self.profile.registers:
            rule = reg.writable_when
            if rule is None or rule.address in view:
                continue
            if start <= rule.address < start + len(values):
                view[rule.address] = values[rule.address - start]
            else:
                view[rule.address] = self.image.snapshot("MW", rule.address, 1)[0]
        return view
