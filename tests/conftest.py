"""Setup shared by the whole suite: the helper modules that live beside the tests
(runtime/st_helpers.py, grader/grader_helpers.py, grader/explore_cases.py, stands/golden.py,
modbus/modbus_support.py, cnc/cnc_st.py) import by their plain names, with pytest's assertion
rewriting so their asserts report like the tests' own. One place instead of a sys.path line in
each test file."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
for folder in ("runtime", "grader", "stands", "modbus", "cnc", "ladder"):
    if str(TESTS / folder) not in sys.path:
        sys.path.insert(0, str(TESTS / folder))
pytest.register_assert_rewrite("st_helpers", "grader_helpers", "explore_cases", "golden", "modbus_support", "cnc_st",
                              "drawing")

# CI is deterministic: under CI=true every property test draws the same examples each run
# (a failure found there reproduces on the next run); a developer's run still explores anew.
import os  # noqa: E402

from hypothesis import settings  # noqa: E402
from hypothesis.configuration import set_hypothesis_home_dir  # noqa: E402

# the examples database stays in the checkout's .hypothesis (a failure found is replayed on
# the next run), though the tests run in a folder of their own (below)
set_hypothesis_home_dir(TESTS.parent / ".hypothesis")

settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")


@pytest.fixture(autouse=True, scope="session")
def _own_working_directory(tmp_path_factory):
    """Every test process (each pytest-xdist worker, scripts/test) works in a folder of its
    own: a command run without an output path writes where a user's would (out/grade,
    out/retain/STAND-VARIANT-SCENARIO.json), and there two workers running the same command
    at once would share, and delete, each other's files; nor does the suite litter the
    checkout. Tests name the repository's files by absolute paths."""
    here = os.getcwd()
    os.chdir(tmp_path_factory.mktemp("cwd"))
    yield
    os.chdir(here)


@pytest.fixture(autouse=True, scope="session")
def _shared_explorations(tmp_path_factory):
    """The folder where this session's workers share the explorations several test files
    make of one fixture (tests/grader/explored.py): pytest's base temporary folder of the
    session, which a pytest-xdist worker's own is a folder of."""
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent
    os.environ["PLCLAB_TESTS_SHARED_DIR"] = str(base / "shared-explorations")
    yield
    os.environ.pop("PLCLAB_TESTS_SHARED_DIR", None)


# The heaviest test files first. scripts/test runs pytest-xdist with --dist loadfile: whole
# files go, in the order collected, to whichever worker is free. A file of minutes collected
# late runs on alone at the end while the other cores idle; longest first keeps every core
# busy to the end (the figures: a run's `--durations=0`, summed per file). The order of the
# tests inside a file, and of the other files, stays as collected.
HEAVY_FIRST = (
    "tests/grader/test_explore.py",
    "tests/grader/test_classroom.py",
    "tests/grader/test_grader_tur10.py",
    "tests/runtime/test_native.py",
    "tests/grader/test_grader_mp9c.py",
    "tests/grader/test_explore_rates.py",
    "tests/grader/test_explore_alternatives.py",
    "tests/lab/test_page_console.py",
    "tests/grader/test_explore_engine.py",
    "tests/grader/test_localize.py",
    "tests/cnc/test_cnc_fine_cycle.py",
    "tests/grader/test_class_untrusted.py",
    "tests/lab/test_page.py",
    "tests/grader/test_rules.py",
    "tests/lab/test_page_program.py",
    "tests/runtime/test_semantics_fastpaths.py",
    "tests/grader/test_class_cluster.py",
    "tests/stands/test_student_programs.py",
    "tests/lab/test_page_stand.py",
)


def pytest_collection_modifyitems(config, items):
    rank = {path: n for n, path in enumerate(HEAVY_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::", 1)[0], len(HEAVY_FIRST)))


@pytest.fixture(autouse=True, scope="session")
def _stall_dumps(tmp_path_factory):
    """Grading processes (grade-class's, a Dask worker's) write their Python stacks here when
    they are still running shortly before their time limit (plclab.grader.classroom.STALL_DUMP_ENV):
    a test that fails on "not graded: ... time limit" then shows where the grading was."""
    folder = tmp_path_factory.mktemp("stalls")
    os.environ["PLCLAB_STALL_DUMP"] = str(folder)
    yield
    os.environ.pop("PLCLAB_STALL_DUMP", None)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """The stacks grading processes dumped during this test, as a section of its report
    (printed with a failure), then removed (the next test starts with none)."""
    outcome = yield
    folder = os.environ.get("PLCLAB_STALL_DUMP")
    if call.when != "call" or not folder or not os.path.isdir(folder):
        return
    dumps = []
    for path in sorted(Path(folder).glob("stall-*.txt")):
        text = path.read_text(encoding="utf-8", errors="replace")
        if text.count("\n") > 1:                # more than the header: the watchdog fired
            dumps.append(text)
        path.unlink(missing_ok=True)
    if dumps:
        outcome.get_result().sections.append(("grading processes that ran near their time limit",
                                              "\n".join(dumps)))
