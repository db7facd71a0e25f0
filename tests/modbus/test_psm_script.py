"""The generated OpenPLC PSM script (`plclab psm-script STAND`, OpenPLC's core/psm/main.py) run
as OpenPLC runs it: a separate process, from a folder of its own, with a Python that has no
PLC Lab on its path (-I -S: no site-packages, no script folder, no environment), driven by
a byte-for-byte mimic of OpenPLC's psm.cpp client and by the console face."""
from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from modbus_support import TIMEOUT, OpenPlcPsm
from plclab.errors import PlcLabError
from plclab.modbus.psm import psm_script
from plclab.modbus.rawclient import RawModbusClient
from plclab.plants import STANDS, make_plant

REPO = Path(__file__).resolve().parents[2]
FRESH_PYTHON = [sys.executable, "-I", "-S"]


def start_script(tmp_path: Path, stand: str, edit=lambda script: script) -> tuple[subprocess.Popen, int, int]:
    script = psm_script(stand, psm=("127.0.0.1", 0), console=("127.0.0.1", 0))
    assert str(REPO) not in script and "/harness" not in script
    script = edit(script)
    (tmp_path / "main.py").write_text(script)
    proc = subprocess.Popen(FRESH_PYTHON + ["-u", "main.py"], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    m = re.search(r"PSM I/O on 127\.0\.0\.1:(\d+), console face on 127\.0\.0\.1:(\d+)", line)
    assert m, (line, proc.stderr.read() if proc.poll() is not None else "")
    return proc, int(m.group(1)), int(m.group(2))


def stop_script(proc: subprocess.Popen, openplc: OpenPlcPsm) -> str:
    openplc.stop_psm()                                    # OpenPLC's finalizeHardware()
    assert proc.wait(timeout=TIMEOUT) == 0
    openplc.close()
    return proc.stdout.read() + proc.stderr.read()


def test_the_fresh_python_has_no_plclab():
    r = subprocess.run(FRESH_PYTHON + ["-c", "import plclab"], capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 1 and "No module named 'plclab'" in r.stderr


def poll(openplc: OpenPlcPsm, bits: list[int], words: list[int]) -> tuple[list[int], list[int]]:
    """One OpenPLC scan's PSM exchange: inputs read, (no program), outputs written."""
    inputs = openplc.read_dig_inp(), openplc.read_ana_inp()
    openplc.write_dig_out(bits)
    openplc.write_ana_out(words)
    return inputs


def test_mp9c_script_runs_alone_steps_per_poll_and_serves_the_console(tmp_path):
    proc, psm_port, console_port = start_script(tmp_path, "mp9c")
    try:
        openplc = OpenPlcPsm(psm_port)
        with RawModbusClient("127.0.0.1", console_port, unit=0, timeout=TIMEOUT) as console:
            console.write_coil(6, True)                       # SB1 (mbpoll -t 0 -r 7 ... 1)
            bits, _ = poll(openplc, [0] * 400, [0] * 50)
            # power-up: arm up (SQ1), released (SQ3), left (SQ4), backward (SQ7); SB1 = %IX1.6
            assert [i for i, b in enumerate(bits) if b] == [0, 2, 3, 6, 14]
            console.write_coil(6, False)
            outputs = [0] * 400
            outputs[2] = outputs[8] = 1                       # L3 (arm down), HL1
            deadline = time.monotonic() + TIMEOUT
            while not bits[1] and time.monotonic() < deadline:   # SQ2: arm down
                bits, _ = poll(openplc, outputs, [0] * 50)
                time.sleep(0.01)
            assert bits[1] == 1 and bits[0] == 0 and bits[14] == 0
            assert console.read_input_registers(0, 4) == [1000, 0, 0, 0]     # lift all the way
            assert console.read_discrete_inputs(0, 2) == [1, 0]             # HL1 on, no fault
        out = stop_script(proc, openplc)
        assert "mp9c plant stopped after" in out and "Traceback" not in out
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(TIMEOUT)


SABOTAGE = """    from plclab.modbus.psm import run_plant
    import plclab.plants.mp9c as mp9c
    healthy_step = mp9c.MP9C.step

    def step(self, outputs, dt, calls=[0]):
        calls[0] += 1
        if calls[0] == 3:
            raise RuntimeError("a bug in the plant model")
        return healthy_step(self, outputs, dt)
    mp9c.MP9C.step = step
"""


def test_a_failing_plant_in_the_script_freezes_inputs_and_keeps_answering_openplc(tmp_path):
    def sabotage(script: str) -> str:
        assert "    from plclab.modbus.psm import run_plant\n" in script
        return script.replace("    from plclab.modbus.psm import run_plant\n", SABOTAGE)
    proc, psm_port, console_port = start_script(tmp_path, "mp9c", sabotage)
    try:
        openplc = OpenPlcPsm(psm_port)
        outputs = [0] * 400
        outputs[2] = 1                                        # L3: arm down
        with RawModbusClient("127.0.0.1", console_port, unit=0, timeout=TIMEOUT) as console:
            seen = [poll(openplc, outputs, [0] * 50)[0][:2] for _scan in range(20)]
            # poll 1 reports the power-up state, poll 2 the arm leaving SQ1; then frozen
            assert seen == [[1, 0]] + [[0, 0]] * 19
            console.write_coil(6, True)                       # the console face still answers
            assert poll(openplc, outputs, [0] * 50)[0][14] == 0     # SB1 not seen: plant frozen
            assert console.read_discrete_inputs(0, 2) == [0, 1]     # PLANT_FAULT
        out = stop_script(proc, openplc)
        assert out.count("the MP9C model raised RuntimeError: a bug in the plant model") == 1   # once
        assert "Traceback (most recent call last)" in out
        assert "self._inputs = dict(self.plant.step(outputs, dt))" in out    # embedded source shown
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(TIMEOUT)


@pytest.mark.parametrize("stand, switch, location, readout", [
    ("tur10", "SB1", 11, 16000),            # %IX1.3; link 1 at 16000 codes
    ("thermo", "DISTURBANCE", 0, 220),      # %IX0.0; 22.0 C
    ("cnc", "SB1", 0, 0),                   # %IX0.0; the table at X = 0 steps
])
def test_tur10_and_thermo_scripts_run_alone(tmp_path, stand, switch, location, readout):
    face = make_plant(stand).FACE
    proc, psm_port, console_port = start_script(tmp_path, stand)
    try:
        openplc = OpenPlcPsm(psm_port)
        with RawModbusClient("127.0.0.1", console_port, unit=0, timeout=TIMEOUT) as console:
            assert console.read_input_registers(0, 1) == [readout]
            console.write_coil(face.switches.index(switch), True)
            bits, _ = poll(openplc, [0] * 400, [0] * 50)
            assert bits[location] == 1
            assert console.read_coils(0, len(face.switches))[face.switches.index(switch)] == 1
        out = stop_script(proc, openplc)
        assert f"{stand} plant stopped after" in out
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(TIMEOUT)


def test_psm_script_cli_prints_the_script_for_openplc_s_fixed_port():
    r = subprocess.run([sys.executable, "-m", "plclab.cli", "psm-script", "tur10"], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0
    compile(r.stdout, "main.py", "exec")
    assert "PSM = ('127.0.0.1', 2605)" in r.stdout and "CONSOLE = ('127.0.0.1', 2606)" in r.stdout
    assert str(REPO) not in r.stdout
    assert set(STANDS) == {"mp9c", "tur10", "thermo", "cnc"}
    with pytest.raises(PlcLabError, match="unknown stand 'kuka'"):
        psm_script("kuka")


def test_cnc_emergency_stop_on_the_console_face_is_pressed_only_while_the_operator_presses_it(tmp_path):
    """SB3 is normally closed: released at power-up (the PLC reads %IX0.3 = 1, the face's coil
    says 0 = not pressed); `plclab console cnc --press SB3` presses and releases it; --set
    SB3=1 keeps it pressed (the PLC reads 0) until SB3=0."""
    from plclab.modbus.console import run_console

    proc, psm_port, console_port = start_script(tmp_path, "cnc")
    where = ("127.0.0.1", console_port)
    try:
        openplc = OpenPlcPsm(psm_port)
        sb3 = 3                                               # %IX0.3 and coil 3
        bits, _ = poll(openplc, [0] * 400, [0] * 50)
        assert bits[sb3] == 1                                 # released: the contact conducts
        lines = run_console("cnc", where)
        assert lines[0] == "switches: SB1=0 SB2=0 SA1=0 SB3=0"      # nothing pressed
        lines = run_console("cnc", where, presses=["SB3=0.05"])
        assert lines[0] == "switches: SB1=0 SB2=0 SA1=0 SB3=0"
        assert poll(openplc, [0] * 400, [0] * 50)[0][sb3] == 1      # released again after the press
        run_console("cnc", where, sets=["SB3=1"])
        assert poll(openplc, [0] * 400, [0] * 50)[0][sb3] == 0      # held pressed: the contact is open
        assert run_console("cnc", where)[0] == "switches: SB1=0 SB2=0 SA1=0 SB3=1"
        run_console("cnc", where, sets=["SB3=0"])
        assert poll(openplc, [0] * 400, [0] * 50)[0][sb3] == 1
        stop_script(proc, openplc)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(TIMEOUT)


def test_cnc_part_program_through_the_console_face_reaches_the_plc_frame_by_frame(tmp_path):
    """`plclab console cnc --part`: the tape registers of the face load the plant's tape
    reader; polled as OpenPLC polls, it shows frame k on %IW4..%IW15 until the PLC
    acknowledges k on %QW4, then k + 1; the `tape` readout counts what the PLC stored."""
    from plclab.modbus.console import run_console
    from plclab.modbus.rawclient import RawModbusError

    frames = [(1, 200, 0, 0, 0, 0, 500, 0, 0), (1, 200, 100, 0, 0, 0, 500, 0, 0),
              (3, 100, 200, 0, -100, 0, 500, 0, 0), (1, -5, -7, 0, 0, 0, 500, 0, 0)]
    proc, psm_port, console_port = start_script(tmp_path, "cnc")
    where = ("127.0.0.1", console_port)
    try:
        openplc = OpenPlcPsm(psm_port)
        with pytest.raises(PlcLabError, match=r"^tape: the PLC stored 0 of 4 frames in 0 s: it acknowledged none"):
            run_console("cnc", where, tape=(1, frames), tape_wait=0.0)      # no scan yet: not loaded
        shown = []
        for _scan in range(8):                                # the PLC: store what is shown, acknowledge it
            openplc.read_dig_inp()
            words = openplc.read_ana_inp()
            if words[4]:
                shown.append((words[4], words[5], words[6], tuple(w - 0x10000 if w & 0x8000 else w
                                                                  for w in words[7:16])))
            openplc.write_dig_out([0] * 400)
            openplc.write_ana_out([0] * 4 + [words[4]] + [0] * 45)
        assert shown == [(k, 4, 1, frame) for k, frame in enumerate(frames, start=1)]
        assert run_console("cnc", where)[2].endswith(" missed=0 tape=4")
        with RawModbusClient("127.0.0.1", console_port, unit=0, timeout=TIMEOUT) as console:
            for count in (0, 201):                            # a tape of no frames, or too many
                with pytest.raises(RawModbusError) as e:
                    console.write_register(0, count)
                assert e.value.code == 3
            assert console.read_holding_registers(0, 2) == [4, 1]       # the last good tape's count, method
        stop_script(proc, openplc)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(TIMEOUT)


PART = "G21 G90 G17\nG01 X2 Y0 F300\nY1\nX0 Y0\n"        # three frames


class PlcSide:
    """OpenPLC's PSM exchange in a thread of its own, every 5 ms, until stopped: `ack` (True:
    store and acknowledge the frame the tape reader shows, as PRG_CncStand does while idle;
    False: never acknowledge) and `hl1` (the program running lamp, %QX0.7)."""

    def __init__(self, port: int, ack: bool, hl1: bool = False):
        import threading

        self.openplc = OpenPlcPsm(port)
        self.ack, self.hl1 = ack, hl1
        self.stored: list[int] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self) -> None:
        ack = 0
        while not self.stop.wait(0.005):
            self.openplc.read_dig_inp()
            words = self.openplc.read_ana_inp()
            if self.ack:
                if words[4] != ack and words[4] and words[4] not in self.stored:
                    self.stored.append(words[4])
                ack = words[4]
            bits = [0] * 400
            bits[7] = int(self.hl1)
            self.openplc.write_dig_out(bits)
            self.openplc.write_ana_out([0] * 4 + [ack] + [0] * 45)

    def close(self) -> OpenPlcPsm:
        self.stop.set()
        self.thread.join(TIMEOUT)
        return self.openplc


def test_console_part_exits_non_zero_unless_every_frame_is_stored_and_acknowledged(tmp_path):
    """`plclab console cnc --part`: against a PLC side that does not acknowledge, exit 1 with
    one line naming how many frames were stored and why; a running part (HL1 lit) is refused
    by name, nothing sent; a PLC that stores every frame: exit 0."""
    part = tmp_path / "part.nc"
    part.write_text(PART, encoding="utf-8")
    proc, psm_port, console_port = start_script(tmp_path, "cnc")
    where = f"127.0.0.1:{console_port}"

    def console(*extra):
        return subprocess.run([sys.executable, "-m", "plclab.cli", "console", "cnc", where, "--part", str(part),
                               *extra], capture_output=True, text=True, timeout=TIMEOUT)
    try:
        plc = PlcSide(psm_port, ack=True, hl1=True)             # a part runs: HL1 lit
        time.sleep(0.1)
        r = console("--wait", "2")
        assert r.returncode == 1 and r.stderr.count("\n") == 1
        assert r.stderr.startswith("plclab: error: tape: not loaded: a part program is running or held (HL1 lit)")
        plc.close().close()
        assert not plc.stored                                   # nothing was put on the reader
        plc = PlcSide(psm_port, ack=False)
        r = console("--wait", "0.5")
        assert r.returncode == 1 and r.stdout == ""
        assert r.stderr == ("plclab: error: tape: the PLC stored 0 of 3 frames in 0.5 s: it acknowledged none "
                            "(TAPE_ACK, %QW4; the cnc program must run in OpenPLC, idle, with this PSM script); "
                            "SB1 runs nothing until every frame is stored (the tape stays on the reader)\n")
        plc.close().close()
        plc = PlcSide(psm_port, ack=True)
        r = console("--wait", "5")
        assert r.returncode == 0, r.stderr
        assert r.stdout.splitlines()[0] == "tape: 3 frames stored and acknowledged by the PLC; SB1 runs them"
        assert plc.stored == [1, 2, 3]
        stop_script(proc, plc.close())
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(TIMEOUT)
