"""A scenario file's simulated devices: its ``device PORT = KIND KEY=VALUE``
lines made into devices on a fresh PLC (devices.py), and the
``device PORT NAME`` values its steps read; each mistake located at its line."""

from __future__ import annotations

from pathlib import Path

from ..errors import LocatedError
from .devices import DeviceError, make_device, port_key
from .plc import PLC
from .scenario import DeviceCounter, ScenarioErrors, ScenarioFile


def open_plc(app: str | Path, file: ScenarioFile, **load) -> PLC:
    """A fresh PLC of ``app`` with the file's devices on their ports (``load``:
    PLC.load's other arguments); ScenarioErrors with every bad device line."""
    errors, devices, lines = [], {}, {}
    for d in file.devices:
        lines[port_key(d.port)] = d
        try:
            devices[port_key(d.port)] = make_device(d.kind, dict(d.options))
        except ValueError as e:
            errors.append(LocatedError(f"expected a simulated device and its options: {e}", file.path, d.line,
                                       d.column))
    try:
        plc = PLC.load(app, devices=devices, **load)
    except DeviceError as e:
        errors += [LocatedError(f"expected a port of the app: {reason}", file.path, lines[key].line,
                                lines[key].column) for key, reason in e.problems]
        raise ScenarioErrors(sorted(errors, key=lambda x: x.line)) from None
    if errors:
        plc.close()
        raise ScenarioErrors(errors)
    return plc


def counter_errors(file: ScenarioFile, plc: PLC) -> list[LocatedError]:
    """Each step's ``device PORT NAME`` names a port with a simulated device
    and a number of its score."""
    errors = []
    for step in file.all_steps():
        name = step.args[0] if step.args else None
        if not isinstance(name, DeviceCounter):
            continue
        try:
            device = plc.device(port_key(name.port))
        except DeviceError as e:
            errors.append(LocatedError(f"expected a port with a simulated device: {e}", file.path, step.line,
                                       step.column))
            continue
        if not isinstance(getattr(device, name.attribute, None), (int, float)) or name.attribute.startswith("_"):
            known = ", ".join(counters(device)) or "none"
            errors.append(LocatedError(f"expected a number of the {device.name} device's score: "
                                       f"{name.attribute} (its numbers: {known})", file.path, step.line, step.column))
    return errors


def counters(device) -> list[str]:
    """The public number attributes of ``device`` (its score and settings)."""
    names = set(vars(device)) | {n for n in dir(type(device)) if isinstance(getattr(type(device), n), property)}
    return sorted(n for n in names if not n.startswith("_") and isinstance(getattr(device, n, None), (int, float)))
