"""openplc.conf: the shipped file equals the built-in defaults, and every mistake is one line
naming section, key, value and what is allowed."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from plclab import config
from plclab.config import HostPort, load
from plclab.errors import ConfigError

REPO_CONF = Path(__file__).resolve().parents[1] / "openplc.conf"


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "openplc.conf"
    path.write_text(text, encoding="utf-8")
    return path


def test_shipped_file_is_the_defaults_and_serves_every_stand():
    shipped, builtin = load(REPO_CONF), config.defaults()
    assert shipped.runtime == builtin.runtime
    assert shipped.modbus == builtin.modbus
    for stand in config.STANDS:
        ours = dataclasses.replace(shipped.stand(stand), retain_file=builtin.stand(stand).retain_file)
        assert ours == builtin.stand(stand)
        assert shipped.stand(stand).retain_file == REPO_CONF.parent / "out" / "retain" / f"{stand}.retain"
    modbus = shipped.modbus
    assert (modbus.enabled, modbus.bind, modbus.port) == (True, "127.0.0.1", 5020)
    assert modbus.unit_ids is None and modbus.idle_timeout_s == 60.0
    assert shipped.runtime.start_in_run_mode is True
    thermo, mp9c = shipped.stand("thermo"), shipped.stand("mp9c")
    assert (thermo.variant, thermo.profile) == ("full", "twido")
    assert (mp9c.variant, mp9c.profile, mp9c.io, mp9c.tick_ms) == ("baseline", "openplc", "inprocess", None)
    assert mp9c.psm == HostPort("127.0.0.1", 2605) and mp9c.program is None


def test_shipped_file_documents_every_key():
    text = REPO_CONF.read_text(encoding="utf-8")
    for section, keys in config._schema().items():
        assert f"[{section}]" in text
        for key in keys:
            assert f"{key} " in text, f"openplc.conf does not mention {key}"


def test_values_are_parsed_and_paths_are_relative_to_the_file(tmp_path):
    cfg = load(write(tmp_path, """
[modbus]
bind = 0.0.0.0
port = 502          ; the standard port
unit_id = 1, 255
idle_timeout_s = 0
[tur10]
variant = task2
program = student/tur10_task2.st
tick_ms = 5
io = psm
psm = localhost:12605
retain_file = /var/tmp/tur10.retain
watchdog_ms = 0
"""))
    assert cfg.modbus.bind == "0.0.0.0" and cfg.modbus.port == 502
    assert cfg.modbus.unit_ids == frozenset({1, 255}) and cfg.modbus.idle_timeout_s is None
    tur10 = cfg.stand("tur10")
    assert tur10.program == tmp_path / "student" / "tur10_task2.st"
    assert (tur10.variant, tur10.tick_ms, tur10.io, tur10.watchdog_ms) == ("task2", 5, "psm", 0)
    assert tur10.psm == HostPort("localhost", 12605)
    assert tur10.retain_file == Path("/var/tmp/tur10.retain")
    assert load(None).modbus.port == 5020


@pytest.mark.parametrize("text, message", [
    ("[modbus]\nprot = 502\n",
     "openplc.conf: [modbus] prot = '502': unknown key (allowed: enabled, bind, port, unit_id, "
     "idle_timeout_s, first_request_timeout_s, max_clients)"),
    ("[plc]\n",
     "openplc.conf: [plc]: unknown section (allowed: runtime, modbus, mp9c, tur10, thermo)"),
    ("[modbus]\nport = 70000\n",
     "openplc.conf: [modbus] port = '70000': expected an integer 1..65535 (TCP port)"),
    ("[modbus]\nenabled = maybe\n",
     "openplc.conf: [modbus] enabled = 'maybe': expected true or false"),
    ("[modbus]\nbind = 300.1.1.1\n",
     "openplc.conf: [modbus] bind = '300.1.1.1': expected an IP address or host name, "
     "e.g. 127.0.0.1 (0.0.0.0 for all interfaces)"),
    ("[runtime]\nslave_polling_ms = fast\n",
     "openplc.conf: [runtime] slave_polling_ms = 'fast': expected an integer 1..3600000 (milliseconds)"),
    ("[mp9c]\nvariant = task4\n",
     "openplc.conf: [mp9c] variant = 'task4': expected one of baseline, task1, task2, task3, full"),
    ("[mp9c]\nprofile = twido\n",
     "openplc.conf: [mp9c] profile = 'twido': expected one of openplc "
     "(twido needs a Twido register table: thermo)"),
    ("[thermo]\nio = serial\n",
     "openplc.conf: [thermo] io = 'serial': expected one of inprocess, psm"),
    ("[thermo]\npsm = 2605\n",
     "openplc.conf: [thermo] psm = '2605': expected HOST:PORT, e.g. 127.0.0.1:2605"),
    ("[tur10]\ntick_ms = 0\n",
     "openplc.conf: [tur10] tick_ms = '0': expected auto, or an integer 1..60000 (milliseconds)"),
    ("[tur10]\nretain_file =\n",
     "openplc.conf: [tur10] retain_file = '': expected a file path"),
])
def test_mistakes_are_one_line_naming_section_key_value_and_allowed(tmp_path, text, message):
    with pytest.raises(ConfigError) as exc:
        load(write(tmp_path, text))
    assert str(exc.value) == message


@pytest.mark.parametrize("text, fragment", [
    ("port = 5020\n", "no section headers"),
    ("[modbus]\nport = 1\nport = 2\n", "option 'port' in section 'modbus' already exists"),
    ("[modbus]\n[modbus]\n", "section 'modbus' already exists"),
    ("[DEFAULT]\nport = 1\n", "[DEFAULT]: unknown section"),
])
def test_malformed_files_are_one_line(tmp_path, text, fragment):
    with pytest.raises(ConfigError) as exc:
        load(write(tmp_path, text))
    assert fragment in str(exc.value) and "\n" not in str(exc.value)


def test_missing_file_and_unknown_stand(tmp_path):
    with pytest.raises(ConfigError, match="no such configuration file"):
        load(tmp_path / "nope.conf")
    with pytest.raises(ConfigError, match=r"unknown stand 'kuka' \(one of mp9c, tur10, thermo\)"):
        config.defaults().stand("kuka")
