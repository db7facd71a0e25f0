"""The robots' exploration declarations (plclab.stands.operators): what an operator at the
MP-9C's and the TUR-10's console may do, what each stand shows, and how closely a student's
stand must agree with the model answer's, in one place per robot.

MP-9C: the stand shows where each valve's spool sends its mechanism (what the plant answers
to L1..L7: both coils off keeps the spool, so a program that drops a coil once the mechanism
is there is as right as one that holds it) and HL1. Task 1 compares all four mechanisms;
Tasks 2 and 3 are lift-only programs (the starting program's manual mode moves the lift
alone), so the operator moves only the lift and only the lift and HL1 are compared. Left
open by the tasks: SA6 "is read at frame boundaries", so after SA6 is flipped in the middle
of a run a program may take it at the start or the end of the next pause or at a press:
nothing is compared from such a flip until the robot leaves automatic mode.

TUR-10: the stand shows each link's motion (at rest, moving forward or backward, slowly or
fast, from the drive reference the plant receives) and the position where it comes to rest
(within a band of 40 codes: the 16-code admissible error on each side, plus a scan of
travel; plus a link's travel at full speed in the time the two stands are apart, since a
link stopped mid-travel by a program a little behind stands that much further on, counted
since the link last stood still on both stands). Task 1 is the manual mode (all five drives);
what automatic mode then does is not its subject (one link regulated, as the starting program,
or all five), so each link's motion is compared in manual mode (after 0.5 s in it) and in
automatic mode only until the first SB1 press (entering it moves nothing), never by position;
Tasks 2 and 3 jog drive 1 only, as the starting program. In Task 3 the enable coming back to 1
after it dropped during a run leaves the rest of the run to the program (read as a level at
the end of the last pause, or latched from its drop: Rules.enable_latched).

The freedoms both the scripted rows and exploration honour are declared once per robot in
`Rules` (MP9C_RULES, TUR10_RULES) below.

HL1 on both robots is compared as the operator sees it: on, off or blinking (operators.
lamp_pattern). A blink may begin in either phase and end up to 2.5 s apart; in manual mode how
the full-memory blink answers more refused presses (restarted or not) is the program's.

Timing tolerance: a few scans (6 on the MP-9C; 0.2 s on the TUR-10, where when a frame counts
as reached depends on how fresh the program's sensor readings are); a program may lag the
model answer in all by up to 1 s on the MP-9C and 5 s on the TUR-10 (a little later at each
frame adds up over a long playback).
"""
from __future__ import annotations

import random
from dataclasses import dataclass
from typing import Any

from plclab.stands.operators import (BLINK_START_TOL, Console, Exploration, Observed, _Writer, aim, generate,
                                     lamp_pattern, lamp_timing, show_lamp)

@dataclass(frozen=True)
class Rules:
    """The freedoms the task texts leave a correct program and the tolerances they imply,
    declared once per robot: the scripted rows (plclab.grader.common and .<stand>) and
    exploration (E1: the Observed declarations below) judge by the same values, so no row can
    fail what another one lets pass (docs/grading.md, "One rule set").

    - `lag_scans`: a program may lag the model answer by this many scans at each start, stop
      and pause (a debounce counted from the next scan, a state machine a scan longer); a row
      that times one such step allows it on top of its own one-scan tolerance, and exploration
      lets the lags add up to `Exploration.max_drift`.
    - `blink_start_tol` (s): a blink may begin in either phase (lit or dark half first) and run
      from a free-running clock (the S7-200 SM0.5 habit): it is judged by its frequency and its
      span, its first change within half a period of its cause.
    - `coil_drop`: a double valve's coil may drop once its mechanism has arrived (both coils off
      keep the spool): the MP-9C's rows read the valves as their spools stand.
    - `enable_latched`: Task 3's enable may be read as a level at the end of the last pause or
      latched from the moment it drops during a run (the text allows both).
    - `automatic_subject`: the tasks whose subject includes automatic mode; elsewhere (the
      TUR-10's Task 1, the manual mode) exploration compares automatic mode only until its first
      SB1 press (entering it moves nothing)."""

    lag_scans: int = 1
    blink_start_tol: float = BLINK_START_TOL
    coil_drop: bool = False
    enable_latched: bool = True
    automatic_subject: tuple[str, ...] = ("task1", "task2", "task3")


