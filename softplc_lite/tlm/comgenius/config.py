"""COMGENIUS.LST: the module's one configuration file (manual chapter 3).

Three sections, each opened by a line ``[DRIVER]``, ``[PORTS]`` or
``[STRINGS]`` (any case):

- ``[DRIVER]``: ``DEBUG=0``, ``1`` or ``2``.
- ``[PORTS]``: one port a line, 8 comma-separated fields: logical port
  (0-35), physical port, encoding, baud, data bits (5-8), parity (N/E/O),
  stop bits (1/2), timeout in ms. The physical port is ``COMn``, a bare
  number ``n`` (the manual's first sample: physical port 0 is COM1), a
  device path, or a pyserial URL; a URL may itself hold commas, so the
  fields are counted from both ends.
- ``[STRINGS]``: see strings.py. Blank lines there take no number; any other
  line does (a line without quotes is the empty string).

``;`` starts a comment everywhere except in ``[STRINGS]``, where every
non-blank line is a string (a warning points out a ``;`` line there,
because it becomes an empty string rather than a comment).

Errors name the file, the line (and column where it helps) and the reason.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ...ports import COM_NAME
from ...ports.urlhandler.protocol_sim import url_problem as sim_url_problem  # COM1..COM99: in [DRIVER] keys and [PORTS]
from ..api import find_file, read_module_file
from ..errors import ModuleError, ModuleErrors
from .strings import MAX_LENGTH, MAX_STRINGS, EscapeError, StringTable, decode_escapes

CONFIG_FILE = "COMGENIUS.LST"
MAX_PORT = 35
ENCODINGS = {name.upper(): name for name in ("ISO-8859-1", "US-ASCII", "UTF-8", "UTF-16BE", "UTF-16LE")}
SECTIONS = ("DRIVER", "PORTS", "STRINGS")
_SECTION = re.compile(r"^\s*\[([A-Za-z_]+)\]\s*$")


@dataclass(frozen=True)
class PortConfig:
    """One ``[PORTS]`` line."""

    logical: int
    physical: str
    encoding: str  # canonical name, e.g. "ISO-8859-1"
    baud: int
    data_bits: int
    parity: str  # "N", "E" or "O"
    stop_bits: int
    timeout_ms: int
    line: int = 0


@dataclass
class ComGeniusConfig:
    path: str = CONFIG_FILE
    debug: int = 0
    ports: dict[int, PortConfig] = field(default_factory=dict)
    strings: StringTable = field(default_factory=StringTable)
    port_errors: str = "STOP"  # or "RETRY": what a port that cannot be opened at start does
    retry_ms: int = 1000  # how often a port that is down is tried again
    com_devices: dict[int, str] = field(default_factory=dict)  # COMn=device overrides
    warnings: list[str] = field(default_factory=list)


def _int_field(text: str, name: str, lo: int, hi: int | None, err) -> int:
    text = text.strip()
    if not re.fullmatch(r"[0-9]+", text):
        raise err(f"{name} must be a number, not {text!r}")
    if len(text) > 9:  # past every range, and too long to convert cheaply (Python stops at 4,300 digits)
        shown = f"{text[:9]}... ({len(text)} digits)"
        raise err(f"{name} {shown} is out of range ({lo}..{hi})" if hi is not None
                  else f"{name} {shown} is too large")
    value = int(text)
    if value < lo or (hi is not None and value > hi):
        raise err(f"{name} {value} is out of range ({lo}..{hi})" if hi is not None
                  else f"{name} must be at least {lo}, not {value}")
    return value


def _port_line(text: str, line: int, path: str) -> PortConfig:
    def err(message: str) -> ModuleError:
        return ModuleError(f"[PORTS]: {message}", path, line)

    parts = text.split(",")
    if len(parts) < 8:
        raise err(f"expected 8 comma-separated fields (logical port, physical port, encoding, baud, "
                  f"data bits, parity, stop bits, timeout ms), found {len(parts)}")
    logical = _int_field(parts[0], "logical port", 0, MAX_PORT, err)
    physical = ",".join(parts[1:-6]).strip()
    if not physical:
        raise err("the physical port is empty (COM1, a device path such as /dev/ttyUSB0, or a URL such as loop://)")
    enc_text, baud_t, bits_t, parity_t, stop_t, timeout_t = (p.strip() for p in parts[-6:])
    encoding = ENCODINGS.get(enc_text.upper())
    if encoding is None:
        raise err(f"unknown encoding {enc_text!r} (encodings: {', '.join(ENCODINGS.values())})")
    baud = _int_field(baud_t, "baud rate", 1, None, err)
    data_bits = _int_field(bits_t, "data bits", 5, 8, err)
    parity = parity_t.upper()
    if parity not in ("N", "E", "O"):
        raise err(f"parity must be N, E or O, not {parity_t!r}")
    stop_bits = _int_field(stop_t, "stop bits", 1, 2, err)
    timeout = _int_field(timeout_t, "timeout", 0, None, err)
    return PortConfig(logical, physical, encoding, baud, data_bits, parity, stop_bits, timeout, line)


def _string_line(raw: str, line: int, path: str, table: StringTable) -> None:
    first, last = raw.find('"'), raw.rfind('"')
    if first >= 0 and first == last:
        raise ModuleError("[STRINGS]: only one double quote; a string goes between an opening and a closing "
                          '" (write \\" for a quote inside it)', path, line, first + 1)
    text = raw[first + 1:last] if first >= 0 else ""
    try:
        value = decode_escapes(text)
    except EscapeError as e:
        raise ModuleError(f"[STRINGS]: {e.message}", path, line, first + 2 + e.offset) from None
    if len(value) > MAX_LENGTH:
        raise ModuleError(f"[STRINGS]: string {len(table)} has {len(value)} characters; "
                          f"at most {MAX_LENGTH} are allowed", path, line, first + 1)
    if len(table) > MAX_STRINGS:
        raise ModuleError(f"[STRINGS]: more than {MAX_STRINGS} strings", path, line)
    table.add(value, line)




def _driver_line(content: str, line: int, path: str, config: "ComGeniusConfig") -> None:
    """``KEY=VALUE`` in [DRIVER]. The manual has DEBUG only; the other keys
    are softplc_lite's (docs/serial.md): PORT_ERRORS, RETRY_MS and COMn."""
    key, eq, value = (part.strip() for part in content.partition("="))
    name = key.upper()
    if not eq:
        raise ModuleError(f"[DRIVER]: expected KEY=VALUE (DEBUG=0, 1 or 2), found {content!r}", path, line)
    if name == "DEBUG":
        if value not in ("0", "1", "2"):
            raise ModuleError(f"[DRIVER]: DEBUG must be 0, 1 or 2, not {value!r}", path, line)
        config.debug = int(value)
    elif name == "PORT_ERRORS":
        if value.upper() not in ("STOP", "RETRY"):
            raise ModuleError(f"[DRIVER]: PORT_ERRORS must be STOP (a port that cannot be opened stops the run) "
                              f"or RETRY (run on, retrying it), not {value!r}", path, line)
        config.port_errors = value.upper()
    elif name == "RETRY_MS":
        config.retry_ms = _int_field(value, "RETRY_MS", 10, None,
                                     lambda m: ModuleError(f"[DRIVER]: {m}", path, line))
    elif COM_NAME.fullmatch(name):
        if not value:
            raise ModuleError(f"[DRIVER]: {key}= needs a device (e.g. {key}=/dev/ttyUSB0) or a URL", path, line)
        config.com_devices[int(COM_NAME.fullmatch(name).group(1))] = value
    else:
        raise ModuleError(f"[DRIVER]: unknown setting {key!r} (settings: DEBUG, PORT_ERRORS, RETRY_MS, "
                          f"COM1..COM99)", path, line)


