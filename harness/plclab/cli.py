"""The `plclab` command: argument parsing only; the work is done by library functions.

Every error reaches the user as one line (or one line per ST diagnostic) and an exit code;
no traceback escapes.
"""
from __future__ import annotations

import argparse
import os
import sys
from typing import Optional, Sequence

from plclab.errors import CompileError, PlcLabError


def _cmd_check(args: argparse.Namespace) -> int:
    from plclab.frontend import check_sources, is_project_file, load_files, read_sources

    if getattr(args, "emit_st", False):      # the ST OpenPLC Editor makes of a plc.xml (LD / FBD bodies translated)
        sources = read_sources(args.files)
        print("".join(text for name, text in sources if is_project_file(name)), end="")
        check_sources(sources)
        return 0
    checked = load_files(args.files)
    if getattr(args, "emit_c", False):
        from plclab.errors import PlcLabError
        from plclab.runtime.cgen import Unsupported, emit_c
        try:
            print(emit_c(checked).source, end="")
        except Unsupported as e:
            raise PlcLabError(f"the native scan path does not cover {e}: this program runs on the Python path "
                              "(docs/runtime.md)") from None
        return 0
    if args.emit_python:
        from plclab.runtime.compiler import compile_unit
        print(compile_unit(checked, optimize=not args.plain).annotated_source(), end="")
        return 0
    print(f"ok: {len(args.files)} file(s) checked")
    return 0


def _seconds(text: str) -> float:
    """A duration on the command line: `10`, `2.5s`, `500ms`, `T#1m30s`."""
    from plclab.frontend.literals import LiteralError, parse_time

    t = text.strip()
    try:
        if t.upper().startswith(("T#", "TIME#")):
            return parse_time(t) / 1e9
        for suffix, scale in (("ms", 1e-3), ("s", 1.0), ("min", 60.0), ("m", 60.0), ("h", 3600.0)):
            if t.lower().endswith(suffix) and t[:-len(suffix)].replace(".", "", 1).isdigit():
                return float(t[:-len(suffix)]) * scale
        value = float(t)
    except (ValueError, LiteralError):
        raise argparse.ArgumentTypeError(f"not a duration: '{text}' (e.g. 10, 2.5s, 500ms, T#1m)") from None
    if value < 0 or value != value:
        raise argparse.ArgumentTypeError(f"not a duration: '{text}'")
    return value


def _cmd_sim(args: argparse.Namespace) -> int:
    from plclab.limits import memory_limited
    from plclab.runtime.simcmd import run_sim

    with memory_limited():               # the program is untrusted: bounded (docs/reliability.md)
        result = run_sim(args.files, duration_s=args.duration, inputs=args.inputs, csv=args.csv, vcd=args.vcd,
                         plot=args.plot, watch=args.watch, tick_s=args.tick)
    print(result.summary)
    if result.fault is not None and result.fault.internal:
        return 70                    # the harness's own bug (the summary asks for a report)
    return 0 if result.fault is None else 1


def _tool(text: str) -> tuple[int, float]:
    """A tool-table entry on the command line: `D1=2.5`."""
    name, _, value = text.partition("=")
    try:
        number, radius = int(name.strip().upper().removeprefix("D")), float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a tool entry: '{text}' (e.g. D1=2.5)") from None
    if number < 1 or radius < 0:
        raise argparse.ArgumentTypeError(f"not a tool entry: '{text}' (D1 or more, radius >= 0)")
    return number, radius


def _cmd_cnc(args: argparse.Namespace) -> int:
    from plclab.nc.gcode import GcodeError
    from plclab.cnc.run import run_cnc

    try:
        result = run_cnc(args.part, method=args.method, step_mm=args.step, feed=args.feed, csv=args.csv,
                         vcd=args.vcd, plot=args.plot, svg=args.svg, diagonal=args.diagonal,
                         tools=dict(args.tool or []), drive=args.drive, program=args.program,
                         fine_cycle=args.fine_cycle)
    except GcodeError as e:              # already `file:line:col: error: ...`; nothing has run
        print(e, file=sys.stderr)
        return 1
    print("\n".join(result.lines))
    for f in result.files:
        print(f"wrote {f}")
    return 0 if result.ok else 1


def _cmd_bench(args: argparse.Namespace) -> int:
    from plclab.bench import run_bench

    run_bench(quick=args.quick)
    return 0


