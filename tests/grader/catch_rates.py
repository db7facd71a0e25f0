"""How often one random operator script shows each fixture's mistake (a developer's tool).

Exploration's catch of a mistake must not hang on one random stream: a budget of B scripts
finds a mistake one script in k shows with probability 1 - (1 - 1/k)^B. This plays N scripts
of a fixed seed (not the submission's) on each fixture against its task's model answer, as
exploration plays them (random or, coverage-guided, kept scripts mutated; every other one
aimed at the moments the one before changed the model answer's stand), and prints, per
fixture, the share of scripts that show a confirmed difference and the chance the stand's
default budget misses it (for a coverage-guided stream the scripts are not independent:
`first` says where the first hits came). Correct alternatives must show 0. --no-coverage
gives the rate without coverage guidance (before and after, issue 29).

    .venv/bin/python tests/grader/catch_rates.py                 # every exploration fixture, 40 scripts
    .venv/bin/python tests/grader/catch_rates.py --scripts 100 --all --jobs 2 --json rates.json
    .venv/bin/python tests/grader/catch_rates.py mp9c/task3_stop_needs_enable
    .venv/bin/python tests/grader/catch_rates.py --no-coverage mp9c/task2_full_memory_wraps   # before
    .venv/bin/python tests/grader/catch_rates.py --stand mp9c --task task3 robot.st   # a program of your own

--all adds the scripted scenarios' own fixtures (tests/grader/fixtures/STAND/*.st): mistakes
too, found by the scenarios, and a wider sample of what exploration reaches.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import re
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

TASK = re.compile(r"\(\* plclab (?:grader|explore) fixture: (task\d)")


def fixtures(all_: bool) -> list[tuple[str, str, Path, bool]]:
    """(stand, task, path, is a mistake) of the exploration fixtures (and with `all_` the
    scenarios' fixtures of the two robots)."""
    import make_explore_fixtures as mf
    out = [(f.stand, f.task, mf.path(f), not f.passes) for f in mf.ALL]
    if all_:
        for stand in ("mp9c", "tur10"):
            for p in sorted((HERE / "fixtures" / stand).glob("*.st")):
                m = TASK.search(p.read_text(encoding="utf-8"))
                if m:
                    out.append((stand, m.group(1), p, True))
    return out


def rate(job: tuple[str, str, str, bool, int, int], stop_at: int | None = None) -> dict:
    """Play `scripts` scripts (seeds base..) on one fixture; which of them show a difference.
    `stop_at`: stop once that many have (a verdict "at least that many" cannot change after:
    the tests ask no more); `played` says how many were played."""
    from plclab.frontend import check_sources, read_sources
    from plclab.grader.explore import Explorer, Program, model_answer, search
    from plclab.grader.registry import requirement_set
    from plclab.stands.base import stand_spec
    stand, task, path, mistake, scripts, base = job[:6]
    explain_first = job[6] if len(job) > 6 else 0
    no_aim = job[7] if len(job) > 7 else False
    coverage = job[8] if len(job) > 8 else True
    expl = stand_spec(stand).explore
    if no_aim:
        expl = dataclasses.replace(expl, aim=None)
    model, why = model_answer(stand, task, None)
    assert model is not None, why
    srcs = read_sources([path])
    student = Program(srcs, check_sources(srcs))
    hits, kinds = [], {}
    n_played = 0
    ex = Explorer(expl, task, requirement_set(stand, task).make_session, student, model)
    for n, (script, _status, found) in enumerate(search(ex, f"rates{base}", scripts, coverage=coverage,
                                                          stop=False)):
        n_played = n + 1
        if found is not None:
            played, div = found
            hits.append(n)
            kinds[div.signal.name] = kinds.get(div.signal.name, 0) + 1
            if explain_first and len(hits) <= explain_first:
                from plclab.grader.explore import explain, shrink
                small, sdiv = shrink(ex, played, div)
                f = explain(ex, small, sdiv, stand)
                print(f"--- {path}: script {n}\n  " + "\n  ".join(f.steps) + f"\n  -> {f.first_difference}"
                      + "".join(f"\n  {k}. {c.where()}" for k, c in enumerate(f.candidates, 1))
                      + (f"\n  line {f.line}" if f.line else ""), flush=True)
            if stop_at is not None and len(hits) >= stop_at:
                break
    p = len(hits) / scripts
    name = f"{stand}/{Path(path).stem}" if HERE in Path(path).resolve().parents else path
    return {"fixture": name, "task": task, "mistake": mistake, "scripts": scripts, "played": n_played, "coverage": coverage,
            "hits": len(hits), "rate": p, "miss": (1 - p) ** expl.episodes, "budget": expl.episodes,
            "signals": kinds, "first": hits[:5]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("only", nargs="*", help="STAND/NAME of the fixtures to measure (default: all), or program "
                    "files (.st, plc.xml) with --stand and --task")
    ap.add_argument("--stand", choices=("mp9c", "tur10"), help="the stand of program files")
    ap.add_argument("--task", choices=("task1", "task2", "task3"), help="the task of program files")
    ap.add_argument("--scripts", type=int, default=40)
    ap.add_argument("--base", type=int, default=0, help="another stream of scripts (a seed of its own)")
    ap.add_argument("--all", action="store_true", help="the scenarios' fixtures too")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--json", help="write the figures here too")
    ap.add_argument("--no-aim", action="store_true", help="random scripts only (none aimed)")
    ap.add_argument("--no-coverage", action="store_true", help="no coverage guidance (no kept script mutated): "
                    "the rate before issue 29's coverage-guided exploration")
    ap.add_argument("--explain", type=int, default=0, metavar="N",
                    help="shrink and print the first N differences of each fixture")
    args = ap.parse_args(argv)
    files = [a for a in args.only if a.endswith((".st", ".xml")) and Path(a).is_file()]
    names = [a for a in args.only if a not in files]
    jobs = []
    for f in files:                      # .../STAND/TASK_anything.st names its own stand and task
        m = re.match(r"(task\d)", Path(f).name)
        stand = args.stand or Path(f).parent.name
        task = args.task or (m.group(1) if m else None)
        if stand not in ("mp9c", "tur10") or task is None:
            ap.error(f"{f}: give --stand and --task (or name it STAND/TASK_....st)")
        jobs.append((stand, task, f, True, args.scripts, args.base, args.explain, args.no_aim, not args.no_coverage))
    todo = [(s, t, str(p), m, args.scripts, args.base, args.explain, args.no_aim, not args.no_coverage)
            for s, t, p, m in fixtures(args.all or bool(names))
            if (not args.only and not files) or f"{s}/{p.stem}" in names]
    todo += jobs
    with ProcessPoolExecutor(args.jobs) as pool:
        results = []
        for r in pool.map(rate, todo):
            results.append(r)
            flag = ("ALT FAILS" if r["hits"] else "") if not r["mistake"] else \
                ("UNSEEN" if not r["hits"] else "weak" if r["miss"] > 0.01 else "")
            print(f"{r['fixture']:48s} {r['task']} {r['hits']:3d}/{r['scripts']:<3d} per script {r['rate']:.3f} "
                  f"budget {r['budget']} misses {r['miss']:.3f} {flag} {r['signals']}", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
