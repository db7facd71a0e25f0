"""How the virtual lab's page shows each stand: labels as the console prints them, hints,
fault parameter choices, the signals trended by default and the plant state the mimic
drawing needs. Presentation only.

What the page has -- the console's contacts in console order, the lamps (and, where the
page draws them, the valve coils and limit switches), the injectable faults and their
parameters -- is what the stand declares once in its StandSpec (plclab.stands.base); each
`Panel` here is derived from that spec and a `Look`. A look that names something the stand
does not have is an error when the panel is built, so the two cannot drift apart. The page
builds its controls from the panel, so a label here is the accessible name a test (or a
screen reader) finds.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

from plclab.errors import PlcLabError
from plclab.lab.cncview import CncPart, cnc_mimic, set_backlash, set_fine_cycle, set_override
from plclab.scenario import ScenarioFailure, Session
from plclab.stands.base import StandSpec, stand_spec


@dataclass(frozen=True)
class Control:
    """A console contact: a toggle `switch` or a push `button` (pressed while held)."""

    label: str            # accessible name: 'SA5', 'SA1 forward', 'I0.7'
    input: str            # the plant's console name: 'SA5', 'SA1_FWD', 'I07'
    kind: str             # 'switch' | 'button'
    hint: str = ""        # what the contact does, shown beside it
    latching: bool = False   # a button that stays pressed until pressed again (an emergency stop)

    @property
    def signal(self) -> str:
        """The GVL label of the contact (trace name)."""
        return self.input


@dataclass(frozen=True)
class Lamp:
    """A lamp, a valve coil or a limit switch: on or off."""

    label: str
    hint: str = ""
    group: str = "lamp"   # 'lamp' (console), 'coil' (valve coil), 'switch' (limit switch)


@dataclass(frozen=True)
class FaultParam:
    name: str
    choices: tuple[str, ...] = ()     # empty: a number
    default: str = ""


@dataclass(frozen=True)
class Fault:
    name: str
    text: str
    params: tuple[FaultParam, ...] = ()


def _no_frames(s: Session) -> Any:
    return None


@dataclass(frozen=True)
class Knob:
    """A console setting that is not a contact: a potentiometer (the CNC's feed override
    RP1) or a plant setting the lab offers (the CNC's backlash)."""

    label: str
    lo: int
    hi: int
    unit: str
    initial: int
    hint: str
    apply: Callable[[Session, int], None] = field(repr=False, default=lambda s, v: None)


@dataclass(frozen=True)
class Panel:
    stand: str
    controls: tuple[Control, ...]
    lamps: tuple[Lamp, ...]
    faults: tuple[Fault, ...]
    trends: tuple[str, ...]                          # signals trended when the page opens
    trend_window: float = 60.0                       # plant seconds a trend shows
    trend_units: Mapping[str, tuple[float, str]] = field(default_factory=dict)   # signal -> (factor, unit)
    trend_overlays: Mapping[str, str] = field(default_factory=dict)  # trend -> signal drawn over it
    mimic: Callable[[Session], dict[str, Any]] = field(repr=False, default=lambda s: {})
    frames: Callable[[Session], Any] = field(repr=False, default=_no_frames)   # the recorded program
    knobs: tuple[Knob, ...] = ()
    part: Any = None             # CNC: load_part(session, text, name, method) -> str, and its methods

    def control(self, label: str) -> Control:
        for c in self.controls:
            if c.label == label:
                return c
        raise KeyError(label)

    def describe(self) -> dict[str, Any]:
        """The static part of the page, sent once when a page connects."""
        return {
            "stand": self.stand,
            "controls": [{"label": c.label, "kind": c.kind, "hint": c.hint, "signal": c.signal, "latching": c.latching}
                         for c in self.controls],
            "lamps": [{"label": lamp.label, "hint": lamp.hint, "group": lamp.group} for lamp in self.lamps],
            "faults": [{"name": f.name, "text": f.text,
                        "params": [{"name": p.name, "choices": list(p.choices), "default": p.default}
                                   for p in f.params]} for f in self.faults],
            "knobs": [{"label": k.label, "lo": k.lo, "hi": k.hi, "unit": k.unit, "initial": k.initial, "hint": k.hint}
                      for k in self.knobs],
            "part": self.part.describe() if self.part is not None else None,
            "trend_units": {k: list(v) for k, v in self.trend_units.items()},
            "trend_overlays": dict(self.trend_overlays),
        }

    def knob(self, label: str) -> Knob:
        for k in self.knobs:
            if k.label == label:
                return k
        raise KeyError(label)


# Which of a spec's I/O groups the page draws as lamps, and in which lamp group.
LAMP_GROUPS = {"actuators": "coil", "lamps": "lamp", "sensors": "switch"}


@dataclass(frozen=True)
class Look:
    """How one stand is shown; every key names a console input, a GVL label, a fault or a
    fault parameter of the stand's StandSpec."""

    labels: Mapping[str, str] = field(default_factory=dict)     # console input -> printed label
    hints: Mapping[str, str] = field(default_factory=dict)      # GVL label -> what it does
    buttons: frozenset[str] = frozenset()                       # push buttons; other inputs are switches
    latching: frozenset[str] = frozenset()                      # push buttons that latch (mushroom buttons)
    lamp_groups: tuple[str, ...] = ("lamps",)                   # spec groups drawn as lamps, in order
    fault_texts: Mapping[str, str] = field(default_factory=dict)   # short text (default: the spec's)
    # (fault, parameter) -> (choices, default); a parameter not here is a number field
    fault_params: Mapping[tuple[str, str], tuple[tuple[str, ...], str]] = field(default_factory=dict)
    trends: tuple[str, ...] = ()
    trend_window: float = 60.0      # plant seconds a trend shows (thermo: its 300-s step response)
    trend_units: Mapping[str, tuple[float, str]] = field(default_factory=dict)   # signal -> (factor, unit) shown
    trend_overlays: Mapping[str, str] = field(default_factory=dict)  # trend -> a signal drawn over it (same unit)
    mimic: Callable[[Session], dict[str, Any]] = field(repr=False, default=lambda s: {})
    frames: Callable[[Session], Any] = field(repr=False, default=_no_frames)
    knobs: tuple[Knob, ...] = ()    # settings that are not contacts (their labels leave the console)
    part: Any = None


def derive_panel(spec: StandSpec, look: Look) -> Panel:
    """The page of `spec`'s stand as `look` shows it. A look naming what the stand does not
    have is a PlcLabError (a stale presentation entry)."""
    shown = {name for group in look.lamp_groups for name in getattr(spec, group)}
    params = {(f.name, p.name) for f in spec.faults for p in f.params}
    knobs = {k.label for k in look.knobs}
    stale = [*(k for k in look.labels if k not in spec.console), *(b for b in look.buttons if b not in spec.console),
             *(b for b in look.latching if b not in look.buttons),
             *(k for k in look.hints if k not in set(spec.console) | shown),
             *(k for k in look.fault_texts if k not in {f.name for f in spec.faults}),
             *(f"{f}.{p}" for f, p in look.fault_params if (f, p) not in params),
             *(g for g in look.lamp_groups if g not in LAMP_GROUPS)]
    if stale:
        raise PlcLabError(f"lab panel of {spec.name}: {', '.join(stale)} not in the stand's StandSpec")
    controls = tuple(Control(look.labels.get(i, i), i, "button" if i in look.buttons else "switch",
                             look.hints.get(i, ""), i in look.latching) for i in spec.console if i not in knobs)
    lamps = tuple(Lamp(name, look.hints.get(name, ""), LAMP_GROUPS[group])
                  for group in look.lamp_groups for name in getattr(spec, group))
    faults = tuple(Fault(f.name, look.fault_texts.get(f.name, f.doc),
                         tuple(_fault_param(look, f.name, p) for p in f.params)) for f in spec.faults)
    return Panel(spec.name, controls, lamps, faults, look.trends, look.trend_window, look.trend_units,
                 look.trend_overlays, look.mimic, look.frames, look.knobs, look.part)


def _fault_param(look: Look, fault: str, param: Any) -> FaultParam:
    choices, default = look.fault_params.get((fault, param.name), ((), None))
    if default is None:
        default = "" if param.required or param.default is None else str(param.default)
    return FaultParam(param.name, choices, default)


# --------------------------------------------------------------------------- the recorded program

def recorded_program(s: Session) -> Any:
    """The control program in the PLC's frame memory, raw: (frames [(data words, pause ns or
    None)], the frame pointer, the playback phase), or None when the program has no frame
    memory where the stand's observables say (FrameCount: `Main.Cp.Count`). The phase is
    'frame' (frame Ptr being executed), 'pause' (the pause after frame Ptr), 'wait' (step
    mode: frame Ptr waits for the next press), 'between' (running, neither known) or
    'stopped' (read from the playback record's InFrame, State and Running, where it has them)."""
    count_path = s.observables.get("FrameCount")
    ptr_path = s.observables.get("FramePtr")
    if not count_path:
        return None
    try:
        cp = s.plc.read(count_path.rsplit(".", 1)[0])
        frames, count = cp.FRAMES, int(cp.COUNT)
    except Exception:        # noqa: BLE001 - a student's program need not have the shipped layout
        return None
    rows = []
    for frame in frames[:max(0, min(count, len(frames)))]:
        pause = getattr(frame, "PAUSE", None)
        rows.append(([int(v) for v in frame.DATA], int(pause) if isinstance(pause, int) else None))
    ptr = None
    phase = "stopped"
    if ptr_path:
        try:
            seq = s.plc.read(ptr_path.rsplit(".", 1)[0])
            ptr = int(seq.PTR)
            state = getattr(seq, "STATE", None)
            if bool(getattr(seq, "INFRAME", False)):
                phase = "frame"
            elif bool(getattr(seq, "RUNNING", False)):
                phase = {2: "pause", 3: "wait"}.get(state, "between") if isinstance(state, int) else "between"
        except Exception:    # noqa: BLE001
            pass
    return rows, ptr, phase


def _pause_text(pause: Any) -> str:
    return "1 s (fixed)" if pause is None else f"{pause / 1e9:g} s"


def _frame_table(s: Session, columns: list[str], decode: Callable[[list[int]], list[str]]) -> Any:
    """The table the page shows: the frames decoded, the one being executed (`current`), the
    one last done while the robot pauses or waits for a step press (`done`), the next one."""
    raw = recorded_program(s)
    if raw is None:
        return None
    rows, ptr, phase = raw
    count = len(rows)
    current = done = None
    nxt = ptr
    if phase == "frame":
        current = ptr
    elif phase == "pause" and ptr is not None:          # the pause after frame Ptr: Ptr is done
        done = ptr
        nxt = 1 if ptr >= count else ptr + 1
    elif phase == "wait" and ptr is not None:           # Ptr already moved on to the next frame
        done = count if ptr <= 1 else ptr - 1
    return {"columns": ["frame", *columns, "pause"], "current": current, "done": done, "next": nxt,
            "phase": phase, "rows": [[str(i), *decode(data), _pause_text(pause)]
                                     for i, (data, pause) in enumerate(rows, 1)]}


# --------------------------------------------------------------------------- MP-9C

def _mp9c_mimic(s: Session) -> dict[str, Any]:
    p = s.plant
    return {
        "lift": p.lift.position, "rotation": p.rotation.position, "extension": p.extension.position,
        "gripper": p.gripper.position,
        "conflict": [link.name for link in p.links.values() if link.conflict],
        "faults": sorted(p.faults),
    }


_SQ_HINTS = ("arm up", "arm down", "gripper released", "rotated left", "rotated right", "arm forward",
             "arm backward")
_L_HINTS = ("gripper clamp", "arm up", "arm down", "rotate left", "rotate right", "arm forward", "arm backward")


def _bits(word: int, names: tuple[str, ...], prefix: str) -> str:
    on = [f"{prefix}{i} {names[i - 1]}" for i in range(1, 8) if word >> (i - 1) & 1]
    return ", ".join(on) or "none"


def _mp9c_frames(s: Session) -> Any:
    """Word 1 the valve byte (L1..L7 packed, bit 0 = L1), word 2 the sensor byte the frame
    waits for (SQ1..SQ7): the coils energised and the position reached."""
    return _frame_table(s, ["valves energised", "position (limit switches made)"],
                        lambda d: [_bits(d[0], _L_HINTS, "L"), _bits(d[1], _SQ_HINTS, "SQ")])

MP9C = derive_panel(stand_spec("mp9c"), Look(
    labels={"I07": "I0.7"},
    hints={"SA1": "mode: off manual, on automatic", "SA2": "gripper: on clamp",
           "SA3": "rotation: off left, on right", "SA4": "extension: off backward, on forward",
           "SA5": "lift: off up, on down", "SA6": "automatic: off continuous, on step",
           "SB1": "short: record / start / stop; hold 3 s: reset", "I07": "spare input (Tasks 2, 3)",
           "HL1": "reset / fault indicator",
           **{f"L{i}": hint for i, hint in enumerate(_L_HINTS, 1)},
           **{f"SQ{i}": hint for i, hint in enumerate(_SQ_HINTS, 1)}},
    buttons=frozenset({"SB1"}),
    lamp_groups=("actuators", "lamps", "sensors"),       # coils L1..L7, HL1, limit switches SQ1..SQ7
    fault_texts={"stuck_switch": "a limit switch reads a fixed state", "jammed": "a mechanism stops where it is",
                 "low_pressure": "every travel takes longer", "dead_coil": "a valve coil does nothing",
                 "bounce": "console contacts chatter"},
    fault_params={("stuck_switch", "switch"): (tuple(f"SQ{i}" for i in range(1, 8)), "SQ1"),
                  ("stuck_switch", "state"): (("on", "off"), "on"),
                  ("jammed", "mechanism"): (("lift", "rotation", "extension", "gripper"), "lift"),
                  ("low_pressure", "factor"): ((), "3"),
                  ("dead_coil", "coil"): (tuple(f"L{i}" for i in range(1, 8)), "L3")},
    trends=("SB1", "SA1", "SQ1", "SQ2", "L2", "L3", "HL1"),
    mimic=_mp9c_mimic,
    frames=_mp9c_frames,
))


# --------------------------------------------------------------------------- TUR-10

def _tur10_mimic(s: Session) -> dict[str, Any]:
    p = s.plant
    targets = []
    for k in range(1, 6):
        try:                       # the stand's observable (one place names its ST path)
            targets.append(int(s.value(f"Target{k}")))
        except (ScenarioFailure, PlcLabError):   # a student's program need not have it
            targets.append(None)
    links = []
    for k, d in p.drives.items():
        links.append({"axis": k, "position": d.position, "code": p._code(k), "reference": d.reference,
                      "tripped": d.tripped, "at_stop": d.at_stop, "in_range": d.in_range,
                      "target": targets[k - 1]})
    return {"links": links, "selected": list(p.selected), "bus": p.bus, "working": list(p.working),
            "stops": list(p.stops), "dac_limit": p.dac_limit, "faults": sorted(p.faults)}


_AXIS = {1: "shoulder", 2: "raceme rotation", 3: "raceme inclination", 4: "platform rotation", 5: "hand"}


def _tur10_frames(s: Session) -> Any:
    """The five words: the link positions (sensor codes) the frame drives the links to."""
    return _frame_table(s, [f"{k} {name}" for k, name in _AXIS.items()], lambda d: [str(v) for v in d])

_WAYS = {"FWD": "forward", "BWD": "backward"}
_AXES = ("1", "2", "3", "4", "5")

TUR10 = derive_panel(stand_spec("tur10"), Look(
    labels={**{f"SA{k}_{w}": f"SA{k} {way}" for k in _AXIS for w, way in _WAYS.items()}, "I15": "I1.5"},
    hints={**{f"SA{k}_{w}": f"drive {k} ({_AXIS[k]}) {way}" for k in _AXIS for w, way in _WAYS.items()},
           "SA6": "low speed", "SB1": "short: record / start / stop; hold 3 s: reset",
           "SA7": "mode: off manual, on automatic", "I15": "spare input (Tasks 2, 3)", "HL1": "reset indicator"},
    # the jog controls are push buttons on the stand: the link moves while one is held
    buttons=frozenset({"SB1", *(f"SA{k}_{w}" for k in _AXIS for w in _WAYS)}),
    fault_texts={"dead_sensor": "a position sensor reads a constant", "stuck_drive": "a link does not move",
                 "slow_drive": "a link runs slower"},
    fault_params={("dead_sensor", "axis"): (_AXES, "1"), ("dead_sensor", "value"): ((), ""),
                  ("stuck_drive", "axis"): (_AXES, "1"),
                  ("slow_drive", "axis"): (_AXES, "1"), ("slow_drive", "factor"): ((), "0.5")},
    trends=("SB1", "SA7", "DRIVE1", "DRIVE2", "HL1"),
    mimic=_tur10_mimic,
    frames=_tur10_frames,
))


# --------------------------------------------------------------------------- thermo

def _thermo_mimic(s: Session) -> dict[str, Any]:
    from plclab.modbus.profiles import THERMO_MODES
    snap = s.plant.snapshot()
    try:                             # the SCADA registers the program works with (%MW0, %MW6)
        mode, setpoint = int(s.value("MODE")), int(s.value("SETPOINT"))
    except (ScenarioFailure, PlcLabError, TypeError, ValueError):
        mode = setpoint = None
    return {"mode": mode, "mode_name": THERMO_MODES.get(mode, f"unknown ({mode})") if mode is not None else None,
            "setpoint": setpoint,
            "temperature": snap["temperature_c"], "heater_w": snap["heater_w"], "fan_rpm": snap["fan_rpm"],
            "heater_command": snap["heater_command"], "fan_command": snap["fan_command"],
            "heater_max_w": s.plant.params.heater_max_w, "fan_max_rpm": s.plant.params.fan_max_rpm,
            "faults": snap["faults"]}


THERMO = derive_panel(stand_spec("thermo"), Look(
    hints={"DISTURBANCE": "switch the disturbance on"},
    fault_texts={"sensor_open": "temperature sensor open circuit", "fan_stalled": "fan rotor jammed",
                 "heater_dead": "heater burnt out"},
    trends=("TEMP_ADC", "SETPOINT", "HEATER", "FAN", "DISTURBANCE"),
    trend_window=600.0,
    # the raw ADC shown in degC (10 counts per degC) on one scale with the setpoint, drawn over it
    trend_units={"TEMP_ADC": (0.1, "\u00b0C"), "SETPOINT": (1.0, "\u00b0C"), "TEMPERATURE": (1.0, "\u00b0C")},
    trend_overlays={"TEMP_ADC": "SETPOINT"},
    mimic=_thermo_mimic,
))

CNC = derive_panel(stand_spec("cnc"), Look(
    hints={"SB1": "start the part program", "SB2": "stop / feed hold", "SA1": "single block",
           "SB3": "emergency stop: latches when pressed, press again to release", "HL1": "program running",
           "HL2": "fault / emergency stop"},
    buttons=frozenset({"SB1", "SB2", "SB3"}),
    latching=frozenset({"SB3"}),          # a mushroom button: stays pressed until released
    lamp_groups=("lamps",),
    fault_texts={"slow_drive": "a drive misses steps above a rate"},
    fault_params={("slow_drive", "axis"): (("X", "Y", "Z"), "X"), ("slow_drive", "rate"): ((), "1000")},
    trends=("SB1", "HL1", "CNT_X", "CNT_Y"),
    knobs=(Knob("RP1", 0, 150, "%", 100, "feed override", set_override),
           Knob("backlash", 0, 50, "steps", 0, "play of every axis's transmission", set_backlash),
           Knob("FINE_MS", 1, 20, "ms", 1, "fine cycle (5: as OpenPLC runs it)", set_fine_cycle)),
    part=CncPart(),
    mimic=cnc_mimic,
))

PANELS = {p.stand: p for p in (MP9C, TUR10, THERMO, CNC)}
