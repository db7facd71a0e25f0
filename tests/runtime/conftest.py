"""The semantics suite runs twice: once with the compiler's fast paths (what users run) and
once on the plain path (`compile_unit(..., optimize=False)`), so a fast path can never
compute something the plain path does not. A test module opts in with
`pytestmark = pytest.mark.usefixtures("compile_mode")`."""
from __future__ import annotations

import pytest

import st_helpers   # on sys.path through tests/conftest.py


@pytest.fixture(params=[True, False], ids=["optimized", "plain"])
def compile_mode(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> bool:
    """Compile every program of the test with (optimized) or without (plain) fast paths."""
    monkeypatch.setattr(st_helpers, "OPTIMIZE", request.param)
    return request.param
