"""The plant <-> image exchange (plclab.runtime.plantio): whatever a plant returns from a step
lands in the input image exactly as the plant contract says (raw values masked to the area's
width, every name it returned, nothing else), however the names change from step to step:
the generated writer that serves the usual case (the same names every step) must never
write what the plain loop would not."""
from __future__ import annotations

from typing import Any

import pytest

from plclab.runtime.image import ProcessImage
from plclab.runtime.plantio import MAX_WRITER_COMPILES, PlantBinding


class ScriptedPlant:
    """A plant that returns, step by step, the inputs it was given, and keeps the outputs it saw."""

    outputs = ["QX0.1", "QW2"]
    period = 0.01

    def __init__(self, steps: list[dict[str, Any]]):
        self.steps = list(steps)
        self.seen: list[dict[str, int]] = []

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, Any]:
        self.seen.append(outputs)
        return self.steps.pop(0)


def test_a_step_reads_the_outputs_and_writes_the_masked_inputs():
    image = ProcessImage()
    image.areas["QX"][1], image.areas["QW"][2] = 1, 1234
    plant = ScriptedPlant([{"IX0.0": True, "IX1.7": 3, "IW4": 70000, "IW5": 2.9}])
    PlantBinding(plant, image).step(0.01)
    assert plant.seen == [{"QX0.1": 1, "QW2": 1234}]
    ix, iw = image.areas["IX"], image.areas["IW"]
    assert (ix[0], ix[15], iw[4], iw[5]) == (1, 1, 70000 & 0xFFFF, 2)
    assert type(ix[0]) is int                        # a bool from the plant is stored as 0/1


def test_outputs_are_a_new_dict_each_step_a_plant_may_keep():
    image = ProcessImage()
    plant = ScriptedPlant([{}, {}])
    binding = PlantBinding(plant, image)
    binding.step(0.01)
    image.areas["QW"][2] = 7
    binding.step(0.01)
    assert plant.seen == [{"QX0.1": 0, "QW2": 0}, {"QX0.1": 0, "QW2": 7}]


def test_names_that_change_between_steps_write_exactly_what_each_step_returned():
    steps = [{"IX0.0": 1, "IW0": 5},
             {"IX0.0": 0, "IW0": 6},                 # the same names: the generated writer
             {"IX0.1": 1, "IW1": 9},                 # other names, as many
             {"IX0.0": 1},                           # fewer
             {"IX0.0": 0, "IW0": 8, "IW1": 10},      # more
             {"IW0": 11, "I0.0": 1},                 # S7 spelling of IX0.0, another order
             *({"IX0.2": n % 2, "IW2": n} for n in range(3 * MAX_WRITER_COMPILES))]
    image, plain = ProcessImage(), ProcessImage()
    binding = PlantBinding(ScriptedPlant(steps), image)
    for inputs in steps:
        binding.step(0.01)
        for name, value in inputs.items():           # what the contract says, written plainly
            area = "IX" if name.startswith(("IX", "I0")) else "IW"
            index = int(name[2:]) if area == "IW" else int(name[-3]) * 8 + int(name[-1])
            plain.areas[area][index] = int(value) & (1 if area == "IX" else 0xFFFF)
        assert image.areas == plain.areas, inputs


def test_two_names_of_one_cell_are_written_in_the_plants_order():
    image = ProcessImage()
    binding = PlantBinding(ScriptedPlant([{"IX0.0": 1, "I0.0": 0}, {"IX0.0": 1, "I0.0": 0},
                                          {"I0.0": 0, "IX0.0": 1}]), image)
    binding.step(0.01)
    assert image.areas["IX"][0] == 0
    binding.step(0.01)
    assert image.areas["IX"][0] == 0                 # the last of the dict wins, every step
    binding.step(0.01)
    assert image.areas["IX"][0] == 1


class IdlePlant:
    """A plant that is idle whenever asked under the outputs of its last full step."""

    outputs = ["QX0.1", "QW2"]
    period = 0.01

    def __init__(self):
        self.time, self.full_steps, self.last = 0.0, 0, None

    def step(self, outputs: dict[str, int], dt: float) -> dict[str, Any]:
        self.time += dt
        self.full_steps += 1
        self.last = (outputs["QX0.1"], outputs["QW2"])
        return {"IX0.0": 1, "IW0": 40 + self.full_steps}

    def idle(self, outputs: tuple[int, ...], dt: float) -> bool:
        if outputs != self.last:
            return False
        self.time += dt
        return True


