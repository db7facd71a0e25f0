"""Ladder versions of parts of the lab programs, drawn as OpenPLC Editor saves them.

Each builds the plc.xml of one POU that takes the place of an ST POU of a stand's starting
program (same name, same interface): test_examples.py runs the stand program with the ST
POU and with the drawn one under the same inputs and compares them scan for scan. The XML
files stored beside (examples/*.xml) are what these functions write; to redraw them:

    PYTHONPATH=harness:tests/ladder python tests/ladder/examples.py
"""
from __future__ import annotations

from pathlib import Path

from drawing import Diagram, Pou, project

EXAMPLES_DIR = Path(__file__).resolve().parent / "examples"


def sb1_button() -> bytes:
    """FB_Sb1Button (textbook Fig. 3 / Fig. 9: SB1 short press, 3 s press) in ladder."""
    d = Diagram("LD")
    # rung 1: the debounce timer; Held is its output
    p = d.contact("Pressed", 0, 0)
    bt = d.invar("BOUNCE_TIME", 1, 0)
    deb = d.block("TON", 0, 1, [("IN", p), ("PT", bt)], ["Q", "ET"], instance="DebounceTimer")
    d.coil("Held", 0, 4, after=(deb, "Q"))
    # rung 2: Press, one scan at the debounced press
    h = d.contact("Held", 3, 0)
    nw = d.contact("WasHeld", 3, 1, after=h, negated=True)
    d.coil("Press", 3, 4, after=nw)
    # rung 3: the 3 s timer gives Long, once per press
    p2 = d.contact("Pressed", 4, 0)
    lt = d.invar("LONG_TIME", 5, 0)
    long_timer = d.block("TON", 4, 1, [("IN", p2), ("PT", lt)], ["Q", "ET"], instance="LongTimer")
    ng = d.contact("LongGiven", 4, 3, after=(long_timer, "Q"), negated=True)
    d.coil("Long", 4, 4, after=ng)
    # rung 4: Short, at the release of a press that gave no Long
    w = d.contact("WasHeld", 7, 0)
    nh = d.contact("Held", 7, 1, after=w, negated=True)
    ng2 = d.contact("LongGiven", 7, 2, after=nh, negated=True)
    d.coil("Short", 7, 4, after=ng2)
    # rungs 5-6: LongGiven latched by Long, released with the button
    lg = d.contact("Long", 8, 0)
    d.coil("LongGiven", 8, 4, after=lg, storage="set")
    nh2 = d.contact("Held", 9, 0, negated=True)
    d.coil("LongGiven", 9, 4, after=nh2, storage="reset")
    # rung 7: remember the state for the next scan
    h3 = d.contact("Held", 10, 0)
    d.coil("WasHeld", 10, 4, after=h3)
    pou = Pou("FB_Sb1Button", "functionBlock", d, {
        "inputVars": [("Pressed", "BOOL", None)],
        "outputVars": [("Press", "BOOL", None), ("Short", "BOOL", None), ("Long", "BOOL", None),
                       ("Held", "BOOL", None)],
        "localVars constant": [("BOUNCE_TIME", "TIME", "T#50ms"), ("LONG_TIME", "TIME", "T#3s")],
        "localVars": [("DebounceTimer", "TON", None), ("LongTimer", "TON", None), ("WasHeld", "BOOL", None),
                      ("LongGiven", "BOOL", None)]})
    return project([pou])


