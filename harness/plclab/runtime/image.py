"""The process image: OpenPLC's I/O and memory areas, shared by the PLC, plants and Modbus faces.

Bit areas are indexed by `8 * byte + bit` (the PSM and Modbus address of `%IX3.2` is 26).
The runtime reads inputs from and writes outputs to this image once per tick; plant models
and Modbus faces never touch the PLC's variables, only the image. Writes coming from other
threads (Modbus clients) are queued and applied by the scan thread at the start of the next
tick, so a scan never sees a half-applied multi-register write.
"""
from __future__ import annotations

import functools
import threading
from dataclasses import dataclass, field

from plclab.iec.address import AddressError, parse_address

BIT_AREA_BYTES = 100     # %IX0.0 .. %IX99.7, %QX0.0 .. %QX99.7
WORD_AREA_SIZE = 1024    # %IW, %QW, %MW, %MD, %ML 0..1023

# area name -> (element count, bit width); bits are stored as 0/1 ints in `bits` areas.
AREAS: dict[str, tuple[int, int]] = {
    "IX": (BIT_AREA_BYTES * 8, 1),
    "QX": (BIT_AREA_BYTES * 8, 1),
    "IW": (WORD_AREA_SIZE, 16),
    "QW": (WORD_AREA_SIZE, 16),
    "MW": (WORD_AREA_SIZE, 16),
    "MD": (WORD_AREA_SIZE, 32),
    "ML": (WORD_AREA_SIZE, 64),
}


@functools.lru_cache(maxsize=4096)
def image_slot(address: str, *, percent: bool = True) -> tuple[str, int]:
    """Where a located address lives in the image: `'%IX1.6'` -> ('IX', 14), `'%QW3'` ->
    ('QW', 3). `percent=False` also takes the plants' spelling ('QW3'). An address outside
    OpenPLC's areas is one AddressError line. Cached: the PSM face and `Session.value` ask
    for the same few addresses on every poll and every scan."""
    a = parse_address(address, percent=percent)
    if a.area not in AREAS:
        raise AddressError(f"{address}: not an OpenPLC area (%IX %QX %IW %QW %MW %MD %ML)")
    if a.index >= AREAS[a.area][0]:
        if a.bit is not None:
            raise AddressError(f"{address}: a bit address is %{a.area}byte.bit with byte "
                               f"0..{BIT_AREA_BYTES - 1}, bit 0..7")
        raise AddressError(f"{address}: a word address is %{a.area}0..{WORD_AREA_SIZE - 1}")
    return a.area, a.index


@dataclass
class ProcessImage:
    """All located storage of one PLC. Values are unsigned raw integers of the area's width."""

    areas: dict[str, list[int]] = field(default_factory=lambda: {
        name: [0] * count for name, (count, _w) in AREAS.items()})
    _pending: list[tuple[str, int, list[int]]] = field(default_factory=list)
    _lock: threading.Lock = field(default_factory=threading.Lock)

    # -- used by the scan thread and in-process plants -------------------------------------
    def get(self, area: str, index: int) -> int:
        return self.areas[area][index]

    def set(self, area: str, index: int, value: int) -> None:
        self.areas[area][index] = value

    def get_bit(self, area: str, byte: int, bit: int) -> bool:
        return bool(self.areas[area][byte * 8 + bit])

    def set_bit(self, area: str, byte: int, bit: int, value: bool) -> None:
        self.areas[area][byte * 8 + bit] = 1 if value else 0

    # -- used by other threads (Modbus faces) ----------------------------------------------
    def snapshot(self, area: str, start: int, count: int) -> list[int]:
        """A consistent copy of `count` elements of `area` from `start` (taken under the lock)."""
        with self._lock:
            values = self.areas[area][start:start + count]
            # writes queued for the next scan are already what a client sees (a Twido or
            # OpenPLC applies a write at once; here the scan takes it at its next tick)
            for p_area, p_start, p_values in self._pending:
                if p_area != area:
                    continue
                lo, hi = max(start, p_start), min(start + count, p_start + len(p_values))
                for i in range(lo, hi):
                    values[i - start] = p_values[i - p_start]
            return values

    def queue_write(self, area: str, start: int, values: list[int]) -> None:
        """Queue a write; the scan thread applies it whole at the start of its next tick."""
        with self._lock:
            self._pending.append((area, start, list(values)))

    def apply_pending(self) -> int:
        """Apply queued writes in arrival order; returns how many were applied."""
        if not self._pending:      # the common case, without the lock: a write queued just now
            return 0               # is applied at the next tick
        with self._lock:
            pending, self._pending = self._pending, []
            for area, start, values in pending:
                self.areas[area][start:start + len(values)] = values
        return len(pending)

    def publish(self, fn) -> None:
        """Run `fn(areas)` under the lock, so snapshots never see a half-published tick."""
        with self._lock:
            fn(self.areas)
