"""The suite runs on a machine where a PLC is already running: the tests
that start a network server pass while another process holds the ports a
user's PLC would (programs/hmi_server's 127.0.0.1:5020, and 44818,
EtherNet/IP's). They run in a pytest of their own, in a subprocess, beside
a process that listens on both (docs/testing.md, "Isolation")."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
HELD = (5020, 44818)

# Every test that runs or loads programs/hmi_server (its MODBTCPS.XML says
# 127.0.0.1:5020), and one test of each other file whose tests start a
# network server (on a port of their own: a port 0 bind or one found free).
SERVER_TESTS = [
    "tests/test_docs.py::test_doctests_in_docs[modbtcps.md]",
    "tests/test_docs.py::test_console_examples[modbtcps.md:softplc run programs/hmi_server --scans 3 --fresh ]",
    "tests/test_compiler.py::test_every_example_program_compiles_to_allowed_names",
    "tests/test_watch_rungs.py::test_every_example_program_renders_at_80_and_120[hmi_server]",
    "tests/test_differential.py::test_programs_dir_executors_agree[programs/hmi_server/main.lad]",
    "tests/test_codecache.py::test_every_shipped_app_caches_and_compiles_the_same_code[hmi_server]",
    "tests/test_watch_servers.py::test_the_docs_example_is_what_the_hmi_server_shows",
    "tests/test_cli_readme.py::test_every_try_it_line_works_in_order",
    "tests/test_modbtcps_server.py::test_read_input_registers_words_and_a_float",
    "tests/test_modbtcps_hostile.py::test_a_request_in_one_byte_segments_is_served",
    "tests/test_modbtcps_runtimes.py::test_ctrl_c_to_the_terminal_group_ends_the_run_cleanly_server_last",
    "tests/test_modbtcps_refusals.py::test_the_first_scan_starts_the_server_and_a_taken_port_fails_it_not_the_run",
    "tests/test_comgenius_ports.py::test_port_down_at_start_with_retry_then_vanishes_and_comes_back[compiled]",
    "tests/test_modbmast_pymodbus.py::test_a_reply_is_stored_at_the_input_point_only[socket]",
    "tests/test_modbus_slave.py::test_pymodbus_reads_the_same_values_at_the_same_addresses",
    "tests/test_modbus_slave_pymodbus.py::test_pymodbus_over_socket_through_a_serial_server",
    "tests/test_modbus_master.py::test_pymodbus_over_tcp_with_rtu_framing",
]

HOLDER = """
import socket, sys
held = []
for port in map(int, sys.argv[1:]):
    s = socket.socket()
    try:
        s.bind(("127.0.0.1", port))
        s.listen()
        held.append(s)
    except OSError:  # already taken by something else: held either way
        s.close()
print("holding", flush=True)
sys.stdin.read()  # until the test closes it
"""


def listening(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=1.0).close()
        return True
    except OSError:
        return False


@pytest.mark.timeout(300)
def test_the_server_tests_pass_while_a_plc_holds_5020_and_44818(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, *map(str, HELD)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline() == "holding\n"
        assert all(listening(port) for port in HELD)
        report = tmp_path / "report.xml"
        env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST_XDIST", "PYTEST_CURRENT"))}
        p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--timeout=60",
                            f"--basetemp={tmp_path / 'inner'}", f"--junitxml={report}", *SERVER_TESTS],
                           cwd=ROOT, env=env, capture_output=True, text=True, timeout=280, check=False)
    finally:
        holder.stdin.close()
        holder.wait(30)
    assert p.returncode == 0, p.stdout[-6000:] + p.stderr[-2000:]
    cases = ET.parse(report).getroot().iter("testcase")
    ran = {f"tests/{c.get('classname').rpartition('.')[2]}.py::{c.get('name')}" for c in cases
           if not any(child.tag in ("skipped", "failure", "error") for child in c)}
    assert ran == set(SERVER_TESTS), sorted(set(SERVER_TESTS) - ran)  # each passed: none skipped