def mp9c_manual(every_mechanism: bool = False) -> bytes:
    """FB_Mp9cManual, the MP-9C manual mode subroutine (textbook Fig. 3): the valves follow
    the console switches (here the lift, SA5), a short SB1 press records a frame, a 3 s press
    resets the program. `every_mechanism`: MP-9C Task 1 done in ladder (SA2..SA5 each drive
    their valves), for the grading test."""
    d = Diagram("LD")
    if every_mechanism:
        d.coil("L1", 0, 4, after=d.contact("SA2", 0, 0))
    else:
        d.coil("L1", 0, 4, after="rail", storage="reset")
    n5 = d.contact("SA5", 1, 0, negated=True)
    d.coil("L2", 1, 4, after=n5)
    s5 = d.contact("SA5", 2, 0)
    d.coil("L3", 2, 4, after=s5)
    if every_mechanism:
        for row, (coil, switch, on) in enumerate((("L4", "SA3", False), ("L5", "SA3", True), ("L6", "SA4", True),
                                                  ("L7", "SA4", False)), 3):
            d.coil(coil, row, 4, after=d.contact(switch, row, 0, negated=not on))
    else:
        for row, coil in enumerate(("L4", "L5", "L6", "L7"), 3):
            d.coil(coil, row, 4, after="rail", storage="reset")
    d.coil("Full", 7, 4, after="rail", storage="reset")
    # 3 s press: the program is emptied
    r = d.contact("Reset", 8, 0)
    zero = d.invar("0", 9, 0)
    mv = d.block("MOVE", 8, 1, [("EN", r), ("IN", zero)], ["ENO", "OUT"])
    d.outvar("Cp.Count", 8, 4, (mv, "OUT"))
    # short press with room for a frame: record it; without room: Full
    cnt = d.invar("Cp.Count", 11, 0)
    mx = d.invar("MAX_FRAMES", 12, 0)
    lt = d.block("LT", 11, 1, [("IN1", cnt), ("IN2", mx)], ["OUT"])
    rec = d.contact("Record", 11, 2, after=(lt, "OUT"))
    nr = d.contact("Reset", 11, 3, after=rec, negated=True)
    d.coil("DoRecord", 11, 4, after=nr)
    rec2 = d.contact("Record", 13, 0)
    nr2 = d.contact("Reset", 13, 1, after=rec2, negated=True)
    nd = d.contact("DoRecord", 13, 2, after=nr2, negated=True)
    d.coil("Full", 13, 4, after=nd, storage="set")
    do1 = d.contact("DoRecord", 14, 0)
    c2 = d.invar("Cp.Count", 15, 0)
    one = d.invar("1", 16, 0)
    add = d.block("ADD", 14, 1, [("EN", do1), ("IN1", c2), ("IN2", one)], ["ENO", "OUT"])
    d.outvar("Cp.Count", 14, 4, (add, "OUT"))
    do2 = d.contact("DoRecord", 18, 0)
    bits = [d.invar(f"L{i}", 19 + i, 0) for i in range(1, 8)]
    pack = d.block("FC_PackBits7", 18, 1, [("EN", do2)] + [(f"B{i}", b) for i, b in enumerate(bits)],
                   ["ENO", "OUT"])
    d.outvar("Cp.Frames[Cp.Count].Data[1]", 18, 4, (pack, "OUT"))
    do3 = d.contact("DoRecord", 28, 0)
    sens = d.invar("Sensors", 29, 0)
    mv2 = d.block("MOVE", 28, 1, [("EN", do3), ("IN", sens)], ["ENO", "OUT"])
    d.outvar("Cp.Frames[Cp.Count].Data[2]", 28, 4, (mv2, "OUT"))
    pou = Pou("FB_Mp9cManual", "functionBlock", d, {
        "inputVars": [("Sensors", "INT", None), ("Record", "BOOL", None), ("Reset", "BOOL", None)],
        "inOutVars": [("Cp", "ST_ControlProgram", None)],
        "outputVars": [("Full", "BOOL", None)],
        "externalVars": [(n, "BOOL", None) for n in (("SA2", "SA3", "SA4") if every_mechanism else ())
                         + ("SA5", "L1", "L2", "L3", "L4", "L5", "L6", "L7")],
        "localVars constant": [("MAX_FRAMES", "INT", "32")],
        "localVars": [("DoRecord", "BOOL", None)]})
    return project([pou])


def tur10_jog() -> bytes:
    """The TUR-10 jog rung (textbook section 3): drive 1's speed reference from its console
    buttons, as an FB (FB_Tur10Jog) the manual mode calls in place of its ST line."""
    d = Diagram("LD")
    fwd = d.contact("SA1_FWD", 0, 0)
    bwd = d.contact("SA1_BWD", 1, 0)
    low = d.contact("SA6", 2, 0)
    jog = d.block("FC_JogReference", 0, 1, [("Forward", fwd), ("Backward", bwd), ("LowSpeed", low)], ["OUT"])
    d.outvar("DRIVE1", 0, 4, (jog, "OUT"))
    pou = Pou("FB_Tur10Jog", "functionBlock", d, {
        "externalVars": [("SA1_FWD", "BOOL", None), ("SA1_BWD", "BOOL", None), ("SA6", "BOOL", None),
                         ("DRIVE1", "INT", None)]})
    return project([pou])


EXAMPLES = {"sb1_button.xml": sb1_button, "mp9c_manual.xml": mp9c_manual, "tur10_jog.xml": tur10_jog}


if __name__ == "__main__":
    EXAMPLES_DIR.mkdir(exist_ok=True)
    for name, make in EXAMPLES.items():
        (EXAMPLES_DIR / name).write_bytes(make())
        print(f"wrote {EXAMPLES_DIR / name}")
