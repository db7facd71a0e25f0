"""The lab holds a student's program to the memory limit of a program run (issue #25 item 1;
plclab.limits): the check and trial load of an upload run under the allowance, `plclab lab`'s
process is held to it for its life, and a scan that runs out is the PLC's out_of_memory fault.
In every case the lab goes on and a program can be loaded and run.

The allowance is made small here (PLCLAB_MEMORY_LIMIT_MB), as tests/test_memory_limit.py does:
a program the checker accepts (4 MB declared as 4 million BOOLs, some 40 MiB of Python lists)
crosses it while a small program still loads under it."""
from __future__ import annotations

import asyncio
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import plclab
from plclab.cli import main
from plclab.stands import bundle
from plclab.stands.mp9c import STAND
from test_server import _files, _post, running  # noqa: F401 - the fixture

BIG_DECLS = "".join(f"    big{i} : ARRAY[1..1000000] OF BOOL;\n" for i in range(4))   # 4 MB: accepted by check


def big_program() -> bytes:
    return bundle(STAND, "full").replace("VAR_GLOBAL\n", "VAR_GLOBAL\n" + BIG_DECLS, 1).encode()


def test_a_scan_out_of_memory_is_a_shown_fault_and_a_program_loads_after(running, tmp_path):  # noqa: F811
    server, url = running("mp9c")
    lab = server.lab

    def allocate() -> None:             # what a scan past the process limit raises
        raise MemoryError()

    def simulate() -> None:
        plc = lab.session.plc
        plc._schedule = [(1, allocate)] + list(plc._schedule)[1:]
        lab.advance(0.05)
    lab.call(simulate).result(10)
    snap = lab.call(lambda: lab.snapshot(full=True)).result(10)
    assert snap["plc"]["state"] == "FAULT"
    assert "out_of_memory" in snap["plc"]["fault"] or "memory" in snap["plc"]["fault"].lower(), snap["plc"]
    assert main(["build", "mp9c", "baseline", "-o", str(tmp_path / "mp9c.st")]) == 0
    loaded = asyncio.run(_post(url + "api/program", _files(("mp9c.st", (tmp_path / "mp9c.st").read_bytes()))))
    assert loaded["ok"] is True
    lab.call(lambda: lab.advance(0.1)).result(10)
    assert lab.session.plc.state == "RUN"


def _trace_end(url: str) -> int:
    """The plant second the lab's trace reaches (its download is named by its window)."""
    import urllib.request
    with urllib.request.urlopen(url + "trace.csv", timeout=10) as r:
        return int(re.search(r"-t\d+-(\d+)s\.csv", r.headers["Content-Disposition"]).group(1))


def test_plclab_lab_is_held_to_the_allowance_and_refuses_an_upload_past_it(tmp_path):
    """A fresh `plclab lab` process (in-process, memory freed by earlier tests would be reused
    and blur what a load needs): its address space is limited for its life; an upload past the
    allowance is refused in one line, a program that fits loads after it and runs."""
    env = dict(os.environ, PYTHONPATH=str(Path(plclab.__file__).resolve().parents[1]), PLCLAB_MEMORY_LIMIT_MB="24")
    proc = subprocess.Popen([sys.executable, "-m", "plclab.cli", "lab", "mp9c", "--port", "0", "--speed", "5"],
                            cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = None
        for _ in range(5):
            m = re.search(r"open (http://\S+) in a browser", proc.stdout.readline())
            if m:
                url = m.group(1)
                break
        assert url, proc.stderr.read() if proc.poll() is not None else "no URL printed"
        limits = Path(f"/proc/{proc.pid}/limits").read_text()
        soft = next(ln for ln in limits.splitlines() if ln.startswith("Max address space")).split()[3]
        assert soft != "unlimited", limits
        answer = asyncio.run(_post(url + "api/program", _files(("big.st", big_program()))))
        assert answer["ok"] is False
        assert [e["text"] for e in answer["errors"]] in (
            [f"big.st:1:1: error: the program cannot be {how} (it needs more memory than the lab has: MemoryError)"]
            for how in ("checked", "loaded")), answer
        assert main(["build", "mp9c", "baseline", "-o", str(tmp_path / "mp9c.st")]) == 0    # a program that fits
        loaded = asyncio.run(_post(url + "api/program", _files(("mp9c.st", (tmp_path / "mp9c.st").read_bytes()))))
        assert loaded["ok"] is True, loaded
        first = _trace_end(url)
        for _ in range(200):                                       # it runs: plant time goes on
            if _trace_end(url) >= first + 2:
                break
            time.sleep(0.05)
        else:
            raise AssertionError("the lab's plant time did not advance after the load")
        assert proc.poll() is None
    finally:
        proc.terminate()
        proc.wait(10)
