"""The robots' exploration declarations (plclab.stands.operators): what an operator at the
MP-9C's and the TUR-10's console may do, what each stand shows, and how closely a student's
stand must agree with the model answer's, in one place per robot.

MP-9C: the stand shows where each valve's spool sends its mechanism (what the plant answers
to L1..L7: both coils off keeps the spool, so a program that drops a coil once the mechanism
is there is as right as one that holds it) and HL1. Task 1 compares all four mechanisms;
Tasks 2 and 3 are lift-only programs (the starting program's manual mode moves the lift
alone), so the operator moves only the lift and only the lift and HL1 are compared.

TUR-10: the stand shows each link's motion (at rest, moving forward or backward, slowly or
fast, from the drive reference the plant receives) and the position where it comes to rest
(within a band of 40 codes: the 16-code admissible error on each side, plus a scan of
travel). Task 1 writes manual mode for all five drives and leaves automatic mode as the
starting program's (drive 1 regulated), so links 2..5 are compared in manual mode only (after
0.5 s in it) and never by position; Tasks 2 and 3 jog drive 1 only, as the starting program.
Timing tolerance: a few scans (6 on the MP-9C, 5 main-task scans on the TUR-10); a program may
lag the model answer by up to 1 s in all (a scan later at each frame adds up).
"""
from __future__ import annotations

import random
from typing import Any

from plclab.stands.operators import Console, Exploration, Observed, _Writer, generate

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


def _mp9c_fault(rng: random.Random) -> str:
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
                       faults=_mp9c_fault, capacity=32, watchdog=10.0)


def _mp9c_observe(plant: Any, _previous: Any) -> dict[str, Any]:
    out: dict[str, Any] = {name: plant.links[name].spool for name in _MECH}
    out["HL1"] = plant.hl1
    return out


def _mp9c_compared(task: str) -> tuple[Observed, ...]:
    mechs = list(_MECH) if task == "task1" else ["lift"]
    out = [Observed(m, (lambda v, m=m: _MECH[m][1 + int(v)]), _MECH[m][3]) for m in mechs]
    out.append(Observed("HL1", lambda v: "on" if v else "off", ("HL1",)))
    return tuple(out)


MP9C = Exploration(
    generate=lambda rng, task, seconds: generate(MP9C_CONSOLE, rng, task, seconds),
    observe=_mp9c_observe, compared=_mp9c_compared,
    references={"task1": "task1", "task2": "task2", "task3": "task3"},
    buttons=("SB1",),
    meaning={"SA1": ("manual", "automatic"), "SA2": ("gripper released", "gripper clamped"),
             "SA3": ("rotation left", "rotation right"), "SA4": ("arm backward", "arm forward"),
             "SA5": ("arm up", "arm down"), "SA6": ("continuous", "step by step"),
             "I07": ("spare input off", "spare input on")},
    timing_tol=0.06, max_drift=1.0, episode_s=45.0, episodes=70, tick_s=0.01)

# --------------------------------------------------------------------------- TUR-10

TUR10_BAND = 40          # codes: rest positions compared within this band
_SLOW, _STILL = 700, 50  # |reference| above _STILL moves; up to _SLOW is the low speed


def _tur10_teach(w: _Writer, task: str) -> None:
    """Jog one or two drives (sometimes both buttons of one, which must give 0)."""
    axes = [1, 2, 3, 4, 5] if task == "task1" else [1]
    if w.rng.random() < 0.4:
        w.set("SA6", w.rng.randint(0, 1))
    for k in w.rng.sample(axes, min(len(axes), w.rng.randint(1, 2))):
        button = f"SA{k}_{w.rng.choice(('FWD', 'BWD'))}"
        hold = w.rng.uniform(0.2, 0.9)
        if w.rng.random() < 0.1:                     # both buttons of one drive
            w.at(w.t + 0.1, f"SA{k}_{'BWD' if button.endswith('FWD') else 'FWD'}", hold=hold / 2)
        w.press(button, hold, w.rng.uniform(0.3, 0.6))


def _tur10_fault(rng: random.Random) -> str:
    r = rng.random()
    if r < 0.4:
        return "stuck_drive axis=1"
    if r < 0.7:
        return f"slow_drive axis=1 factor={rng.choice((0.3, 0.5))}"
    return "dead_sensor axis=1"


TUR10_CONSOLE = Console(mode="SA7", button="SB1", spare="I15", step=None, teach=_tur10_teach,
                        faults=_tur10_fault, capacity=32, watchdog=20.0)


def _level(reference: float) -> int:
    a = abs(reference)
    lvl = 0 if a <= _STILL else 1 if a <= _SLOW else 2
    return lvl if reference >= 0 else -lvl


def _tur10_observe(plant: Any, previous: Any) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, d in plant.drives.items():
        lvl = _level(d.reference)
        prev = previous.get(f"link{k}") if previous else None
        if lvl == 0 and prev is not None and prev[0] == 0:
            out[f"link{k}"] = prev                 # at rest: where it stopped
        else:
            out[f"link{k}"] = (lvl, round(d.position) if lvl == 0 else 0)
    out["HL1"] = plant.reset_indicator
    return out


_LEVEL_WORDS = {2: "moving forward fast", 1: "moving forward slowly", -1: "moving backward slowly",
                -2: "moving backward fast"}


def _show_link(v: Any) -> str:
    lvl, pos = v
    return f"at rest at {pos} codes" if lvl == 0 else _LEVEL_WORDS[lvl]


def _same_link(a: Any, b: Any) -> bool:
    return a[0] == b[0] and abs(a[1] - b[1]) <= TUR10_BAND


def _same_motion(a: Any, b: Any) -> bool:
    return a[0] == b[0]


def _tur10_compared(task: str) -> tuple[Observed, ...]:
    out = [Observed("link1", _show_link, ("DRIVE1",), _same_link, tolerance=f"+/- {TUR10_BAND} codes")]
    if task == "task1":
        out += [Observed(f"link{k}", _show_link, (f"DRIVE{k}",), _same_motion, only_when=("SA7", 0, 0.5))
                for k in (2, 3, 4, 5)]
    out.append(Observed("HL1", lambda v: "on" if v else "off", ("HL1",)))
    return tuple(out)


TUR10 = Exploration(
    generate=lambda rng, task, seconds: generate(TUR10_CONSOLE, rng, task, seconds),
    observe=_tur10_observe, compared=_tur10_compared,
    references={"task1": "task1", "task2": "task2", "task3": "task3"},
    buttons=("SB1",) + tuple(f"SA{k}_{d}" for k in (1, 2, 3, 4, 5) for d in ("FWD", "BWD")),
    meaning={"SA7": ("manual", "automatic"), "SA6": ("normal speed", "low speed"),
             "I15": ("spare input off", "spare input on")},
    timing_tol=0.1, max_drift=1.0, episode_s=60.0, episodes=36, tick_s=0.01)
