"""The grader's one rule set (issue 29): exploration (E1) keeps each freedom and tolerance the
stand declares, judges what a correct program does inside them as a pass, and reports what it
finds in true words; the unit tests here play no PLC (synthetic stand traces), the graded
programs under fixtures/rules/ are correct programs inside each freedom."""
from __future__ import annotations

from dataclasses import dataclass, field

from plclab.grader.explore import Divergence, compare, shrink
from plclab.stands.base import stand_spec
from plclab.stands.scripts import Event, Script


def _compare(name, model, student, rows=(), stand="tur10", task="task2", end=30.0):
    expl = stand_spec(stand).explore
    observed = [o for o in expl.compared(task) if o.name == name]
    events = tuple(Event(t, n, v) for t, n, v in rows)
    return compare({name: model}, {name: student}, observed, expl, Script(events, end), end, task)


# --------------------------------------------------------------------------- a blink cut by END

def _blink(start, until, first=True):
    return [(round(start + 0.5 * k, 3), (k % 2 == 0) == first) for k in range(int((until - start) / 0.5) + 1)]


def test_a_blink_cut_by_the_scripts_end_is_not_compared_by_its_last_on_off_state():
    # both stands blink to the end of the script, in opposite phases: the last toggle leaves
    # one lamp on and the other off, a state END cut, not one the lamp settled in
    model = [(0.0, False)] + _blink(10.0, 19.8, first=True)
    student = [(0.0, False)] + _blink(10.02, 19.8, first=False)
    assert _compare("HL1", model, student, [(0.5, "SA7", "1")], end=20.0) is None
    # a lamp that stops blinking well before the end and stays in the wrong state is compared
    student_stops = [(0.0, False)] + _blink(10.0, 14.0, first=True) + [(14.3, True)]
    model_stops = [(0.0, False)] + _blink(10.0, 14.0, first=True) + [(14.3, False)]
    d = _compare("HL1", model_stops, student_stops, [(0.5, "SA7", "1")], end=25.0)
    assert d is not None and d.signal.name == "HL1"


# --------------------------------------------------------------------------- the rest allowance

def test_links_stopped_in_the_same_scan_keep_the_travel_allowance_of_a_later_start():
    # the student's link starts fast one TUR-10 scan (20 ms) later; a stop pressed at the same
    # moment on both stands: the model's link stands 120 codes further on (6000 codes/s), as
    # physics has it. The allowance is the lag since both stood still, not the stop's own 0 lag
    model = [(0.0, (0, 0)), (1.00, (1, 0)), (1.20, (2, 0)), (3.00, (0, 10800))]
    student = [(0.0, (0, 0)), (1.02, (1, 0)), (1.20, (2, 0)), (3.00, (0, 10685))]    # 115 codes short
    assert _compare("link1", model, student) is None
    # the allowance is the travel in the time apart, not a blank cheque: 400 codes short fails
    student_far = [(0.0, (0, 0)), (1.02, (1, 0)), (1.20, (2, 0)), (3.00, (0, 10400))]
    d = _compare("link1", model, student_far)
    assert d is not None and d.signal.name == "link1" and d.kind == "value"
    # and it is not carried over from an earlier motion: after both stood still, a new move
    # started and stopped in the same scans keeps the 40-code band
    again = [(4.00, (2, 0)), (5.00, (0, 16800))]
    d = _compare("link1", model + again, student + [(4.00, (2, 0)), (5.00, (0, 16685))])
    assert d is not None and d.time == 5.0


# --------------------------------------------------------------------------- a 1-minimal script

@dataclass
class _Stub:
    """An explorer whose 'programs' differ exactly when the script has SB1 at 1.0 s and SA1
    after it (any other step does not matter): each candidate is one play."""

    expl: object = field(default_factory=lambda: stand_spec("mp9c").explore)
    plays: int = 0

    def diverges(self, script: Script):
        self.plays += 1
        names = [(e.name, e.time) for e in script.events]
        press = next((t for n, t in names if n == "SB1"), None)
        mode = next((t for n, t in names if n == "SA1" and press is not None and t > press), None)
        if press is None or mode is None:
            return None
        return Divergence(mode + 0.5, stand_spec("mp9c").explore.compared("task2")[0], 1, 0, "value", 0.0, 0.0)


def test_a_shrunk_script_is_one_minimal_no_single_step_can_go():
    events = [Event(0.5 + 0.3 * k, "SA5", str(k % 2)) for k in range(9)] + \
        [Event(3.3, "SB1", "1", 0.2)] + [Event(3.8 + 0.2 * k, "I07", str(k % 2)) for k in range(6)] + \
        [Event(5.2, "SA1", "1")] + [Event(5.4 + 0.1 * k, "SA6", str(k % 2)) for k in range(4)]
    script = Script(tuple(sorted(events, key=lambda e: e.time)), 12.0)
    ex = _Stub()
    first = ex.diverges(script)
    small, _div = shrink(ex, script, first, budget=30)          # a budget too small for the rounds alone
    assert [e.name for e in small.events] == ["SB1", "SA1"], small.events
