"""Wrong solutions whose mistake the grader once reported on the wrong row (or not at all):
each fails the row that names it, with words a student recognises, and no other row is
charged for it where the mistake concerns one requirement only (docs/grading.md, "The
robots' tasks").
"""
from __future__ import annotations

import pytest

from graded import graded_fixture
from grader_helpers import FIXTURES_DIR, assert_fault_stop_named, assert_row_names_mistake, fixtures

NAMED = {   # (stand, fixture): (its row, words the row must say, the only rows that may fail)
    ("mp9c", "task1_hl1_inverted"): ("G3", "HL1=1 at power-up (no frame recorded)", ["G3", "G4"]),
    ("mp9c", "task2_pauses_swapped"): ("T2.1", "the pauses are swapped", None),
    ("mp9c", "task2_pause_off_by_one"): ("T2.2", "off by one: after each frame came the pause recorded with the "
                                         "next frame", None),
    ("mp9c", "task2_step_pause_ignored"): ("T2.2", "step mode: a 3.0 s pause", None),
    ("mp9c", "task2_watchdog_whole_run"): ("G10", "the watchdog timed the whole run (10 s from the start), not "
                                           "each frame", None),
    ("mp9c", "task2_record_on_press"): ("G3", "the frame was recorded on the press, not at its release",
                                        ["G3", "G11"]),
    ("mp9c", "task3_step_wraps_with_i07_0"): ("T3.5", "step mode: no frame starts after frame 4 (the last)", None),
    ("mp9c", "task3_enable_read_when_reached"): ("T3.7", "I0.7 was read when frame 4 was reached, not when its "
                                                 "pause was over", ["T3.7"]),
    ("mp9c", "task3_hl1_never_off"): ("G3", "HL1 still 1", ["G3"]),
    ("mp9c", "task3_reset_on_release"): ("G5", "the program was reset at the release, not while SB1 was held", None),
    ("tur10", "task1_admissible_160"): ("G8", "every reference 0 at t = 4.57 s with link 1 at 16137 (+137 codes "
                                        "from the target, beyond the admissible 16); the link was still moving",
                                        None),
    ("tur10", "task2_hl1_inverted"): ("G5", "HL1=1 at power-up (no frame recorded)", ["G5", "G6"]),
    ("tur10", "task2_hl1_never_off"): ("G5", "HL1 still 1", ["G5"]),
    ("tur10", "task2_pauses_swapped"): ("T2.1", "the pauses are swapped", None),
    ("tur10", "task2_pause_off_by_one"): ("T2.2", "off by one: after each frame came the pause recorded with the "
                                          "next frame", None),
    ("tur10", "task2_watchdog_whole_run"): ("G11", "the watchdog timed the whole run (20 s from the start), not "
                                            "each frame", None),
    ("tur10", "task3_enable_read_when_reached"): ("T3.7", "I1.5 was read when frame 3 was reached, not when its "
                                                  "pause was over", ["T3.7"]),
    ("tur10", "task3_reset_on_release"): ("G7", "the program was reset at the release, not while SB1 was held",
                                          None),
}


@pytest.mark.parametrize("stand,name", sorted(NAMED))
def test_wrong_solution_row_names_its_mistake(stand, name):
    task = next(t for n, t, _ in fixtures(stand) if n == f"{name}.st")
    report = graded_fixture(stand, task, FIXTURES_DIR / stand / f"{name}.st")
    assert_row_names_mistake(report, *NAMED[stand, name])


@pytest.mark.parametrize("stand,watchdog", [("mp9c", "G10"), ("tur10", "G11")])
def test_a_fault_stop_is_not_taken_for_a_task_mistake(stand, watchdog):
    """The whole-run watchdog stops playback with HL1 blinking: the task's rows say so and
    point at the watchdog requirement instead of blaming the pause input."""
    report = graded_fixture(stand, "task2", FIXTURES_DIR / stand / "task2_watchdog_whole_run.st")
    assert_fault_stop_named(report, "T2", watchdog)
