"""Golden traces of the CNC stand's scenarios (tests/stands/golden/cnc-full-*.csv): the
console, lamps, KM1, the frame, the direction bits and the table's position at each frame
change, compared with a fresh run in virtual time (tolerance: one scan). After an intended
change of behaviour regenerate with PLCLAB_UPDATE_GOLDEN=1 and review the diff."""
from __future__ import annotations

from pathlib import Path

import pytest

from golden import check_golden

from plclab.stands import cnc

SCENARIOS = ("square", "circle", "star", "pocket", "backlash", "blank", "estop")


@pytest.mark.parametrize("name", SCENARIOS)
def test_scenario_matches_its_golden_trace(name):
    s = cnc.session()
    cnc.SCENARIOS[name](s)                # raises ScenarioFailure if the scenario's own checks fail
    cnc.check_never(s)
    summary = cnc.summary_trace(s)
    assert summary.change_count("Frame") >= (1 if name == "estop" else 2)   # estop: frame 1 only
    check_golden(summary, f"cnc-full-{name}", s.tick)


def test_summary_keeps_the_table_position_at_every_frame_change():
    s = cnc.session()
    cnc.SCENARIOS["square"](s)
    summary = cnc.summary_trace(s)
    starts = [(summary.value_at_ns("TableX", t), summary.value_at_ns("TableY", t))
              for t, _ in summary.changes("Frame")[1:]]
    assert starts == [(2000, 0), (2000, 2000), (0, 2000)]          # frames 2, 3, 4 of the 20 mm square


def test_docs_show_every_plotted_scenario(tmp_path):
    from plclab.cnc.run import PLOTTED_SCENARIOS, plot_scenario

    docs = Path(__file__).resolve().parents[2] / "docs"
    text = (docs / "cnc.md").read_text(encoding="utf-8")
    for name in PLOTTED_SCENARIOS:
        assert f"](img/cnc-{name}.png)" in text
        assert (docs / "img" / f"cnc-{name}.png").stat().st_size > 10_000
    out = plot_scenario("square", str(tmp_path / "square.png"))
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
