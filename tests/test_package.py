"""The installable package: `pip install` of a wheel built from this tree, run from another
folder, builds, runs and grades with the ST sources, the grammar, the task sheets and the
static files inside the package, and carries no reference solution.

Bounded and offline: the wheel is built with the project's own setuptools (no build
isolation), installed without dependencies into a fresh venv, whose dependencies are the
project venv's (one .pth line pointing at its site-packages: the editable install there is
not activated by a plain path line, so `plclab` comes from the wheel).
"""
from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SOLUTIONS = REPO / "solutions"


def _run(cmd: list[str], cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout, env=env)


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[Path, Path]:
    """(the wheel, the venv's bin directory)."""
    tmp = tmp_path_factory.mktemp("package")
    tree = tmp / "tree"
    shutil.copytree(REPO, tree, ignore=shutil.ignore_patterns(".git", ".venv", "out", "build", "*.egg-info",
                                                               "__pycache__", ".pytest_cache", ".hypothesis"))
    dist = tmp / "dist"
    r = _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index",
              "--disable-pip-version-check", "-q", "-w", str(dist), str(tree)], cwd=tmp)
    assert r.returncode == 0, r.stdout + r.stderr
    [wheel] = dist.glob("plclab-*.whl")
    venv = tmp / "venv"
    r = _run([sys.executable, "-m", "venv", "--without-pip", str(venv)], cwd=tmp)
    assert r.returncode == 0, r.stderr
    py = venv / "bin" / "python"
    r = _run([sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps", "--no-index",
              "--disable-pip-version-check", "-q", str(wheel)], cwd=tmp)
    assert r.returncode == 0, r.stdout + r.stderr
    site = _run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], cwd=tmp).stdout.strip()
    Path(site, "project_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n", encoding="utf-8")
    return wheel, venv / "bin"


def test_the_wheel_carries_the_shipped_st_and_no_solution(installed):
    wheel, _ = installed
    names = zipfile.ZipFile(wheel).namelist()
    for must in ("plclab/frontend/st.lark", "plclab/plc/GVL/GVL_MP9C.st", "plclab/plc/POUs/PRG_Mp9cBaseline.st",
                 "plclab/plc/POUs/PRG_Thermo.st", "plclab/handouts/mp9c-tasks.md",
                 "plclab/benchprograms/bench300.st"):
        assert must in names
    solution_files = {p.name for p in SOLUTIONS.rglob("*") if p.is_file()}
    assert {"mp9c.toml", "tur10.toml", "FB_CncEvalLinear.st"} <= solution_files
    assert not [n for n in names if n.startswith("solutions") or Path(n).name in solution_files - {"FB_CncEvalLinear.st"}]
    texts = "\n".join(zipfile.ZipFile(wheel).read(n).decode("utf-8", "replace") for n in names if n.endswith(".st"))
    answer = (SOLUTIONS / "POUs" / "FB_CncEvalLinear.st").read_text(encoding="utf-8")
    assert answer.strip() not in texts                      # the wheel has the students' stub, not the answer
    assert "SHORT_PAUSE" not in texts and "LONG_PAUSE" not in texts     # nothing of the task references


def test_installed_plclab_builds_runs_and_grades_from_another_folder(installed, tmp_path):
    _, bin_dir = installed
    plclab = str(bin_dir / "plclab")
    where = _run([str(bin_dir / "python"), "-c", "import plclab; print(plclab.__file__)"], cwd=tmp_path)
    assert str(bin_dir.parent) in where.stdout, where.stdout + where.stderr     # the wheel, not the checkout

    r = _run([plclab, "build", "mp9c", "baseline", "-o", "start.st", "--xml", "start.xml"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "start.st").read_text(encoding="utf-8").startswith("(* MP-9C")

    r = _run([plclab, "handout", "tur10", "-o", "lab"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in (tmp_path / "lab").iterdir()) == ["io-map.md", "tasks.md", "tur10-openplc", "tur10.st"]

    r = _run([plclab, "run", "mp9c", "--scenario", "lift", "--csv", "lift.csv"], cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert (tmp_path / "lift.csv").read_text(encoding="utf-8").startswith("time_s,name,value")

    r = _run([plclab, "grade", "mp9c", "task1", "start.st", "--out", "grade"], cwd=tmp_path)
    assert r.returncode == 1 and "FAIL" in r.stdout and "T1.1" in r.stdout, r.stdout + r.stderr
    # the wheel carries no model answer: the scenarios ran, one line says exploration did not
    assert "exploration not run: no model answer here" in r.stdout and "E1" not in r.stdout, r.stdout

    r = _run([plclab, "build", "mp9c", "task2", "-o", "ref.st"], cwd=tmp_path)
    assert r.returncode == 1 and r.stderr.count("\n") == 1 and "reference solution" in r.stderr
    assert not (tmp_path / "ref.st").exists()


def test_installed_plclab_serves_a_stand_and_writes_a_psm_script(installed, tmp_path):
    _, bin_dir = installed
    plclab = str(bin_dir / "plclab")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    proc = subprocess.Popen([plclab, "serve", "tur10", "--port", "0", "--console", "127.0.0.1:0"], cwd=tmp_path, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        line = proc.stdout.readline()
        assert re.search(r"modbus on 127\.0\.0\.1:\d+", line), line + (proc.stderr.read() if proc.poll() else "")
        assert str(bin_dir.parent) in line              # the ST sources come from the installed package
    finally:
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=20)
    assert proc.returncode == 0, err
    assert "stopped:" in out

    r = _run([plclab, "psm-script", "mp9c"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    compile(r.stdout, "psm.py", "exec")             # a whole Python script, from the installed package
    assert "mp9c" in r.stdout