MP9C_RULES = Rules(coil_drop=True)
TUR10_RULES = Rules(automatic_subject=("task2", "task3"))


def _hl1(mode_switch: str) -> Observed:
    """HL1 as the operator sees it: on, off or blinking. Left open by the tasks: the phase a
    blink begins in, how long it goes on after its cause (operators.lamp_timing), and in manual
    mode how the full-memory blink answers more refused presses (restarted or not: not compared
    while either stand blinks there)."""
    return Observed("HL1", show_lamp, ("HL1",), pattern=lamp_pattern, timing=lamp_timing,
                    freedom="a blink may begin in either phase and end up to 2.5 s apart; in manual mode "
                            "how the full-memory blink answers more presses is free",
                    free_blinks=(mode_switch, 0))

# The model answers' state, as coverage-guided exploration counts it (both robots' model
# answers share the playback's structure): phase, frame, frames recorded, watchdog fault.
MODEL_STATE = ("Main.Robot.Sequencer.State", "Main.Robot.Sequencer.Ptr", "Main.Cp.Count",
               "Main.Robot.Sequencer.Fault")

# --------------------------------------------------------------------------- MP-9C

_MECH = {   # mechanism -> (switch, spool 0 words, spool 1 words, coils)
    "gripper": ("SA2", "released (L1 = 0)", "clamped (L1 = 1)", ("L1",)),
    "rotation": ("SA3", "left (L4)", "right (L5)", ("L4", "L5")),
    "extension": ("SA4", "backward (L7)", "forward (L6)", ("L6", "L7")),
    "lift": ("SA5", "up (L2)", "down (L3)", ("L2", "L3")),
}


def _mp9c_teach(w: _Writer, task: str) -> None:
    """Move the robot somewhere in manual mode and let it get there (1.2 s longest travel)."""
    switches = ["SA5"] if task != "task1" else ["SA2", "SA3", "SA4", "SA5"]
    for sw in w.rng.sample(switches, w.rng.randint(1, len(switches))):
        w.flip(sw)
    w.wait(w.rng.uniform(1.4, 2.0))


def _mp9c_fault(rng: random.Random, _task: str) -> str:
    r = rng.random()
    if r < 0.35:
        return f"jammed mechanism={rng.choice(('lift', 'lift', 'rotation', 'extension'))}"
    if r < 0.5:
        return f"stuck_switch switch=SQ{rng.randint(1, 2)} state={rng.randint(0, 1)}"
    if r < 0.65:
        return f"dead_coil coil=L{rng.choice((2, 3))}"
    if r < 0.85:
        return "low_pressure factor=3"
    return f"bounce duration=0.02 seed={rng.randint(0, 99)}"


MP9C_CONSOLE = Console(mode="SA1", button="SB1", spare="I07", step="SA6", teach=_mp9c_teach,
                       faults=_mp9c_fault, capacity=32, watchdog=10.0, frame_s=1.2, bounce_max=0.044)


def _mp9c_observe(plant: Any, _previous: Any) -> dict[str, Any]:
    links = plant.links
    out: dict[str, Any] = {name: links[name].spool for name in _MECH}
    out["HL1"] = plant.hl1
    # not compared: which mechanisms stand at an end of their travel (a frame's arrival, where
    # the next script aims its actions)
    out["ends"] = tuple([links[name].position in (0.0, 1.0) for name in _MECH])
    return out


def _mp9c_compared(task: str) -> tuple[Observed, ...]:
    mechs = list(_MECH) if task == "task1" else ["lift"]
    out = [Observed(m, (lambda v, m=m: _MECH[m][1 + int(v)]), _MECH[m][3]) for m in mechs]
    out.append(_hl1("SA1"))
    return tuple(out)


def _mp9c_free_after(task: str) -> tuple[tuple[str, tuple[tuple[str, int], ...]], ...]:
    """SA6 flipped in automatic mode (read "at frame boundaries": the next pause's start or
    end, or a press); in Task 3 also I0.7 changed in step mode: whether the press that begins
    frame 1 again after the wrap is "a start" that needs I0.7 = 1 the task leaves open."""
    free: tuple[tuple[Any, ...], ...] = (("SA6", (("SA1", 1),)),)
    if task == "task3":
        free += (("I07", (("SA1", 1), ("SA6", 1))),)
        if MP9C_RULES.enable_latched:
            free += _enable_back("I07", "SA1")
    return free


