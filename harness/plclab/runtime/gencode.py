"""Generated helper code, compiled once per text.

The runtime generates small straight-line functions where a loop would run every scan: the
image <-> variable copies of a PLC (plc.py, native.py), a plant binding's exchange
(plantio.py), a simulation's sampler (sim.py), readers of variables (tracing.py). An
exploration makes a new PLC and new bindings for every script it plays and at every power
cycle in one, and their functions are the same text each time with other objects in their
namespace. So the text's code object is kept (compiling it was most of making a PLC), and only
the functions are made anew, from the objects given.
"""
from __future__ import annotations

from functools import lru_cache
from types import CodeType
from typing import Any


@lru_cache(maxsize=1024)
def _code(source: str, filename: str) -> CodeType:
    return compile(source, filename, "exec")


def define(source: str, filename: str, namespace: dict[str, Any]) -> dict[str, Any]:
    """Run `source` (definitions) in `namespace`, as exec(compile(source, filename, "exec"))
    would; returns the namespace."""
    exec(_code(source, filename), namespace)
    return namespace
