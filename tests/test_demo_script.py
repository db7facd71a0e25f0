"""scripts/demo is the README's main command: after setting up it checks the shipped ST as one
unit and runs the MP-9C demo. Its check line names the repository's plc/ folders (the layout
users are promised): a glob that matches nothing (as after a move of the ST) fails here, not
on a user's fresh clone."""
from __future__ import annotations

import glob
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_demo_checks_the_shipped_st_where_it_lives():
    lines = [line for line in (ROOT / "scripts" / "demo").read_text(encoding="utf-8").splitlines()
             if line.startswith(".venv/bin/plclab check ")]
    assert len(lines) == 1, lines
    patterns = shlex.split(lines[0])[2:]
    files = [f for p in patterns for f in sorted(glob.glob(str(ROOT / p)))]
    assert all(glob.glob(str(ROOT / p)) for p in patterns), patterns            # every glob matches
    assert {Path(f).parent.relative_to(ROOT).as_posix() for f in files} == {"plc/GVL", "plc/POUs"}
    run = subprocess.run([sys.executable, "-m", "plclab.cli", "check", *files], cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "run mp9c" in (ROOT / "scripts" / "demo").read_text(encoding="utf-8")