def _enable_back(enable: str, mode: str) -> tuple[tuple[Any, ...], ...]:
    """Task 3's enable back to 1 after it dropped during a run (since the last SB1 press), in
    automatic mode: a program may read it as a level at the end of the last pause or have
    latched its drop (Rules.enable_latched), so nothing is compared from there until the
    robot leaves automatic mode."""
    return ((enable, ((mode, 1),), "SB1"),)


MP9C = Exploration(
    generate=lambda rng, task, seconds: generate(MP9C_CONSOLE, rng, task, seconds),
    aim=lambda rng, task, script, times: aim(MP9C_CONSOLE, rng, task, script, times),
    observe=_mp9c_observe, compared=_mp9c_compared,
    references={"task1": "task1", "task2": "task2", "task3": "task3"},
    buttons=("SB1",),
    free_after=_mp9c_free_after,
    meaning={"SA1": ("manual", "automatic"), "SA2": ("gripper released", "gripper clamped"),
             "SA3": ("rotation left", "rotation right"), "SA4": ("arm backward", "arm forward"),
             "SA5": ("arm up", "arm down"), "SA6": ("continuous", "step by step"),
             "I07": ("spare input off", "spare input on")},
    state_paths=MODEL_STATE, timing_tol=0.06, max_drift=1.0, drift_rate=0.02, episode_s=45.0, episodes=90,
    tick_s=0.01)

# --------------------------------------------------------------------------- TUR-10

TUR10_BAND = 40          # codes: rest positions compared within this band
TUR10_TOP_SPEED = 6000   # codes/s: a link at full reference (1500, the drive's 4 codes/s per unit)
_SLOW, _STILL = 700, 50  # |reference| above _STILL moves; up to _SLOW is the low speed
_AUTO_STILL = 400        # in automatic mode: |reference| above this moves (the regulator's profile is free)
TUR10_START_S = 0.0      # s: Task 1 compares link 1 this long after the first press (0: until the press)


def _tur10_teach(w: _Writer, task: str) -> None:
    """Jog one or two drives (sometimes both buttons of one, which must give 0)."""
    axes = [1, 2, 3, 4, 5] if task == "task1" else [1]
    if w.rng.random() < 0.4:
        w.set("SA6", w.rng.randint(0, 1))
    for k in w.rng.sample(axes, min(len(axes), w.rng.randint(1, 2))):
        button = f"SA{k}_{w.rng.choice(('FWD', 'BWD'))}"
        hold = w.rng.uniform(0.2, 0.9)
        r = w.rng.random()
        if r < 0.1:                                  # both buttons of one drive
            w.at(w.t + 0.1, f"SA{k}_{'BWD' if button.endswith('FWD') else 'FWD'}", hold=hold / 2)
        elif r < 0.2:                                # the speed switch turned while jogging
            w.switches["SA6"] = 1 - w.switches.get("SA6", 0)
            w.at(w.t + hold / 2, "SA6", str(w.switches["SA6"]))
        w.press(button, hold, w.rng.uniform(0.3, 0.6))


def _tur10_fault(rng: random.Random, task: str) -> str:
    """A fault on a drive the task moves: any of the five in Task 1, drive 1 in Tasks 2, 3."""
    axis = rng.randint(1, 5) if task == "task1" else 1
    r = rng.random()
    if r < 0.4:
        return f"stuck_drive axis={axis}"
    if r < 0.7:
        return f"slow_drive axis={axis} factor={rng.choice((0.3, 0.5))}"
    return f"dead_sensor axis={axis}"


TUR10_CONSOLE = Console(mode="SA7", button="SB1", spare="I15", step=None, teach=_tur10_teach,
                        faults=_tur10_fault, capacity=32, watchdog=20.0, frame_s=2.0)


def _level(reference: float, automatic: bool = False) -> int:
    """How a link moves: 0 at rest, 1 slowly, 2 fast, signed. In automatic mode the speed
    profile of a move is the program's regulator's (and a move of a few dozen codes, a frame
    recorded where the link had coasted a little further, peaks at a reference anywhere near
    any threshold), so there a link moves (2) only above _AUTO_STILL and is at rest below."""
    a = abs(reference)
    if automatic:
        lvl = 0 if a <= _AUTO_STILL else 2
    else:
        lvl = 0 if a <= _STILL else 1 if a <= _SLOW else 2
    return lvl if reference >= 0 else -lvl


