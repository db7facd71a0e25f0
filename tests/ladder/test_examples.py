"""The lab programs' blocks drawn in ladder behave as the ST they replace, scan for scan.

Each example (examples.py, stored as examples/*.xml) is an OpenPLC Editor plc.xml holding
one POU of a stand's starting program. The stand program runs twice in the soft PLC, once as
shipped and once with that POU taken from the plc.xml, under the same console inputs; every
scan's outputs and recorded control program must be the same.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import pytest

from examples import EXAMPLES, EXAMPLES_DIR
from plclab.frontend import check_sources
from plclab.frontend.plcxml import source_from_xml
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.runtime.sim import Simulation
from plclab.stands import get_stand, sources


def test_stored_examples_are_what_examples_py_draws_and_valid_tc6():
    from plclab import plcopen
    from plclab.frontend import plcxml

    for name, make in EXAMPLES.items():
        data = (EXAMPLES_DIR / name).read_bytes()
        assert data == make(), f"{name}: run examples.py to redraw it"
        plcopen.validate(plcxml.parse_xml(data, name), name)       # the TC6 model: raises on a bad file


def stand_sources(stand: str) -> list[tuple[str, str]]:
    s = get_stand(stand)
    return sources(s, s.starting_variant)


def with_ladder(srcs: list[tuple[str, str]], replaced: str, xml: str) -> list[tuple[str, str]]:
    """The program with `replaced`.st taken out and the POU of examples/`xml` put in."""
    kept = [(n, t) for n, t in srcs if Path(n).name != f"{replaced}.st"]
    assert len(kept) == len(srcs) - 1 or replaced == ""
    path = EXAMPLES_DIR / xml
    return kept + [(str(path), source_from_xml(path, path.read_bytes(), kept))]


def plain(value: Any) -> Any:
    """A variable's value as plain data (structures and arrays of the runtime unpacked)."""
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if hasattr(value, "__dict__"):
        return {k: plain(v) for k, v in vars(value).items() if not k.startswith("_")}
    return repr(value)


def trace(srcs: list[tuple[str, str]], inputs: Callable[[int], dict[str, Any]], scans: int,
          watch: list[str]) -> list:
    sim = Simulation(PLC(compile_unit(check_sources(srcs))))
    rows = []
    for n in range(scans):
        for address, value in inputs(n).items():
            sim.set(address, value)
        sim.step(1)
        outputs = {a: list(v) for a, v in sim.plc.image.areas.items() if a.startswith("Q")}
        rows.append((n, outputs, [plain(sim.plc.read(w)) for w in watch]))
    return rows


def first_mismatch(a: list, b: list) -> Any:
    return next(((x, y) for x, y in zip(a, b) if x != y), None)


# --------------------------------------------------------------------------- MP-9C

def mp9c_console(n: int) -> dict[str, Any]:
    """10 ms scans: manual mode; SA5 toggled every 0.7 s; SB1 pressed 0.2 s every 0.5 s for
    35 presses (more frames than fit: 32), then held 3.5 s (program reset), then presses
    with a 20 ms bounce before each (five presses in the last 3 s)."""
    t = n * 10
    sb1 = False
    if t < 17_500:
        sb1 = t % 500 < 200
    elif 18_000 <= t < 21_500:
        sb1 = True
    elif t >= 22_000:
        phase = (t - 22_000) % 600
        sb1 = phase < 20 or 40 <= phase < 240
    return {"%IX1.0": False, "%IX1.4": (t // 700) % 2 == 1, "%IX1.6": sb1,
            "%IX0.0": (t // 300) % 2 == 0, "%IX0.4": (t // 900) % 2 == 1}


@pytest.mark.parametrize("replaced,xml", [("FB_Mp9cManual", "mp9c_manual.xml"), ("FB_Sb1Button", "sb1_button.xml")])
def test_mp9c_block_in_ladder_runs_as_the_st_it_replaces(replaced, xml):
    st = stand_sources("mp9c")
    watch = ["Main.Cp", "Main.Button.Short", "Main.Button.Long", "Main.Manual.Full"]
    scans = 2_500
    a = trace(st, mp9c_console, scans, watch)
    b = trace(with_ladder(st, replaced, xml), mp9c_console, scans, watch)
    assert first_mismatch(a, b) is None
    # the inputs did exercise what the block does: frames recorded up to full, a reset, valves
    counts = [_count(row[2][0]) for row in a]
    assert max(counts) == 32 and 0 in counts[1900:2200] and counts[-1] == 5   # 5 debounced presses after the reset
    assert any(row[1] != a[0][1] for row in a)


def _count(cp: Any) -> int:
    if isinstance(cp, dict):
        for k, v in cp.items():
            if k.upper() == "COUNT":
                return v
    raise AssertionError(f"no Count in {cp!r}")


# --------------------------------------------------------------------------- TUR-10

JOG_LINE = "DRIVE1 := FC_JogReference(SA1_FWD, SA1_BWD, SA6);"


def test_tur10_jog_rung_drives_as_the_st_line_it_replaces():
    st = stand_sources("tur10")
    ladder = []
    for name, text in st:
        if Path(name).name == "FB_Tur10Manual.st":
            assert text.count(JOG_LINE) == 1
            text = text.replace(JOG_LINE, "Jog();").replace("VAR CONSTANT", "VAR\n    Jog : FB_Tur10Jog;\nEND_VAR\n"
                                                                          "VAR CONSTANT", 1)
        ladder.append((name, text))
    ladder = with_ladder(ladder, "", "tur10_jog.xml")

    def console(n: int) -> dict[str, Any]:        # every combination of the three inputs, 50 ms each
        k = (n // 5) % 8
        return {"%IX1.4": False, "%IX0.0": bool(k & 1), "%IX0.1": bool(k & 2), "%IX1.2": bool(k & 4)}

    a = trace(st, console, 120, [])
    b = trace(ladder, console, 120, [])
    assert first_mismatch(a, b) is None
    drive = {row[1]["QW"][0] for row in a}
    assert len(drive) >= 4          # 0, both speeds both ways: the inputs exercised the rung
