"""openplc.conf: the runtime's and the harness's settings, read into typed dataclasses.

The file mirrors the settings page of an OpenPLC runtime (Modbus server, start in run mode,
slave polling / timeout) plus this project's own per-stand settings. Every value goes through
one parser per key, the same parsers read the built-in defaults, and anything unknown or
malformed is a ConfigError whose one line names the section, key, value and what is allowed:
a typo must never silently fall back to a default.

Relative paths are relative to the directory of the file (the current directory for the
built-in defaults).
"""
from __future__ import annotations

import configparser
import ipaddress
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from plclab.errors import ConfigError

STANDS = ("mp9c", "tur10", "thermo")
VARIANTS = {
    "mp9c": ("baseline", "task1", "task2", "task3", "full"),
    "tur10": ("baseline", "task1", "task2", "task3", "full"),
    "thermo": ("full",),
}
IO_LAYERS = ("inprocess", "psm")
PROFILES = ("openplc", "twido")
TWIDO_STANDS = ("thermo",)          # stands with a Twido register table (modbus/profiles.py)


@dataclass(frozen=True)
class RuntimeConfig:
    """[runtime]: OpenPLC's "Settings" page."""

    start_in_run_mode: bool
    slave_polling_ms: int
    slave_timeout_ms: int


@dataclass(frozen=True)
class ModbusConfig:
    """[modbus]: the Modbus TCP server face (OpenPLC's "Enable Modbus Server")."""

    enabled: bool
    bind: str
    port: int
    unit_ids: frozenset[int] | None      # None: answer any unit id
    idle_timeout_s: float | None         # None: never close idle clients
    max_clients: int
    first_request_timeout_s: float | None = 5.0   # None: the idle timeout applies from the start

    @property
    def client_host(self) -> str:
        """Where a client on this machine reaches the server: the bind address, or
        loopback when the server listens on every interface."""
        return "127.0.0.1" if self.bind in ("0.0.0.0", "::", "") else self.bind


@dataclass(frozen=True)
class HostPort:
    host: str
    port: int

    def __str__(self) -> str:
        return f"{self.host}:{self.port}"


@dataclass(frozen=True)
class StandConfig:
    """[mp9c], [tur10], [thermo]: what `plclab serve STAND` runs and how."""

    name: str
    variant: str
    program: Path | None                 # an .st bundle to run instead of the variant
    tick_ms: int | None                  # None: the GCD of the program's task intervals
    io: str                              # "inprocess" | "psm"
    psm: HostPort
    profile: str                         # "openplc" | "twido"
    retain_file: Path
    retain_period_ms: int
    watchdog_ms: int                     # 0: no watchdog
    retain_save_error: str = "continue"  # "continue" (report once, retry) | "fault"

    def check_paths(self, source: str = "") -> None:
        """Refuse, before anything runs, a retain_file that can never be written: an existing
        directory, link or device, or a path through a file. (A full disk or a permission
        that changes later is reported while running, and the PLC goes on.)"""
        from plclab.errors import PlcLabError
        from plclab.fileio import check_output
        try:
            check_output(self.retain_file)
        except PlcLabError as exc:
            raise ConfigError(f"{_where(source)}[{self.name}] retain_file: {exc}") from None


@dataclass(frozen=True)
class Config:
    path: Path | None
    runtime: RuntimeConfig
    modbus: ModbusConfig
    stands: dict[str, StandConfig]

    def stand(self, name: str) -> StandConfig:
        try:
            return self.stands[name]
        except KeyError:
            raise ConfigError(f"unknown stand {name!r} (one of {', '.join(STANDS)})") from None


# --------------------------------------------------------------------------- value parsers
# Each takes the raw text and returns the value or raises ValueError("what is allowed").

def _bool(text: str) -> bool:
    low = text.lower()
    if low in ("true", "yes", "on", "1"):
        return True
    if low in ("false", "no", "off", "0"):
        return False
    raise ValueError("true or false")


