"""The shipped apps (programs/) as tests run them: copied into the test's
temporary directory without their ``.softplc`` state, so nothing is written
inside the repository, and with every network server (MODBTCPS.XML's,
ENIPS.XML's, OPCUAS.XML's) moved to a port found free, so a PLC already running on this
machine (serving the shipped 127.0.0.1:5020, or 44818) does not stand in the
way (docs/testing.md, "Isolation")."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from helpers.modbus_peer import free_tcp_port

ROOT = Path(__file__).resolve().parents[2]
PROGRAMS = ROOT / "programs"
SHIPPED_PORT = 5020  # programs/hmi_server/MODBTCPS.XML
# Each network server's config file, and its root element (where its port is).
SERVER_CONFIGS = {"MODBTCPS.XML": "ModbusTcpServer", "ENIPS.XML": "EtherNetIpServer", "OPCUAS.XML": "OpcUaServer"}


def free_server_port(app_dir: Path) -> int | None:
    """Moves the app's network server (MODBTCPS, ENIPS or OPCUAS) to a free port;
    the port, or None for an app without one."""
    for name, root in SERVER_CONFIGS.items():
        config = app_dir / name
        if not config.exists():
            continue
        port = free_tcp_port()
        pattern = re.compile(rf'(<{root}\b[^>]*?\bport=")(\d+)(")')
        text, n = pattern.subn(lambda m: f"{m.group(1)}{port}{m.group(3)}", config.read_text(encoding="utf-8"),
                               count=1)
        assert n == 1, f"{config}: no port attribute to move"
        config.write_text(text, encoding="utf-8")
        return port
    return None


def copy_app(name: str, dest: Path) -> Path:
    """programs/NAME copied to DEST/NAME, its server on a free port."""
    app = dest / name
    shutil.copytree(PROGRAMS / name, app, ignore=shutil.ignore_patterns(".softplc"))
    free_server_port(app)
    return app


def copy_programs(dest: Path) -> dict[str, int]:
    """All of programs/ copied to DEST/programs; each server's new port by
    app name."""
    target = dest / "programs"
    shutil.copytree(PROGRAMS, target, ignore=shutil.ignore_patterns(".softplc"))
    ports = {}
    for app in sorted(p for p in target.iterdir() if p.is_dir()):
        if (port := free_server_port(app)) is not None:
            ports[app.name] = port
    return ports


def shipped_app_names() -> list[str]:
    """The shipped apps that are app directories (programs/NAME with .lad
    files), by name."""
    return sorted(p.name for p in PROGRAMS.iterdir() if p.is_dir() and any(p.glob("*.lad")))


def shipped_exports() -> list[Path]:
    """The shipped Studio 5000 exports (programs/logix/*.L5X, *.L5K): apps
    of one file each (docs/logix.md)."""
    return sorted(p for p in (PROGRAMS / "logix").iterdir() if p.suffix.lower() in (".l5x", ".l5k"))
