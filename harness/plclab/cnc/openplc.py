"""The CNC stand's program for a real OpenPLC v3 (`plclab build cnc VARIANT [--part PART.nc]`,
docs/openplc.md).

Why a bundle of its own:
- Fine cycle. OpenPLC exchanges its I/O with the PSM script by Modbus TCP once per scan
  (about 0.9 ms measured in OpenPLC, spikes of a few ms on a loaded machine); with the
  stand's 1 ms task it falls behind, then runs scans back to back to catch up (its main loop
  sleeps to absolute tick times). The bundle for OpenPLC runs PRG_CncStand every
  OPENPLC_FINE_MS and tells the program so (its FINE_MS constant: feeds and the interpolation
  cycle T = NFINE fine cycles stay right); the PSM script's pulse generator spreads a
  cycle's counts over that T (plant_params).
- Part program. Inside OpenPLC nothing but the program reaches the frame table of GVL_CNC
  (the PSM layer moves located I/O only, the table is not located), so a part program is
  given to OpenPLC in the program itself: its frames become the table's initial values.
  OpenPLC sets them at every start of the PLC, so the part survives OpenPLC's Stop/Start.
"""
from __future__ import annotations

import re
from typing import Optional

from plclab.nc.gcode import Frame
from plclab.errors import PlcLabError

OPENPLC_FINE_MS = 5            # ms: the fine cycle in OpenPLC (over 5 times the PSM exchange)
NFINE = 4                      # fine cycles per interpolation cycle T (PRG_CncStand's NFINE)
STEP_MM = 0.01                 # the drives' step: GVL_CNC.StepMm's initial value, the plant's default
PER_LINE = 12                  # initial values per line of the bundle


def plant_params(fine_ms: int = OPENPLC_FINE_MS) -> dict[str, float]:
    """The PSM script's plant for the bundle of fine cycle `fine_ms`: its pulse generator
    spreads a cycle's counts over the program's interpolation cycle T."""
    from plclab.stands.cnc import fine_cycle_params
    return {"pulse_cycle": fine_cycle_params(fine_ms)["pulse_cycle"]}


def openplc_bundle(text: str, frames: Optional[list[Frame]] = None, method: str = "evalfn",
                   diagonal: bool = False, part: str = "", fine_ms: int = OPENPLC_FINE_MS,
                   drive: str = "step") -> str:
    """The bundle `text` (plclab.stands.bundle of the cnc stand) made for OpenPLC: the fine
    cycle `fine_ms` in the task and FINE_MS (plclab.stands.cnc.with_fine_cycle, the edit
    `plclab cnc --fine-cycle` runs), and with `frames` the part program `part` as the frame
    table's initial values; `drive` "pulse": GVL_CNC.PulseDrive starts TRUE (the pulse-count
    drive, DDA and digital integration up to PULSE_FEED_MAX). Raises PlcLabError if the
    program is not the shape this relies on."""
    from plclab.stands.cnc import FRAME_ARRAYS, MAX_FRAMES, frame_table, with_fine_cycle

    _expect(text, r"NFINE : INT := (\d+);", str(NFINE), "NFINE")
    _expect(text, r"StepMm : LREAL := ([\d.]+);", str(STEP_MM), "StepMm")
    text = with_fine_cycle([("bundle", text)], fine_ms)[0][1]
    note = [f"(* For OpenPLC: PRG_CncStand every {fine_ms} ms (FINE_MS = {fine_ms}.0), the PSM exchange "
            f"needs about 1 ms a scan;", f"   plclab cnc --fine-cycle {fine_ms} runs the twin at this cycle."]
    if drive not in ("step", "pulse"):
        raise PlcLabError(f"build: unknown drive {drive!r} (step or pulse)")
    if frames is None and drive == "pulse":
        at = text.find("\nCONFIGURATION ")
        text = text[:at] + _replace(text[at:], r"^(\s*PulseDrive : BOOL);", r"\g<1> := TRUE;", "PulseDrive", re.M)
        note.append("   The pulse-count drive (PulseDrive := TRUE): counts on %QW, spread by the PSM script.")
    if frames is not None:
        if not frames:
            raise PlcLabError(f"{part}: no motion in the part program")
        if len(frames) > MAX_FRAMES:
            raise PlcLabError(f"{part}: {len(frames)} frames: the frame table holds {MAX_FRAMES}")
        table = frame_table(frames, STEP_MM, method, diagonal, drive)
        at = text.find("\nCONFIGURATION ")
        if at < 0:
            raise PlcLabError("build: the cnc program has no CONFIGURATION for the frame table")
        head, text = text[:at], text[at:]      # the globals are declared in the configuration
        for name, value in table.items():
            if isinstance(value, list):
                init = _array_init(value, MAX_FRAMES)
            else:
                init = ("TRUE" if value else "FALSE") if isinstance(value, bool) else str(value)
            pattern = rf"^(\s*{name} : (?:ARRAY\[1\.\.{MAX_FRAMES}\] OF )?\w+);" if name in FRAME_ARRAYS \
                else rf"^(\s*{name} : \w+);"
            text = _replace(text, pattern, lambda m, init=init: f"{m.group(1)} := {init};", name, re.M)
        text = head + text
        note.append(f"   Part program {part}: {len(frames)} frames in the frame table (GVL_CNC), method {method}"
                    + (", the pulse-count drive" if drive == "pulse" else "") + "; SB1 on the console face runs it.")
    first_end = text.index("*)") + 2                   # after the bundle's own first comment
    return text[:first_end] + "\n" + "\n".join(note) + " *)" + text[first_end:]