def parse_config(text: str, path: str = CONFIG_FILE) -> ComGeniusConfig:
    """Read COMGENIUS.LST text; every problem (a line with a problem is
    skipped, and the lines after it are still read): one ModuleError, or
    ModuleErrors listing them."""
    config = ComGeniusConfig(path=path)
    problems: list[ModuleError] = []
    state = {"section": None}
    for number, raw in enumerate(text.splitlines(), start=1):
        try:
            _config_line(raw, number, path, config, state)
        except ModuleError as e:
            problems.append(e)
    if problems:
        raise problems[0] if len(problems) == 1 else ModuleErrors(problems)
    return config


def _config_line(raw: str, number: int, path: str, config: ComGeniusConfig, state: dict) -> None:
    """One line of COMGENIUS.LST into ``config``; ``state["section"]``: the section it is in."""
    section = state["section"]
    header = _SECTION.match(raw)
    if header:
        name = header.group(1).upper()
        if name not in SECTIONS:
            raise ModuleError(f"unknown section [{header.group(1)}] (sections: "
                              f"{', '.join(f'[{s}]' for s in SECTIONS)})", path, number)
        state["section"] = name
        return
    if section == "STRINGS":
        if not raw.strip():
            return
        _string_line(raw, number, path, config.strings)
        if raw.lstrip().startswith(";") and '"' not in raw:
            config.warnings.append(f"{path}:{number}: ';' does not start a comment in [STRINGS]: this line "
                                   f"is string {len(config.strings) - 1}, the empty string")
        return
    content = raw.split(";", 1)[0].strip()
    if not content:
        return
    if section is None:
        raise ModuleError(f"{content!r} is outside any section (start with [DRIVER], [PORTS] or [STRINGS])",
                          path, number)
    if section == "DRIVER":
        _driver_line(content, number, path, config)
    else:
        port = _port_line(content, number, path)
        if port.physical.lower().startswith("sim://") and (problem := sim_url_problem(port.physical)):
            raise ModuleError(f"COMGENIUS port {port.logical}: {problem}", path, number)  # what run would refuse
        if port.logical in config.ports:
            raise ModuleError(f"[PORTS]: logical port {port.logical} is defined twice (first on line "
                              f"{config.ports[port.logical].line})", path, number)
        config.ports[port.logical] = port


def load_config(app_dir: Path) -> ComGeniusConfig:
    """COMGENIUS.LST from the app directory (the name in any case)."""
    path = find_file(app_dir, CONFIG_FILE)
    if path is None:
        raise ModuleError(f"COMGENIUS is enabled in MODULES.LST but {app_dir / CONFIG_FILE} does not exist "
                          "(it holds the [DRIVER], [PORTS] and [STRINGS] sections)")
    return parse_config(read_module_file(path), str(path))
