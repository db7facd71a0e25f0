"""The reference solutions are the model answers of docs/instructors.md: the starting program
with exactly the changes of the task (solutions/<stand>.toml), so each is a correct solution
in the starting program's own structure (main program, manual / automatic / continuous /
step-by-step subroutines) and a real change of it: tens of changed lines over several POUs,
never one line away from what the student is handed. That they pass their tasks is
test_grader_mp9c / test_grader_tur10's `test_reference_solution_passes_its_task`.
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from plclab.cli import main
from plclab.stands import get_stand

DOCS = Path(__file__).resolve().parents[2] / "docs"
CASES = [(s, t) for s in ("mp9c", "tur10") for t in ("task1", "task2", "task3")]


def changed_lines(outline: str) -> list[str]:
    return [line for line in outline.splitlines() if line[:1] in "+-" and not line.startswith(("+++", "---"))]


def added_code(outline: str) -> set[str]:
    """The statements and declarations a diff adds (comment text left out)."""
    return {line for line in changed_lines(outline) if line.startswith("+")
            and re.sub(r"\(\*.*?\*\)", "", line[1:]).strip().endswith((";", "THEN"))}


def changed_files(outline: str) -> list[str]:
    return re.findall(r"^\+\+\+ b/\S+/(\w+)\.st$", outline, re.M)


@pytest.mark.parametrize("stand,task", CASES)
def test_model_answer_is_a_real_change_of_the_starting_program(stand, task):
    outline = get_stand(stand).outline(task)
    code = [line for line in changed_lines(outline) if not line[1:].lstrip().startswith(("(*", "*"))]
    assert len(changed_lines(outline)) >= 14, outline
    assert len(code) >= 5, outline                      # not only comments
    if task != "task1":                                 # Tasks 2 and 3 span the program's subroutines
        assert len(changed_files(outline)) >= 2, outline


@pytest.mark.parametrize("stand,task", CASES)
def test_the_instructors_outline_names_every_file_the_model_answer_changes(stand, task):
    """docs/instructors.md's section of the task lists each POU the reference changes."""
    text = (DOCS / "instructors.md").read_text(encoding="utf-8")
    title = {"mp9c": "MP-9C", "tur10": "TUR-10"}[stand] + f" Task {task[-1]}"
    section = text.split(f"### {title}", 1)[1].split("\n### ", 1)[0].split("\n## ", 1)[0]
    missing = [pou for pou in changed_files(get_stand(stand).outline(task)) if f"`{pou}`" not in section]
    assert missing == [], f"docs/instructors.md '### {title}' does not name {missing}"


def test_full_is_the_three_tasks_together():
    """`full` is the three tasks' edits in one program (plus, on the TUR-10, every axis
    regulated): each task's added lines are in it."""
    for stand in ("mp9c", "tur10"):
        s = get_stand(stand)
        full = added_code(s.outline("full"))
        for task in ("task1", "task2", "task3"):
            added = added_code(s.outline(task))
            assert added and added <= full, (stand, task, added - full)


def test_plclab_build_outline_prints_the_diff_and_writes_nothing(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["build", "tur10", "task2", "--outline"]) == 0
    out = capsys.readouterr().out
    assert out == get_stand("tur10").outline("task2")
    assert "+++ b/plc/POUs/FB_Tur10Manual.st" in out and "+        Cp.Frames[Cp.Count].Pause := SEL(" in out
    assert list(tmp_path.iterdir()) == []
    assert main(["build", "tur10", "baseline", "--outline"]) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "not a task reference" in err and "task1, task2, task3, full" in err
    assert main(["build", "cnc", "full", "--outline"]) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "cnc has none" in err
