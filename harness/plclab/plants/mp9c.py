"""MP-9C pneumatic cyclic robot (docs/mp9c.md, sections Plant and I/O map): the plant model.

Three double-acting cylinders on bistable 5/2 valves (lift, rotation, extension), a gripper on a
single-coil spring-return valve, reed switches SQ1..SQ7 at the end stops, and the operator
console (SA1..SA6, SB1, the spare I0.7). The console belongs to the plant model, not to the
scenario layer, because the plant is the single writer of every %IX input of the stand: the
harness steps the plant each tick and whatever it returns overwrites the input image.

A link position is the fraction of its travel: 0 is the power-up end (up, left, backward,
released), 1 the other end. Links move at constant speed and stop on their supports, so a
switch is ON only at exactly 0 or 1. Standard library only (OpenPLC runs the PSM script in its
own virtualenv).
"""
from __future__ import annotations

import inspect
import random
from typing import Any, Mapping

from plclab.plants.base import ConsoleFace, PlantError, PlantModel, unsigned16

# I/O map (docs/mp9c.md): console names -> OpenPLC locations.
SENSORS = {"SQ1": "IX0.0", "SQ2": "IX0.1", "SQ3": "IX0.2", "SQ4": "IX0.3",
           "SQ5": "IX0.4", "SQ6": "IX0.5", "SQ7": "IX0.6"}
CONSOLE = {"I07": "IX0.7", "SA1": "IX1.0", "SA2": "IX1.1", "SA3": "IX1.2", "SA4": "IX1.3",
           "SA5": "IX1.4", "SA6": "IX1.5", "SB1": "IX1.6"}
COILS = {"L1": "QX0.0", "L2": "QX0.1", "L3": "QX0.2", "L4": "QX0.3",
         "L5": "QX0.4", "L6": "QX0.5", "L7": "QX0.6"}
HL1 = "QX1.0"
MECHANISMS = ("lift", "rotation", "extension", "gripper")
# The console face (docs/openplc.md): coils SA1..SA6, SB1, I0.7; lamp HL1; link positions.
FACE = ConsoleFace(
    switches=("SA1", "SA2", "SA3", "SA4", "SA5", "SA6", "SB1", "I07"),
    lamps=(("HL1", HL1),),
    readouts=tuple((name, "thousandths of travel from the power-up end") for name in MECHANISMS))

_COIL_ITEMS = tuple(COILS.items())
_OUTPUT_LOCS = (*COILS.values(), HL1)
_EPS = 1e-9     # float sums of dt never hit 1.0 exactly; closer than this is "at the stop"


def _bit(value: Any, what: str) -> int:
    """0/1 from a bool, an int or 'on'/'off' (fault parameters are typed by people)."""
    if isinstance(value, str):
        if value.strip().lower() in ("on", "1", "true"):
            return 1
        if value.strip().lower() in ("off", "0", "false"):
            return 0
        raise PlantError(f"{what} must be on/off or 1/0, not {value!r}")
    return 1 if value else 0


class Link:
    """A link between two mechanical stops, driven toward the end its valve spool selects."""

    def __init__(self, name: str, travel_time: float, start_switch: str, end_switch: str | None):
        self.name = name
        self.travel_time = travel_time
        self.switches = (start_switch, end_switch)   # ON at position 0.0, at 1.0 (MP9C._reeds)
        self.position = 0.0      # fraction of travel, 0 = power-up end
        self.spool = 0           # the end the valve drives the link to

    def move(self, dt: float, slowdown: float) -> None:
        """Constant speed (full travel in travel_time * slowdown), clamped at the stops."""
        delta = dt / (self.travel_time * slowdown)
        if self.spool:
            self.position = min(1.0, self.position + delta)
            if self.position > 1.0 - _EPS:
                self.position = 1.0
        else:
            self.position = max(0.0, self.position - delta)
            if self.position < _EPS:
                self.position = 0.0


