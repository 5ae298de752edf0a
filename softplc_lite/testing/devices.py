"""Simulated devices on an app's ports, for tests: what ``PLC.load(app,
devices={PORT: DEVICE})`` and a scenario file's ``device`` lines attach.

A PORT is a port number (``0``) or ``MODULE:N`` (``"MODBMAST:1"``) when two
modules have a port N. A DEVICE is a simulated device object
(``ModbusMaster(1)``, ``ModbusSlave(2)``, ``ScriptedLine([(b"?", b"OK\\r\\n")])``,
any ``simdevices.SimDevice``) or a URL ``sim://NAME?device=KIND&...``. Each is
put on the port as a ``--port`` override to a ``sim://`` link of a fresh name
(``plcN-MODULE-PORT``), so two PLCs of one app in a process never share a
link; the object itself reaches the link through the device kind
``_from_python`` (``ref=`` a key of ``_GIVEN``, dropped when the PLC closes).
Every mistake (no such port, a port two modules have, an unknown kind, a bad
option) is a ``DeviceError`` that says which port and why, all at once.
"""

from __future__ import annotations

import itertools
import threading
from dataclasses import dataclass
from typing import Iterable, Mapping

from ..ports import parse_port_overrides, simdevices
from ..ports.simdevices import SimDevice, check_options
from ..ports.urlhandler.protocol_sim import parse_url

KIND = "_from_python"
_GIVEN: dict[str, SimDevice] = {}
_lock = threading.Lock()
_numbers = itertools.count(1)


class DeviceError(ValueError):
    """Devices that cannot be attached: ``problems`` is [(port key, reason)]."""

    def __init__(self, problems: list[tuple[object, str]]) -> None:
        self.problems = problems
        super().__init__("\n".join(f"device on port {key}: {reason}" for key, reason in problems))


def _from_python(options: dict[str, str]) -> SimDevice:
    check_options(KIND, options, ["ref"])
    device = _GIVEN.get(options.get("ref", ""))
    if device is None:
        raise ValueError(f"{KIND} device: no device is given under ref={options.get('ref', '')!r}")
    return device


simdevices.register_device(KIND, _from_python)


def port_key(port: str) -> int | str:
    """A PORT as a scenario file writes it (``0``, ``MODBMAST:1``) as the API takes it."""
    return int(port) if port.isdigit() else port


def make_device(kind: str, options: Mapping[str, str]) -> SimDevice:
    """A new device of ``kind`` (ValueError naming the bad kind or option)."""
    if kind == KIND:
        raise ValueError(f"unknown device kind {kind!r}")
    return simdevices.create_device(kind, dict(options))


def as_device(spec) -> tuple[SimDevice, bool]:
    """(the device, whether its port runs at rate=unlimited) of a DEVICE:
    a SimDevice, or a ``sim://NAME?device=KIND&...`` URL (its NAME is not used)."""
    if isinstance(spec, SimDevice):
        return spec, False
    if isinstance(spec, str):
        text = spec.strip()
        try:
            _, kind, options, unlimited = parse_url(text)
        except ValueError as e:
            raise ValueError(f"{text!r}: expected a simulated device or sim://NAME?device=KIND&...: {e}") from None
        if kind is None:
            raise ValueError(f"{text!r}: expected sim://NAME?device=KIND&... (a device, not a port-to-port link)")
        return make_device(kind, options), unlimited
    raise ValueError(f"expected a simulated device (ModbusMaster, ModbusSlave, ScriptedLine, ...) "
                     f"or a sim:// URL with device=KIND, not {spec!r}")


