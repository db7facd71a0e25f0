"""Regenerate the one-rule-set fixtures (tests/grader/fixtures/rules/STAND/*.st): correct
programs inside each freedom the tasks leave (issue 29; docs/grading.md, "One rule set"),
written for the tests on the independent solutions (fixtures/explore/independent, written from
the task texts alone), never on the model answers. Each must pass every row of its task,
scripted and exploration (tests/grader/test_rules.py).

    .venv/bin/python tests/grader/make_rules_fixtures.py            # (re)write the files
    .venv/bin/python tests/grader/make_rules_fixtures.py --check    # exit 1 if a file is out of date
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
INDEPENDENT = HERE / "fixtures" / "explore" / "independent"
OUT = HERE / "fixtures" / "rules"

COIL_DROP = """    (* a coil is dropped once its mechanism has arrived: both coils off keep the spool *)
    IF L2 AND SQ1 THEN
        L2 := FALSE;
    END_IF;
    IF L3 AND SQ2 THEN
        L3 := FALSE;
    END_IF;
    IF L4 AND SQ4 THEN
        L4 := FALSE;
    END_IF;
    IF L5 AND SQ5 THEN
        L5 := FALSE;
    END_IF;
    IF L6 AND SQ6 THEN
        L6 := FALSE;
    END_IF;
    IF L7 AND SQ7 THEN
        L7 := FALSE;
    END_IF;
"""
START_OF_FRAME = "        MoveTmr(IN := FALSE);\n        MoveTmr(IN := TRUE, PT := TIMEOUT);\n    END_IF;\n"
LATE_VARS = ("    StartIt : BOOL;\n", "    StartIt : BOOL;\n    IdlePress : BOOL;           (* a debounced press while stopped ... *)\n"
             "    PressLate : BOOL;           (* ... taken one scan later *)\n")
LATE_PRESS = ("    CASE Mode OF", "    PressLate := IdlePress;\n    IdlePress := EvPress AND Mode = 0;\n    CASE Mode OF")


def _latched(inp: str, modes: str) -> tuple[tuple[str, str], ...]:
    return (("    StartIt : BOOL;\n", "    StartIt : BOOL;\n    Disabled : BOOL;            (* the enable dropped during this run *)\n"),
            (f"IF EvPress AND NumFrames > 0 AND {inp} THEN", f"IF EvPress AND NumFrames > 0 AND {inp} THEN\n"
             "            Disabled := FALSE;"),
            ("    CASE Mode OF", f"    IF ({modes}) AND NOT {inp} THEN\n        Disabled := TRUE;\n    END_IF;\n    CASE Mode OF"),
            (f"IF Cur >= NumFrames AND NOT {inp} THEN", "IF Cur >= NumFrames AND Disabled THEN"))


# (file, based on, what it does inside which freedom, edits (old, new): old occurs exactly once)
FIXTURES = (
    ("mp9c/task1_coil_dropped.st", "mp9c/task1.st",
     "in automatic mode a double valve's coil is dropped once its mechanism has arrived (both coils off keep the "
     "spool).", ((START_OF_FRAME + "END_IF;", START_OF_FRAME + COIL_DROP + "END_IF;"),)),
    ("mp9c/task1_blink_dark_first_free_clock.st", "mp9c/task1.st",
     "the fault blink begins with its dark half, the full-memory blink runs from a free-running 1-s clock (the "
     "S7-200 SM0.5 habit), gated for its 2 s.",
     (("    FaultFlash : FB_Flasher;\n    FullFlash : FB_Flasher;\n",
       "    FaultFlash : FB_Flasher;\n    FullFlash : FB_Flasher;\n"
       "    ClockTmr : TON;             (* a free-running 1 s clock, as SM0.5 *)\n    Clock1s : BOOL;\n"),
      ("FaultFlash(Enable := SA1 AND Mode = 4, Restart := FALSE, Half := T#250ms);      (* 2 Hz *)",
       "FaultFlash(Enable := SA1 AND Mode = 4, Restart := FALSE, Half := T#250ms);      (* 2 Hz *)\n"
       "ClockTmr(IN := NOT ClockTmr.Q, PT := T#500ms);\nIF ClockTmr.Q THEN\n    Clock1s := NOT Clock1s;\nEND_IF;"),
      ("    HL1 := FaultFlash.Q;", "    HL1 := NOT FaultFlash.Q;    (* the dark half first *)"),
      ("    HL1 := FullFlash.Q;", "    HL1 := Clock1s;             (* the free-running clock, gated *)"))),
    ("mp9c/task3_enable_latched.st", "mp9c/task3.st",
     "the enable is latched from the moment I07 drops during a run (back to 1 before the last pause ends, it does "
     "not cancel the stop), where the model answer reads it as a level at the end of the last pause.",
     _latched("I07", "Mode = 1 OR Mode = 2 OR Mode = 3")),
    ("tur10/task1_auto_all_five.st", "tur10/task1.st",
     "automatic mode regulates all five links (Task 1 is the manual mode: what playback does is not its subject).",
     (("    AXES : INT := 1;            (* automatic mode regulates drive 1, as the starting program *)",
       "    AXES : INT := 5;            (* automatic mode regulates all five drives *)"),)),
    ("tur10/task2_start_scan_later.st", "tur10/task2.st",
     "playback starts one scan (20 ms) after the debounced press, one scan later than the model answer.",
     (LATE_VARS, ("IF EvPress AND NumFrames > 0 THEN", "IF PressLate AND NumFrames > 0 THEN"), LATE_PRESS)),
    ("tur10/task3_start_scan_later.st", "tur10/task3.st",
     "playback starts one scan (20 ms) after the debounced press, one scan later than the model answer.",
     (LATE_VARS, ("IF EvPress AND NumFrames > 0 AND I15 THEN", "IF PressLate AND NumFrames > 0 AND I15 THEN"),
      LATE_PRESS)),
    ("tur10/task3_enable_latched.st", "tur10/task3.st",
     "the enable is latched from the moment I15 drops during a run (back to 1 before the last pause ends, it does "
     "not cancel the stop), where the model answer reads it as a level at the end of the last pause.",
     _latched("I15", "Mode = 1 OR Mode = 2")),
)


def text(name: str, base: str, what: str, edits: tuple) -> str:
    s = (INDEPENDENT / base).read_text(encoding="utf-8")
    for old, new in edits:
        if s.count(old) != 1:
            raise SystemExit(f"{name}: {old[:50]!r} occurs {s.count(old)} times in {base}")
        s = s.replace(old, new)
    stand, stem = name.split("/")
    header = (f"(* plclab rules fixture: {stand} {stem.split('_')[0]}, a correct program inside a declared freedom: "
              f"{what}\n   Made by tests/grader/make_rules_fixtures.py from fixtures/explore/independent/{base}; "
              "regenerate, do not edit. *)\n")
    return header + s


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if a committed file differs")
    args = ap.parse_args()
    stale = []
    for name, base, what, edits in FIXTURES:
        path = OUT / name
        want = text(name, base, what, edits)
        if args.check:
            if not path.exists() or path.read_text(encoding="utf-8") != want:
                stale.append(name)
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(want, encoding="utf-8")
            print(f"wrote {path}")
    if stale:
        print("out of date: " + ", ".join(stale) + " (run tests/grader/make_rules_fixtures.py)")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
