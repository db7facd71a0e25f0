"""Where the ST lives: what ships in the package (plc/ in the repository, plclab/plc in the wheel) and what stays in a checkout
(solutions/). A student's starting program and thermo's program are built from package data
alone; a task's reference solution needs the checkout and is refused in one line without it.
"""
from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from plclab import stands
from plclab.build import write_build
from plclab.errors import PlcLabError
from plclab.stands import PLC_DIR, SOLUTIONS_DIR, STANDS, get_stand, references


def _stems(folder):
    return {p.stem for p in folder.glob("*.st")}


def test_the_checkout_has_the_solutions_tree():
    assert SOLUTIONS_DIR is not None and (SOLUTIONS_DIR / "POUs").is_dir()
    assert (SOLUTIONS_DIR / "mp9c.toml").is_file() and (SOLUTIONS_DIR / "tur10.toml").is_file()


def test_a_task_reference_is_the_starting_program_with_the_tasks_edits():
    """T_ControlProgram: the student's has no pause per frame, Task 2's model answer has; a
    block the task does not touch is the shipped file itself."""
    stand = get_stand("mp9c")
    starting = dict(stand.pou_sources("baseline"))
    answer = stand.pou_sources("task2")
    assert [name for name, _ in answer if name.startswith("<")] == [
        "<mp9c task2: T_ControlProgram.st>", "<mp9c task2: FB_Mp9cManual.st>", "<mp9c task2: FB_Mp9cContinuous.st>",
        "<mp9c task2: FB_Mp9cStep.st>", "<mp9c task2: PRG_Mp9cBaseline.st>"]
    untouched = [(name, text) for name, text in answer if not name.startswith("<")]
    assert untouched and all(starting[name] == text for name, text in untouched)
    assert all(PLC_DIR in Path(name).parents for name, _ in untouched)
    changed = dict(answer)["<mp9c task2: T_ControlProgram.st>"]
    assert "Pause" not in starting[str(PLC_DIR / "POUs" / "T_ControlProgram.st")] and "Pause : TIME" in changed


@pytest.mark.parametrize("name", STANDS)
def test_shipped_variants_are_built_from_package_data_only(name):
    stand = get_stand(name)
    for vname, v in stand.variants.items():
        files = stand.files(vname)
        shipped = [f for f in files if PLC_DIR in f.parents]
        if v.edited:
            assert shipped == files and stand.outline(vname), f"{name} {vname}: an edited reference changes nothing"
        elif v.reference:
            assert len(shipped) < len(files), f"{name} {vname} is marked reference but uses no solution file"
        else:
            assert shipped == files, f"{name} {vname} is handed to students but reads {set(files) - set(shipped)}"


def test_every_solution_file_belongs_to_a_reference_variant():
    used = {f.stem for name in STANDS for vname, v in get_stand(name).variants.items() if v.reference
            for f in get_stand(name).files(vname)}
    assert _stems(SOLUTIONS_DIR / "POUs") <= used
    for edits in SOLUTIONS_DIR.glob("*.toml"):
        stand = get_stand(edits.stem)
        with edits.open("rb") as f:
            sections = set(tomllib.load(f))
        assert sections == {n for n, v in stand.variants.items() if v.edited}


def test_an_edit_that_no_longer_matches_the_starting_program_is_one_clear_error(tmp_path, monkeypatch):
    broken = (SOLUTIONS_DIR / "mp9c.toml").read_text(encoding="utf-8").replace(
        "old = \"IF Press AND Cp.Count > 0 THEN\"", "old = \"IF Press AND Count > 0 THEN\"", 1)
    (tmp_path / "mp9c.toml").write_text(broken, encoding="utf-8")
    monkeypatch.setattr(stands, "SOLUTIONS_DIR", tmp_path)
    references._table.cache_clear()
    try:
        with pytest.raises(PlcLabError) as e:
            write_build("mp9c", "task3", str(tmp_path / "x.st"), None)
    finally:
        references._table.cache_clear()
    msg = str(e.value)
    assert "\n" not in msg and "mp9c.toml: [task3] edit 8 (FB_Mp9cContinuous)" in msg and "occurs 0 times, not 1" in msg
    assert not (tmp_path / "x.st").exists()


@pytest.mark.parametrize("name,variant", [("mp9c", "task2"), ("tur10", "full")])
def test_a_reference_without_the_checkout_is_one_clear_error_and_nothing_is_written(name, variant, tmp_path,
                                                                                      monkeypatch):
    monkeypatch.setattr(stands, "SOLUTIONS_DIR", None)
    with pytest.raises(PlcLabError) as e:
        write_build(name, variant, str(tmp_path / "x.st"), str(tmp_path / "x.xml"))
    msg = str(e.value)
    assert "\n" not in msg and "reference solution" in msg and "checkout" in msg and f"{name} baseline" in msg
    assert list(tmp_path.iterdir()) == []
    write_build(name, "baseline", str(tmp_path / "b.st"), None)      # the starting program still builds
    assert (tmp_path / "b.st").read_text(encoding="utf-8").startswith("(*")


def test_the_repository_keeps_the_promised_layout():
    """plc/POUs and plc/GVL at the top are the one copy of the shipped ST; a checkout and an
    editable install read exactly those files (the wheel carries them as plclab/plc)."""
    root = Path(__file__).resolve().parents[2]
    for must in ("plc/POUs", "plc/GVL", "harness/plclab", "tests", "solutions", "docs"):
        assert (root / must).is_dir(), must
    for must in ("openplc.conf", "README.md", "pyproject.toml"):
        assert (root / must).is_file(), must
    assert PLC_DIR == root / "plc"
    assert {"GVL_MP9C", "GVL_TUR10", "GVL_THERMO", "GVL_CNC"} <= _stems(root / "plc" / "GVL")
    assert {"PRG_Mp9cBaseline", "PRG_Tur10Baseline", "PRG_Thermo", "PRG_CncStand"} <= _stems(root / "plc" / "POUs")
    assert not (root / "harness" / "plclab" / "plc").exists(), "a second copy of the shipped ST"
    for name in STANDS:
        for vname in get_stand(name).variants:
            files = get_stand(name).files(vname)
            assert all((root / "plc") in f.parents or (root / "solutions") in f.parents for f in files), (name, vname)
