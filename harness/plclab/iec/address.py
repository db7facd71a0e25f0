"""IEC 61131-3 located addresses (`%IX0.1`, `%QW100`, `%MW3`): the project's one parser.

The runtime (variables and scripted inputs at addresses), the I/O layer (the process image,
the PSM faces of plants, which name their points without the `%`: "IX0.1") and the trace
readers (a CSV column named like an address has the address's type) all read addresses
here. Standard library only: the PSM script embeds this module to run a plant inside
OpenPLC. A malformed address is an `AddressError`, one line that names it.

    prefix  I (input), Q (output), M (memory)
    size    X bit (the default when left out: `%I0.1` is `%IX0.1`), B byte, W word,
            D double word, L long word
    number  `byte.bit` for a bit, one element number for the others
"""
from __future__ import annotations

import functools
import re
from dataclasses import dataclass

from plclab.errors import PlcLabError

SIZE_BITS = {"X": 1, "B": 8, "W": 16, "D": 32, "L": 64}

_ADDRESS = re.compile(r"(%)?([IQM])([XBWDL])?(\d+)(?:\.(\d+))?", re.IGNORECASE)


class AddressError(PlcLabError, ValueError):
    """A malformed located address (or one outside the place it is used in)."""


@dataclass(frozen=True)
class Address:
    """One located address: `%IX1.6` is prefix 'I', size 'X', number 1, bit 6."""

    prefix: str
    size: str
    number: int                  # the byte of a bit address, else the element number
    bit: int | None = None

    @property
    def area(self) -> str:
        """'IX', 'QW', 'MD': OpenPLC's name of the area (plclab.runtime.image.AREAS)."""
        return self.prefix + self.size

    @property
    def index(self) -> int:
        """The element within its area: `8 * byte + bit` for a bit (also its PSM and Modbus
        address), the number for the others."""
        return self.number * 8 + self.bit if self.bit is not None else self.number

    @property
    def bits(self) -> int:
        return SIZE_BITS[self.size]

    def __str__(self) -> str:
        return f"%{self.area}{self.number}" + (f".{self.bit}" if self.bit is not None else "")


@functools.lru_cache(maxsize=4096)      # an Address is immutable; every PLC binds its I/O by them
def parse_address(text: str, *, percent: bool = True) -> Address:
    """`'%IX1.6'` -> Address('I', 'X', 1, 6). `percent=False` also takes the plants' spelling
    without the `%` ('QW3'). A bit address needs `byte.bit` with bit 0..7, the others take no
    bit part; anything else raises AddressError."""
    m = _ADDRESS.fullmatch(text.strip())
    if not m or (percent and not m.group(1)):
        raise AddressError(f"malformed address '{text}' (e.g. %IX0.0, %QW1)")
    prefix, size = m.group(2).upper(), (m.group(3) or "X").upper()
    number, bit = int(m.group(4)), m.group(5)
    if size == "X":
        if bit is None or int(bit) > 7:
            raise AddressError(f"{text}: a bit address is %{prefix}Xbyte.bit with bit 0..7")
        return Address(prefix, size, number, int(bit))
    if bit is not None:
        raise AddressError(f"{text}: a {size} address has no bit part (%{prefix}{size}n)")
    return Address(prefix, size, number)


def is_address(text: str) -> bool:
    """Whether `text` is a well-formed located address (with its `%`)."""
    try:
        parse_address(text)
    except AddressError:
        return False
    return True
