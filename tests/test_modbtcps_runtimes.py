"""MODBTCPS end to end: 20 clients writing counters
while the ladder runs on the wall clock, and two runtimes, one polling the
other with COMGENIUS over a ``socket://`` port.

The runtimes are ``softplc run`` processes (the clients' threads must not
share an interpreter with the scan they judge); each is ended with SIGTERM,
which prints its --print values, and said how many scans were late."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from pymodbus.client import ModbusTcpClient

from helpers.modbtcps_apps import LIMIT_S, server_xml, write_app
from helpers.modbus_peer import free_tcp_port, wait_for_tcp
from helpers.runtimes import Runtime, late_scans, printed, prints, wait_for_a_client

pytestmark = pytest.mark.timeout(120)
PROGRAMS = Path(__file__).resolve().parent.parent / "programs"
CLIENTS = 20
SECONDS = 10.0


@pytest.mark.alone  # counts late real-time scans (docs/testing.md)
def test_20_clients_write_counters_for_10_seconds_every_write_lands_and_no_scan_is_late(tmp_path):
    port = free_tcp_port()
    units = '<Unit id="1"><HoldingRegisters start="0" count="20" address="N7:0" writable="yes"/></Unit>\n'
    # The ladder works on what the clients write: the sum of the counters, every scan.
    ladder = "CLR N9:0\n" + "".join(f"ADD N9:0 N7:{k} N9:0\n" for k in range(CLIENTS))
    app = write_app(tmp_path / "app", server_xml(units, port=port, maxRequestsPerSecond=100000,
                                                 maxConnections=CLIENTS + 2), ladder)
    runtime = Runtime(app, *prints([f"N7:{k}" for k in range(CLIENTS)] + ["S:9"]))
    try:
        wait_for_tcp(port, LIMIT_S)
        last = [0] * CLIENTS
        errors: list[str] = []
        start = threading.Barrier(CLIENTS)

        def client(k: int) -> None:
            try:
                with ModbusTcpClient("127.0.0.1", port=port, timeout=LIMIT_S, retries=0) as c:
                    start.wait()
                    end = time.monotonic() + SECONDS
                    value = 0
                    while time.monotonic() < end:
                        value = (value + 1) & 0x7FFF
                        r = c.write_register(k, value, device_id=1)
                        if r.isError():
                            errors.append(f"client {k}: {r}")
                            return
                        last[k] = value
            except Exception as e:  # said by the assertion below
                errors.append(f"client {k}: {type(e).__name__}: {e}")

        threads = [threading.Thread(target=client, args=(k,)) for k in range(CLIENTS)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(SECONDS + LIMIT_S)
    finally:
        out, err = runtime.stop()
    assert not errors, errors[:3]
    values = printed(out)
    assert [int(values[f"N7:{k}"]) for k in range(CLIENTS)] == last  # every client's last write is there
    assert min(last) > 50  # each client wrote many times (a write takes one scan at most 10 ms apart)
    late, scans = late_scans(err)
    assert late == 0 and scans >= SECONDS * 100 * 0.8, err
    assert int(values["S:9"]) < 100  # the longest scan, far under the 500 ms watchdog


MBAP_STRINGS = """\
[STRINGS]
1 "unused"
2 "\\x00\\x01\\x00\\x00\\x00\\x06\\x01\\x03%.2C%.2C"
3 "unused"
4 "\\x00\\x01\\x00\\x00\\x00\\x17\\x01\\x03\\x14%.20C"
5 "\\x00\\x01\\x00\\x00\\x00\\x03\\x01\\x83%c"
"""


def test_one_runtime_polls_another_with_comgenius_over_socket(tmp_path):
    """Runtime B serves its N7 over MODBTCPS; runtime A is the shipped
    COMGENIUS Modbus master with Modbus TCP (MBAP) formats instead of RTU
    ones, its port 0 on socket:// to B, reading 10 registers each poll."""
    port = free_tcp_port()
    units = '<Unit id="1"><HoldingRegisters start="0" count="10" address="N7:0"/></Unit>\n'
    server = write_app(tmp_path / "b", server_xml(units, port=port), "ADD N7:0 1 N7:0\nMOV 4242 N7:5\n")
    client = tmp_path / "a"
    shutil.copytree(PROGRAMS / "modbus_master", client, ignore=shutil.ignore_patterns(".softplc"))
    (client / "softplc.toml").unlink()  # its [display] is about the simulated slave's registers
    lst = (client / "COMGENIUS.LST").read_text()
    (client / "COMGENIUS.LST").write_text(lst[:lst.index("\n[STRINGS]\n") + 1] + MBAP_STRINGS)
    ladder = (client / "main.lad").read_text()
    (client / "main.lad").write_text(ladder.replace("DATA N7 22 = 0 125", "DATA N7 22 = 0 10"))
    b = Runtime(server)
    a = None
    try:
        wait_for_tcp(port, LIMIT_S)
        a = Runtime(client, "--port", f"0=socket://127.0.0.1:{port}",
                    *prints(["N11:0", "N11:5", "C5:1.ACC", "C5:2.ACC", "C5:3.ACC", "C5:4.ACC"]))
        wait_for_a_client(port)  # A has started (seconds on a busy machine): then it polls for 3 s
        time.sleep(3.0)
    finally:
        try:
            out_a, err_a = a.stop() if a is not None else ("", "")
        finally:
            b.stop()
    values = printed(out_a)
    assert int(values["C5:1.ACC"]) >= 10, (out_a, err_a)  # good replies: about one every 60 ms
    assert values["N11:5"] == "4242" and int(values["N11:0"]) > 0
    assert values["C5:2.ACC"] == values["C5:3.ACC"] == values["C5:4.ACC"] == "0"  # no exception, timeout, garbage


