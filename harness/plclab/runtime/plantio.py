"""Connecting plant models to the process image.

A plant is a plain object (docs/contributing.md): `outputs` (the PLC outputs it reads, OpenPLC location
names such as "QX0.1" or "QW0"), `period` (seconds between steps in real time) and
`step(outputs, dt) -> inputs`, where both dicts map location names to raw values (bits 0/1,
words unsigned 16-bit) and dt is in seconds. The same object runs in-process here and in a
real OpenPLC runtime through the PSM protocol (plclab.modbus.psm), which uses the same names.

The exchange runs once per scan next to the scan itself, so it is generated code: one
function builds the outputs dict from the image cells, another writes a step's inputs back
(by the names the plant returned last time, looked up once), instead of a loop over names.

A plant may also offer `idle(outputs, dt) -> bool` (outputs: the values of `outputs`, in
order): True when a step of dt under those outputs would change nothing but its time, which
it then advances. Where the outputs and the input cells are what they were after the last
step and the plant says it is idle, the binding neither builds the outputs dict nor writes
the inputs again, and says so (`idle`) to whoever observes the plant after it in the scan.
"""
from __future__ import annotations

from typing import Any, Callable, Optional, Protocol

from plclab.runtime.gencode import define
from plclab.runtime.image import ProcessImage, image_slot


MAX_WRITER_COMPILES = 4       # input writers generated per binding before the plain loop stays


class Plant(Protocol):
    outputs: list[str]
    period: float

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, int]: ...


