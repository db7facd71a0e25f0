"""CONFIGURATION / RESOURCE / TASK / PROGRAM instances and globals -> TC6 `instances` (read
back by frontend.plcxml).

Task intervals are written as the IEC literal of the source (`interval="T#10ms"`): the TC6
schema leaves the attribute's format to the vendor, and Beremiz / OpenPLC Editor paste it
verbatim after `INTERVAL :=` when they generate ST, so an XML duration (`PT0.01S`) would not
compile there. The schema orders a configuration's children resources first, then global
variable lists.
"""
from __future__ import annotations

from lxml import etree

from plclab.errors import PlcLabError
from plclab.frontend import ast as A
from plclab.frontend import sttext
from plclab.frontend.tc6 import NS
from plclab.plcopen.datatypes import sub
from plclab.plcopen.interface import var_list_element
from plclab.plcopen.source import SourceText


def configurations_element(parent: etree._Element, config: A.Configuration | None, src: SourceText) -> None:
    configs = sub(parent, "configurations")
    if config is None:
        return
    el = sub(configs, "configuration", name=config.name)
    for res in config.resources:
        if not res.name:
            raise PlcLabError(f"line {config.line}: PLCopen XML needs the tasks of CONFIGURATION {config.name} "
                              f"inside a named RESOURCE")
        r = sub(el, "resource", name=res.name)
        for task in res.tasks:
            sub(r, "task", name=task.name, priority=_priority(task),
                interval=sttext.expr(task.interval) if task.interval is not None else None,
                single=sttext.expr(task.single) if task.single is not None else None)
        for block in res.globals:
            var_list_element(r, block, src, tag="globalVars")
        for prog in res.programs:
            if prog.args or prog.retain is not None:
                what = "parameters" if prog.args else "RETAIN" if prog.retain else "NON_RETAIN"
                raise PlcLabError(f"line {prog.line}: PLCopen XML has no form for the {what} of program "
                                  f"instance {prog.name}")
            if prog.task is None:
                sub(r, "pouInstance", name=prog.name, typeName=prog.type_name)
            else:
                task_el = r.find(f"ppx:task[@name='{prog.task}']", NS)
                if task_el is None:   # the checker matches task names case-insensitively
                    task_el = next(t for t in r.findall("ppx:task", NS) if t.get("name").upper() == prog.task.upper())
                sub(task_el, "pouInstance", name=prog.name, typeName=prog.type_name)
    for block in config.globals:
        var_list_element(el, block, src, tag="globalVars")


def _priority(task: A.TaskDecl) -> str:
    p = task.priority
    if isinstance(p, A.Literal) and p.kind == "int" and 0 <= p.value <= 65535:
        return str(p.value)
    raise PlcLabError(f"line {task.line}: task {task.name}: PLCopen XML needs PRIORITY as a number 0..65535")