_LINK_NAMES = {k: f"link{k}" for k in (1, 2, 3, 4, 5)}
_LEVELS: tuple[dict[int, int], dict[int, int]] = ({}, {})   # _level by reference: manual, automatic


def _tur10_observe(plant: Any, previous: Any) -> dict[str, Any]:
    # every scan of an exploration, twice: no names built, the previous value looked up once
    out: dict[str, Any] = {}
    automatic = bool(plant.console_bits.get("SA7"))
    get = previous.get if previous else None
    levels = _LEVELS[automatic]
    for k, d in plant.drives.items():
        name = _LINK_NAMES[k]
        lvl = levels.get(d.reference)
        if lvl is None:                            # a few hundred references: each worked out once
            lvl = levels[d.reference] = _level(d.reference, automatic)
        if lvl == 0 and get is not None:
            prev = get(name)
            if prev is not None and prev[0] == 0:
                out[name] = prev                   # at rest: where it stopped
                continue
        out[name] = (lvl, round(d.position) if lvl == 0 else 0)
    out["HL1"] = plant.reset_indicator
    return out


def _tur10_unchanged(plant: Any) -> tuple[int, int]:
    """_tur10_observe reads the links, the reset lamp and SA7: while no step changed a link or
    the lamp and no console contact changed, it gives what it gave (the sensor bus, which the
    program scans every few scans, is not observed)."""
    return plant.state_changes, plant.console_changes


_LEVEL_WORDS = {2: "moving forward fast", 1: "moving forward slowly", -1: "moving backward slowly",
                -2: "moving backward fast"}


def _show_link(v: Any) -> str:
    lvl, pos = v
    return f"at rest at {pos} codes" if lvl == 0 else _LEVEL_WORDS[lvl]


def _same_link(a: Any, b: Any, extra: float = 0.0) -> bool:
    return a[0] == b[0] and abs(a[1] - b[1]) <= TUR10_BAND + extra


def _at_rest(v: Any) -> bool:
    return v[0] == 0


def _same_motion(a: Any, b: Any) -> bool:
    return a[0] == b[0]


def _tur10_compared(task: str) -> tuple[Observed, ...]:
    if task not in TUR10_RULES.automatic_subject:
        # Task 1 is the manual mode: each link's motion there; in automatic mode only that
        # entering it moves nothing until SB1 is pressed (what playback does then -- one link
        # regulated as the starting program, or all five -- is not the task's subject)
        # link 1 also while the press starts frame 1 (TUR10_START_S: the regulator's ramp and a
        # link's start), links 2..5 (regulated or not) only until the press
        out = [Observed(f"link{k}", _show_link, (f"DRIVE{k}",), _same_motion, only_when=("SA7", 0, 0.5),
                        until_press=("SA7", 1, "SB1", TUR10_START_S if k == 1 else 0.0),
                        freedom="in automatic mode compared only until the first SB1 press starts frame 1")
               for k in (1, 2, 3, 4, 5)]
    else:
        out = [Observed("link1", _show_link, ("DRIVE1",), _same_link, lag_band=TUR10_TOP_SPEED, rest=_at_rest,
                        tolerance=f"+/- {TUR10_BAND} codes, plus a link's travel in the time the two stands "
                                  "are apart")]
    out.append(_hl1("SA7"))
    return tuple(out)


TUR10 = Exploration(
    generate=lambda rng, task, seconds: generate(TUR10_CONSOLE, rng, task, seconds),
    aim=lambda rng, task, script, times: aim(TUR10_CONSOLE, rng, task, script, times),
    observe=_tur10_observe, compared=_tur10_compared, unchanged=_tur10_unchanged,
    references={"task1": "task1", "task2": "task2", "task3": "task3"},
    buttons=("SB1",) + tuple(f"SA{k}_{d}" for k in (1, 2, 3, 4, 5) for d in ("FWD", "BWD")),
    free_after=lambda task: _enable_back("I15", "SA7") if task == "task3" and TUR10_RULES.enable_latched else (),
    meaning={"SA7": ("manual", "automatic"), "SA6": ("normal speed", "low speed"),
             "I15": ("spare input off", "spare input on")},
    state_paths=MODEL_STATE, timing_tol=0.2, max_drift=5.0, drift_rate=0.12, episode_s=60.0, episodes=50,
    tick_s=0.01)
