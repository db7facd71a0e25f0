"""The model answers of docs/instructors.md, made real: the starting program of each robot
with exactly the changes the outline lists, graded. Each passes its task, so the outline is a
correct solution in the starting program's own structure (main program, manual / automatic /
continuous / step-by-step subroutines), and each is a real change: no task is one line away
from the starting program (MP-9C: 13, 11, 19 changed lines; TUR-10: 16, 7, 7; Tasks 2 and 3
change several POUs each, the frame type included for Task 2).
"""
from __future__ import annotations

import difflib

import pytest

from plclab.grader import grade_sources
from plclab.stands import bundle, get_stand

PAUSE_FIELD = ("        Data : T_FrameData;\n    END_STRUCT;",
               "        Data : T_FrameData;\n        Pause : TIME;\n    END_STRUCT;", 1)

MP9C = {
    "task1": [
        ("VAR_EXTERNAL\n    SA5 : BOOL;\n", "VAR_EXTERNAL\n    SA2 : BOOL;\n    SA3 : BOOL;\n    SA4 : BOOL;\n"
         "    SA5 : BOOL;\n", 1),
        ("L1 := FALSE;\nL2 := NOT SA5;\nL3 := SA5;\nL4 := FALSE;\nL5 := FALSE;\nL6 := FALSE;\nL7 := FALSE;\n",
         "L1 := SA2;\nL2 := NOT SA5;\nL3 := SA5;\nL4 := NOT SA3;\nL5 := SA3;\nL6 := SA4;\nL7 := NOT SA4;\n", 1),
    ],
    "task2": [
        PAUSE_FIELD,
        ("VAR_EXTERNAL\n    SA5 : BOOL;\n", "VAR_EXTERNAL\n    SA5 : BOOL;\n    I07 : BOOL;\n", 1),
        ("        Cp.Frames[Cp.Count].Data[2] := Sensors;\n",
         "        Cp.Frames[Cp.Count].Data[2] := Sensors;\n"
         "        Cp.Frames[Cp.Count].Pause := SEL(G := I07, IN0 := T#500ms, IN1 := T#3s);\n", 1),
        ("Duration := PAUSE_TIME", "Duration := Cp.Frames[Sequencer.Ptr].Pause", 4),
    ],
    "task3": [
        ("VAR_EXTERNAL\n    L1 : BOOL;\n", "VAR_EXTERNAL\n    I07 : BOOL;\n    L1 : BOOL;\n", 1),
        ("FrameDone := Sensors = Cp.Frames[Sequencer.Ptr].Data[2],",
         "FrameDone := Sensors = Cp.Frames[Sequencer.Ptr].Data[2], Enable := I07,", 2),
        ("    FrameDone : BOOL;               (* the sensors show frame Ptr reached *)\n",
         "    FrameDone : BOOL;               (* the sensors show frame Ptr reached *)\n"
         "    Enable : BOOL;                  (* I0.7: execution allowed *)\n", 2),
        ("IF Press AND Cp.Count > 0 THEN", "IF Press AND Cp.Count > 0 AND Enable THEN", 2),
        ("IF Pause.Done THEN\n",
         "IF Pause.Done AND Sequencer.Ptr >= Cp.Count AND NOT Enable THEN\n"
         "        Sequencer.State := STOPPED;\n    ELSIF Pause.Done THEN\n", 2),
    ],
}

TUR10 = {
    "task1": [
        ("VAR_EXTERNAL\n    SA1_FWD : BOOL;\n    SA1_BWD : BOOL;\n",
         "VAR_EXTERNAL\n    SA1_FWD : BOOL;\n    SA1_BWD : BOOL;\n" + "".join(
             f"    SA{k}_FWD : BOOL;\n    SA{k}_BWD : BOOL;\n" for k in range(2, 6)), 1),
        ("\nDRIVE2 := 0;\nDRIVE3 := 0;\nDRIVE4 := 0;\nDRIVE5 := 0;\nSensors();",
         "\n" + "".join(f"DRIVE{k} := FC_JogReference(SA{k}_FWD, SA{k}_BWD, SA6);\n" for k in range(2, 6))
         + "Sensors();", 1),
    ],
    "task2": [
        PAUSE_FIELD,
        ("    SA6 : BOOL;\n    DRIVE1 : INT;\n", "    SA6 : BOOL;\n    I15 : BOOL;\n    DRIVE1 : INT;\n", 1),
        ("        Cp.Frames[Cp.Count].Data := Positions;\n",
         "        Cp.Frames[Cp.Count].Data := Positions;\n"
         "        Cp.Frames[Cp.Count].Pause := SEL(G := I15, IN0 := T#500ms, IN1 := T#3s);\n", 1),
        ("Duration := PAUSE_TIME", "Duration := Cp.Frames[Sequencer.Ptr].Pause", 2),
    ],
    "task3": [
        ("    RegHold : BOOL;\n    Targets : T_FrameData;\n    AllReached : BOOL;\nEND_VAR",
         "    RegHold : BOOL;\n    Targets : T_FrameData;\n    AllReached : BOOL;\n    I15 : BOOL;\nEND_VAR", 1),
        ("IF Press AND Cp.Count > 0 THEN", "IF Press AND Cp.Count > 0 AND I15 THEN", 1),
        ("IF Pause.Done THEN\n",
         "IF Pause.Done AND Sequencer.Ptr >= Cp.Count AND NOT I15 THEN\n"
         "                Sequencer.State := STOPPED;\n            ELSIF Pause.Done THEN\n", 1),
    ],
}


def model_answer(stand: str, task: str) -> tuple[str, str]:
    """(starting program, model answer) as OpenPLC bundles."""
    start = bundle(get_stand(stand), "baseline")
    text = start
    for old, new, count in {"mp9c": MP9C, "tur10": TUR10}[stand][task]:
        assert text.count(old) == count, f"{stand} {task}: {old!r} occurs {text.count(old)} times, not {count}"
        text = text.replace(old, new)
    return start, text


CASES = [(s, t) for s in ("mp9c", "tur10") for t in ("task1", "task2", "task3")]


@pytest.mark.parametrize("stand,task", CASES)
def test_model_answer_passes_its_task(stand, task):
    _, answer = model_answer(stand, task)
    report = grade_sources(stand, task, [(f"{stand}_{task}_model.st", answer)])
    assert report.passed, report.text()


@pytest.mark.parametrize("stand,task", CASES)
def test_model_answer_is_a_real_change_of_the_starting_program(stand, task):
    start, answer = model_answer(stand, task)
    changed = [line for line in difflib.unified_diff(start.splitlines(), answer.splitlines(), lineterm="", n=0)
               if line[:1] in "+-" and not line.startswith(("+++", "---"))]
    assert len(changed) >= 5, changed