def _int_range(low: int, high: int | None = None, unit: str = "") -> Callable[[str], int]:
    def parse(text: str) -> int:
        allowed = f"an integer {low}..{high}" if high is not None else f"an integer >= {low}"
        allowed += f" ({unit})" if unit else ""
        if not re.fullmatch(r"[+-]?\d+", text):
            raise ValueError(allowed)
        value = int(text)
        if value < low or (high is not None and value > high):
            raise ValueError(allowed)
        return value
    return parse


_port = _int_range(1, 65535, "TCP port")
_HOSTNAME = re.compile(r"^(?=.{1,253}$)[A-Za-z0-9]([A-Za-z0-9-]{0,62})(\.[A-Za-z0-9][A-Za-z0-9-]{0,62})*$")


def _host(text: str) -> str:
    try:
        ipaddress.ip_address(text)
        return text
    except ValueError:
        if _HOSTNAME.match(text) and not text.replace(".", "").isdigit():
            return text
    raise ValueError("an IP address or host name, e.g. 127.0.0.1 (0.0.0.0 for all interfaces)")


def _host_port(text: str) -> HostPort:
    allowed = "HOST:PORT, e.g. 127.0.0.1:2605"
    host, sep, port = text.rpartition(":")
    if not sep:
        raise ValueError(allowed)
    try:
        return HostPort(_host(host), _port(port))
    except ValueError:
        raise ValueError(allowed) from None


def _unit_ids(text: str) -> frozenset[int] | None:
    allowed = "any, or unit ids 0..255 separated by commas"
    if text.lower() == "any":
        return None
    parse = _int_range(0, 255)
    try:
        ids = frozenset(parse(part.strip()) for part in text.split(","))
    except ValueError:
        raise ValueError(allowed) from None
    return ids


def _idle(text: str) -> float | None:
    allowed = "seconds > 0, or 0 to never close idle clients"
    try:
        value = float(text)
    except ValueError:
        raise ValueError(allowed) from None
    if value != value or value < 0 or value == float("inf"):
        raise ValueError(allowed)
    return value or None


def _choice(options: tuple[str, ...], note: str = "") -> Callable[[str], str]:
    def parse(text: str) -> str:
        if text not in options:
            raise ValueError("one of " + ", ".join(options) + (f" ({note})" if note else ""))
        return text
    return parse


def _tick(text: str) -> int | None:
    if text.lower() == "auto":
        return None
    try:
        return _int_range(1, 60000)(text)
    except ValueError:
        raise ValueError("auto, or an integer 1..60000 (milliseconds)") from None


def _path(text: str) -> str:
    if not text:
        raise ValueError("a file path")
    return text


def _optional_path(text: str) -> str | None:
    return text or None


# --------------------------------------------------------------------------- schema
# section -> key -> (parser, default text). Stand sections get their defaults from _stand_defaults.

_RUNTIME_KEYS: dict[str, tuple[Callable[[str], Any], str]] = {
    "start_in_run_mode": (_bool, "true"),
    "slave_polling_ms": (_int_range(1, 3600000, "milliseconds"), "100"),
    "slave_timeout_ms": (_int_range(1, 3600000, "milliseconds"), "1000"),
}
_MODBUS_KEYS: dict[str, tuple[Callable[[str], Any], str]] = {
    "enabled": (_bool, "true"),
    "bind": (_host, "127.0.0.1"),
    "port": (_port, "5020"),
    "unit_id": (_unit_ids, "any"),
    "idle_timeout_s": (_idle, "60"),
    "first_request_timeout_s": (_idle, "5"),
    "max_clients": (_int_range(1, 1000), "100"),
}


def _stand_keys(stand: str) -> dict[str, tuple[Callable[[str], Any], str]]:
    default_variant = "full" if stand == "thermo" else "baseline"
    default_profile = "twido" if stand in TWIDO_STANDS else "openplc"
    profiles = PROFILES if stand in TWIDO_STANDS else ("openplc",)
    note = "" if stand in TWIDO_STANDS else "twido needs a Twido register table: " + ", ".join(TWIDO_STANDS)
    return {
        "variant": (_choice(VARIANTS[stand]), default_variant),
        "program": (_optional_path, ""),
        "tick_ms": (_tick, "auto"),
        "io": (_choice(IO_LAYERS), "inprocess"),
        "psm": (_host_port, "127.0.0.1:2605"),
        "profile": (_choice(profiles, note), default_profile),
        "retain_file": (_path, f"out/retain/{stand}.retain"),
        "retain_period_ms": (_int_range(10, 3600000, "milliseconds"), "1000"),
        "watchdog_ms": (_int_range(0, 60000, "milliseconds, 0 = off"), "500"),
        "retain_save_error": (_choice(("continue", "fault")), "continue"),
    }


