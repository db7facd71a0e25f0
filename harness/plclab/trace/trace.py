"""The trace: every change of every recorded signal, stamped with integer virtual nanoseconds.

A trace is the single record a scenario check, a golden-file diff, a CSV, a VCD and a plot are
all made from, so it stores changes only (a signal that holds for a minute costs one entry) and
keeps time exact. The query helpers answer what the checks of the labs ask: when did a condition
first hold, when did a signal next change, how long was a lamp on. They take and return float
seconds because scenarios are written in plant seconds (`moved - done == approx(3.0)`).

Value model (see plclab.iec.types): 'bool' -> bool, 'int' -> int, 'real' -> float, 'str' -> str.
At one instant a signal has one value: a second change at the same time replaces the first, and
a change back to the value before that time cancels it (a zero-width glitch is not an event).
"""
from __future__ import annotations

import difflib
import itertools
import operator
from bisect import bisect_left, bisect_right
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Literal, Optional, Sequence, Union

from .times import format_seconds, ns_to_s, s_to_ns

Kind = Literal["bool", "int", "real", "str"]
KINDS: tuple[str, ...] = ("bool", "int", "real", "str")
Edge = Literal["rising", "falling", "any"]

_RAISE: Any = object()   # sentinel: "no default given, raise NotFound"
_NEVER = 1 << 126        # a time later than any trace


class UnknownSignal(LookupError):
    """A name that is neither a signal nor an alias of the trace; the message suggests names."""


class NotFound(LookupError):
    """A query found nothing (condition never held, no change): the message says where it looked."""


@dataclass(frozen=True)
class SignalInfo:
    """What a trace knows about a signal besides its changes: kind and (for VCD) bit width."""

    name: str
    kind: str
    width: Optional[int]
    index: int           # declaration order, used to order rows that share a time


def same_value(a: Any, b: Any) -> bool:
    """Equality where NaN equals NaN, so a NaN signal is not recorded as changing every scan."""
    return a == b or (a != a and b != b)


def _to_int(v: Any) -> int:
    return operator.index(v)


_CONVERTERS: dict[str, Callable[[Any], Any]] = {"bool": bool, "int": _to_int, "real": float, "str": str}

Condition = Union[str, Callable[["State"], Any]]


def _never_held(pred: Callable[..., Any]) -> str:
    """How a query's NotFound names a predicate that never held: by its name, if it has one."""
    name = getattr(pred, "__name__", "<lambda>")
    return ("the condition" if name == "<lambda>" else name) + " never held"


