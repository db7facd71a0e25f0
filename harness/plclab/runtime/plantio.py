"""Connecting plant models to the process image.

A plant is a plain object (docs/contributing.md): `outputs` (the PLC outputs it reads, OpenPLC location
names such as "QX0.1" or "QW0"), `period` (seconds between steps in real time) and
`step(outputs, dt) -> inputs`, where both dicts map location names to raw values (bits 0/1,
words unsigned 16-bit) and dt is in seconds. The same object runs in-process here and in a
real OpenPLC runtime through the PSM protocol (plclab.modbus.psm), which uses the same names.
"""
from __future__ import annotations

from typing import Protocol

from plclab.runtime.image import ProcessImage, image_slot


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

    def step(self, dt: float) -> None:
        outputs = {loc: area[i] for loc, area, i in self._outs}
        cells = self._cells
        for loc, value in self.plant.step(outputs, dt).items():
            cell = cells.get(loc)
            if cell is None:
                a, i = image_slot(loc, percent=False)
                cell = cells[loc] = (self.image.areas[a], i, 1 if a[1] == "X" else 0xFFFF)
            area, i, mask = cell
            area[i] = int(value) & mask
