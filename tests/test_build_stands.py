"""Every shipped program of every stand builds: the bundle checks and the PLCopen XML passes
the TC6 model and reads back to the same program (tests/test_build.py covers the details)."""
from __future__ import annotations

import pytest

from plclab import plcopen
from plclab.frontend import plcxml
from plclab.build import write_build
from plclab.frontend import check_sources, load_files
from plclab.plcopen import schema
from plclab.stands import get_stand

PROGRAMS = [(stand, v) for stand in ("mp9c", "tur10", "thermo") for v in get_stand(stand).variants]


@pytest.mark.parametrize("stand,variant", PROGRAMS)
def test_every_program_builds_to_a_loadable_bundle_and_a_valid_xml(stand, variant, tmp_path):
    st, xml = write_build(stand, variant, str(tmp_path / f"{stand}.st"), str(tmp_path / "plc.xml"))
    bundle = load_files([st])
    assert bundle.config is not None and bundle.config.name == "Config0"
    assert [r.name for r in bundle.config.resources] == ["Res0"]
    schema.validate_bindings(xml.read_bytes(), xml.name)
    again = check_sources([("plc.xml (as ST)", plcxml.st_from_xml(xml))])
    assert plcopen.first_difference(bundle, again) is None
