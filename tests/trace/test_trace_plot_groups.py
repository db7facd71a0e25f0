"""Grouped signals share one subplot (a link's position with its target)."""
from __future__ import annotations

import matplotlib.image as mpimg
import pytest

from plclab.trace import Trace, plot_trace


def make() -> Trace:
    tr = Trace()
    tr.declare("pos", "int", 0)
    tr.declare("target", "int", 100)
    tr.declare("go", "bool", False)
    for k in range(1, 11):
        tr.change(k * 100_000_000, "pos", 10 * k)
    tr.change(500_000_000, "go", True)
    tr.advance(1_200_000_000)
    return tr


def test_a_group_is_one_subplot_so_the_figure_is_shorter(tmp_path):
    separate, grouped = tmp_path / "a.png", tmp_path / "b.png"
    plot_trace(make(), separate, names=["pos", "target", "go"])
    plot_trace(make(), grouped, names=[("pos", "target"), "go"])
    h_sep = mpimg.imread(separate).shape[0]
    h_grp = mpimg.imread(grouped).shape[0]
    assert h_grp < h_sep                      # two int subplots became one
    assert mpimg.imread(grouped).std() > 0.05  # something was drawn


def test_an_unknown_name_in_a_group_is_an_error(tmp_path):
    with pytest.raises(LookupError):
        plot_trace(make(), tmp_path / "c.png", names=[("pos", "nope")])
