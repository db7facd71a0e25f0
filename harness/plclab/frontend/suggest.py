"""The name a student probably meant, for "unknown type" and "undeclared identifier" errors.

A typo (`Coutn` for `Count`, `BOOOL`) or a type name from another language (`INTEGER`,
`FLOAT`, `TIMER`) is the usual cause of those errors; naming the likely intent saves the
search through the declarations.
"""
from __future__ import annotations

import difflib
import re
from typing import Iterable

# type names of C, Pascal, Python or other PLCs, and what IEC 61131-3 calls them
FOREIGN_TYPES = {
    "INTEGER": "INT (16-bit) or DINT (32-bit)", "LONG": "DINT", "SHORT": "INT", "BOOLEAN": "BOOL",
    "BIT": "BOOL", "FLOAT": "REAL", "DOUBLE": "LREAL", "CHAR": "STRING", "TIMER": "TON, TOF or TP",
    "COUNTER": "CTU, CTD or CTUD",
}
_IDENT = re.compile(r"[A-Za-z_]\w*")


def foreign_type(name: str) -> str:
    """` (in IEC 61131-3: REAL)` for a type name of another language, else ''."""
    iec = FOREIGN_TYPES.get(name.upper())
    return f" (in IEC 61131-3: {iec})" if iec else ""


def did_you_mean(name: str, candidates: Iterable[str]) -> str:
    """` (did you mean 'Count'?)` when one of `candidates` is close to `name`, else ''.
    Case is ignored (ST ignores it); a candidate is shown as it was declared."""
    spelled: dict[str, str] = {}
    for c in candidates:
        if _IDENT.fullmatch(c) and c.upper() != name.upper():
            spelled.setdefault(c.upper(), c)
    close = difflib.get_close_matches(name.upper(), list(spelled), n=1, cutoff=0.75)
    return f" (did you mean '{spelled[close[0]]}'?)" if close else ""
