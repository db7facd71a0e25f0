"""What an S7-200 address is called in OpenPLC, for the error a student gets on writing one.

The stands' original programs are S7-200 ladder, so `I0.1`, `Q0.3`, `AIW0` and `VW100` come
naturally. In ST they are no addresses (`I0` is read as a name, `.1` as nothing), and the bare
syntax or "undeclared" error would not say why. The conversions are those of the I/O maps
(docs/mp9c.md, docs/tur10.md): `I0.1` -> `%IX0.1`, `Q0.0` -> `%QX0.0`, `AIW2` -> `%IW1`,
`AQW8` -> `%QW4`; OpenPLC has no byte view of the bit areas and no bit addresses in memory.
"""
from __future__ import annotations

import re
from typing import Optional

_BIT = re.compile(r"(I|Q|M|V|SM)(\d+)", re.I)
_WORD = re.compile(r"(AIW|AQW|IB|QB|MB|VB|SMB|VW|VD)(\d+)", re.I)


def bit_address_hint(word: str, bit: str) -> Optional[str]:
    """`I0` followed by `.1`: what to write instead, or None when `word` is no S7 bit area."""
    m = _BIT.fullmatch(word)
    if m is None:
        return None
    area, byte = m.group(1).upper(), int(m.group(2))
    s7 = f"{area}{byte}.{bit}"
    if area in ("I", "Q"):
        return (f"{s7} is an S7-200 address: in OpenPLC it is %{area}X{byte}.{bit} "
                f"(or the name the I/O map gives it)")
    return (f"{s7} is an S7-200 memory bit: OpenPLC's memory has no bit addresses; "
            f"declare a BOOL variable instead")


def word_address_hint(word: str) -> Optional[str]:
    """`AIW0`, `VW100`...: what to write instead, or None when `word` is no S7 word address."""
    m = _WORD.fullmatch(word)
    if m is None:
        return None
    area, n = m.group(1).upper(), int(m.group(2))
    if area == "AIW":
        return f"{word} is an S7-200 address: in OpenPLC it is %IW{n // 2} (or the name the I/O map gives it)"
    if area == "AQW":
        return f"{word} is an S7-200 address: in OpenPLC it is %QW{n // 2} (or the name the I/O map gives it)"
    if area in ("IB", "QB"):
        return (f"{word} is an S7-200 byte address: OpenPLC has no byte view of %{area[0]}X{n}.0..7; "
                f"pack or unpack the bits in ST")
    return (f"{word} is an S7-200 memory address: in OpenPLC declare a variable instead "
            f"(located memory is %MW, %MD or %ML)")
