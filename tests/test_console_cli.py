"""The console face of `plclab serve` (in-process plant) operated with `plclab console`: the
operator's switches reach the PLC through the plant, the face shows lamps and readouts."""
from __future__ import annotations

import re
import signal
import subprocess
import sys
import time

from plclab.modbus.console import ConsoleClient
from plclab.plants.mp9c import FACE

PLCLAB = [sys.executable, "-m", "plclab.cli"]
TIMEOUT = 60


def console(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(PLCLAB + ["console", *args], capture_output=True, text=True, timeout=TIMEOUT)


def test_serve_console_face_operated_with_plclab_console(tmp_path):
    conf = tmp_path / "openplc.conf"
    conf.write_text(f"[mp9c]\nretain_file = {tmp_path / 'retain.json'}\nio = inprocess\nvariant = baseline\n")
    proc = subprocess.Popen(PLCLAB + ["serve", "mp9c", "--config", str(conf), "--port", "0",
                                      "--console", "127.0.0.1:0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        line = proc.stdout.readline()
        m = re.search(r"console face on 127\.0\.0\.1:(\d+)", line)
        assert m, (line, proc.stderr.read() if proc.poll() is not None else "")
        where = f"127.0.0.1:{m.group(1)}"
        # the baseline's manual mode: SA5 on drives the arm down (L3)
        r = console("mp9c", where, "--set", "SA5=1", "SA6=0")
        assert r.returncode == 0, r.stderr
        assert r.stdout.splitlines()[0] == "switches: SA1=0 SA2=0 SA3=0 SA4=0 SA5=1 SA6=0 SB1=0 I07=0"
        with ConsoleClient(FACE, "127.0.0.1", int(m.group(1))) as client:
            deadline = time.monotonic() + TIMEOUT
            while client.state()[2][0] != 1000 and time.monotonic() < deadline:
                time.sleep(0.05)
            assert client.state()[2][0] == 1000                # lift readout: all the way down
        r = console("mp9c", where, "--press", "SB1=0.1")
        assert r.returncode == 0, r.stderr
        lines = r.stdout.splitlines()
        assert re.fullmatch(r"lamps:    HL1=[01] PLANT_FAULT=0", lines[1])   # HL1 = %QX1.0, program's own
        assert lines[2] == "readouts: lift=1000 rotation=0 extension=0 gripper=0"
        bad = console("mp9c", where, "--set", "SA9=1")
        assert bad.returncode == 1 and bad.stdout == ""
        assert bad.stderr == ("plclab: error: no console switch 'SA9'; this stand has "
                              "SA1, SA2, SA3, SA4, SA5, SA6, SB1, I07\n")
        bad = console("mp9c", where, "--press", "SB1=-1")
        assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "0..60 seconds" in bad.stderr
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=TIMEOUT)
    nobody = console("tur10", "127.0.0.1:1")
    assert nobody.returncode == 1
    assert nobody.stderr.startswith("plclab: error: cannot reach the console face at 127.0.0.1:1: ")


def test_docs_console_tables_are_the_plants_face_tables():
    """docs/openplc.md's console tables say what FACE says (one source: the plants)."""
    import importlib
    from pathlib import Path

    from plclab.plants import STANDS, make_plant

    text = (Path(__file__).resolve().parents[1] / "docs" / "openplc.md").read_text(encoding="utf-8")
    sections = dict(zip(("mp9c", "tur10", "thermo", "cnc"), re.split(r"^### (?:MP-9C|TUR-10|Thermo|CNC) console face$",
                                                              text, flags=re.M)[1:]))
    assert set(sections) == set(STANDS)
    for stand, section in sections.items():
        face = make_plant(stand).FACE
        rows = re.findall(r"^\| (\d+) \| (\w+) \| (%\w+\.\d)?", section.split("\n## ")[0], flags=re.M)
        n = len(face.switches)
        inputs = getattr(importlib.import_module(f"plclab.plants.{stand}"), "CONSOLE", {"DISTURBANCE": "IX0.0"})
        assert [(int(i), name, loc) for i, name, loc in rows[:n]] == \
            [(i, name, "%" + inputs[name]) for i, name in enumerate(face.switches)], stand
        lamps = [(label, "%" + loc) for label, loc in face.lamps] + [("PLANT_FAULT", "")]
        readouts = [(name, "") for name, _ in face.readouts]
        assert [(name, loc) for _, name, loc in rows[n:]] == lamps + readouts, stand
