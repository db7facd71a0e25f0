"""The plant inside OpenPLC, as OpenPLC drives it: the PSM server steps the plant once per
poll of OpenPLC's PSM client (psm.cpp, played byte for byte by OpenPlcPsm), the operator uses
the console face, and whatever the plant raises the PLC keeps its I/O.

The PLC side is this project's soft PLC running the TUR-10 program; the plant's clock is a
test clock advanced by each scan's period (10 ms, or a seeded jittery one), so the checks are
on positions and bus events, never on wall-clock durations."""
from __future__ import annotations

import random

import pytest

from modbus_support import TIMEOUT, OpenPlcPsm
from plclab.frontend import check_sources
from plclab.modbus.console import FAULT_LAMP
from plclab.modbus.psm import PlantService
from plclab.modbus.rawclient import RawModbusClient, RawModbusError
from plclab.plants import make_plant
from plclab.plants.host import PlantHost
from plclab.plants.tur10 import FACE
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.stands import get_stand, sources
from plclab.stands.tur10 import OBSERVABLES

# the ST paths of the stand's observables (the PLC here is read directly, not through a Session)
FRAME_COUNT, FRAME_PTR, IN_FRAME = (OBSERVABLES[n] for n in ("FrameCount", "FramePtr", "InFrame"))

LOOPBACK = ("127.0.0.1", 0)


class TestClock:
    """The plant's clock: what the real time between two polls would be."""

    __test__ = False

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


class OpenPlcWithProgram:
    """OpenPLC's main loop with the PSM hardware layer: each tick, updateBuffersIn (one PSM
    poll: the plant steps), the program, updateBuffersOut; PLC time advances one tick."""

    def __init__(self, program: list[tuple[str, str]], psm_port: int, clock: TestClock,
                 period: callable):
        self.plc = PLC(compile_unit(check_sources(program)))
        self.psm = OpenPlcPsm(psm_port)
        self.clock = clock
        self.period = period

    def scan(self) -> None:
        self.clock.now += self.period()
        self.psm.update_buffers_in(self.plc.image)
        assert self.plc.scan(), self.plc.fault
        self.psm.update_buffers_out(self.plc.image)
        self.plc.advance()

    def run(self, seconds: float) -> None:
        for _ in range(round(seconds / 0.01)):
            self.scan()

    def run_until(self, condition, seconds: float, what: str) -> None:
        for _ in range(round(seconds / 0.01)):
            if condition():
                return
            self.scan()
        raise AssertionError(f"{what}: not within {seconds} s of PLC time")


class Console:
    """An operator at the console face, with any Modbus client (coil n = FACE.switches[n])."""

    def __init__(self, port: int, openplc: OpenPlcWithProgram):
        self.client = RawModbusClient("127.0.0.1", port, unit=0, timeout=TIMEOUT)
        self.openplc = openplc

    def set(self, name: str, value: int) -> None:
        self.client.write_coil(FACE.switches.index(name), bool(value))

    def hold(self, name: str, seconds: float) -> None:
        self.set(name, 1)
        self.openplc.run(seconds)
        self.set(name, 0)

    def positions(self) -> list[int]:
        return self.client.read_input_registers(0, 5)


def teach_and_play(period: callable) -> tuple[list[list[int]], list[tuple[int, list[int]]], PlantHost]:
    """Teach four frames in manual mode through the console face, play them back in
    automatic mode for a whole cycle; (taught positions, [(frame, positions when the PLC
    says it reached it)], the plant host)."""
    clock = TestClock()
    host = PlantHost(make_plant("tur10"), clock=clock)
    with PlantService(host, LOOPBACK, LOOPBACK) as service:
        openplc = OpenPlcWithProgram(sources(get_stand("tur10"), "full"), service.psm.port, clock, period)
        console = Console(service.console.port, openplc)
        plc = openplc.plc
        taught: list[list[int]] = []

        def record() -> None:
            before = plc.read(FRAME_COUNT)
            console.hold("SB1", 0.2)
            openplc.run(0.2)
            assert plc.read(FRAME_COUNT) == before + 1, "a short SB1 press did not record a frame"
            taught.append(console.positions())

        openplc.run(0.2)
        record()
        for k in (1, 2, 3, 4, 5):
            console.hold(f"SA{k}_FWD", 0.6 if k % 2 else 0.4)
            openplc.run(0.4)
        record()
        console.set("SA6", 1)                                   # low speed
        for k in (1, 3, 5):
            console.hold(f"SA{k}_BWD", 0.9)
            openplc.run(0.4)
        console.set("SA6", 0)
        record()
        for k in (2, 4):
            console.hold(f"SA{k}_BWD", 0.5)
            openplc.run(0.4)
        record()

        console.set("SA7", 1)                                   # automatic
        console.set("I15", 1)                                   # Task 3: execution enabled
        openplc.run(0.1)
        console.hold("SB1", 0.2)
        reached: list[tuple[int, list[int]]] = []
        was_in_frame = False
        for _ in range(round(80 / 0.01)):
            openplc.scan()
            in_frame = bool(plc.read(IN_FRAME))
            if was_in_frame and not in_frame:                   # the PLC: frame reached
                reached.append((plc.read(FRAME_PTR), console.positions()))
            was_in_frame = in_frame
            if len(reached) == 5:                               # frames 1..4, then 1 again
                break
        openplc.psm.stop_psm()
        assert service.wait(TIMEOUT), "the stop request did not end the PSM server"
        openplc.psm.close()
    return taught, reached, host