def children(pid: int) -> list[int]:
    path = Path(f"/proc/{pid}/task/{pid}/children")
    return [int(p) for p in path.read_text().split()] if path.exists() else []


def mapped_images(pid: int) -> set[str]:
    """The shared image files process ``pid`` has mapped."""
    maps = Path(f"/proc/{pid}/maps").read_text().splitlines()
    return {line.split(None, 5)[5].removesuffix(" (deleted)") for line in maps if "softplc-modbtcps-" in line}


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux's /proc")
def test_the_server_process_ends_when_its_runtime_is_killed(tmp_path):
    port = free_tcp_port()
    runtime = Runtime(write_app(tmp_path / "app", server_xml(port=port)))
    try:
        wait_for_tcp(port, LIMIT_S)
        (server,) = children(runtime.proc.pid)
        images = mapped_images(server)  # this runtime's own: other PLCs on the machine have theirs
        assert images
        runtime.proc.kill()  # no close(): the server sees its standard input end
        runtime.proc.wait(LIMIT_S)
        deadline = time.monotonic() + LIMIT_S
        while Path(f"/proc/{server}").exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not Path(f"/proc/{server}").exists() or "Z" in Path(f"/proc/{server}/stat").read_text().split()[2]
        assert not any(Path(image).exists() for image in images)  # the image was unlinked at start
    finally:
        if runtime.proc.poll() is None:
            runtime.proc.kill()
        runtime.proc.communicate()


def test_ctrl_c_to_the_terminal_group_ends_the_run_cleanly_server_last(tmp_path):
    """Ctrl-C in a terminal signals the whole process group: the runtime
    saves and prints, and its server process, which ignores SIGINT, ends
    when the runtime closes it, without a word."""
    port = free_tcp_port()
    app = write_app(tmp_path / "app", server_xml(port=port))
    proc = subprocess.Popen([sys.executable, "-m", "softplc_lite", "run", str(app), "--fresh", "--print", "N40:0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        wait_for_tcp(port, LIMIT_S)
        with ModbusTcpClient("127.0.0.1", port=port, timeout=LIMIT_S, retries=0) as c:
            deadline = time.monotonic() + LIMIT_S  # scanning, past start-up (a Ctrl-C there exits 130)
            while c.read_input_registers(0, count=1, device_id=1).registers[0] < 3:
                assert time.monotonic() < deadline, "the runtime did not scan"
                time.sleep(0.01)
        (server,) = children(proc.pid)
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=LIMIT_S)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err
    bits = int(printed(out)["N40:0"])  # bit /2 (a client) may still show the probe connections
    assert bits & 1 and not bits & 2, out  # still listening at the last scan, not failed
    assert "MODBTCPS" not in err and "Traceback" not in err, err
    assert not Path(f"/proc/{server}").exists() or "Z" in Path(f"/proc/{server}/stat").read_text().split()[2]
