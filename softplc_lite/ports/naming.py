"""Which device a port opens, who claims it, and ``--port`` overrides.

Every module that drives serial ports names them the same way:

- ``COMn`` (COM1..COM99) is the n-th serial port of the machine: the device
  a module's config maps it to, else the platform default (``COMn`` on
  Windows, ``/dev/ttyS{n-1}`` elsewhere: the on-board UARTs);
- anything else is a device path (``/dev/ttyUSB0``, a pty) or a pyserial URL
  (``loop://``, ``socket://``, ``rfc2217://``, ``spy://``, and softplc_lite's
  ``sim://`` and ``replay://``).

``softplc run APP --port N=DEVICE`` puts a module's port N on DEVICE for one
run. In an app whose modules both have a port N, ``--port MODULE:N=DEVICE``
says which (``--port MODBMAST:1=sim://bus``); a plain ``N`` that two modules
have is refused, as is an N no module has.

Two ports may not open the same device (``claim_key``): a serial device can
have one owner. Shareable URLs have no key: each ``loop://`` and each
``sim://NAME?device=KIND`` opening is a port of its own, and the two ends of
a ``sim://NAME`` link are meant to be opened twice (a third opening fails
when it opens).
"""

from __future__ import annotations

import os
import re
import sys
from dataclasses import dataclass
from typing import Iterable, Mapping

from .errors import PortError

COM_NAME = re.compile(r"COM([1-9][0-9]?)", re.IGNORECASE)  # COM1..COM99
_OVERRIDE = re.compile(r"^\s*(?:([A-Za-z][A-Za-z0-9_]*)\s*:\s*)?([0-9]{1,6})\s*=\s*(\S.*?)\s*$")


def default_com_device(n: int, platform: str = sys.platform) -> str:
    """The device of COMn when the config does not say: ``COMn`` on
    Windows, the n-th on-board UART ``/dev/ttyS{n-1}`` elsewhere."""
    return f"COM{n}" if platform.startswith("win") else f"/dev/ttyS{n - 1}"


def com_url(n: int, com_devices: Mapping[int, str] | None = None, platform: str = sys.platform) -> str:
    """The device or URL of COMn."""
    return (com_devices or {}).get(n) or default_com_device(n, platform)


def physical_url(physical: str, com_devices: Mapping[int, str] | None = None, platform: str = sys.platform) -> str:
    """What to give ``serial_for_url`` for a physical port field: ``COMn``
    through the mapping, anything else as it is."""
    text = physical.strip()
    m = COM_NAME.fullmatch(text)
    if m:
        return com_url(int(m.group(1)), com_devices, platform)
    return text


def claim_key(url: str) -> str | None:
    """What identifies the device ``url`` opens, for "two ports on one
    device" checks; None for URLs each opening of which is its own port."""
    scheme = url.split("://", 1)[0].lower() if "://" in url else ""
    if scheme in ("loop", "replay"):
        return None
    if scheme == "sim":
        return None  # a device link is new at each opening; a port link has two ends
    if scheme in ("socket", "rfc2217"):
        return f"{scheme}://{url.split('://', 1)[1].split('?', 1)[0].lower()}"
    if scheme == "spy":
        url = url.split("://", 1)[1].split("?", 1)[0]
    elif scheme:
        return url
    path = url
    try:
        path = os.path.realpath(url) if os.path.exists(url) else url
    except (OSError, ValueError):
        pass
    return path.upper() if sys.platform.startswith("win") else path


@dataclass(frozen=True)
class PortClaim:
    """A port a module will open: its number, device or URL, and where its
    config says so (``file:line``)."""

    module: str
    number: int
    url: str
    where: str


def claim_conflicts(claims: Iterable[PortClaim]) -> list[str]:
    """A message for each port that would open a device another port opens."""
    first: dict[str, PortClaim] = {}
    out = []
    for claim in claims:
        key = claim_key(claim.url)
        if key is None:
            continue
        other = first.get(key)
        if other is None:
            first[key] = claim
            continue
        out.append(f"{claim.where}: {claim.module} port {claim.number} would open {claim.url}, which "
                   f"{other.module} port {other.number} opens ({other.where}); a serial device has one owner")
    return out


class OverrideError(PortError):
    """A ``--port`` item that cannot be used."""


PortKey = tuple[str | None, int]  # (module name or None, port number)


def parse_port_overrides(items: Iterable[str]) -> dict[PortKey, str]:
    """``--port`` items (``N=DEVICE`` or ``MODULE:N=DEVICE``) by (module, N)."""
    out: dict[PortKey, str] = {}
    for text in items:
        m = _OVERRIDE.match(text)
        if m is None:
            raise OverrideError(f"--port {text!r}: expected N=DEVICE or MODULE:N=DEVICE, e.g. "
                                "--port 0=/dev/ttyUSB0, --port 1=socket://127.0.0.1:5020 or "
                                "--port MODBMAST:1=sim://bus")
        module, number, device = m.group(1), int(m.group(2)), m.group(3)
        key = (module.upper() if module else None, number)
        if key in out:
            raise OverrideError(f"--port {text!r}: port {number} is given twice")
        out[key] = device
    return out


def assign_port_overrides(overrides: Mapping[PortKey, str], ports: Mapping[str, Iterable[int]]) -> dict[str, dict[int, str]]:
    """Split ``--port`` overrides between modules. ``ports``: each module's
    port numbers. Returns {module: {N: device}}; OverrideError when an
    override names no module's port, or a port two modules have."""
    have = {name.upper(): set(numbers) for name, numbers in ports.items()}
    out: dict[str, dict[int, str]] = {name: {} for name in have}
    for (module, number), device in overrides.items():
        if module is not None:
            if module not in have:
                names = ", ".join(sorted(have)) or "none"
                raise OverrideError(f"--port {module}:{number}={device}: no module {module} drives ports in this "
                                    f"app (modules with ports: {names})")
            if number not in have[module]:
                raise OverrideError(f"--port {module}:{number}={device}: {module} has no port {number} "
                                    f"(its ports: {_list(have[module])})")
            out[module][number] = device
            continue
        owners = sorted(name for name, numbers in have.items() if number in numbers)
        if not owners:
            listing = "; ".join(f"{name}: {_list(numbers)}" for name, numbers in sorted(have.items())) or "none"
            raise OverrideError(f"--port {number}={device}: no module has a port {number} (ports: {listing})")
        if len(owners) > 1:
            raise OverrideError(f"--port {number}={device}: {' and '.join(owners)} both have a port {number}; "
                                f"say which: " + " or ".join(f"--port {o}:{number}=..." for o in owners))
        out[owners[0]][number] = device
    return out


def _list(numbers: Iterable[int]) -> str:
    return ", ".join(map(str, sorted(numbers))) or "none"