def _port(text: str) -> int:
    """A TCP port: 1..65535, or 0 for "any free port" (printed when listening)."""
    try:
        port = int(text)
    except ValueError:
        port = -1
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"not a TCP port: '{text}' (1..65535, or 0 for any free port)")
    return port


def _load_config(path: Optional[str]):
    from pathlib import Path

    from plclab import config

    if path is None:
        default = Path("openplc.conf")
        return config.load(default) if default.exists() else config.defaults()
    if not Path(path).exists():
        raise PlcLabError(f"{path}: no such configuration file")
    return config.load(path)


def _program_sources(stand_name: str, variant: Optional[str], program: Optional[list[str]], cfg) -> list:
    from plclab.frontend import read_sources
    from plclab.stands import get_stand, sources

    files = program or ([str(cfg.program)] if cfg.program else None)
    if files:
        return read_sources(files)
    return sources(get_stand(stand_name), variant or cfg.variant)


def _cmd_serve(args: argparse.Namespace) -> int:
    import dataclasses

    from plclab.serve import ServeOptions, serve_forever

    conf = _load_config(args.config)
    stand_cfg = conf.stand(args.stand)
    stand_cfg.check_paths(conf.path.name if conf.path is not None else "")   # a retain_file that can never be written
    modbus = conf.modbus
    if args.port is not None:
        modbus = dataclasses.replace(modbus, port=args.port)
    if args.bind is not None:
        modbus = dataclasses.replace(modbus, bind=args.bind)
    srcs = _program_sources(args.stand, args.variant, args.program, stand_cfg)
    plant = None
    if stand_cfg.io == "inprocess":
        from plclab.plants import make_plant
        try:
            plant = make_plant(args.stand)
        except ModuleNotFoundError:
            plant = None
    profile = None
    if stand_cfg.profile == "twido":
        from plclab.stands import twido_profile
        profile = twido_profile(args.stand)
    console = None if args.console == "none" else _host_port(args.console, "--console")
    opts = ServeOptions(srcs, stand_cfg, modbus, plant, stand_cfg.profile, profile, console)
    return serve_forever(opts, duration=args.duration, hmi=args.hmi)


def _host_port(text: str, what: str) -> tuple[str, int]:
    """HOST:PORT on the command line (HOST may be left out: 127.0.0.1; PORT 0: any free one)."""
    from plclab.config import _host

    host, sep, port = text.rpartition(":")
    try:
        if not sep:
            raise ValueError
        return (_host(host) if host else "127.0.0.1"), _port(port)
    except (ValueError, argparse.ArgumentTypeError):
        raise PlcLabError(f"{what} '{text}': expected HOST:PORT, e.g. 127.0.0.1:5020") from None


def _cmd_hmi(args: argparse.Namespace) -> int:
    from plclab.hmi import run_hmi

    if args.period < 0.05:
        raise PlcLabError(f"--period {args.period:g} s: the HMI polls at most 20 times a second (0.05 s)")
    if args.where:
        host, port = _host_port(args.where, "the stand's Modbus face")
    else:
        modbus = _load_config(args.config).modbus
        host, port = modbus.client_host, modbus.port
    return run_hmi(host, port, period=args.period, once=args.once, sets=tuple(args.set or ()),
                   commands=None if args.once else sys.stdin)


def _plant_params(command: str, stand: str, fine_cycle: Optional[int] = None) -> dict:
    """The parameters a plant run for OpenPLC starts with (PSM script, `plant --psm`): the cnc
    stand's in step with `plclab build cnc`'s fine cycle (`--fine-cycle`, default the build's),
    the others' none."""
    if stand != "cnc":
        if fine_cycle is not None:
            raise PlcLabError(f"{command}: --fine-cycle is for the cnc stand, not {stand}")
        return {}
    from plclab.cnc.openplc import plant_params
    return plant_params() if fine_cycle is None else plant_params(fine_cycle)


def _cmd_plant(args: argparse.Namespace) -> int:
    from plclab.modbus.psm import run_plant

    psm = _host_port(args.psm, "--psm")
    console = None if args.console == "none" else _host_port(args.console, "--console")
    params = _plant_params("plant", args.stand, args.fine_cycle)
    return run_plant(args.stand, psm, console, traceback=bool(os.environ.get("PLCLAB_DEBUG")),
                     out=lambda line: print(line, flush=True), params=params)


