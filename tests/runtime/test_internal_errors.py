"""A bug of the harness inside a scan (an exception that is no PLC fault, raised by generated
or library code) stops the PLC as a fault does, but is marked internal, asks for a report and
is never charged to the student's program; a fault of the program stays the program's."""
from __future__ import annotations

import pytest

from plclab.grader import grade_sources
from plclab.runtime import stdfb
from plclab.runtime.faults import REPORT_THIS
from plclab.stands import get_stand, sources
from st_helpers import program, val


def _harness_bug(self) -> None:
    raise TypeError("unsupported operand type(s) for +: 'int' and 'NoneType'")


@pytest.fixture(autouse=True)
def _python_path(monkeypatch):
    """The harness bugs here are injected into the Python path (its TON): run it."""
    monkeypatch.setenv("PLCLAB_NATIVE", "0")


def test_an_error_of_the_harness_is_marked_internal_and_asks_for_a_report(monkeypatch):
    monkeypatch.setattr(stdfb.TON, "_body", _harness_bug)
    sim = program("VAR t : TON; n : INT; END_VAR", "n := n + 1;\nt(IN := TRUE, PT := T#1s);")
    sim.step(3)
    f = sim.plc.fault
    assert sim.plc.state == "FAULT" and val(sim, "n") == 1          # stopped in the first scan
    assert f.internal and f.kind == "internal"
    assert (f.file, f.line, f.pou) == ("t.st", 5, "main")           # the ST line that called it
    text = str(f)
    assert "internal error of plclab" in text and REPORT_THIS in text and "TypeError" in text
    assert "PLC FAULT" not in text
    assert "_harness_bug" in f.detail                                # the traceback, for the report


@pytest.mark.parametrize("body, kind", [("q := 10 / z;", "division_by_zero"),
                                        ("a[i] := 1;", "index_out_of_range")])
def test_a_fault_of_the_program_stays_the_programs(body, kind):
    sim = program("VAR z, q : INT; i : INT := 7; a : ARRAY[1..3] OF INT; END_VAR", body)
    sim.step(1)
    f = sim.plc.fault
    assert f.kind == kind and not f.internal
    assert str(f).startswith("t.st:") and "PLC FAULT" in str(f) and REPORT_THIS not in str(f)


def test_the_grader_does_not_charge_a_harness_error_to_the_student(monkeypatch):
    monkeypatch.setattr(stdfb.TON, "_body", _harness_bug)
    report = grade_sources("mp9c", "task1", sources(get_stand("mp9c"), "task1"))
    assert report.row("G1").passed                                   # no PLC fault of the program
    stopped = [r for r in report.failed()]
    assert stopped and not report.passed                             # nothing could be graded ...
    for row in stopped:                                              # ... and each row says why
        assert row.observed.startswith("not checked") and REPORT_THIS in row.observed, row