def _array_init(values: list[int], size: int) -> str:
    """`[v1, v2, ..., n(0)]`, wrapped PER_LINE values a line (IEC 61131-3 array initial value)."""
    items = [str(v) for v in values] + ([f"{size - len(values)}(0)"] if len(values) < size else [])
    rows = [", ".join(items[i:i + PER_LINE]) for i in range(0, len(items), PER_LINE)]
    return "[" + ",\n            ".join(rows) + "]"


def _replace(text: str, pattern: str, repl, what: str, flags: int = 0) -> str:
    new, n = re.subn(pattern, repl, text, flags=flags)
    if n != 1:
        raise PlcLabError(f"build: the cnc program has {n} of {what} where the OpenPLC bundle expects one")
    return new


def _expect(text: str, pattern: str, value: str, what: str) -> None:
    found = re.findall(pattern, text)
    if found != [value] and [float(v) for v in found] != [float(value)]:
        raise PlcLabError(f"build: the cnc program's {what} is {found or 'missing'}, the OpenPLC bundle "
                          f"expects {value}")


def part_tape(part: str, method: str = "evalfn", tools: Optional[dict[int, float]] = None
              ) -> tuple[int, list[tuple[int, ...]], list[str]]:
    """A part program for the stand's tape reader (`plclab console cnc --part`): the method's
    number, per frame the frame table's nine values in steps (plclab.plants.cnc: TAPE_WORDS
    order), and the part's notes. The same table `plclab cnc` and the bundle's --part load."""
    from plclab.nc.gcode import parse_file
    from plclab.stands.cnc import FRAME_ARRAYS, MAX_FRAMES, frame_table

    program = parse_file(part, tools, STEP_MM)
    if not program.frames:
        raise PlcLabError(f"{part}: no motion in the part program")
    if len(program.frames) > MAX_FRAMES:
        raise PlcLabError(f"{part}: {len(program.frames)} frames: the frame table holds {MAX_FRAMES}")
    table = frame_table(program.frames, STEP_MM, method)
    frames = list(zip(*(table[name] for name in FRAME_ARRAYS)))
    for f, values in zip(program.frames, frames):
        for name, v in zip(FRAME_ARRAYS, values):
            if not -0x8000 <= v <= 0x7FFF:
                raise PlcLabError(f"{part}:{f.line}: {name} of {v} steps does not fit the tape reader's "
                                  f"16-bit words (-32768..32767)")
    return int(table["Method"]), frames, list(program.notes)