def _cmd_psm_script(args: argparse.Namespace) -> int:
    from plclab.modbus.psm import psm_script

    sys.stdout.write(psm_script(args.stand, console=_host_port(args.console, "--console"),
                                plant=_plant_params("psm-script", args.stand, args.fine_cycle)))
    return 0


def _cmd_console(args: argparse.Namespace) -> int:
    from plclab.modbus.console import CONSOLE_PORT, run_console

    where = _host_port(args.where, "the console face") if args.where else ("127.0.0.1", CONSOLE_PORT)
    tape = None
    if args.part:
        from plclab.nc.gcode import GcodeError
        from plclab.cnc.openplc import part_tape

        if args.stand != "cnc":
            raise PlcLabError(f"console: --part is for the cnc stand (a G-code part program), not {args.stand}")
        try:
            method, frames, notes = part_tape(args.part, args.method, dict(args.tool or []))
        except GcodeError as e:          # already `file:line:col: error: ...`; nothing sent
            print(e, file=sys.stderr)
            return 1
        for note in notes:
            print(note, file=sys.stderr)
        tape = (method, frames)
    if args.wait is not None and not 0 <= args.wait <= 600:
        raise PlcLabError(f"console: --wait {args.wait:g}: 0..600 seconds")
    for line in run_console(args.stand, where, sets=args.set or (), presses=args.press or (), tape=tape,
                            tape_wait=10.0 if args.wait is None else args.wait):
        print(line)
    return 0


def _cmd_lab(args: argparse.Namespace) -> int:
    from plclab.lab import open_lab, serve_lab

    server = open_lab(args.stand, program=args.program, variant=args.variant, bind=args.bind, port=args.port,
                      speed=args.speed, modbus_port=args.modbus_port)
    return serve_lab(server)


def _cmd_build(args: argparse.Namespace) -> int:
    from plclab.build import write_build

    if args.outline:
        from plclab.stands import get_stand
        print(get_stand(args.stand).outline(args.variant), end="")
        return 0
    from plclab.nc.gcode import GcodeError

    try:
        paths = write_build(args.stand, args.variant, args.output, args.xml, part=args.part, method=args.method,
                            tools=dict(args.tool or []), report=lambda line: print(line, file=sys.stderr),
                            fine_cycle=args.fine_cycle, drive=args.drive)
    except GcodeError as e:              # already `file:line:col: error: ...`; nothing written
        print(e, file=sys.stderr)
        return 1
    for path in paths:
        print(f"wrote {path}")
    return 0


def _cmd_handout(args: argparse.Namespace) -> int:
    from plclab.handout import write_handout

    for path in write_handout(args.stand, args.output):
        print(f"wrote {path}")
    return 0


def _cmd_grade(args: argparse.Namespace) -> int:
    from plclab.grader import grade, requirement_table, requirements_text, task_title

    if args.requirements:
        if args.files or args.listen or args.traffic or args.duration is not None:
            raise PlcLabError("grade: --requirements lists what the task checks; it grades nothing (no files, "
                              "--listen, --duration or --traffic with it)")
        table = requirement_table(args.stand, args.task, exploration=True)
        print(requirements_text(task_title(args.stand, args.task), table), end="")
        return 0
    if args.stand == "thermo":
        return _cmd_grade_scada(args)
    if args.listen or args.traffic or args.duration is not None:
        raise PlcLabError("grade: --listen, --duration and --traffic are for the thermo SCADA tasks "
                          "(plclab grade thermo scada1|scada2)")
    if not args.files:
        raise PlcLabError("grade: give the program's ST files (plclab grade STAND TASK FILE.st...)")
    if args.explore is not None and args.explore < 0:
        raise PlcLabError(f"grade: --explore takes a number of scripts >= 0, not {args.explore}")
    if args.jobs < 1:
        raise PlcLabError(f"grade: --jobs takes a number of processes >= 1, not {args.jobs}")
    from plclab.grader.explore import ExploreOptions
    from plclab.limits import memory_limited
    with memory_limited():               # the student's program is untrusted: bounded (docs/reliability.md)
        report = grade(args.stand, args.task, args.files, out_dir=args.out, reference=args.reference,
                       explore=args.explore, explore_options=ExploreOptions(jobs=args.jobs))
    print(report.text(), end="")
    return report.exit_code