class PlantBinding:
    """One plant stepped against one image: reads its outputs, writes the inputs it returns."""

    def __init__(self, plant: Plant, image: ProcessImage):
        self.plant = plant
        self.image = image
        areas = image.areas
        self._outs = [(loc, areas[a], i) for loc in plant.outputs for a, i in [image_slot(loc, percent=False)]]
        self._cells: dict[str, tuple[list[int], int, int]] = {}   # input name -> (area, index, mask)
        self.read_outputs: Callable[[], dict[str, int]] = self._compile_reader()
        # the outputs' values in the plant's `outputs` order (what `idle` and `step_values` take)
        self.output_values: Callable[[], tuple[int, ...]] = self._compile_reader(as_tuple=True)
        self._writer: Optional[Callable[[dict[str, Any]], tuple[int, ...]]] = None
        self._writer_size = -1       # how many names the generated writer writes
        self._compiles = 0
        self._idle: Optional[Callable[[tuple[int, ...], float], bool]] = getattr(plant, "idle", None)
        self._written: Optional[tuple[int, ...]] = None    # what the last write put in the cells
        self._read_written: Optional[Callable[[], tuple[int, ...]]] = None
        self._stepped: Optional[tuple[int, ...]] = None    # the outputs of the last full step
        self.idle = False            # this scan's step changed nothing but the plant's time
        # the plant's step on values in order (the contract's optional form): no dicts
        self.step_values: Optional[Callable[[tuple[int, ...], float], tuple[int, ...]]] = \
            getattr(plant, "step_values", None)
        self._values_writer: Optional[tuple[Callable[[tuple[int, ...]], None], Callable[[], tuple[int, ...]]]] = None
        # a full step's three parts: read the outputs, step the plant, write what it returns
        # (on values in order where the plant offers step_values, else on dicts by name)
        self.exchange: tuple[Callable[[], Any], Callable[[Any, float], Any], Callable[[Any], None]] = \
            (self.output_values, self.step_values, self.write_values) if self.step_values is not None else \
            (self.read_outputs, plant.step, self.write_inputs)

    def step(self, dt: float) -> None:
        if self.step_idle(dt):
            return
        read, step, write = self.exchange
        # step_idle has just read this scan's output values into _stepped (where the plant has idle)
        write(step(self._stepped if self._idle is not None and self.step_values is not None else read(), dt))

    def write_values(self, values: tuple[int, ...]) -> None:
        """A `step_values` result (the values of the plant's `inputs`, in order, raw) into the
        image, one generated assignment per cell."""
        writer = self._values_writer
        if writer is None:
            writer = self._values_writer = self._compile_values_writer()
        writer[0](values)
        self._written, self._read_written = values, writer[1]

    def step_idle(self, dt: float) -> bool:
        """The step of dt where the plant is idle under unchanged outputs and its input cells
        still hold what it wrote last (nothing else wrote them): then only its time moves and
        the answer is True; else False, and the caller steps it in full (the outputs that
        step sees are remembered: most scans of a moving stand fail here, at one comparison)."""
        idle, written = self._idle, self._written
        if idle is None:
            return False
        outputs = self.output_values()
        if outputs != self._stepped:
            self._stepped = outputs
            self.idle = False
            return False
        self.idle = (written is not None and self._read_written() == written     # type: ignore[misc]
                     and idle(outputs, dt))
        return self.idle

    @property
    def can_idle(self) -> bool:
        """Whether the plant has the `idle` shortcut (the plant contract's optional method)."""
        return self._idle is not None

    def repeat_idle(self, count: int, dt: float) -> None:
        """`count` more idle steps of dt under the outputs of this tick's idle step: where the
        closed loop ran the scans of those ticks in one go (plclab.runtime.sim), the plant's
        time moves on as stepping it tick by tick would. The contract says `idle` holds for
        the same outputs; a plant that breaks it is the harness's bug, said as such."""
        idle, outputs = self._idle, self._stepped
        for _ in range(count):
            if idle is None or not idle(outputs, dt):
                raise RuntimeError(f"{type(self.plant).__name__}.idle changed its answer under the same outputs")

    def _compile_reader(self, as_tuple: bool = False) -> Callable[[], Any]:
        """`read_outputs()`: the plant's outputs as the PLC's last scan left them in the image,
        a new dict each call (the plant may keep it); `as_tuple`: their values only, in the
        plant's order (what `idle` compares)."""
        ns: dict[str, Any] = {}
        items = []
        for n, (loc, area, i) in enumerate(self._outs):
            ns[f"a{n}"] = area                    # the image's area lists are never replaced
            items.append(f"a{n}[{i}]" if as_tuple else f"{loc!r}: a{n}[{i}]")
        body = "(" + "".join(f"{x}, " for x in items) + ")" if as_tuple else "{" + ", ".join(items) + "}"
        define(f"def read_outputs():\n    return {body}\n", "<plant-outputs>", ns)
        return ns["read_outputs"]

    def _cell(self, loc: str) -> tuple[list[int], int, int]:
        cell = self._cells.get(loc)
        if cell is None:
            a, i = image_slot(loc, percent=False)
            cell = self._cells[loc] = (self.image.areas[a], i, 1 if a[1] == "X" else 0xFFFF)
        return cell

    def write_inputs(self, inputs: dict[str, Any]) -> None:
        """The inputs a plant step returned, into the image (raw, masked to the area's width)."""
        writer = self._writer
        if writer is not None and len(inputs) == self._writer_size:
            try:
                self._written = writer(inputs)    # the same names as last time (nearly always)
                return
            except KeyError:                      # other names of the same count: written below
                pass
        self._written = None                      # (idle needs a generated writer's record)
        for loc, value in inputs.items():
            area, i, mask = self._cell(loc)
            area[i] = int(value) & mask
        if self._compiles < MAX_WRITER_COMPILES:  # a plant that returns other names each step
            self._compiles += 1                   # keeps the loop above
            compiled = self._compile_writer(list(inputs))
            self._writer, self._read_written = compiled if compiled is not None else (None, None)
            self._writer_size = len(inputs)

    def _compile_values_writer(self) -> tuple[Callable[[tuple[int, ...]], None], Callable[[], tuple[int, ...]]]:
        """write(values): the plant's `inputs` cells set in order (a later name of the same cell
        wins, as in a dict's loop); read(): those cells' values, in the same order."""
        ns: dict[str, Any] = {}
        cells = []
        for n, loc in enumerate(self.plant.inputs):        # type: ignore[attr-defined]
            area, i, _mask = self._cell(loc)
            ns[f"a{n}"] = area
            cells.append(f"a{n}[{i}]")
        targets = "".join(f"{c}, " for c in cells)          # "a0[3], a0[4], ": a tuple either side
        src = (f"def write(v):\n    {targets}= v\n" if cells else "def write(v):\n    pass\n") + \
            f"def read():\n    return ({targets})\n"
        define(src, "<plant-input-values>", ns)
        return ns["write"], ns["read"]

    def _compile_writer(self, names: list[str]) -> Optional[tuple[Callable[[dict[str, Any]], tuple[int, ...]],
                                                                  Callable[[], tuple[int, ...]]]]:
        """A function writing exactly `names` of an inputs dict into their image cells and
        returning the values written, with one reading those cells back; None where two names
        share a cell (then the dict's order decides, as the loop keeps it)."""
        ns: dict[str, Any] = {"int": int}
        lines = ["def write(d):"]
        cells = set()
        for n, loc in enumerate(names):
            area, i, mask = self._cell(loc)
            if (id(area), i) in cells:
                return None
            cells.add((id(area), i))
            ns[f"a{n}"] = area
            lines.append(f"    v{n} = a{n}[{i}] = int(d[{loc!r}]) & {mask}")
        lines.append("    return (" + "".join(f"v{n}, " for n in range(len(names))) + ")")
        lines.append("def read():")
        lines.append("    return (" + "".join(f"a{n}[{self._cell(loc)[1]}], " for n, loc in enumerate(names)) + ")")
        define("\n".join(lines) + "\n", "<plant-inputs>", ns)
        return ns["write"], ns["read"]