def check_playback(taught, reached, host) -> None:
    assert [frame for frame, _ in reached] == [1, 2, 3, 4, 1]
    assert len({tuple(p) for p in taught}) == 4 and max(abs(a - b) for a, b in zip(taught[0], taught[1])) > 1000
    for frame, positions in reached:
        errors = [p - t for p, t in zip(positions, taught[frame - 1])]
        assert max(map(abs, errors)) <= 16, f"frame {frame}: link errors {errors} codes"
    bad = [e for e in host.plant.events if e.kind in ("bus_contention", "overvoltage", "collision")]
    assert bad == [], bad[0].detail
    assert host.fault is None


def test_tur10_playback_in_lockstep_with_a_10_ms_openplc_scan():
    check_playback(*teach_and_play(lambda: 0.010))


def test_tur10_playback_in_lockstep_with_a_jittery_openplc_scan():
    rng = random.Random(13)
    check_playback(*teach_and_play(lambda: rng.uniform(0.004, 0.025)))


class FailingPlant:
    """A plant model that raises at its third step (any bug in plant code)."""

    FACE = make_plant("mp9c").FACE
    outputs = ["QX0.2", "QX1.0"]
    period = 0.01

    def __init__(self) -> None:
        self.steps = 0
        self.switch = 0

    def step(self, outputs, dt):
        self.steps += 1
        if self.steps == 3:
            raise ZeroDivisionError("float division by zero")
        return {"IX0.1": outputs["QX0.2"], "IX1.6": self.switch, "IW0": self.steps}

    def set_switch(self, name, value):
        self.switch = value

    def readouts(self):
        return [self.steps, 0, 0, 0]


def test_a_plant_that_raises_freezes_its_inputs_and_never_drops_the_plc():
    reports: list[str] = []
    clock = TestClock()
    host = PlantHost(FailingPlant(), clock=clock, report=reports.append, traceback=True)
    with PlantService(host, LOOPBACK, LOOPBACK) as service:
        openplc = OpenPlcPsm(service.psm.port)
        console = RawModbusClient("127.0.0.1", service.console.port, unit=0, timeout=TIMEOUT)
        image_bits = [0] * 400
        image_bits[2] = 1                                       # %QX0.2 on
        console.write_coil(FACE_SB1 := 6, True)
        seen = []
        for _scan in range(6):
            clock.now += 0.01
            bits, words = openplc.read_dig_inp(), openplc.read_ana_inp()
            seen.append((bits[1], bits[14], words[0]))       # %IX0.1, %IX1.6, %IW0
            openplc.write_dig_out(image_bits)
            openplc.write_ana_out([0] * 50)
            console.write_coil(FACE_SB1, False)
        # steps 1 and 2 answered; from the third poll on, the inputs of step 2, frozen
        assert seen == [(0, 1, 1), (1, 0, 2)] + [(1, 0, 2)] * 4
        assert len(reports) == 1 and "ZeroDivisionError: float division by zero" in reports[0]
        assert "Traceback (most recent call last)" in reports[0] and "in step" in reports[0]
        lamps = console.read_discrete_inputs(0, 2)
        assert lamps == [0, 1]                                  # HL1 off, PLANT_FAULT on
        assert console.read_input_registers(0, 1) == [2]        # readouts frozen with the plant
        assert not service.psm.should_quit()
        openplc.stop_psm()
        assert service.wait(TIMEOUT)
        openplc.close()
        console.close()


def test_console_face_table_and_refusals():
    host = PlantHost(make_plant("tur10"))
    with PlantService(host, LOOPBACK, LOOPBACK) as service:
        with RawModbusClient("127.0.0.1", service.console.port, unit=0, timeout=TIMEOUT) as c:
            c.write_coils(10, [1, 1])                           # SA6 (low speed), SB1
            assert c.read_coils(0, 14) == [0] * 10 + [1, 1, 0, 0]
            host.exchange({})
            inputs = host.exchange({"QX1.0": 1})
            assert (inputs["IX1.2"], inputs["IX1.3"], inputs["IX1.4"]) == (1, 1, 0)
            assert c.read_discrete_inputs(0, 2) == [1, 0]      # HL1 = %QX1.0, no plant fault
            assert c.read_input_registers(0, 5) == [16000] * 5
            for bad in (lambda: c.read_coils(0, 15), lambda: c.write_coil(14, True),
                        lambda: c.read_input_registers(5, 1), lambda: c.read_discrete_inputs(1, 2)):
                with pytest.raises(RawModbusError) as exc:
                    bad()
                assert exc.value.code == 2
            with pytest.raises(RawModbusError) as exc:
                c.read_holding_registers(0, 1)
            assert exc.value.code == 1
    assert FAULT_LAMP == "PLANT_FAULT"
