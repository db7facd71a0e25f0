"""PNG plots: a real image, one strip per chosen signal, no display needed."""
from __future__ import annotations

import numpy as np
import pytest
from matplotlib.image import imread

from plclab.trace import Trace, UnknownSignal, plot_trace

MS = 1_000_000


def sample() -> Trace:
    t = Trace()
    t.declare("%QX0.0", "bool", False)
    t.declare("PRG.level", "int", 0)
    t.declare("PRG.temp", "real", 20.0)
    t.declare("PRG.mode", "str", "IDLE")
    t.alias("L1", "%QX0.0")
    for k in range(1, 20):
        t.change(k * 100 * MS, "%QX0.0", k % 2 == 1)
        t.change(k * 100 * MS, "PRG.level", k * 3)
        t.change(k * 100 * MS, "PRG.temp", 20.0 + k * 0.7)
    t.change(500 * MS, "PRG.mode", "RUN")
    t.advance(2_000 * MS)
    return t


def test_png_is_written_and_has_ink(tmp_path):
    path = tmp_path / "run.png"
    plot_trace(sample(), path, title="MP-9C task 2")
    img = imread(path)
    h, w = img.shape[:2]
    assert w == 1000 and h > 300
    gray = img[..., :3].mean(axis=2)
    assert (gray < 0.5).mean() > 0.005          # lines and labels, not a blank canvas
    assert np.unique(gray).size > 10


def test_height_grows_with_the_number_of_strips(tmp_path):
    one, four = tmp_path / "one.png", tmp_path / "four.png"
    plot_trace(sample(), one, names=["L1"])
    plot_trace(sample(), four)
    assert imread(four).shape[0] > imread(one).shape[0] + 200


def test_window_and_bad_requests(tmp_path):
    plot_trace(sample(), tmp_path / "zoom.png", names=["PRG.temp"], start_s=0.5, end_s=1.0)
    assert (tmp_path / "zoom.png").stat().st_size > 1000
    with pytest.raises(UnknownSignal):
        plot_trace(sample(), tmp_path / "x.png", names=["PRG.nope"])
    with pytest.raises(ValueError, match="no signals"):
        plot_trace(sample(), tmp_path / "x.png", names=[])
