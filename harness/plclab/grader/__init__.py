"""The grader (docs/instructors.md, docs/cli.md): a task's requirement checks run against a student's program.

    report = grade("mp9c", "task2", ["my_robot.st"], out_dir="out/grade")
    print(report.text())            # one row per requirement: id, what, PASS/FAIL, why
    sys.exit(report.exit_code)      # 0 only if every requirement passed

Requirement sets are registered per (stand, task) by `plclab.grader.<stand>`; see registry.
"""
from .engine import grade, grade_sources, requirement_table
from .registry import (EVERY, Checks, Requirement, RequirementSet, Scenario, register, registered,
                       requirement_set, tasks)
from .report import GradeReport, Row

__all__ = [
    "EVERY", "Checks", "GradeReport", "Requirement", "RequirementSet", "Row", "Scenario", "grade",
    "grade_sources", "register", "registered", "requirement_set", "requirement_table", "tasks",
]