def _schema() -> dict[str, dict[str, tuple[Callable[[str], Any], str]]]:
    schema = {"runtime": _RUNTIME_KEYS, "modbus": _MODBUS_KEYS}
    for stand in STANDS:
        schema[stand] = _stand_keys(stand)
    return schema


# --------------------------------------------------------------------------- loading

def _where(source: str) -> str:
    return f"{source}: " if source else ""


def _parse_section(source: str, section: str, given: dict[str, str]) -> dict[str, Any]:
    keys = _schema()[section]
    for key, text in given.items():
        if key not in keys:
            raise ConfigError(f"{_where(source)}[{section}] {key} = {text!r}: unknown key "
                              f"(allowed: {', '.join(keys)})")
    values: dict[str, Any] = {}
    for key, (parse, default) in keys.items():
        text = given.get(key, default).strip()
        try:
            values[key] = parse(text)
        except ValueError as exc:
            raise ConfigError(f"{_where(source)}[{section}] {key} = {text!r}: expected {exc}") from None
    return values


def _build(path: Path | None, sections: dict[str, dict[str, str]]) -> Config:
    source = path.name if path is not None else ""
    base = path.parent if path is not None else Path.cwd()
    runtime = _parse_section(source, "runtime", sections.get("runtime", {}))
    modbus = _parse_section(source, "modbus", sections.get("modbus", {}))
    stands: dict[str, StandConfig] = {}
    for stand in STANDS:
        v = _parse_section(source, stand, sections.get(stand, {}))
        stands[stand] = StandConfig(
            name=stand, variant=v["variant"],
            program=base / v["program"] if v["program"] else None,
            tick_ms=v["tick_ms"], io=v["io"], psm=v["psm"], profile=v["profile"],
            retain_file=base / v["retain_file"], retain_period_ms=v["retain_period_ms"],
            watchdog_ms=v["watchdog_ms"], retain_save_error=v["retain_save_error"])
    return Config(
        path=path,
        runtime=RuntimeConfig(**runtime),
        modbus=ModbusConfig(enabled=modbus["enabled"], bind=modbus["bind"], port=modbus["port"],
                            unit_ids=modbus["unit_id"], idle_timeout_s=modbus["idle_timeout_s"],
                            max_clients=modbus["max_clients"],
                            first_request_timeout_s=modbus["first_request_timeout_s"]),
        stands=stands)


def defaults() -> Config:
    """The built-in settings: what the shipped openplc.conf says, paths relative to the cwd."""
    return _build(None, {})


def load(path: str | Path | None = None) -> Config:
    """Read an openplc.conf; `None` gives the built-in defaults. Raises ConfigError."""
    if path is None:
        return defaults()
    path = Path(path)
    parser = configparser.ConfigParser(
        interpolation=None, strict=True, empty_lines_in_values=False,
        default_section="\x00no default section", inline_comment_prefixes=(";", "#"))
    try:
        with open(path, encoding="utf-8") as fh:
            parser.read_file(fh)
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such configuration file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read: {getattr(exc, 'strerror', None) or exc}") from None
    except configparser.Error as exc:
        line = " ".join(str(exc).split()) or type(exc).__name__
        raise ConfigError(f"{path.name}: {line}") from None
    schema = _schema()
    for section in parser.sections():
        if section not in schema:
            raise ConfigError(f"{path.name}: [{section}]: unknown section "
                              f"(allowed: {', '.join(schema)})")
    sections = {name: dict(parser.items(name)) for name in parser.sections()}
    return _build(path.resolve(), sections)
