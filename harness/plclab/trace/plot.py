"""PNG plots of chosen signals, one stacked strip per signal over a shared time axis.

Uses matplotlib's object API with the Agg canvas (no pyplot, no display, no global state), so
it works in CI, in threads and under `plclab serve`. Every signal is drawn as steps: a trace
stores changes only and a value holds until the next change, so steps are the truthful
picture (a line between two changes far apart would invent a ramp). BOOL strips are short and
labelled 0/1; STRING strips show each distinct value as a level.
"""
from __future__ import annotations

import os
from typing import Optional, Sequence, Union

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from plclab.fileio import open_atomic

from .times import ns_to_s, s_to_ns
from .trace import Trace

MAX_SIGNALS = 64      # beyond this a PNG is unreadable: choose the signals to show


def plot_trace(trace: Trace, dest: Union[str, "os.PathLike[str]"],
               names: Optional[Sequence[Union[str, Sequence[str]]]] = None, start_s: float = 0.0,
               end_s: Optional[float] = None, title: Optional[str] = None,
               width_in: float = 10.0, dpi: int = 100) -> None:
    """Write a PNG of `names` (default: every signal) between start_s and end_s (default: end).

    An entry of `names` may be a group of signals (a tuple or list): they share one subplot,
    with a legend, e.g. a link's position and its target."""
    groups = [[n] if isinstance(n, str) else list(n) for n in (trace.signals() if names is None else names)]
    chosen = [n for g in groups for n in g]
    if not chosen:
        raise ValueError("no signals to plot")
    if len(chosen) > MAX_SIGNALS:
        raise ValueError(f"{len(chosen)} signals is too many for one plot "
                         f"(at most {MAX_SIGNALS}); choose the signals to show")
    t0 = s_to_ns(start_s)
    t1 = max(trace.end_ns if end_s is None else s_to_ns(end_s), t0 + 1)
    labels_by_target = {t: a for a, t in trace.aliases.items()}

    def label_of(name: str) -> str:
        alias = labels_by_target.get(name)
        return f"{alias}\n{name}" if alias else name

    heights = [0.6 if all(trace.info(n).kind == "bool" for n in g) else 1.2 for g in groups]
    fig = Figure(figsize=(width_in, sum(heights) + 1.2), dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(groups), 1, sharex=True, squeeze=False,
                        gridspec_kw={"height_ratios": heights})[:, 0]
    for ax, group in zip(axes, groups):
        for name in group:
            info = trace.info(name)
            changes = trace.changes(name)
            xs = [ns_to_s(t) for t, _v in changes] + [ns_to_s(max(t1, changes[-1][0]))]
            ys = [v for _t, v in changes]
            if info.kind == "str":
                levels = sorted(set(ys))
                ys = [levels.index(v) for v in ys]
                ax.set_yticks(range(len(levels)), [str(v) for v in levels], fontsize=7)
            elif info.kind == "bool":
                ys = [int(v) for v in ys]
                ax.set_yticks([0, 1])
                ax.set_ylim(-0.25, 1.25)
            else:
                ax.yaxis.set_major_locator(MaxNLocator(nbins=4, integer=info.kind == "int"))
            ys = ys + ys[-1:]
            ax.step(xs, ys, where="post", linewidth=1.2, label=name)
        if len(group) > 1:
            ax.legend(fontsize=7, loc="upper left")
            ax.set_ylabel(" / ".join(group) if len(" / ".join(group)) < 28 else group[0] + " ...",
                          rotation=0, ha="right", va="center", fontsize=8)
        else:
            ax.set_ylabel(label_of(group[0]), rotation=0, ha="right", va="center", fontsize=8)
        ax.tick_params(axis="y", labelsize=7)
        ax.grid(True, axis="x", alpha=0.3)
    axes[-1].set_xlim(ns_to_s(t0), ns_to_s(t1))
    axes[-1].set_xlabel("time (s)")
    if title:
        fig.suptitle(title)
    with open_atomic(dest, binary=True) as f:     # plclab.fileio: refuses links and devices
        fig.savefig(f, format="png")
