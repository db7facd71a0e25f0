"""Recording a PLC's signals once per scan, cheaply.

The simulator calls this on its hot path: once per scan, a few hundred signals, where almost
every scan changes nothing. So the recorder keeps the previous scan's values as one tuple and
compares whole tuples first (a single C-level comparison); only when something differs does it
walk the signals in Python to find and record what changed.
"""
from __future__ import annotations

from itertools import compress
from operator import itemgetter, ne
from typing import Any, Callable, Mapping, Optional, Sequence

from .trace import Trace


class Recorder:
    """Diffs successive snapshots of a fixed list of trace signals and records the changes.

    The recorder owns its signals: it assumes nobody else calls `trace.change` for them, so
    its remembered values stay the trace's last values.
    """

    __slots__ = ("trace", "names", "_indices", "_last", "_get", "_snapshot")

    def __init__(self, trace: Trace, snapshot: Optional[Callable[[], Mapping[str, Any]]] = None,
                 names: Optional[Sequence[str]] = None):
        """`snapshot()` returns a dict-like {name: value}; `names` defaults to every signal."""
        self.trace = trace
        self.names: tuple[str, ...] = tuple(trace.signals() if names is None else names)
        self._indices = tuple(trace._resolve(n) for n in self.names)
        self._last = tuple(trace._values[i][-1] for i in self._indices)
        self._snapshot = snapshot
        if len(self.names) == 1:
            only = self.names[0]
            self._get: Callable[[Mapping[str, Any]], tuple[Any, ...]] = lambda m: (m[only],)
        elif self.names:
            self._get = itemgetter(*self.names)
        else:
            self._get = lambda m: ()

    def sample(self, time_ns: int) -> int:
        """Take a snapshot with the function given at construction and record it."""
        if self._snapshot is None:
            raise TypeError("this Recorder was made without a snapshot function")
        return self.record(time_ns, self._get(self._snapshot()))

    def record_mapping(self, time_ns: int, snapshot: Mapping[str, Any]) -> int:
        """Record the recorder's signals read by name from `snapshot`."""
        return self.record(time_ns, self._get(snapshot))

    def record(self, time_ns: int, values: Sequence[Any]) -> int:
        """Record `values` (in `names` order) at `time_ns`; returns how many signals changed."""
        trace = self.trace
        if time_ns > trace._end_ns:
            trace._end_ns = time_ns
        if type(values) is not tuple:
            values = tuple(values)
        last = self._last
        if values == last:
            return 0
        if len(values) != len(last):
            raise ValueError(f"expected {len(last)} values, got {len(values)}")
        changed = 0
        record = trace._record
        indices = self._indices
        for k in compress(range(len(values)), map(ne, values, last)):   # C-speed scan
            new, old = values[k], last[k]
            if new == new or old == old:      # not NaN -> NaN
                record(indices[k], time_ns, new)
                changed += 1
        self._last = values
        return changed
