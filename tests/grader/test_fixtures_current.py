"""The committed wrong-solution fixtures are exactly what tests/grader/make_fixtures.py makes
from today's reference bundles: a change of a reference or of a shared block that a fixture
is built on shows here, not as a fixture silently testing yesterday's program."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

GENERATOR = Path(__file__).resolve().parent / "make_fixtures.py"


def test_fixture_generator_check_finds_every_fixture_current():
    r = subprocess.run([sys.executable, str(GENERATOR), "--check"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
