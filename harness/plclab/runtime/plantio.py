"""Connecting plant models to the process image.

A plant is a plain object (docs/contributing.md): `outputs` (the PLC outputs it reads, OpenPLC location
names such as "QX0.1" or "QW0"), `period` (seconds between steps in real time) and
`step(outputs, dt) -> inputs`, where both dicts map location names to raw values (bits 0/1,
words unsigned 16-bit) and dt is in seconds. The same object runs in-process here and in a
real OpenPLC runtime through the PSM protocol (plclab.modbus.psm), which uses the same names.

The exchange runs once per scan next to the scan itself, so it is generated code: one
function builds the outputs dict from the image cells, another writes a step's inputs back
(by the names the plant returned last time, looked up once), instead of a loop over names.
"""
from __future__ import annotations

from typing import Any, Callable, Optional, Protocol

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
        self._writer: Optional[Callable[[dict[str, Any]], None]] = None
        self._writer_size = -1       # how many names the generated writer writes
        self._compiles = 0

    def step(self, dt: float) -> None:
        self.write_inputs(self.plant.step(self.read_outputs(), dt))

    def _compile_reader(self) -> Callable[[], dict[str, int]]:
        """`read_outputs()`: the plant's outputs as the PLC's last scan left them in the image,
        a new dict each call (the plant may keep it)."""
        ns: dict[str, Any] = {}
        items = []
        for n, (loc, area, i) in enumerate(self._outs):
            ns[f"a{n}"] = area                    # the image's area lists are never replaced
            items.append(f"{loc!r}: a{n}[{i}]")
        source = "def read_outputs():\n    return {" + ", ".join(items) + "}\n"
        exec(compile(source, "<plant-outputs>", "exec"), ns)
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
                writer(inputs)                    # the same names as last time (nearly always)
                return
            except KeyError:                      # other names of the same count: written below
                pass
        for loc, value in inputs.items():
            area, i, mask = self._cell(loc)
            area[i] = int(value) & mask
        if self._compiles < MAX_WRITER_COMPILES:  # a plant that returns other names each step
            self._compiles += 1                   # keeps the loop above
            self._writer, self._writer_size = self._compile_writer(list(inputs)), len(inputs)

    def _compile_writer(self, names: list[str]) -> Optional[Callable[[dict[str, Any]], None]]:
        """A function writing exactly `names` of an inputs dict into their image cells, or None
        where two names share a cell (then the dict's order decides, as the loop keeps it)."""
        ns: dict[str, Any] = {"int": int}
        lines = ["def write(d):"]
        cells = set()
        for n, loc in enumerate(names):
            area, i, mask = self._cell(loc)
            if (id(area), i) in cells:
                return None
            cells.add((id(area), i))
            ns[f"a{n}"] = area
            lines.append(f"    a{n}[{i}] = int(d[{loc!r}]) & {mask}")
        lines.append("    return None")
        exec(compile("\n".join(lines) + "\n", "<plant-inputs>", "exec"), ns)
        return ns["write"]