def _cmd_grade_scada(args: argparse.Namespace) -> int:
    from plclab.grader import grade
    from plclab.grader.thermo import grade_live, scada_task

    scada_task(args.task)
    if args.files:
        raise PlcLabError(f"grade: thermo {args.task} grades the Modbus traffic of the student's SCADA client, "
                          f"not ST files: serve the stand with --listen HOST:PORT [--duration T], or grade a "
                          f"recording with --traffic FILE")
    if args.traffic:
        if args.listen or args.duration is not None:
            raise PlcLabError("grade: --traffic grades a recording, --listen/--duration make one: give one or the other")
        report = grade(args.stand, args.task, [args.traffic], out_dir=args.out)
    else:
        host, port = _host_port(args.listen or "127.0.0.1:5020", "--listen")
        until = f"grading after {args.duration:g} s or Ctrl-C" if args.duration else "Ctrl-C ends it and grades"

        def listening(h: str, p: int) -> None:
            print(f"thermo stand on {h}:{p} (Modbus TCP, holding register n = %MWn): start the SCADA client "
                  f"and do {args.task}; recording, {until}", flush=True)
        report, traffic, log = grade_live(args.task, host, port, args.duration, args.out, on_listening=listening)
        print(f"recorded {len(traffic.exchanges)} requests in {traffic.duration_s:.1f} s: {log}")
    print(report.text(), end="")
    return report.exit_code


def _cmd_grade_class(args: argparse.Namespace) -> int:
    if args.explore is not None and args.explore < 0:
        raise PlcLabError(f"grade-class: --explore takes a number of scripts >= 0, not {args.explore}")
    from plclab.grader.classroom import ClassInterrupted, grade_class, write_class_outputs, write_partial_results

    def progress(result, done: int, total: int) -> None:
        print(f"[{done:>{len(str(total))}}/{total}] {result.student}: {result.summary()}", flush=True)

    try:
        report = grade_class(args.stand, args.task, args.folder, args.out, jobs=args.jobs,
                             time_limit_s=args.time_limit, on_result=progress,
                             memory_limit_mib=args.memory_limit or None, scheduler=args.scheduler,
                             explore=args.explore, reference=args.reference)
    except ClassInterrupted as e:       # the verdicts so far apart from a previous run's results
        print(f"plclab: {e}", file=sys.stderr)
        if e.report.results:
            print(f"wrote {write_partial_results(e.report, args.out)} (the verdicts so far; results.csv, junit.xml, "
                  f"report.html and traces/ were left as they were)", file=sys.stderr)
        return 128 + e.signum
    for path in report.ignored:
        print(f"ignored {path}: not a {report.suffix} file or a folder")
    for note in report.notes:
        print(note)
    counts = {s: sum(r.status == s for r in report.results) for s in ("PASS", "FAIL", "ERROR")}
    print(f"{len(report.results)} submissions: {counts['PASS']} pass, {counts['FAIL']} fail, "
          f"{counts['ERROR']} not graded")
    for path in write_class_outputs(report, args.out):
        print(f"wrote {path}")
    return 0 if report.complete else 1


def _cmd_run(args: argparse.Namespace) -> int:
    from plclab.limits import memory_limited
    from plclab.runner import run_scenario

    with memory_limited(None if not args.program else -1):   # your program is bounded like a student's
        r = run_scenario(args.stand, args.variant, args.scenario, args.csv, args.vcd, args.plot,
                         program=args.program, inputs=args.inputs, against=args.against,
                         reference=args.reference, fine_cycle=args.fine_cycle)
    print("\n".join(r.timeline))
    if r.absent_note:
        print(r.absent_note)
    for f in r.files:
        print(f"wrote {f}")
    if r.session.fault is not None:
        print(r.session.fault)
    if r.failure and args.inputs:
        print(f"difference from the {args.against} model answer: {r.failure}")
        return 1
    if r.failure:
        print(f"scenario FAILED: {r.failure}")
        return 1
    if args.inputs:
        print(f"script {args.inputs} played ({r.session.now:.1f} s of plant time)"
              + (f": no difference from the {args.against} model answer" if args.against else ""))
        return 0
    print(f"scenario {args.scenario or 'demo'} passed ({r.session.now:.1f} s of plant time)")
    return 0


