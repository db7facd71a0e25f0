"""ST checker, configuration: resources, tasks and program instances of the CONFIGURATION."""
from __future__ import annotations


from plclab.frontend import ast as A
from plclab.frontend.check_base import CheckerBase, _library_variable_message, _Scope
from plclab.frontend.checked import LiteralType
from plclab.frontend.stdsigs import LIBRARY_VARIABLES
from plclab.iec import types as T


class ConfigurationChecks(CheckerBase):
    """The CONFIGURATION: tasks and program instances."""

    # ------------------------------------------------------------------ configuration
    def _check_config(self, config: A.Configuration) -> None:
        if config.name.upper() in LIBRARY_VARIABLES:
            self.error(config, _library_variable_message(config.name, "configuration"))
        seen_tasks: dict[str, A.TaskDecl] = {}
        seen_progs: set[str] = set()
        # compile_program.sh moves Config0.c and Res0.c into OpenPLC's core, the files iec2c
        # names after the CONFIGURATION and its RESOURCE ("Error moving files" otherwise)
        if config.name.upper() != "CONFIG0":
            self.error(config, f"OpenPLC builds a CONFIGURATION named Config0 (it looks for Config0.c), not "
                               f"'{config.name}': rename it")
        elif config.resources and not config.resources[0].name:
            self.error(config, "OpenPLC builds the RESOURCE Res0 (it looks for Res0.c): put the TASK and PROGRAM "
                               "lines in RESOURCE Res0 ON PLC ... END_RESOURCE")
        elif config.resources and config.resources[0].name.upper() != "RES0":
            res = config.resources[0]
            self.error(res, f"OpenPLC builds a RESOURCE named Res0 (it looks for Res0.c), not '{res.name}': rename it")
        if len(config.resources) > 1:
            # webserver/scripts/compile_program.sh compiles Config0.c and Res0.c only: the calls
            # Config0.c makes into the other resources never link
            extra = config.resources[1]
            self.error(extra, f"OpenPLC builds one RESOURCE (its build compiles Res0.c only): put the tasks and "
                              f"programs of '{extra.name}' in the first RESOURCE")
        for res in config.resources:
            for task in res.tasks:
                if task.key in seen_tasks:
                    self.error(task, f"task '{task.name}' is already declared")
                    continue
                seen_tasks[task.key] = task
                sc = _Scope(None, dict(self.globals))
                if task.interval is not None:
                    t = self.expr(task.interval, sc, T.TIME)
                    if t is not None and T.base_of(t) is not T.TIME:
                        what = f"an {t.name}" if isinstance(t, LiteralType) else self._tname(t)
                        self.error(task.interval, f"INTERVAL must be a TIME (e.g. T#20ms), not {what}")
                    else:
                        v = self.const_value(task.interval)
                        if isinstance(v, int) and v > 0:
                            task.interval_ns = v
                        elif v is None:
                            self.error(task.interval, "INTERVAL must be a constant TIME (e.g. T#10ms)")
                        else:
                            self.error(task.interval, "INTERVAL must be greater than zero")
                if task.single is not None:
                    t = self.expr(task.single, sc, T.BOOL)
                    if t is not None and T.base_of(t) is not T.BOOL:
                        self.error(task.single, "SINGLE must be a BOOL")
                p = self.const_value(task.priority)
                if not isinstance(p, int) or isinstance(p, bool) or p < 0:
                    self.error(task.priority, "PRIORITY must be a non-negative integer constant")
                else:
                    task.priority.ty = T.UINT
                if task.interval is None and task.single is None:
                    self.error(task, f"task '{task.name}' has neither INTERVAL nor SINGLE: it would never run")
            for prog in res.programs:
                if prog.key in seen_progs:
                    self.error(prog, f"program instance '{prog.name}' is already declared")
                    continue
                seen_progs.add(prog.key)
                pou = self.pous.get(prog.type_name.upper())
                if pou is None:
                    self.error(prog, f"unknown program '{prog.type_name}'")
                    continue
                if pou.kind != "PROGRAM":
                    kind = pou.kind.lower().replace("_", " ")
                    self.error(prog, f"'{prog.type_name}' is a {kind}, not a PROGRAM: only programs run in a task")
                    continue
                prog.pou = pou
                if prog.task is not None:
                    task = seen_tasks.get(prog.task.upper())
                    if task is None:
                        self.error(prog, f"unknown task '{prog.task}'")
                    prog.task_decl = task
                if prog.args:
                    self.error(prog.args[0], "program instance parameters are not supported; "
                                             "connect programs through VAR_GLOBAL / VAR_EXTERNAL")
