"""The plant as an OpenPLC PSM I/O server, from the command line, driven by our own PSM client
(what `plclab serve` does with io = psm) and stopped the way OpenPLC stops it (127 in
holding register 50). The PSM script OpenPLC runs: tests/modbus/test_psm_script.py."""
from __future__ import annotations

import re
import subprocess
import sys
import time

from plclab.modbus.psm import PsmClient
from plclab.modbus.rawclient import RawModbusClient
from plclab.runtime.image import ProcessImage

PLCLAB = [sys.executable, "-m", "plclab.cli"]


def start_plant(stand: str) -> tuple[subprocess.Popen, int]:
    """`plclab plant STAND` on a port the OS picks (it prints which): no two tests ever ask
    for the same one."""
    proc = subprocess.Popen(PLCLAB + ["plant", stand, "--psm", "127.0.0.1:0", "--console", "none"],
                            stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    m = re.search(r"PSM I/O on 127\.0\.0\.1:(\d+)", line)
    assert m, (line, proc.stderr.read() if proc.poll() else "")
    return proc, int(m.group(1))


def test_mp9c_plant_answers_a_psm_client_like_openplc_and_stops_on_127():
    proc, port = start_plant("mp9c")
    try:
        image = ProcessImage()
        client = PsmClient("127.0.0.1", port).connect()
        client.read_inputs(image)
        # power-up: arm up, gripper released, rotated left, backward (SQ1, SQ3, SQ4, SQ7)
        assert [image.areas["IX"][i] for i in range(7)] == [1, 0, 1, 1, 0, 0, 1]
        image.areas["QX"][2] = 1                          # L3: arm down
        client.write_outputs(image)
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline:
            client.read_inputs(image)
            if image.areas["IX"][1]:                      # SQ2: arm down reached
                break
            time.sleep(0.05)
        assert image.areas["IX"][1] == 1 and image.areas["IX"][0] == 0
        client.request_stop()
        client.close()
        assert proc.wait(timeout=10) == 0
        assert "plant stopped" in proc.stdout.read()
    finally:
        if proc.poll() is None:
            proc.kill()


def test_serve_as_psm_client_runs_the_program_against_a_plant_in_another_process(tmp_path):
    proc, port = start_plant("mp9c")
    conf = tmp_path / "openplc.conf"
    conf.write_text(f"[mp9c]\nio = psm\npsm = 127.0.0.1:{port}\nretain_file = {tmp_path / 'r.json'}\n"
                    "[modbus]\nenabled = false\n")
    try:
        serve = subprocess.run(PLCLAB + ["serve", "mp9c", "--variant", "baseline", "--config", str(conf),
                                         "--duration", "1.5"], capture_output=True, text=True, timeout=60)
        assert serve.returncode == 0, serve.stderr
        # what the PLC wrote to the plant over PSM: the baseline in manual mode drives L2 (arm
        # up, SA5 = 0) and lights HL1 (empty program), which it knows from the plant's inputs
        with RawModbusClient("127.0.0.1", port, unit=0) as client:
            coils = client.read_coils(0, 9)
        assert coils[1] == 1 and coils[2] == 0            # L2 on, L3 off
        assert coils[8] == 1                              # HL1 (%QX1.0)
    finally:
        proc.kill()
        proc.wait(timeout=10)
