"""The suite runs on a machine where a PLC is already running: every test
runs while another process holds the ports a user's PLC would
(programs/hmi_server's 127.0.0.1:5020, and 44818, EtherNet/IP's). The
run's first act is to start that process (tests/helpers/isolation.py), so the tests
that start a network server (every one that runs or loads
programs/hmi_server, the MODBTCPS, Modbus and serial-over-TCP tests) pass
beside it or the suite fails (docs/testing.md, "Isolation"). This test
checks that the ports are held, and by another process."""

from __future__ import annotations

import errno
import os
import shutil
import socket

import pytest
from helpers.cli import softplc
from helpers.isolation import HELD_PORTS, HOLDER_ENV
from helpers.shipped_apps import PROGRAMS


@pytest.mark.parametrize("port", HELD_PORTS)
def test_the_suite_runs_while_another_process_holds_the_port(port):
    holder = int(os.environ[HOLDER_ENV])
    assert holder != os.getpid()
    os.kill(holder, 0)  # alive
    with socket.socket() as s, pytest.raises(OSError) as taken:
        s.bind(("127.0.0.1", port))
    assert taken.value.errno == errno.EADDRINUSE
    with socket.create_connection(("127.0.0.1", port), timeout=5):  # someone listens there
        pass


def test_a_shipped_server_on_its_own_port_fails_beside_the_held_port(tmp_path):
    """The guard bites: programs/hmi_server run as shipped (127.0.0.1:5020)
    cannot serve during the suite; its server reports the port taken."""
    app = tmp_path / "hmi_server"
    shutil.copytree(PROGRAMS / "hmi_server", app, ignore=shutil.ignore_patterns(".softplc"))
    p = softplc("run", str(app), "--fresh", "--scans", "5", "--state", str(tmp_path / "state"))
    assert "5020" in p.stderr and "in use" in p.stderr, p.stderr
