"""The semantics suite runs three times: with the compiler's fast paths, on the plain path
(`compile_unit(..., optimize=False)`), so a fast path can never compute something the plain
path does not, and on the native scan path (the program's C, plclab.runtime.native), so the
C can never compute something the Python does not. A test module opts in with
`pytestmark = pytest.mark.usefixtures("compile_mode")`."""
from __future__ import annotations

import pytest

import st_helpers   # on sys.path through tests/conftest.py


@pytest.fixture(params=["optimized", "plain", "native"])
def compile_mode(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """Run every program of the test with (optimized) or without (plain) the Python fast
    paths, or on the native path (where its C backend covers the program)."""
    monkeypatch.setattr(st_helpers, "OPTIMIZE", request.param != "plain")
    monkeypatch.setattr(st_helpers, "NATIVE", request.param == "native")
    if request.param == "native":
        from plclab.runtime import native
        monkeypatch.setattr(native, "PREFER_API", False)     # same C, a third of the build time
    return request.param
