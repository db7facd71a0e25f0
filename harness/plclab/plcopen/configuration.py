"""CONFIGURATION / RESOURCE / TASK / PROGRAM instances and globals <-> TC6 `instances`.

Task intervals are written as the IEC literal of the source (`interval="T#10ms"`): the TC6
schema leaves the attribute's format to the vendor, and Beremiz / OpenPLC Editor paste it
verbatim after `INTERVAL :=` when they generate ST, so an XML duration (`PT0.01S`) would not
compile there. Reading accepts both forms. The schema orders a configuration's children
resources first, then global variable lists; the ST written back puts globals first, as
IEC 61131-3 requires.
"""
from __future__ import annotations

import re

from lxml import etree

from plclab.errors import PlcLabError
from plclab.frontend import ast as A
from plclab.plcopen import sttext
from plclab.plcopen.datatypes import NS, sub
from plclab.plcopen.interface import var_list_element, var_list_text
from plclab.plcopen.source import SourceText

_DURATION = re.compile(r"P(?:(\d+(?:\.\d+)?)D)?(?:T(?:(\d+(?:\.\d+)?)H)?(?:(\d+(?:\.\d+)?)M)?(?:(\d+(?:\.\d+)?)S)?)?$", re.I)


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


def configuration_text(el: etree._Element) -> str:
    """The ST CONFIGURATION of one `<configuration>`."""
    name = el.get("name")
    where = f"configuration {name}"
    lines = [f"CONFIGURATION {name}\n"]
    lines += [var_list_text(g, where, "    ") for g in el.findall("ppx:globalVars", NS)]
    for r in el.findall("ppx:resource", NS):
        rwhere = f"resource {r.get('name')}"
        lines.append(f"    RESOURCE {r.get('name')} ON PLC\n")
        lines += [var_list_text(g, rwhere, "        ") for g in r.findall("ppx:globalVars", NS)]
        instances = []
        for t in r.findall("ppx:task", NS):
            params = []
            if t.get("single"):
                params.append(f"SINGLE := {t.get('single')}")
            if t.get("interval"):
                params.append(f"INTERVAL := {interval_literal(t.get('interval'))}")
            params.append(f"PRIORITY := {t.get('priority')}")
            lines.append(f"        TASK {t.get('name')} ({', '.join(params)});\n")
            instances += [f"        PROGRAM {p.get('name')} WITH {t.get('name')} : {p.get('typeName')};\n"
                          for p in t.findall("ppx:pouInstance", NS)]
        instances += [f"        PROGRAM {p.get('name')} : {p.get('typeName')};\n"
                      for p in r.findall("ppx:pouInstance", NS)]
        lines += instances
        lines.append("    END_RESOURCE\n")
    lines.append("END_CONFIGURATION\n")
    return "".join(lines)


def interval_literal(text: str) -> str:
    """A task interval as an ST literal: IEC text as is, an XML duration (`PT0.01S`) converted."""
    m = _DURATION.match(text.strip())
    if not m or not any(m.groups()):
        return text
    days, hours, minutes, seconds = (float(g) if g else 0.0 for g in m.groups())
    total_ms = round((((days * 24 + hours) * 60 + minutes) * 60 + seconds) * 1000, 3)
    return "T#" + f"{total_ms:f}".rstrip("0").rstrip(".") + "ms"