class Trace:
    """Changes of named signals over virtual time (integer ns inside, seconds in queries)."""

    def __init__(self) -> None:
        self._infos: list[SignalInfo] = []
        self._index: dict[str, int] = {}
        self._times: list[list[int]] = []
        self._values: list[list[Any]] = []
        self._conv: list[Callable[[Any], Any]] = []
        self._end_ns = 0
        self._prefixes: Optional[frozenset[str]] = None
        self.aliases: dict[str, str] = {}
        self._dropped: list[int] = []        # entries `drop_before` removed, per signal
        self._versions: list[int] = []       # edits per signal (any append, replace, drop)
        self.start_ns = 0                    # nothing before this instant is kept (drop_before)

    # ------------------------------------------------------------------ recording
    def declare(self, name: str, kind: str, initial: Any, time_ns: int = 0,
                width: Optional[int] = None) -> SignalInfo:
        """Add a signal with its value from `time_ns` on (normally 0: the value at start)."""
        if name in self._index:
            raise ValueError(f"signal {name!r} is declared twice")
        if not name:
            raise ValueError("a signal needs a non-empty name")
        if kind not in KINDS:
            raise ValueError(f"signal {name!r}: kind {kind!r} is not one of {', '.join(KINDS)}")
        if width is not None and (width < 1 or (kind == "bool" and width != 1)):
            raise ValueError(f"signal {name!r}: width {width} does not fit kind {kind}")
        if time_ns < 0:
            raise ValueError(f"signal {name!r}: negative declaration time {time_ns} ns")
        info = SignalInfo(name, kind, width, len(self._infos))
        conv = _CONVERTERS[kind]
        self._infos.append(info)
        self._index[name] = info.index
        self._times.append([time_ns])
        self._values.append([conv(initial)])
        self._dropped.append(0)
        self._versions.append(0)
        self._conv.append(conv)
        self._prefixes = None
        if time_ns > self._end_ns:
            self._end_ns = time_ns
        return info

    def change(self, time_ns: int, name: str, value: Any) -> bool:
        """Record `value` for `name` at `time_ns` if it differs; True if the trace changed."""
        return self._record(self._resolve(name), time_ns, value)

    def changes_into(self, name: str, changes: Iterable[tuple[int, Any]], offset_ns: int = 0) -> None:
        """`change(offset_ns + t, name, v)` for each (t, v) of `changes`, the name looked up
        once (a session copies its simulation's recording this way after every run)."""
        i = self._resolve(name)
        record = self._record
        for t, v in changes:
            record(i, offset_ns + t, v)

    def _record(self, i: int, time_ns: int, value: Any) -> bool:
        times = self._times[i]
        values = self._values[i]
        last_t = times[-1]
        if time_ns > last_t:
            last = values[-1]
            if last == value or (last != last and value != value):     # same_value, inline
                return False
            times.append(time_ns)
            values.append(self._conv[i](value))
            self._versions[i] += 1
            if time_ns > self._end_ns:
                self._end_ns = time_ns
            return True
        if time_ns < last_t:
            raise ValueError(f"change of {self._infos[i].name} at {format_seconds(time_ns)} s is "
                             f"before its last change at {format_seconds(last_t)} s")
        if same_value(values[-1], value):
            return False
        self._versions[i] += 1
        if len(times) > 1 and same_value(values[-2], value):
            times.pop()          # back to the value before this instant: no event at all
            values.pop()
        else:
            values[-1] = self._conv[i](value)
        return True

    def advance(self, time_ns: int) -> None:
        """Mark that the trace covers time up to `time_ns` even if nothing changed."""
        if time_ns > self._end_ns:
            self._end_ns = time_ns

    def drop_before(self, time_ns: int) -> int:
        """Forget what happened before `time_ns` (a long-running recorder keeps a window,
        as the virtual lab does): each signal keeps the value in effect then, stamped
        `time_ns`, and what follows. `change_count` and `changes_from` go on counting every
        entry ever recorded, so incremental readers are not disturbed. Returns the number of
        entries dropped."""
        if time_ns <= self.start_ns:
            return 0
        self.start_ns = time_ns
        total = 0
        for i, times in enumerate(self._times):
            k = bisect_right(times, time_ns) - 1
            if k >= 0:
                self._versions[i] += 1
            if k > 0:
                del times[:k]
                del self._values[i][:k]
                self._dropped[i] += k
                total += k
            if k >= 0 and times[0] < time_ns:
                times[0] = time_ns
        return total

    def alias(self, alias: str, name: str) -> None:
        """Let queries and predicates use a console label (`SQ2`) for an address (`%IX0.2`)."""
        self._resolve(name)
        if alias in self._index and alias != name:
            raise ValueError(f"alias {alias!r} would hide the signal of that name")
        self.aliases[alias] = name

    # ------------------------------------------------------------------ inspection
    @property
    def end_ns(self) -> int:
        """The last instant the trace covers (last change or last `advance`)."""
        return self._end_ns

    @property
    def end_s(self) -> float:
        return ns_to_s(self._end_ns)

    def signals(self) -> list[str]:
        """Signal names in declaration order."""
        return [info.name for info in self._infos]

    def info(self, name: str) -> SignalInfo:
        return self._infos[self._resolve(name)]

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and (name in self._index or name in self.aliases)

    def __repr__(self) -> str:
        return f"<Trace {len(self._infos)} signals, until t={format_seconds(self._end_ns)} s>"

    def change_count(self, name: str) -> int:
        """How many entries were recorded for `name` (the initial value counts): as many as
        `changes(name)` has, plus what `drop_before` dropped."""
        i = self._resolve(name)
        return len(self._times[i]) + self._dropped[i]

    def versions(self) -> list[int]:
        """A count of the edits of each signal (declaration order): a signal whose count is the
        same as at an earlier call has not changed since, so an incremental reader (a session
        copying its simulation's trace after every scan) skips it without reading it."""
        return self._versions[:]

    def changes_from(self, name: str, start: int) -> list[tuple[int, Any]]:
        """`changes(name)[start:]` without copying the rest (for incremental readers); `start`
        counts every entry ever recorded (what `drop_before` dropped, too)."""
        i = self._resolve(name)
        start = max(0, start - self._dropped[i])
        return list(zip(self._times[i][start:], self._values[i][start:]))

    def changes(self, name: str) -> list[tuple[int, Any]]:
        """(time_ns, value) pairs; the first is the declared initial value."""
        i = self._resolve(name)
        return list(zip(self._times[i], self._values[i]))

    def value_at(self, name: str, time_s: float) -> Any:
        """The value in effect at `time_s`, after the changes stamped with that time.

        None before the signal was declared (normally never: signals start at 0).
        """
        return self.value_at_ns(name, s_to_ns(time_s))

    def value_at_ns(self, name: str, time_ns: int) -> Any:
        return self._value(self._resolve(name), time_ns)

    def _value(self, i: int, time_ns: int) -> Any:
        k = bisect_right(self._times[i], time_ns) - 1
        return self._values[i][k] if k >= 0 else None

    def state_at(self, time_s: float) -> "State":
        """All values at one instant, read as `state.SQ2` or `state['%QX1.0']`."""
        return State(self, s_to_ns(time_s), None, "")

    # ------------------------------------------------------------------ queries
    def first(self, cond: Condition, after: float = 0.0, until: Optional[float] = None,
              default: Any = _RAISE) -> Any:
        """The earliest time in [after, until] at which `cond` holds (a name: the signal is true).

        `cond` may be a signal name or a predicate over a `State` (`lambda io: io.SQ2 and
        not io.L1`). Raises NotFound, or returns `default` if given (`default=None` makes
        "never" checks read well: `assert trace.first(conflict, default=None) is None`).
        Only the instants where a signal the predicate read changes are tried, so it is cheap
        on long traces.
        """
        pred: Callable[[State], Any]
        if isinstance(cond, str):
            idx = self._resolve(cond)
            pred = lambda s: s._get_index(idx)  # noqa: E731
            what = f"{cond} was never true"
        else:
            pred = cond
            what = _never_held(cond)
        t = s_to_ns(after)
        end = self._window_end(until)
        while t <= end:
            read: set[int] = set()
            if pred(State(self, t, read, "")):
                return ns_to_s(t)
            nxt = _NEVER
            for i in read:
                times = self._times[i]
                k = bisect_right(times, t)
                if k < len(times) and times[k] < nxt:
                    nxt = times[k]
            t = nxt
        return self._not_found(default, f"{what} {self._window_text(after, until)}")

    def first_values(self, names: Sequence[str], pred: Callable[[tuple], Any], after: float = 0.0,
                     until: Optional[float] = None, default: Any = _RAISE) -> Any:
        """`first` for a predicate of the values of `names` alone, given to it as a tuple in
        that order (None before a signal's declaration, as a State reads it): the same answer,
        found in one pass over the signals' changes instead of a State and a look-up per name
        at each instant (a check that holds over a whole run, of signals that change at most
        scans: the TUR-10's read enables)."""
        idx = [self._resolve(n) for n in names]
        t = s_to_ns(after)
        end = self._window_end(until)
        current = [self._value(i, t) for i in idx]
        changes = []
        for j, i in enumerate(idx):
            times, values = self._times[i], self._values[i]
            k = bisect_right(times, t)
            last = bisect_right(times, end)
            changes.extend(zip(times[k:last], itertools.repeat(j), values[k:last]))
        changes.sort(key=operator.itemgetter(0, 1))
        n = len(changes)
        k = 0
        while t <= end:
            while k < n and changes[k][0] == t:
                current[changes[k][1]] = changes[k][2]
                k += 1
            if pred(tuple(current)):
                return ns_to_s(t)
            if k == n:
                break
            t = changes[k][0]
        return self._not_found(default, f"{_never_held(pred)} {self._window_text(after, until)}")

    def next_change(self, names: Union[str, Iterable[str]], after: float = 0.0,
                    until: Optional[float] = None, default: Any = _RAISE) -> Any:
        """The earliest change at or after `after` of any of `names` (initial values do not count)."""
        if isinstance(names, str):
            names = [names]
        names = list(names)
        t0 = s_to_ns(after)
        end = self._window_end(until)
        best = _NEVER
        for name in names:
            times = self._times[self._resolve(name)]
            k = max(1, bisect_left(times, t0))
            if k < len(times) and times[k] < best:
                best = times[k]
        if best <= end:
            return ns_to_s(best)
        return self._not_found(
            default, f"{', '.join(names)} did not change {self._window_text(after, until)}")

    def edges(self, name: str, edge: Edge = "rising", after: float = 0.0,
              until: Optional[float] = None) -> list[float]:
        """Times where the signal's truth value goes false->true ('rising'), true->false or either."""
        if edge not in ("rising", "falling", "any"):
            raise ValueError(f"edge must be 'rising', 'falling' or 'any', not {edge!r}")
        i = self._resolve(name)
        t0, end = s_to_ns(after), self._window_end(until)
        out: list[float] = []
        times, values = self._times[i], self._values[i]
        for k in range(1, len(times)):
            was, now = bool(values[k - 1]), bool(values[k])
            if was == now or not t0 <= times[k] <= end:
                continue
            if edge == "any" or (edge == "rising") == now:
                out.append(ns_to_s(times[k]))
        return out

    def pulses(self, name: str, after: float = 0.0,
               until: Optional[float] = None) -> list[tuple[float, float]]:
        """(start, end) of every interval where the signal is true, for starts in [after, until].

        A pulse still on when the trace ends is closed at the trace's end.
        """
        return [(ns_to_s(s), ns_to_s(e)) for s, e in self._pulses_ns(name, after, until)]

    def durations_high(self, name: str, after: float = 0.0,
                       until: Optional[float] = None) -> list[float]:
        """How long each pulse of `name` lasted (seconds, exact to the ns), in time order."""
        return [ns_to_s(e - s) for s, e in self._pulses_ns(name, after, until)]

    def _pulses_ns(self, name: str, after: float,
                   until: Optional[float]) -> list[tuple[int, int]]:
        i = self._resolve(name)
        t0, end = s_to_ns(after), self._window_end(until)
        out: list[tuple[int, int]] = []
        start: Optional[int] = None
        for t, v in zip(self._times[i], self._values[i]):
            if v and start is None:
                start = t
            elif not v and start is not None:
                if t0 <= start <= end:
                    out.append((start, t))
                start = None
        if start is not None and t0 <= start <= end:
            out.append((start, max(start, self._end_ns)))
        return out

    # ------------------------------------------------------------------ helpers
    def _resolve(self, name: str) -> int:
        i = self._index.get(name)
        if i is None:
            target = self.aliases.get(name)
            i = self._index.get(target) if target is not None else None
            if i is None:
                raise UnknownSignal(self._unknown_text(name))
        return i

    def _unknown_text(self, name: str) -> str:
        close = difflib.get_close_matches(name, [*self._index, *self.aliases], n=3)
        hint = f" (did you mean {', '.join(close)}?)" if close else ""
        return f"no signal {name!r} in the trace{hint}"

    def _window_end(self, until: Optional[float]) -> int:
        return self._end_ns if until is None else min(s_to_ns(until), self._end_ns)

    def _window_text(self, after: float, until: Optional[float]) -> str:
        end = self._window_end(until)
        return f"between t={format_seconds(s_to_ns(after))} s and t={format_seconds(end)} s"

    @staticmethod
    def _not_found(default: Any, message: str) -> Any:
        if default is _RAISE:
            raise NotFound(message)
        return default

    def _is_prefix(self, prefix: str) -> bool:
        if self._prefixes is None:
            found: set[str] = set()
            for name in (*self._index, *self.aliases):
                if name.startswith("%"):
                    continue
                parts = name.split(".")
                for n in range(1, len(parts)):
                    found.add(".".join(parts[:n]))
            self._prefixes = frozenset(found)
        return prefix in self._prefixes


