"""Where the ST lives: what ships in the package (plclab/plc) and what stays in a checkout
(solutions/). A student's starting program and thermo's program are built from package data
alone; a task's reference solution needs the checkout and is refused in one line without it.
"""
from __future__ import annotations

import pytest

from plclab import stands
from plclab.build import write_build
from plclab.errors import PlcLabError
from plclab.stands import PLC_DIR, SOLUTIONS_DIR, STANDS, get_stand


def _stems(folder):
    return {p.stem for p in folder.glob("*.st")}


def test_the_checkout_has_the_solutions_tree():
    assert SOLUTIONS_DIR is not None and (SOLUTIONS_DIR / "POUs").is_dir()


def test_a_reference_reads_its_own_version_of_a_starting_block():
    """T_ControlProgram: the student's has no pause per frame, Task 2's model answer has."""
    stand = get_stand("mp9c")
    [starting] = [f for f in stand.files("baseline") if f.stem == "T_ControlProgram"]
    [answer] = [f for f in stand.files("task2") if f.stem == "T_ControlProgram"]
    assert PLC_DIR in starting.parents and SOLUTIONS_DIR in answer.parents
    assert "Pause" not in starting.read_text(encoding="utf-8") and "Pause" in answer.read_text(encoding="utf-8")


@pytest.mark.parametrize("name", STANDS)
def test_shipped_variants_are_built_from_package_data_only(name):
    stand = get_stand(name)
    for vname, v in stand.variants.items():
        files = stand.files(vname)
        shipped = [f for f in files if PLC_DIR in f.parents]
        if v.reference:
            assert len(shipped) < len(files), f"{name} {vname} is marked reference but uses no solution file"
        else:
            assert shipped == files, f"{name} {vname} is handed to students but reads {set(files) - set(shipped)}"


def test_every_solution_file_belongs_to_a_reference_variant():
    used = {f.stem for name in STANDS for vname, v in get_stand(name).variants.items() if v.reference
            for f in get_stand(name).files(vname)}
    assert _stems(SOLUTIONS_DIR / "POUs") <= used


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
