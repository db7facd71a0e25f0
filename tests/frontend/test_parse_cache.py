"""A program parsed again is read back from the parser's cache (a grading's restarts, the lab's
reloads and a class's model answer check the same text again and again): the tree is the
one a fresh parse gives, the checker's annotations on one copy never reach the next, and the
cache stays within its bound."""
from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from typing import Any

from plclab.frontend import check_sources
from plclab.frontend import parser as P
from plclab.stands import bundle, get_stand


def _shape(x: Any) -> Any:
    """A tree as plain nested values: node class, then every field (annotations included)."""
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return (type(x).__name__,) + tuple((f.name, _shape(getattr(x, f.name))) for f in dataclasses.fields(x))
    if isinstance(x, (list, tuple)):
        return [_shape(v) for v in x]
    if isinstance(x, dict):
        return {k: _shape(v) for k, v in x.items()}
    return (type(x).__name__, x) if isinstance(x, (int, float, str, bool, type(None))) else repr(type(x))


def _fresh(text: str, file: str):
    """What parsing gives without the cache."""
    unit, diags = P._parse(text, file)
    assert not diags
    return unit


def test_a_text_parsed_again_is_the_fresh_parse_and_not_the_checked_copy():
    text = bundle(get_stand("mp9c"), "task3")
    P.parse_source(text, "robot.st")                      # kept from the second parse on
    first, _ = P.parse_source(text, "robot.st")
    assert P._PARSED
    again, _ = P.parse_source(text, "robot.st")
    assert again is not first
    assert _shape(again) == _shape(first) == _shape(_fresh(text, "robot.st"))
    checked = check_sources([("robot.st", text)])         # annotates the tree it parsed in place
    assert checked.pous
    third, _ = P.parse_source(text, "robot.st")
    assert _shape(third) == _shape(_fresh(text, "robot.st"))
    other, _ = P.parse_source(text, "other.st")            # the same text under another name
    assert other.pous[0].file == "other.st"


def test_errors_are_found_each_time_and_the_cache_keeps_within_its_bound(monkeypatch):
    bad = "PROGRAM p\nVAR x : INT; END_VAR\nx := ;\nEND_PROGRAM\n"
    for _ in range(2):
        unit, diags = P.parse_source(bad, "bad.st")
        assert unit is None and diags and diags[0].line == 3
    monkeypatch.setattr(P, "PARSE_CACHE_BYTES", 20_000)
    for n in range(40):
        for _ in range(2):
            P.parse_source(f"PROGRAM p{n}\nVAR x : INT; END_VAR\nx := {n};\nEND_PROGRAM\n", f"p{n}.st")
    assert 0 < sum(len(v) for v in P._PARSED.values()) == P._parsed_bytes <= 20_000
    unit, _ = P.parse_source("PROGRAM p39\nVAR x : INT; END_VAR\nx := 39;\nEND_PROGRAM\n", "p39.st")
    assert unit.pous[0].name == "p39"


# The parser's LALR tables: built from the grammar by the first process, read from the user's
# cache by every later one (a CLI command, a lab upload's trial, a class's grading process).
_TABLES_PROBE = r"""
from plclab.frontend import parser as P
from plclab.stands import bundle, get_stand
unit, diags = P._parse(bundle(get_stand("tur10"), "task2"), "robot.st")
bad = P._parse("PROGRAM main\nVAR x : INT; END_VAR\nIF x THEN x := 1; END_IF\nx := ;\nEND_PROGRAM\n", "bad.st")[1]
print(repr((unit is not None and not diags, len(unit.pous), [str(d) for d in bad])))
"""


def _tables_probe(cache) -> str:
    """A new process's parses of a stand's program and of a wrong one, with `cache` as its
    XDG_CACHE_HOME."""
    env = dict(os.environ, XDG_CACHE_HOME=str(cache))
    r = subprocess.run([sys.executable, "-c", _TABLES_PROBE], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_the_parsers_tables_are_built_once_and_read_back_by_the_next_process(tmp_path):
    first = _tables_probe(tmp_path)
    assert "True" in first and "bad.st:4:1: error: missing ';'" in first
    files = list((tmp_path / "plclab" / "parser").iterdir())
    assert len(files) == 1 and files[0].stat().st_size > 10_000
    saved = files[0].read_bytes()
    assert _tables_probe(tmp_path) == first
    assert files[0].read_bytes() == saved                 # read back, not built and written again
    # a damaged file (a process stopped while writing it): the tables are built again and saved
    files[0].write_bytes(saved[:5000])
    assert _tables_probe(tmp_path) == first
    assert files[0].stat().st_size > 10_000
    assert _tables_probe(tmp_path) == first
