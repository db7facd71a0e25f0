"""What the virtual lab's page shows of each stand: its console (in console order), its lamps
and limit switches, the plant faults it can inject, the signals trended by default and the
plant state the mimic drawing needs.

The controls come in the stand's declared console order (`StandSpec.console`, tested to
agree); the labels are the stands' console and wiring labels (the GVLs), written the way the console
prints them (`I0.7`, `SA1 forward`); `input` is the plant's name for the same contact. The
page builds its controls from this table, so a label here is the accessible name a test (or
a screen reader) finds.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

from plclab.errors import PlcLabError
from plclab.scenario import ScenarioFailure, Session


@dataclass(frozen=True)
class Control:
    """A console contact: a toggle `switch` or a push `button` (pressed while held)."""

    label: str            # accessible name: 'SA5', 'SA1 forward', 'I0.7'
    input: str            # the plant's console name: 'SA5', 'SA1_FWD', 'I07'
    kind: str             # 'switch' | 'button'
    hint: str = ""        # what the contact does, shown beside it

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


@dataclass(frozen=True)
class Panel:
    stand: str
    controls: tuple[Control, ...]
    lamps: tuple[Lamp, ...]
    faults: tuple[Fault, ...]
    trends: tuple[str, ...]                          # signals trended when the page opens
    mimic: Callable[[Session], dict[str, Any]] = field(repr=False, default=lambda s: {})

    def control(self, label: str) -> Control:
        for c in self.controls:
            if c.label == label:
                return c
        raise KeyError(label)

    def describe(self) -> dict[str, Any]:
        """The static part of the page, sent once when a page connects."""
        return {
            "stand": self.stand,
            "controls": [{"label": c.label, "kind": c.kind, "hint": c.hint, "signal": c.signal}
                         for c in self.controls],
            "lamps": [{"label": lamp.label, "hint": lamp.hint, "group": lamp.group} for lamp in self.lamps],
            "faults": [{"name": f.name, "text": f.text,
                        "params": [{"name": p.name, "choices": list(p.choices), "default": p.default}
                                   for p in f.params]} for f in self.faults],
        }


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

MP9C = Panel(
    stand="mp9c",
    controls=(
        Control("SA1", "SA1", "switch", "mode: off manual, on automatic"),
        Control("SA2", "SA2", "switch", "gripper: on clamp"),
        Control("SA3", "SA3", "switch", "rotation: off left, on right"),
        Control("SA4", "SA4", "switch", "extension: off backward, on forward"),
        Control("SA5", "SA5", "switch", "lift: off up, on down"),
        Control("SA6", "SA6", "switch", "automatic: off continuous, on step"),
        Control("SB1", "SB1", "button", "short: record / start / stop; hold 3 s: reset"),
        Control("I0.7", "I07", "switch", "spare input (Tasks 2, 3)"),
    ),
    lamps=tuple(Lamp(f"L{i}", _L_HINTS[i - 1], "coil") for i in range(1, 8))
    + (Lamp("HL1", "reset / fault indicator"),)
    + tuple(Lamp(f"SQ{i}", _SQ_HINTS[i - 1], "switch") for i in range(1, 8)),
    faults=(
        Fault("stuck_switch", "a limit switch reads a fixed state",
              (FaultParam("switch", tuple(f"SQ{i}" for i in range(1, 8)), "SQ1"), FaultParam("state", ("on", "off"), "on"))),
        Fault("jammed", "a mechanism stops where it is",
              (FaultParam("mechanism", ("lift", "rotation", "extension", "gripper"), "lift"),)),
        Fault("low_pressure", "every travel takes longer", (FaultParam("factor", (), "3"),)),
        Fault("dead_coil", "a valve coil does nothing", (FaultParam("coil", tuple(f"L{i}" for i in range(1, 8)), "L3"),)),
        Fault("bounce", "console contacts chatter", (FaultParam("duration", (), "0.02"),)),
    ),
    trends=("SB1", "SA1", "SQ1", "SQ2", "L2", "L3", "HL1"),
    mimic=_mp9c_mimic,
)


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

TUR10 = Panel(
    stand="tur10",
    controls=tuple(
        Control(f"SA{k} {way}", f"SA{k}_{'FWD' if way == 'forward' else 'BWD'}", "switch",
                f"drive {k} ({_AXIS[k]}) {way}")
        for k in range(1, 6) for way in ("forward", "backward"))
    + (
        Control("SA6", "SA6", "switch", "low speed"),
        Control("SB1", "SB1", "button", "short: record / start / stop; hold 3 s: reset"),
        Control("SA7", "SA7", "switch", "mode: off manual, on automatic"),
        Control("I1.5", "I15", "switch", "spare input (Tasks 2, 3)"),
    ),
    lamps=(Lamp("HL1", "reset indicator"),),
    faults=(
        Fault("dead_sensor", "a position sensor reads a constant",
              (FaultParam("axis", ("1", "2", "3", "4", "5"), "1"), FaultParam("value", (), ""))),
        Fault("stuck_drive", "a link does not move", (FaultParam("axis", ("1", "2", "3", "4", "5"), "1"),)),
        Fault("slow_drive", "a link runs slower", (FaultParam("axis", ("1", "2", "3", "4", "5"), "1"),
                                                   FaultParam("factor", (), "0.5"))),
    ),
    trends=("SB1", "SA7", "DRIVE1", "DRIVE2", "HL1"),
    mimic=_tur10_mimic,
)


# --------------------------------------------------------------------------- thermo

def _thermo_mimic(s: Session) -> dict[str, Any]:
    snap = s.plant.snapshot()
    return {"temperature": snap["temperature_c"], "heater_w": snap["heater_w"], "fan_rpm": snap["fan_rpm"],
            "heater_command": snap["heater_command"], "fan_command": snap["fan_command"],
            "heater_max_w": s.plant.params.heater_max_w, "fan_max_rpm": s.plant.params.fan_max_rpm,
            "faults": snap["faults"]}


THERMO = Panel(
    stand="thermo",
    controls=(Control("DISTURBANCE", "DISTURBANCE", "switch", "switch the disturbance on"),),
    lamps=(),
    faults=(
        Fault("sensor_open", "temperature sensor open circuit"),
        Fault("fan_stalled", "fan rotor jammed"),
        Fault("heater_dead", "heater burnt out"),
    ),
    trends=("TEMP_ADC", "SETPOINT", "HEATER", "FAN", "DISTURBANCE"),
    mimic=_thermo_mimic,
)

PANELS = {p.stand: p for p in (MP9C, TUR10, THERMO)}