def test_an_idle_plant_only_moves_its_time_until_an_output_or_one_of_its_input_cells_changes():
    """The closed loop's shortcut (a robot at rest): under the outputs of the last step the
    plant is asked whether it is idle, and then neither stepped nor its inputs written; an
    output that changes, or a cell of its inputs that something else wrote (a scenario's
    set, a force), steps it in full and its inputs are written again."""
    image = ProcessImage()
    plant = IdlePlant()
    binding = PlantBinding(plant, image)
    for _ in range(5):
        binding.step(0.01)
    # the first step writes by the plain loop, the second generates the writer: idle from then
    assert (plant.full_steps, binding.idle, image.areas["IW"][0]) == (2, True, 42)
    assert plant.time == pytest.approx(0.05)
    image.areas["QW"][2] = 9                          # an output changes
    binding.step(0.01)
    assert (plant.full_steps, binding.idle, image.areas["IW"][0]) == (3, False, 43)
    binding.step(0.01)
    assert (plant.full_steps, binding.idle) == (3, True)
    image.areas["IX"][0] = 0                          # someone else wrote an input cell
    binding.step(0.01)
    assert (plant.full_steps, binding.idle, image.areas["IX"][0]) == (4, False, 1)
    binding.step(0.01)
    assert (plant.full_steps, binding.idle, plant.time) == (4, True, pytest.approx(0.09))


class ValuesPlant(IdlePlant):
    """IdlePlant with the step on values in order too (the contract's optional form), which
    the binding then uses; a second input names the same cell as the first (the later wins)."""

    inputs = ["IX0.0", "IW0", "IX1.1", "IX1.1"]

    def step_values(self, outputs: tuple[int, ...], dt: float) -> tuple[int, ...]:
        self.seen_values = outputs
        got = self.step(dict(zip(self.outputs, outputs)), dt)
        return got["IX0.0"], got["IW0"], 1, self.full_steps % 2


def test_a_plant_stepped_on_values_gets_them_in_order_and_its_inputs_land_where_they_belong():
    """Where a plant has `step_values`, the binding builds no dict: the plant gets the outputs'
    values in its `outputs` order and its result lands in its `inputs` cells, in order (a
    later name of the same cell wins, as a dict's loop writes it); the idle shortcut holds
    from its second step, and a cell written by someone else steps it in full again."""
    image = ProcessImage()
    image.areas["QX"][1], image.areas["QW"][2] = 1, 7
    plant = ValuesPlant()
    binding = PlantBinding(plant, image)
    binding.step(0.01)
    assert plant.seen_values == (1, 7) and binding.output_values() == (1, 7)
    assert (image.areas["IX"][0], image.areas["IW"][0], image.areas["IX"][9]) == (1, 41, 1)
    for _ in range(3):
        binding.step(0.01)
    assert (plant.full_steps, binding.idle, plant.time) == (1, True, pytest.approx(0.04))
    image.areas["IW"][0] = 0                          # someone else wrote an input cell
    binding.step(0.01)
    assert (plant.full_steps, binding.idle, image.areas["IW"][0], image.areas["IX"][9]) == (2, False, 42, 0)
    other = ProcessImage()                            # a second binding of its kind: its own image
    PlantBinding(ValuesPlant(), other).step(0.01)
    assert (other.areas["IW"][0], image.areas["IW"][0]) == (41, 42)


def test_the_ticks_a_quiet_run_skipped_move_the_plants_time_and_a_broken_idle_is_said():
    """Where the closed loop ran several idle ticks' scans in one go, the binding moves the
    plant's time by as many idle steps; a plant whose `idle` says no under the same outputs
    breaks the contract, and that is raised as the harness's error, never taken as a step."""
    image = ProcessImage()
    plant = IdlePlant()
    binding = PlantBinding(plant, image)
    for _ in range(3):
        binding.step(0.01)
    assert binding.can_idle and binding.idle
    binding.repeat_idle(7, 0.01)
    assert plant.time == pytest.approx(0.10) and plant.full_steps == 2
    plant.last = None                       # its idle now says no to the same outputs
    with pytest.raises(RuntimeError, match="IdlePlant.idle changed its answer"):
        binding.repeat_idle(1, 0.01)
