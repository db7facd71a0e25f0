"""`plclab check --emit-python`: the Python a program compiles to, each line from ST marked
`# FILE:LINE POU`, compared with reviewed snapshots (tests/runtime/snapshots/NAME.py with
fast paths, NAME.plain.py without); and a traceback through compiled code shows those lines.

After an intended change of the generated code regenerate the snapshots with
    PLCLAB_UPDATE_SNAPSHOTS=1 .venv/bin/python -m pytest tests/runtime/test_emit_python.py
and review their diff before committing it.
"""
from __future__ import annotations

import os
import traceback
from pathlib import Path

import pytest

from plclab.cli import main
from st_helpers import program

SNAPSHOTS = Path(__file__).resolve().parent / "snapshots"
UPDATE = os.environ.get("PLCLAB_UPDATE_SNAPSHOTS") == "1"


@pytest.mark.parametrize("plain", [False, True], ids=["optimized", "plain"])
@pytest.mark.parametrize("name", ["pous", "statements"])
def test_emitted_python_matches_its_snapshot(name, plain, capsys, monkeypatch):
    monkeypatch.chdir(SNAPSHOTS)               # the `# file:line` marks name the file as given
    assert main(["check", "--emit-python", f"{name}.st"] + (["--plain"] if plain else [])) == 0
    out = capsys.readouterr().out
    snap = SNAPSHOTS / f"{name}{'.plain' if plain else ''}.py"
    if UPDATE:
        snap.write_text(out, encoding="utf-8")
    assert snap.exists(), f"missing snapshot {snap}: run with PLCLAB_UPDATE_SNAPSHOTS=1 and review it"
    assert out == snap.read_text(encoding="utf-8"), f"{snap.name} differs: review, then regenerate"


@pytest.mark.parametrize("plain", [False, True], ids=["optimized", "plain"])
def test_plclab_compile_is_check_emit_python(plain, capsys, monkeypatch):
    monkeypatch.chdir(SNAPSHOTS)
    flags = ["--plain"] if plain else []
    assert main(["compile", "pous.st"] + flags) == 0
    assert capsys.readouterr().out == (SNAPSHOTS / f"pous{'.plain' if plain else ''}.py").read_text(encoding="utf-8")
    assert main(["compile", "missing.st"]) == 1
    err = capsys.readouterr().err
    assert "missing.st" in err and len(err.strip().splitlines()) == 1


def test_every_statement_line_names_its_st_line(capsys, monkeypatch):
    monkeypatch.chdir(SNAPSHOTS)
    main(["check", "--emit-python", "statements.st"])
    st_lines = (SNAPSHOTS / "statements.st").read_text().splitlines()
    marked = [line.rsplit("# statements.st:", 1)[1] for line in capsys.readouterr().out.splitlines()
              if "# statements.st:" in line]
    seen = {int(m.split()[0]) for m in marked}
    body = range(st_lines.index("END_VAR") + 2, st_lines.index("END_PROGRAM") + 1)
    statements = {n for n in body if st_lines[n - 1].strip() not in ("", "ELSE", "END_IF;", "END_FOR;",
                                                                       "END_WHILE;", "END_CASE;")}
    assert statements <= seen, sorted(statements - seen)


def test_a_traceback_through_compiled_code_shows_the_st_line():
    sim = program("VAR a, z, q : INT; END_VAR", "a := a + 1;\nq := 10 / z;")
    run = sim.plc.compiled.namespace["PRG_MAIN"]()._run
    with pytest.raises(Exception) as info:
        run()
    text = "".join(traceback.format_exception(info.value))
    assert "_op" in text and "# t.st:5 main" in text
