"""matplotlib is imported only when a plot is asked for (issue #25, item 10): it costs about
0.3 s, a third of a `plclab run`. Each command runs in a fresh interpreter, which then reports
whether matplotlib was ever imported."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import plclab
from plclab.stands import bundle
from plclab.stands.mp9c import STAND

PROBE = """
import sys
from plclab.cli import main
rc = main(sys.argv[1:])
print("RC", rc, "MATPLOTLIB", "matplotlib" in sys.modules)
"""


def _imports_matplotlib(args: list[str], cwd: Path) -> bool:
    env = dict(os.environ, PYTHONPATH=str(Path(plclab.__file__).resolve().parents[1]))   # this checkout's plclab
    done = subprocess.run([sys.executable, "-c", PROBE, *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=300)
    last = done.stdout.strip().splitlines()[-1]
    assert last.startswith("RC 0 "), done.stdout + done.stderr
    return last.endswith("True")


def test_run_without_a_plot_does_not_import_matplotlib(tmp_path):
    assert not _imports_matplotlib(["run", "mp9c", "--scenario", "step"], tmp_path)
    assert not _imports_matplotlib(["run", "mp9c", "--csv", str(tmp_path / "t.csv")], tmp_path)


def test_run_with_a_plot_still_plots(tmp_path):
    """The demo writes out/mp9c-demo.png: there matplotlib is needed, and imported."""
    assert _imports_matplotlib(["run", "mp9c", "--scenario", "step", "--plot", str(tmp_path / "p.png")], tmp_path)
    assert (tmp_path / "p.png").stat().st_size > 0


def test_grade_does_not_import_matplotlib(tmp_path):
    program = tmp_path / "task1.st"
    program.write_text(bundle(STAND, "task1"), encoding="utf-8")
    # scenarios, exploration (a few scripts: every module a grade loads, not the stand's whole
    # budget) and the trace files
    assert not _imports_matplotlib(["grade", "mp9c", "task1", str(program), "--out", str(tmp_path / "g"),
                                    "--explore", "3"], tmp_path)


def test_serve_does_not_import_matplotlib(tmp_path):
    assert not _imports_matplotlib(["serve", "mp9c", "--duration", "0.3", "--port", "0", "--console", "none"],
                                   tmp_path)
