"""`plclab build STAND VARIANT`: the OpenPLC bundle (.st) and the PLCopen TC6 XML project.

Everything is made and checked in memory first; files are written only when all checks pass,
so a failed build never leaves a half-written or unchecked program behind:
1. the variant's ST sources check (diagnostics name the files as they are on disk);
2. the bundle text, exactly what goes into the .st file, checks too;
3. the XML project (if asked for) validates against the TC6 schema when the schema is on this
   machine (see plclab.plcopen.schema), and reads back, as OpenPLC Editor reads it (frontend.plcxml),
   through ST and the front end, to the same program as the bundle.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

from plclab import plcopen
from plclab.errors import PlcLabError
from plclab.fileio import check_output, write_bytes
from plclab.frontend import check_sources, plcxml
from plclab.frontend.checked import CheckedUnit
from plclab.stands import bundle, get_stand, sources


@dataclass(frozen=True)
class BuildOutput:
    """A checked build, not yet written."""

    name: str                    # '<stand>_<variant>'
    st_text: str
    xml_bytes: Optional[bytes]
    schema: Optional[Path]       # the XSD the XML was validated against; None: no schema here
    notes: tuple[str, ...] = ()  # cnc --part: the part program's notes and warnings


def build_outputs(stand: str, variant: str, xml: bool = True, xml_name: Optional[str] = None,
                  part: Optional[str] = None, method: str = "evalfn",
                  tools: Optional[dict[int, float]] = None, fine_cycle: Optional[int] = None,
                  drive: Optional[str] = None) -> BuildOutput:
    """Make and check the bundle (and the XML project) of `variant` of `stand`. The cnc
    stand's bundle is made for OpenPLC (plclab.cnc.openplc: its fine cycle, `fine_cycle` ms
    or the OpenPLC default of 5, and with `part` a G-code part program in its frame table,
    run with `method`, tool table `tools`; `drive` "pulse": the pulse-count drive)."""
    s = get_stand(stand)
    s.variant(variant)                       # an unknown variant is one clear error
    if part is not None and stand != "cnc":
        raise PlcLabError(f"build: --part is for the cnc stand (a G-code part program), not {stand}")
    if drive is not None and stand != "cnc":
        raise PlcLabError(f"build: --drive is for the cnc stand (GVL_CNC.PulseDrive), not {stand}")
    if fine_cycle is not None and stand != "cnc":
        raise PlcLabError(f"build: --fine-cycle is for the cnc stand (PRG_CncStand's fine cycle), not {stand}")
    name = f"{stand}_{variant}"
    check_sources(sources(s, variant))
    text = bundle(s, variant)
    if stand == "cnc":
        from plclab.nc.gcode import parse_file
        from plclab.cnc.openplc import OPENPLC_FINE_MS, STEP_MM, openplc_bundle

        program = parse_file(part, tools, STEP_MM) if part is not None else None
        notes = tuple(program.notes) if program is not None else ()
        text = openplc_bundle(text, program.frames if program is not None else None, method, part=part or "",
                              fine_ms=OPENPLC_FINE_MS if fine_cycle is None else fine_cycle, drive=drive or "step")
    else:
        notes = ()
    checked = check_sources([(f"{name}.st", text)])
    if not xml:
        return BuildOutput(name, text, None, None, notes)
    data, schema = xml_project(text, name, xml_name or f"{name}.xml", checked)
    return BuildOutput(name, text, data, schema, notes)


def xml_project(text: str, name: str, where: str,
                checked: Optional[CheckedUnit] = None) -> tuple[bytes, Optional[Path]]:
    """The PLCopen XML project of one ST text (`checked`: its front-end result, if at hand),
    validated and proven to read back to the same program; `where` names it in errors."""
    if checked is None:
        checked = check_sources([(f"{name}.st", text)])
    tree = plcopen.project_tree(checked, text, name)
    data = plcopen.to_bytes(tree)
    schema = plcopen.validate(tree, where)
    try:
        st_again = plcxml.st_from_tree(plcxml.parse_xml(data, where))   # as OpenPLC Editor reads it
    except PlcLabError as e:
        raise PlcLabError(f"{where}: OpenPLC Editor would not make the same program of this PLCopen XML: "
                          f"{str(e).splitlines()[0]}") from None
    try:
        again = check_sources([(f"{where} (as ST)", st_again)])
    except PlcLabError as e:
        raise PlcLabError(f"{where}: the XML does not read back as valid ST: {str(e).splitlines()[0]}") from None
    diff = plcopen.first_difference(checked, again)
    if diff:
        raise PlcLabError(f"{where}: the XML does not read back to the same program: {diff}")
    return data, schema


def write_build(stand: str, variant: str, st_path: str | None, xml_path: str | None,
                part: Optional[str] = None, method: str = "evalfn",
                tools: Optional[dict[int, float]] = None,
                report: Callable[[str], None] = lambda line: None, fine_cycle: Optional[int] = None,
                drive: Optional[str] = None) -> list[Path]:
    """Write `<stand>_<variant>.st` (or `st_path`) and, if `xml_path` is given, the PLCopen XML
    project; returns the paths written. Raises PlcLabError / CompileError, writing nothing.
    `report` gets the part program's notes and warnings (cnc --part)."""
    out = build_outputs(stand, variant, xml=xml_path is not None, xml_name=xml_path, part=part, method=method,
                        tools=tools, fine_cycle=fine_cycle, drive=drive)
    for line in out.notes:
        report(line)
    targets = [(Path(st_path) if st_path else Path.cwd() / f"{out.name}.st", out.st_text.encode("utf-8"))]
    if xml_path is not None:
        targets.append((Path(xml_path), out.xml_bytes))
    for path, _data in targets:
        check_output(path, parents=False)      # refuse a bad target before writing either file
    for path, data in targets:
        write_bytes(path, data, parents=False)  # atomic: OpenPLC's upload never sees half a file
    return [path for path, _data in targets]