def _fine_cycle_option(c: argparse.ArgumentParser, text: str) -> None:
    c.add_argument("--fine-cycle", type=int, metavar="MS", help=text)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="plclab", description="IEC 61131-3 ST lab programs and soft-PLC harness")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    c = sub.add_parser("check", help="parse and type-check ST files (one compilation unit; a plc.xml from "
                                     "OpenPLC Editor counts as ST, its LD / FBD translated)")
    c.add_argument("files", nargs="+", metavar="FILE.st")
    c.add_argument("--emit-python", action="store_true",
                   help="print the Python the program compiles to, each line with its ST file:line")
    c.add_argument("--plain", action="store_true", help="with --emit-python: without the compiler's fast paths")
    c.add_argument("--emit-c", action="store_true",
                   help="print the C of the native scan path (docs/runtime.md); an error if it does not cover "
                        "the program")
    c.add_argument("--emit-st", action="store_true",
                   help="print the ST a plc.xml turns into (its LD / FBD bodies as OpenPLC Editor translates them)")
    c.set_defaults(func=_cmd_check)

    c = sub.add_parser("compile", help="the same as check --emit-python: print the Python the program compiles to")
    c.add_argument("files", nargs="+", metavar="FILE.st")
    c.add_argument("--plain", action="store_true", help="without the compiler's fast paths")
    c.set_defaults(func=_cmd_check, emit_python=True)

    c = sub.add_parser("sim", help="run any ST program in virtual time with scripted inputs; write traces")
    c.add_argument("files", nargs="+", metavar="FILE.st")
    c.add_argument("--duration", type=_seconds, required=True, metavar="T", help="simulated time (e.g. 10s)")
    c.add_argument("--inputs", metavar="IN.csv", help="input script: rows time_s,name,value")
    c.add_argument("--csv", metavar="OUT.csv", help="write the trace as CSV (time_s,name,value)")
    c.add_argument("--vcd", metavar="OUT.vcd", help="write the trace as VCD (GTKWave)")
    c.add_argument("--plot", metavar="OUT.png", help="write a PNG plot of the trace")
    c.add_argument("--watch", action="append", default=[], metavar="NAME",
                   help="also trace an internal variable (instance.var), repeatable")
    c.add_argument("--tick", type=_seconds, metavar="T", help="base tick (default: GCD of task intervals)")
    c.set_defaults(func=_cmd_sim)

    stands = ("mp9c", "tur10", "thermo")
    every_stand = stands + ("cnc",)          # cnc has no serve config or Modbus register face yet

    c = sub.add_parser("build", help="write the OpenPLC bundle (.st) and a PLCopen TC6 XML project")
    c.add_argument("stand", choices=every_stand)
    c.add_argument("variant", choices=("baseline", "task1", "task2", "task3", "full"))
    c.add_argument("-o", "--output", metavar="FILE.st", help="default: STAND_VARIANT.st")
    c.add_argument("--xml", metavar="FILE.xml", help="also write the PLCopen XML project")
    c.add_argument("--outline", action="store_true",
                   help="write nothing; print a task reference's changes to the starting program as a diff")
    c.add_argument("--part", metavar="PART.nc", help="cnc: a G-code part program in the frame table (OpenPLC)")
    c.add_argument("--method", choices=("evalfn", "dda", "integration"), default="evalfn",
                   help="cnc --part: the interpolator (default evalfn)")
    c.add_argument("--tool", type=_tool, action="append", metavar="DN=R", help="cnc --part: the tool-radius table")
    _fine_cycle_option(c, "cnc: PRG_CncStand's fine cycle, in its task and FINE_MS (default 5, what OpenPLC holds)")
    c.add_argument("--drive", choices=("step", "pulse"),
                   help="cnc: step/direction bits (default) or pulse counts (GVL_CNC.PulseDrive: higher feeds)")
    c.set_defaults(func=_cmd_build)

    c = sub.add_parser("handout", help="the student's starting program, I/O map and task sheet (no solution)")
    c.add_argument("stand", choices=every_stand)
    c.add_argument("-o", "--output", metavar="DIR", required=True, help="directory to write into")
    c.set_defaults(func=_cmd_handout)

    c = sub.add_parser("run", help="run a scenario of a stand in virtual time; timeline and traces")
    c.add_argument("stand", choices=every_stand)
    c.add_argument("--variant", choices=("baseline", "task1", "task2", "task3", "full"))
    c.add_argument("--scenario", metavar="NAME", help="default: the demo")
    c.add_argument("--csv", metavar="F")
    c.add_argument("--vcd", metavar="F")
    c.add_argument("--plot", metavar="F")
    c.add_argument("--program", nargs="+", metavar="FILE.st", help="run these ST files (your program) instead "
                   "of a variant")
    c.add_argument("--inputs", metavar="SCRIPT.csv", help="play this operator script (time_s,name,value; "
                   "a grade's exploration writes one) instead of a scenario")
    c.add_argument("--against", metavar="TASK", help="with --inputs: play it on the task's model answer too and "
                   "show the first difference (a checkout, or --reference)")
    c.add_argument("--reference", nargs="+", metavar="FILE.st", help="with --against: the course's own model answer")
    _fine_cycle_option(c, "cnc: run PRG_CncStand at this fine cycle (default 1; 5 is the OpenPLC build's)")
    c.set_defaults(func=_cmd_run)

    c = sub.add_parser("grade", help="grade a program on a lab task: one row per requirement")
    c.add_argument("stand", choices=every_stand)
    c.add_argument("task", metavar="TASK", help="task1, task2 or task3; thermo: scada1 or scada2; cnc: task4")
    c.add_argument("files", nargs="*", metavar="FILE.st")
    c.add_argument("--out", default="out/grade", metavar="DIR", help="trace files (CSV + VCD per scenario)")
    c.add_argument("--listen", metavar="HOST:PORT",
                   help="thermo SCADA tasks: serve the stand here and record the client (default 127.0.0.1:5020)")
    c.add_argument("--duration", type=_seconds, metavar="T", help="thermo SCADA tasks: record for T, then grade")
    c.add_argument("--traffic", metavar="FILE.csv", help="thermo SCADA tasks: grade a recorded traffic log")
    c.add_argument("--reference", nargs="+", metavar="FILE.st", help="the course's own model answer to explore "
                   "against (default: the checkout's solutions/)")
    c.add_argument("--explore", type=int, metavar="N", help="random operator scripts explored against the model "
                   "answer (default: the stand's budget; 0: scenarios only)")
    c.add_argument("--jobs", type=int, default=1, metavar="N", help="processes playing the exploration's scripts "
                   "(default 1; the same verdicts and report whatever N)")
    c.add_argument("--requirements", action="store_true",
                   help="grade nothing: list what the task checks (id and requirement, as the report's rows)")
    c.set_defaults(func=_cmd_grade)

    c = sub.add_parser("grade-class", help="grade a folder of submissions (a .st file or a folder per student; "
                                           "thermo: a traffic log .csv) in parallel: results.csv, junit.xml, "
                                           "report.html")
    c.add_argument("stand", choices=stands)
    c.add_argument("task", metavar="TASK", help="task1, task2 or task3; thermo: scada1 or scada2")
    c.add_argument("folder", metavar="DIR", help="one .st file or one folder of .st files per student "
                                                 "(thermo: one traffic log .csv, or a folder holding it)")
    c.add_argument("--jobs", type=int, metavar="N", help="submissions graded at once (default: CPU count)")
    c.add_argument("--out", default="out/grade-class", metavar="DIR",
                   help="results.csv, junit.xml, report.html and traces/<student>/ (default out/grade-class)")
    c.add_argument("--time-limit", type=_seconds, default=300.0, metavar="T",
                   help="per submission; past it the student's row says 'not graded' (default 300 s)")
    c.add_argument("--memory-limit", type=int, default=1024, metavar="MIB",
                   help="address space each submission's grading may take beyond the grader's own; past it "
                        "the student FAILs 'memory limit of N MiB exceeded' (default 1024; 0: no limit)")
    c.add_argument("--scheduler", metavar="ADDRESS",
                   help="grade on a Dask distributed cluster (e.g. tcp://host:8786) instead of this machine")
    c.add_argument("--explore", type=int, metavar="N", help="random operator scripts each robot program is explored "
                   "with against the model answer, as plclab grade does (default: the stand's budget; 0: none)")
    c.add_argument("--reference", nargs="+", metavar="FILE.st", help="the course's own model answer to explore "
                   "against (default: the checkout's solutions/)")
    c.set_defaults(func=_cmd_grade_class)

    c = sub.add_parser("serve", help="real time: soft PLC + plant + Modbus face until Ctrl-C")
    c.add_argument("stand", choices=stands)
    c.add_argument("--variant", choices=("baseline", "task1", "task2", "task3", "full"))
    c.add_argument("--config", metavar="FILE", help="openplc.conf to use (default: ./openplc.conf)")
    c.add_argument("--port", type=_port, metavar="P", help="Modbus TCP port (overrides the config)")
    c.add_argument("--bind", metavar="ADDR", help="address to listen on (default 127.0.0.1)")
    c.add_argument("--program", nargs="+", metavar="FILE.st", help="run these ST files instead of the variant")
    c.add_argument("--duration", type=_seconds, metavar="T", help="stop by itself after T (for scripts)")
    c.add_argument("--hmi", action="store_true",
                   help="run the stand's reference HMI in this terminal (thermo); quitting it stops")
    c.add_argument("--console", default="127.0.0.1:2606", metavar="HOST:PORT",
                   help="the console face of an in-process plant (default 127.0.0.1:2606; none = off)")
    c.set_defaults(func=_cmd_serve)

    c = sub.add_parser("lab", help="the virtual lab in the browser: mimic, console, trends, grade")
    c.add_argument("stand", choices=stands + ("cnc",))
    c.add_argument("--program", nargs="+", metavar="FILE.st", help="run these ST files instead of the variant")
    c.add_argument("--variant", choices=("baseline", "task1", "task2", "task3", "full"),
                   help="default: the starting program a student gets (the robots: Appendix 1, as the real stand has it loaded)")
    c.add_argument("--port", type=_port, default=8080, metavar="P", help="web page port (default 8080; 0: any free)")
    c.add_argument("--bind", default="127.0.0.1", metavar="ADDR", help="address to listen on (default 127.0.0.1)")
    c.add_argument("--speed", type=float, default=1.0, metavar="X", help="x0.1 .. x50 (x1: real time)")
    c.add_argument("--modbus-port", type=_port, default=5020, metavar="P",
                   help="thermo: port of the Twido Modbus face for an external SCADA client (default 5020)")
    c.set_defaults(func=_cmd_lab)

    c = sub.add_parser("hmi", help="the reference SCADA HMI of a stand (thermo): a Modbus TCP client")
    c.add_argument("stand", choices=("thermo",))
    c.add_argument("where", nargs="?", metavar="HOST:PORT",
                   help="the stand's Modbus TCP face (default: bind and port of openplc.conf)")
    c.add_argument("--config", metavar="FILE", help="openplc.conf for the default address")
    c.add_argument("--period", type=_seconds, default=1.0, metavar="T", help="scan period (default 1 s)")
    c.add_argument("--set", action="append", metavar="POINT=VALUE",
                   help="write a point first (heater=1500, mode=manual, %%MW6=50); repeatable")
    c.add_argument("--once", action="store_true", help="show the registers once and stop")
    c.set_defaults(func=_cmd_hmi)

    c = sub.add_parser("plant", help="only the plant model, as an OpenPLC PSM I/O server")
    c.add_argument("stand", choices=every_stand)
    c.add_argument("--psm", nargs="?", const="127.0.0.1:2605", default="127.0.0.1:2605", metavar="HOST:PORT")
    c.add_argument("--console", default="127.0.0.1:2606", metavar="HOST:PORT",
                   help="the console face (default 127.0.0.1:2606; none = no console face)")
    _fine_cycle_option(c, "cnc: the program's fine cycle, for the pulse generator (default 5, as plclab build)")
    c.set_defaults(func=_cmd_plant)

    c = sub.add_parser("psm-script", help="print an OpenPLC PSM script (core/psm/main.py) running the plant")
    c.add_argument("stand", choices=every_stand)
    c.add_argument("--console", default="127.0.0.1:2606", metavar="HOST:PORT",
                   help="where the script serves the console face (default 127.0.0.1:2606)")
    _fine_cycle_option(c, "cnc: the program's fine cycle, for the pulse generator (default 5, as plclab build)")
    c.set_defaults(func=_cmd_psm_script)

    c = sub.add_parser("console", help="operate a stand's console face (switches, SB1) and show it")
    c.add_argument("stand", choices=every_stand)
    c.add_argument("where", nargs="?", metavar="HOST:PORT", help="the console face (default 127.0.0.1:2606)")
    c.add_argument("--set", nargs="+", metavar="NAME=V", help="set switches, e.g. SA5=1 SA6=0")
    c.add_argument("--press", nargs="+", metavar="NAME[=SECONDS]",
                   help="press and release, e.g. SB1 (0.3 s) or SA1_FWD=1.5")
    c.add_argument("--part", metavar="PART.nc", help="cnc: load a G-code part program through the tape reader")
    c.add_argument("--method", choices=("evalfn", "dda", "integration"), default="evalfn",
                   help="cnc --part: the interpolator (default evalfn)")
    c.add_argument("--tool", type=_tool, action="append", metavar="DN=R", help="cnc --part: the tool-radius table")
    c.add_argument("--wait", type=float, metavar="SECONDS",
                   help="cnc --part: how long to wait for the PLC to store every frame (default 10)")
    c.set_defaults(func=_cmd_console)

    c = sub.add_parser("cnc", help="run a G-code part program on the CNC stand; contour error per frame")
    c.add_argument("part", metavar="PART.nc")
    c.add_argument("--method", choices=("evalfn", "dda", "integration"), default="evalfn")
    c.add_argument("--diagonal", action="store_true", help="evaluation function: the diagonal variant")
    c.add_argument("--drive", choices=("step", "pulse"), default="step",
                   help="step/direction bits on %%QX (default) or pulse counts per cycle on %%QW")
    c.add_argument("--step", type=float, default=0.01, metavar="MM", help="the drives' step (default 0.01 mm)")
    c.add_argument("--feed", type=float, metavar="MM_MIN", help="feed of every cutting block (replaces F)")
    c.add_argument("--tool", type=_tool, action="append", metavar="DN=R",
                   help="the tool-radius table: D number = radius in mm (repeatable), e.g. --tool D1=2.5")
    c.add_argument("--program", nargs="+", metavar="FILE.st",
                   help="your ST: FB_CncEvalLinear.st (Task 4) in place of the stub, or a complete program")
    _fine_cycle_option(c, "PRG_CncStand's fine cycle (default 1; 5 is what plclab build cnc gives OpenPLC)")
    for opt in ("csv", "vcd", "plot", "svg"):
        c.add_argument(f"--{opt}", metavar="F")
    c.set_defaults(func=_cmd_cnc)

    c = sub.add_parser("bench", help="performance figures: front end, scan cost, virtual-time speed-up, Modbus")
    c.add_argument("--quick", action="store_true", help="shorter runs")
    c.set_defaults(func=_cmd_bench)
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except CompileError as e:
        for d in e.diagnostics:
            print(d, file=sys.stderr)
        return 1
    except PlcLabError as e:
        print(f"plclab: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("plclab: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError as e:
        if _stdout_reader_gone():         # `plclab ... | head`: the reader has what it wanted
            return 141                    # as a Unix tool ended by SIGPIPE reports it
        return _internal_error(e)
    except MemoryError:               # past plclab.limits' process limit: the run's own failure
        from plclab.limits import out_of_memory_message
        print(out_of_memory_message("plclab grade: FAIL" if args.command == "grade" else f"plclab {args.command}"),
              file=sys.stderr)
        return 1
    except Exception as e:  # a bug of ours: one line for the user, the traceback on request
        return _internal_error(e)


def _internal_error(e: Exception) -> int:
    """A bug of ours: one line for the user, the traceback on request (PLCLAB_DEBUG=1)."""
    if os.environ.get("PLCLAB_DEBUG"):
        raise e
    print(f"plclab: internal error ({type(e).__name__}: {e}); please report it with the input "
          f"that caused it (PLCLAB_DEBUG=1 shows the traceback)", file=sys.stderr)
    return 70


def _stdout_reader_gone() -> bool:
    """Whether standard output is a pipe whose reader has closed it (poll says POLLERR on its
    write end); if so, what is still buffered goes nowhere (else Python's own flush at exit
    would print a traceback)."""
    import select
    try:
        fd = sys.stdout.fileno()
        poller = select.poll()
        poller.register(fd, select.POLLOUT)
        gone = any(events & select.POLLERR for _fd, events in poller.poll(0))
    except (AttributeError, OSError, ValueError):
        return False
    if gone:
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), fd)
        except OSError:
            pass
    return gone


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