class State:
    """The values of all signals at one instant, as predicates read them.

    `io.SQ2` (a name or alias), `io['%QX1.0']` (any name), `io.PRG_Main.fb.Q` (qualified names
    by parts). When a predicate runs inside `Trace.first`, the state notes which signals were
    read, so the search only revisits instants where one of them changes.
    """

    __slots__ = ("_trace", "_t", "_read", "_prefix")

    def __init__(self, trace: Trace, time_ns: int, read: Optional[set[int]], prefix: str):
        self._trace = trace
        self._t = time_ns
        self._read = read
        self._prefix = prefix

    @property
    def time_s(self) -> float:
        return ns_to_s(self._t)

    def _get_index(self, i: int) -> Any:
        if self._read is not None:
            self._read.add(i)
        return self._trace._value(i, self._t)

    def _lookup(self, key: str) -> Any:
        full = self._prefix + key
        tr = self._trace
        i = tr._index.get(full)
        if i is None and full in tr.aliases:
            i = tr._resolve(full)
        if i is not None:
            return self._get_index(i)
        if tr._is_prefix(full):
            return State(tr, self._t, self._read, full + ".")
        raise UnknownSignal(tr._unknown_text(full))

    def __getitem__(self, name: str) -> Any:
        return self._lookup(name)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        try:
            return self._lookup(name)
        except UnknownSignal as e:
            raise AttributeError(str(e)) from None

    def __repr__(self) -> str:
        return f"<State t={format_seconds(self._t)} s {self._prefix or ''}>"