def resolve_port(modules: Iterable, key) -> tuple[str, int]:
    """(module name, port number) of a PORT key; ValueError saying why not."""
    have = [(m.name.upper(), c.number) for m in modules for c in m.port_claims()]
    listing = ", ".join(f"{name}:{n}" for name, n in have) or "none"
    if isinstance(key, bool) or not isinstance(key, (int, str)):
        raise ValueError(f"expected a port number or MODULE:N, not {key!r}")
    module, _, number = str(key).strip().rpartition(":")
    if not number.isascii() or not number.isdigit():
        raise ValueError(f"expected a port number or MODULE:N, not {key!r}")
    found = [(name, n) for name, n in have if n == int(number) and (not module or name == module.strip().upper())]
    if not found:
        raise ValueError(f"the app has no port {key} (its ports: {listing})")
    if len(found) > 1:
        raise ValueError(f"{' and '.join(f'{name}:{n}' for name, n in found)} both have a port {number}; "
                         f"say which, e.g. {found[0][0]}:{number}")
    return found[0]


@dataclass
class Attached:
    """The devices a PLC put on its ports: the ``--port`` overrides that do
    it, and the refs to drop when it closes."""

    overrides: tuple[str, ...]
    refs: tuple[str, ...]

    def release(self) -> None:
        with _lock:
            for ref in self.refs:
                _GIVEN.pop(ref, None)


def attach(modules: list, devices: Mapping, ports: Iterable[str] = ()) -> Attached:
    """The overrides that put ``devices`` ({PORT: DEVICE}) on the ports of
    ``modules`` (the app's, configured), and that give the app's own
    port-to-port ``sim://NAME`` links a name of this PLC's (both ends
    alike); ``ports``: the ``--port`` overrides given besides, whose ports
    are left alone. DeviceError with every problem."""
    problems: list[tuple[object, str]] = []
    chosen: dict[tuple[str, int], tuple[SimDevice, bool]] = {}
    given = set()
    for module, number in parse_port_overrides(ports):
        try:
            given.add(resolve_port(modules, f"{module}:{number}" if module else number))
        except ValueError:
            pass  # the override's own check says why
    for key, spec in devices.items():
        try:
            port = resolve_port(modules, key)
            device = as_device(spec)
        except ValueError as e:
            problems.append((key, str(e)))
            continue
        if port in chosen:
            problems.append((key, f"{port[0]}:{port[1]} is given a device twice"))
        elif port in given:
            problems.append((key, f"{port[0]}:{port[1]} is given a device and a ports= override"))
        chosen[port] = device
    if problems:
        raise DeviceError(problems)
    plc = next(_numbers)
    overrides, refs = _own_links(modules, set(chosen) | given, plc), []
    with _lock:
        for (module, number), (device, unlimited) in chosen.items():
            ref = f"{plc}-{module}-{number}"
            _GIVEN[ref] = device
            refs.append(ref)
            rate = "&rate=unlimited" if unlimited else ""
            overrides.append(f"{module}:{number}=sim://plc{ref.lower()}?device={KIND}&ref={ref}{rate}")
    return Attached(tuple(overrides), tuple(refs))


def _own_links(modules: list, taken: set, plc: int) -> list[str]:
    """Overrides renaming the app's port-to-port sim:// links (not a device's,
    which is new at each opening) to ``plcN-NAME``."""
    out = []
    for m in modules:
        for c in m.port_claims():
            if (m.name.upper(), c.number) in taken or not c.url.lower().startswith("sim://"):
                continue
            try:
                name, kind, _, _ = parse_url(c.url)
            except ValueError:
                continue  # the port's own open says why
            if kind is None:
                rest = c.url.split("://", 1)[1][len(name):]
                out.append(f"{m.name.upper()}:{c.number}=sim://plc{plc}-{name}{rest}")
    return out


def device_on(modules: list, key) -> SimDevice:
    """The simulated device at the far end of port ``key`` of a running
    app's ``modules``; DeviceError when the port has none."""
    try:
        module, number = resolve_port(modules, key)
    except ValueError as e:
        raise DeviceError([(key, str(e))]) from None
    for m in modules:
        if m.name.upper() != module:
            continue
        for port in m.serial_ports():
            if port.label not in (str(number), f"{module}:{number}"):
                continue
            link = getattr(port.serial, "sim_link", None)
            if link is None or link.device is None:
                state = port.url if port.up else f"{port.url}, down: {port.error}"
                raise DeviceError([(key, f"no simulated device on it ({state})")])
            return link.device
    raise DeviceError([(key, "the port is not open")])