class Cylinder(Link):
    """Double-acting cylinder on a bistable double-solenoid valve.

    The spool remembers the last coil energized alone (so a one-scan pulse is enough to move
    the link all the way); both coils at once is a conflict: the spool stays. Conflict is judged
    on the commanded coils (it is the program's error even if a coil is dead).
    """

    def __init__(self, name: str, travel_time: float, start_switch: str, end_switch: str,
                 coil_start: str, coil_end: str):
        super().__init__(name, travel_time, start_switch, end_switch)
        self.coil_start = coil_start
        self.coil_end = coil_end
        self.conflict = False

    def drive(self, coils: Mapping[str, int], dead: str | None) -> bool:
        """Set the spool from the coils; True when a new conflict episode begins."""
        to_start, to_end = bool(coils[self.coil_start]), bool(coils[self.coil_end])
        began = to_start and to_end and not self.conflict
        self.conflict = to_start and to_end
        if not self.conflict:
            if to_start and self.coil_start != dead:
                self.spool = 0
            if to_end and self.coil_end != dead:
                self.spool = 1
        return began


class Gripper(Link):
    """Gripper on a single-coil valve: coil on = clamp, coil off = the spring opens it."""

    def __init__(self, name: str, travel_time: float, released_switch: str, coil: str):
        super().__init__(name, travel_time, released_switch, None)
        self.coil = coil
        self.conflict = False    # a single-coil valve cannot conflict

    def drive(self, coils: Mapping[str, int], dead: str | None) -> bool:
        self.spool = int(bool(coils[self.coil]) and self.coil != dead)
        return False


def _console_aliases() -> dict[str, str]:
    """'SA5', 'IX1.4', '%IX1.4' and S7 'I1.4' all name the same console input."""
    aliases = {}
    for name, loc in CONSOLE.items():
        aliases[name] = aliases[loc] = aliases["I" + loc[2:]] = name
    return aliases


_ALIASES = _console_aliases()


def chatter(rng: random.Random, new: int, max_duration: float) -> list[tuple[float, int]]:
    """One contact-bounce burst as (offset s, value) transitions ending on `new`.

    The contact changes at once, then bounces at random intervals for 50..100 % of
    max_duration, then stays at `new`; `rng` makes the burst reproducible.
    """
    duration = max_duration * rng.uniform(0.5, 1.0)
    burst = [(0.0, new)]
    t, value = 0.0, new
    while True:
        t += duration * rng.uniform(0.05, 0.25)
        if t >= duration:
            break
        value ^= 1
        burst.append((t, value))
    burst.append((duration, new))
    return burst


class Console:
    """The stand's console: switches SA1..SA6, button SB1 and the spare input I0.7.

    `values` is what the operator set; `reported` is what the contacts show the PLC at plant
    time (different only during a bounce burst). A change takes effect at the plant's current
    time, so the next step reports it.
    """

    def __init__(self, plant: "MP9C"):
        self._plant = plant
        self.values = {name: 0 for name in CONSOLE}
        self.reported = dict(self.values)
        self._pending: dict[str, list[tuple[float, int]]] = {name: [] for name in CONSOLE}
        self.changes = 0          # counts every change of `values` or `reported` (the plant's rest shortcut)

    def set(self, **values: Any) -> None:
        """Set several inputs at once: console.set(SA1=0, SA5=1, I07=1)."""
        for name, value in values.items():
            self.set_input(name, value)

    def set_input(self, name: str, value: Any) -> None:
        """Set one console input (by console name or location); bounces if 'bounce' is injected."""
        name = self.canonical(name)
        value = _bit(value, name)
        if value == self.values[name]:
            return
        self.values[name] = value
        self.changes += 1
        now = self._plant.time
        burst = self._plant.bounce_burst(value)
        self._pending[name] = [(now + offset, v) for offset, v in burst]
        self._settle(name, now)

    set_switch = set_input

    def press(self, name: str = "SB1") -> None:
        self.set_input(name, 1)

    def release(self, name: str = "SB1") -> None:
        self.set_input(name, 0)

    @staticmethod
    def canonical(name: str) -> str:
        key = name.strip().lstrip("%").upper()
        if key not in _ALIASES:
            raise PlantError(f"unknown console input {name!r} (one of {', '.join(CONSOLE)})")
        return _ALIASES[key]

    def pending(self) -> bool:
        """Whether a bounce burst still has transitions to report."""
        return any(self._pending.values())

    def advance(self, now: float) -> None:
        """Apply the bounce transitions due by plant time `now`."""
        for name, pending in self._pending.items():
            if pending:                   # nothing pending (every tick but a bounce's few)
                self._settle(name, now)

    def _settle(self, name: str, now: float) -> None:
        pending = self._pending[name]
        while pending and pending[0][0] <= now + _EPS:
            self.reported[name] = pending.pop(0)[1]
            self.changes += 1


