"""The grader (docs/instructors.md, docs/cli.md): a task's requirement checks run against a student's program.

    report = grade("mp9c", "task2", ["my_robot.st"], out_dir="out/grade")
    print(report.text())            # one row per requirement: id, what, PASS/FAIL, why
    sys.exit(report.exit_code)      # 0 only if every requirement passed

Requirement sets are registered per (stand, task) by `plclab.grader.<stand>`. How to declare a
requirement (once: id, sentence built from the thresholds it quotes, scenario) and check it
(`with c.requirement(REQ) as rid:` passes on exit unless a failure was recorded) is in
`plclab.grader.registry`. Exit codes: 0 every requirement passed, 1 the program failed one,
2 the grader itself failed (ERROR rows: never charged to the student).
"""
from .engine import grade, grade_sources, replayed, requirement_table, task_title
from .registry import (EVERY, Checks, Requirement, RequirementSet, Scenario, register, registered,
                       requirement_set, tasks)
from .report import GradeReport, Row, requirements_text

__all__ = [
    "EVERY", "Checks", "GradeReport", "Requirement", "RequirementSet", "Row", "Scenario", "grade",
    "grade_sources", "register", "replayed", "registered", "requirement_set", "requirement_table", "requirements_text",
    "task_title", "tasks",
]