class MP9C(PlantModel):
    """The MP-9C robot with its console, as the PLC sees it through the I/O map."""

    outputs = [*COILS.values(), HL1]
    inputs = [*SENSORS.values(), *CONSOLE.values()]
    FACE = FACE
    FAULTS = {
        "stuck_switch": "switch=SQ1..SQ7 reads state=1/0 (on/off) whatever the link does",
        "jammed": "mechanism=lift|rotation|extension|gripper stops where it is",
        "low_pressure": "all travel times x factor (default: the plant's low_pressure_factor, 3)",
        "dead_coil": "coil=L1..L7: energizing it does nothing",
        "bounce": "each console input change chatters for up to duration s (default 0.02), "
                  "reproducibly (seed, default 0)",
    }

    def __init__(self, *, lift_time: float = 0.8, rotation_time: float = 1.2,
                 extension_time: float = 1.0, gripper_time: float = 0.3,
                 low_pressure_factor: float = 3.0, bounce_time: float = 0.02,
                 period: float = 0.01):
        super().__init__()
        for what, value in (("lift_time", lift_time), ("rotation_time", rotation_time),
                            ("extension_time", extension_time), ("gripper_time", gripper_time),
                            ("low_pressure_factor", low_pressure_factor),
                            ("bounce_time", bounce_time), ("period", period)):
            if not isinstance(value, (int, float)) or not value > 0:
                raise PlantError(f"mp9c: {what} must be a positive number of seconds, not {value!r}")
        self.low_pressure_factor = float(low_pressure_factor)
        self.bounce_time = float(bounce_time)
        self.period = float(period)
        self.lift = Cylinder("lift", lift_time, "SQ1", "SQ2", "L2", "L3")
        self.rotation = Cylinder("rotation", rotation_time, "SQ4", "SQ5", "L4", "L5")
        self.extension = Cylinder("extension", extension_time, "SQ7", "SQ6", "L7", "L6")
        self.gripper = Gripper("gripper", gripper_time, "SQ3", "L1")
        self.links: dict[str, Cylinder | Gripper] = {
            link.name: link for link in (self.lift, self.rotation, self.extension, self.gripper)}
        self.console = Console(self)
        # each reed switch, SENSORS order: (location, its link, the position where it is ON)
        self._reeds = tuple((SENSORS[switch], link, float(end))
                            for name in SENSORS for link in self.links.values()
                            for end, switch in enumerate(link.switches) if switch == name)
        self.coils = {name: 0 for name in COILS}
        self.hl1 = 0
        self._bounce_rng = random.Random(0)
        # (outputs, console changes, inputs, fault changes) of the last step of time, and
        # whether it ended at rest (every link at its spool's end or jammed, no bounce under way)
        self._last: tuple[Any, int, dict[str, int], int] | None = None
        self._quiet = False

    # -- console shortcuts (scenarios read better with plant.press("SB1")) -------------------
    def set_input(self, name: str, value: Any) -> None:
        self.console.set_input(name, value)

    set_switch = set_input

    def press(self, name: str = "SB1") -> None:
        self.console.press(name)

    def release(self, name: str = "SB1") -> None:
        self.console.release(name)

    # -- stepping -------------------------------------------------------------------------------
    REST_SHORTCUT = True     # False: every step computed in full (the tests compare both)

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, int]:
        """Valves take the coil states at the start of the interval, links move for dt.

        Under the same outputs as the step before, with the same faults and the console as it
        was, the valves stay as they are: at rest (every link at the end its spool selects, no
        bounce under way) nothing can change but the time, and a link on its way only moves on,
        so the step returns the inputs it returned then unless a link reached or left an end.
        Most of a robot's scans are such (a pause, a wait for the operator, a travel), and
        this is where the closed loop spent most of its time."""
        if dt < 0:
            raise PlantError(f"mp9c: dt must not be negative ({dt})")
        seen = tuple(map(outputs.get, _OUTPUT_LOCS))
        last = self._same_valves(seen, dt)
        if last is not None:
            if self._quiet:
                self.time += dt
                return dict(last[2])
            if not self.console.pending():
                return self._travel(dt, last)
        inputs = self._step(outputs, dt)
        # a zero-length step drives no valve: only a step of time says what the outputs did;
        # links and bounces move only in a step, so "at rest" holds until the next one (or a
        # console change, which the count says)
        if dt == 0:
            self._last, self._quiet = None, False
        else:
            self._last = (seen, self.console.changes, dict(inputs), self.fault_changes)
            self._quiet = self._at_rest() and not self.console.pending()
        return inputs

    def _same_valves(self, outputs: tuple[Any, ...], dt: float) -> tuple[Any, int, dict[str, int], int] | None:
        """The last step's record where a step of dt under `outputs` keeps the valves as that
        step left them (the same outputs, the console as it was, the same faults: a fault
        acts the same way at every step it stays); else None."""
        last = self._last
        if (last is not None and dt > 0 and last[0] == outputs and last[1] == self.console.changes
                and last[3] == self.fault_changes and self.REST_SHORTCUT):
            return last
        return None

    def _fault_effects(self) -> tuple[str | None, str | None, float]:
        """(dead coil, jammed mechanism, slowdown factor) of the injected faults."""
        faults = self.faults
        if not faults:
            return None, None, 1.0
        return (faults.get("dead_coil", {}).get("coil"), faults.get("jammed", {}).get("mechanism"),
                faults.get("low_pressure", {}).get("factor", 1.0))

    def _travel(self, dt: float, last: tuple[Any, int, dict[str, int], int]) -> dict[str, int]:
        """`_step` under the valves of the step before (no bounce under way): only the links
        move, as the faults let them; the inputs are read again where one reached an end. (A
        link leaves an end only in the step that turns its valve, which is a full one.)"""
        _dead, jammed, slowdown = self._fault_effects()
        ends = False
        for link in self.links.values():
            if link.name == jammed:
                continue
            before = link.position
            link.move(dt, slowdown)
            after = link.position
            if after != before and (after == 0.0 or after == 1.0):
                ends = True
        self.time += dt
        self.console.advance(self.time)          # nothing pending: as _step, for the record
        if not ends:
            inputs = dict(last[2])
        else:
            inputs = self.read()
            self._last = (last[0], last[1], dict(inputs), last[3])
        self._quiet = self._at_rest()
        return inputs

    def idle(self, outputs: tuple[int, ...], dt: float) -> bool:
        """The plant contract's optional shortcut (plclab.runtime.plantio): would a step of dt
        under `outputs` (the values of self.outputs, in order) change nothing but the time?
        Then the time has moved on by dt and the answer is True: the inputs, switches, spools
        and lamp are those of the last step. The closed loop then neither builds the outputs
        nor writes the inputs again, and a grader's probe need not look (most scans of a
        robot: a pause, a wait for the operator)."""
        if self._quiet and self._same_valves(outputs, dt) is not None:
            self.time += dt
            return True
        return False

    def _at_rest(self) -> bool:
        """Every link at the end its spool drives it to, or jammed: the same coils move nothing."""
        jammed = self.faults.get("jammed", {}).get("mechanism") if self.faults else None
        for link in self.links.values():
            if link.position != link.spool and link.name != jammed:
                return False
        return True

    def _step(self, outputs: dict[str, int], dt: float) -> dict[str, int]:
        get = outputs.get
        self.coils = {name: 1 if get(loc, 0) else 0 for name, loc in _COIL_ITEMS}
        self.hl1 = 1 if get(HL1, 0) else 0
        if dt > 0:
            dead, jammed, slowdown = self._fault_effects()
            for link in self.links.values():
                if link.drive(self.coils, dead):
                    self.event("valve_conflict",
                               f"{link.name} valve: {link.coil_start} and {link.coil_end} both energized")
                if link.name != jammed:
                    link.move(dt, slowdown)
            self.time += dt
            self.console.advance(self.time)
        return self.read()

    def readouts(self) -> list[int]:
        """Lift, rotation, extension and gripper positions in thousandths of their travel."""
        return [unsigned16(round(self.links[name].position * 1000)) for name in MECHANISMS]

    def switches(self) -> dict[str, int]:
        """SQ1..SQ7 as the reed switches report them (a stuck switch wins)."""
        return dict(zip(SENSORS, self._reed_states().values()))

    def _reed_states(self) -> dict[str, int]:
        """SQ1..SQ7 by location (a stuck switch wins): a switch is ON only at its own end stop."""
        values = {loc: 1 if link.position == at else 0 for loc, link, at in self._reeds}
        stuck = self.faults.get("stuck_switch")
        if stuck:
            values[SENSORS[stuck["switch"]]] = stuck["state"]
        return values

    def read(self) -> dict[str, int]:
        """Every %IX input of the stand by location, as step() returns it."""
        values = self._reed_states()
        reported = self.console.reported
        values.update(zip(map(CONSOLE.__getitem__, reported), reported.values()))
        return values

    def snapshot(self) -> dict[str, Any]:
        """A flat, plot-friendly view: positions, spools, conflicts, switches, console, coils."""
        snap: dict[str, Any] = {"time": self.time}
        for link in self.links.values():
            snap[link.name] = link.position
            snap[f"{link.name}.spool"] = link.spool
            snap[f"{link.name}.conflict"] = int(link.conflict)
        snap.update(self.switches())
        snap.update(self.console.reported)
        snap.update(self.coils)
        snap["HL1"] = self.hl1
        snap["faults"] = sorted(self.faults)
        return snap

    # -- faults ---------------------------------------------------------------------------------
    def bounce_burst(self, new: int) -> list[tuple[float, int]]:
        """The transitions one console change produces now: a clean edge unless 'bounce' is on."""
        bounce = self.faults.get("bounce")
        if not bounce:
            return [(0.0, new)]
        return chatter(self._bounce_rng, new, bounce["duration"])

    def inject(self, fault: str, **params: Any) -> None:
        """Check and complete the parameters (one-line errors), then record the fault."""
        if fault in self.FAULTS:
            params = self._fault_params(fault, params)
            if fault == "bounce":
                self._bounce_rng = random.Random(params["seed"])
        super().inject(fault, **params)

    def clear(self, fault: str | None = None) -> None:
        for name in ([fault] if fault else sorted(self.faults)):
            if name in self.faults:
                self.event("fault_cleared", name)
        super().clear(fault)

    def _fault_params(self, fault: str, params: dict[str, Any]) -> dict[str, Any]:
        defaults: dict[str, dict[str, Any]] = {
            "stuck_switch": {"switch": None, "state": 1},
            "jammed": {"mechanism": None},
            "low_pressure": {"factor": self.low_pressure_factor},
            "dead_coil": {"coil": None},
            "bounce": {"duration": self.bounce_time, "seed": 0},
        }[fault]
        unknown = set(params) - set(defaults)
        if unknown:
            raise PlantError(f"{fault}: unknown parameter {sorted(unknown)[0]!r} "
                             f"(it takes {', '.join(defaults)})")
        full = {**defaults, **params}
        missing = [k for k, v in full.items() if v is None]
        if missing:
            raise PlantError(f"{fault}: say which {missing[0]} (e.g. {fault}, {missing[0]}=...)")

        def one_of(key: str, names: tuple[str, ...] | dict[str, str], upper: bool = True) -> str:
            value = str(full[key]).strip()
            value = value.upper() if upper else value.lower()
            if value not in names:
                raise PlantError(f"{fault}: unknown {key} {full[key]!r} (one of {', '.join(names)})")
            return value

        if fault == "stuck_switch":
            full["switch"] = one_of("switch", SENSORS)
            full["state"] = _bit(full["state"], "stuck_switch state")
        elif fault == "jammed":
            full["mechanism"] = one_of("mechanism", MECHANISMS, upper=False)
        elif fault == "dead_coil":
            full["coil"] = one_of("coil", COILS)
        else:
            key = "factor" if fault == "low_pressure" else "duration"
            if not isinstance(full[key], (int, float)) or not full[key] > 0:
                raise PlantError(f"{fault}: {key} must be a positive number, not {full[key]!r}")
            full[key] = float(full[key])
        return full


def create(**params: Any) -> MP9C:
    """Entry point of make_plant('mp9c', ...): an unknown parameter is a one-line error."""
    if not params:                 # the defaults (every session of a grading): nothing to check
        return MP9C()
    known = inspect.signature(MP9C.__init__).parameters
    unknown = [name for name in params if name not in known or name == "self"]
    if unknown:
        names = ", ".join(n for n in known if n != "self")
        raise PlantError(f"mp9c: unknown parameter {unknown[0]!r} (one of {names})")
    return MP9C(**params)
