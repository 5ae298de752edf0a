"""The watch view's servers panel (clients connected, requests per second,
refusals), rendered from a
real MODBTCPS app with pymodbus's client making real requests, and once in
the real ``softplc watch`` in tmux."""

from __future__ import annotations

import io
import re
import shutil
import socket
import sys
import time
from pathlib import Path

import pytest
from pymodbus.client import ModbusTcpClient
from rich.console import Console

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions
from softplc_lite.watch.snapshot import render
from softplc_lite.watch.serversview import TABLE_WIDTH, ServersView
from softplc_lite.watch.session import WatchOptions, WatchSession

from helpers.modbtcps_apps import LIMIT_S, Running, server_xml, write_app
from helpers.modbus_peer import free_tcp_port

pytestmark = pytest.mark.timeout(120)

ROOT_PROGRAMS = Path(__file__).resolve().parent.parent / "programs"
NOT_SERVED = 999  # no holding register there in UNIT_1: exception 02


@pytest.fixture
def clients():
    opened: list[ModbusTcpClient] = []

    def connect(port: int) -> ModbusTcpClient:
        c = ModbusTcpClient("127.0.0.1", port=port, timeout=LIMIT_S, retries=0)
        opened.append(c)
        assert c.connect()
        return c

    yield connect
    for c in opened:
        c.close()


def shown(engine, width: int) -> str:
    console = Console(width=width, record=True, file=io.StringIO(), color_system=None)
    console.print(ServersView(engine))
    return console.export_text()


def styled(engine, width: int) -> str:
    console = Console(width=width, record=True, file=io.StringIO(), color_system="truecolor", force_terminal=True)
    console.print(ServersView(engine))
    return console.export_text(styles=True)


def lines_with(text: str, word: str) -> list[str]:
    return [line for line in text.splitlines() if word in line]


def test_a_connected_client_and_its_refused_request_in_both_forms(tcp_apps, clients):
    plc = tcp_apps.start()
    client = clients(plc.port)
    assert client.read_holding_registers(NOT_SERVED, count=1, device_id=1).isError()
    plc.wait_for(lambda: plc.module.server_status().refusals == 1 and plc.module.server_status().clients == 1,
                 "one client and one refusal")

    table = shown(plc.engine, 100)  # one row, a column per count
    assert table.splitlines()[0].strip() == "servers"
    (heading,) = lines_with(table, "clients")
    assert heading.split() == ["server", "┃", "clients", "┃", "req/s", "┃", "requests", "┃", "writes", "┃",
                               "refusals"]
    (row,) = lines_with(table, "MODBTCPS")
    cells = [c.strip() for c in row.split("│")]
    assert cells[0] == f"MODBTCPS 127.0.0.1:{plc.port} up"
    assert cells[1] == "1"  # clients
    assert cells[3] == "0"  # requests answered normally: none, the one read was refused
    assert cells[4] == "0"  # writes
    assert cells[5] == "1 (exception 02 1)"

    narrow = shown(plc.engine, 46)  # the side panel of a wide terminal
    assert [line.rstrip() for line in narrow.splitlines()] == ["servers",
                                                              f"MODBTCPS 127.0.0.1:{plc.port} up",
                                                              "  clients 1  req/s 0  requests 0  writes 0",
                                                              "  refusals 1 (exception 02 1)"]


def test_requests_writes_rate_and_refusals_by_kind_add_up(tcp_apps, clients):
    plc = tcp_apps.start()
    client = clients(plc.port)
    assert not client.write_register(0, 7, device_id=1).isError()  # answered once the scan applied it
    assert client.read_holding_registers(NOT_SERVED, count=1, device_id=1).isError()  # exception 02
    assert client.diag_read_bus_message_count(device_id=1).isError()  # a function not served: exception 01
    assert client.read_holding_registers(0, count=1, device_id=7).isError()  # no unit 7: exception 0B
    deadline = time.monotonic() + LIMIT_S
    while plc.module.rate == 0:  # requests for a whole second at least, the rate's window
        assert time.monotonic() < deadline, "no request rate after reading for the time limit"
        assert not client.read_holding_registers(0, count=2, device_id=1).isError()
        time.sleep(0.02)
    status = plc.module.server_status()
    assert status.writes == 1 and status.requests >= 2
    row = [c.strip() for c in lines_with(shown(plc.engine, 120), "MODBTCPS")[0].split("│")]
    rate = int(row[2])
    assert 1 <= rate <= 100  # one request each 20 ms and more (a round trip): at most 50 a second
    assert int(row[3]) >= status.requests and row[4] == "1"
    assert row[5] == "3 (exception 01 1, exception 02 1, exception 0B 1)"


def test_req_per_s_is_measured_without_a_status_block_too(tcp_apps, clients):
    xml = server_xml().replace(' status="N40:0"', "")
    assert "status=" not in xml
    plc = tcp_apps.start(xml)
    client = clients(plc.port)
    deadline = time.monotonic() + 3.0  # three of the rate's one-second windows
    while time.monotonic() < deadline and plc.module.server_status().rate == 0:
        assert not client.read_holding_registers(0, count=2, device_id=1).isError()
        time.sleep(0.02)
    status = plc.module.server_status()
    assert status.requests > 0 and status.rate > 0, status


def test_a_client_outside_the_allow_list_is_a_refusal_not_a_client(tcp_apps):
    plc = tcp_apps.start(server_xml(units='<Allow network="10.0.0.0/8"/>\n<Unit id="1">\n'
                                      '<HoldingRegisters start="0" count="10" address="N7:0"/>\n</Unit>\n'))
    with socket.create_connection(("127.0.0.1", plc.port), timeout=LIMIT_S) as s:
        assert s.recv(1) == b""  # closed at once
    plc.wait_for(lambda: plc.module.server_status().refusals == 1, "the network refusal")
    text = shown(plc.engine, 46)
    assert "  clients 0  req/s 0  requests 0  writes 0" in text
    assert "  refusals 1 (not allowed 1)" in text


def test_a_server_that_died_is_down_in_red_with_why(tcp_apps):
    plc = tcp_apps.start()
    plc.module.process.kill()
    plc.wait_for(lambda: not plc.module.server_status().up, "the module to see its server gone")
    assert lines_with(shown(plc.engine, 46), "MODBTCPS") == ["MODBTCPS down the server process ended"]
    (row,) = lines_with(shown(plc.engine, 100), "MODBTCPS")
    assert row.split("│")[0].strip() == "MODBTCPS down the server process ended"
    for width in (46, 100):
        assert "\x1b[1;31mdown\x1b[0m\x1b[31m the server process ended" in styled(plc.engine, width)  # red


def test_the_panel_is_in_the_watch_screen_only_for_apps_with_a_server(tmp_path):
    app_dir = write_app(tmp_path / "hmi", server_xml())
    s = WatchSession(load_app(app_dir, state_dir=None), WatchOptions(run=RunOptions(fresh=True)))
    try:
        s.scan()
        assert ServersView(s.engine)
        wide = render(s, 130, 30).export_text()  # the side panel: the lines under the rungs' right
        assert "servers" in wide and "clients 0  req/s 0" in wide
        narrow = render(s, 100, 30).export_text()  # below the rungs: the table
        assert len(lines_with(narrow, "requests")) == 1 and "MODBTCPS 127.0.0.1:" in narrow
    finally:
        s.quit()
    plain = WatchSession(load_app(ROOT_PROGRAMS / "blinker", tmp_path / "state"), WatchOptions(run=RunOptions(fresh=True)))
    try:
        assert not ServersView(plain.engine)
        assert "servers" not in render(plain, 100, 30).export_text()
    finally:
        plain.quit()


def test_the_table_form_starts_where_its_columns_fit(tcp_apps):
    plc = tcp_apps.start()
    table = shown(plc.engine, TABLE_WIDTH).splitlines()
    assert [line.split() for line in table if "┃" in line] == [
        ["server", "┃", "clients", "┃", "req/s", "┃", "requests", "┃", "writes", "┃", "refusals"]]
    assert all(len(line.rstrip()) <= TABLE_WIDTH for line in table)
    (row,) = [k for k, line in enumerate(table) if "MODBTCPS" in line]  # the address wraps in its cell
    assert [table[k].split("│")[0].strip() for k in (row, row + 1)] == ["MODBTCPS", f"127.0.0.1:{plc.port} up"]
    narrow = shown(plc.engine, TABLE_WIDTH - 1)
    assert "┃" not in narrow and f"MODBTCPS 127.0.0.1:{plc.port} up" in narrow.splitlines()


def docs_examples() -> list[str]:
    """The ```text blocks of docs/watch.md's "Network servers" section."""
    doc = (ROOT_PROGRAMS.parent / "docs" / "watch.md").read_text(encoding="utf-8")
    section = doc.split("## Network servers\n", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```text\n(.*?)```", section, re.DOTALL)


def words(text: str, port: int) -> list[list[str]]:
    """Each line's words, the port as the docs give it, a rule of any length one ━."""
    return [re.sub("━+", "━", line).split() for line in text.replace(f":{port} ", ":5020 ").splitlines()]


def test_the_docs_example_is_what_the_hmi_server_shows(tmp_path, clients):
    app_dir = tmp_path / "hmi_server"
    shutil.copytree(ROOT_PROGRAMS / "hmi_server", app_dir)
    port = free_tcp_port()
    xml = app_dir / "MODBTCPS.XML"
    assert 'port="5020"' in xml.read_text()
    xml.write_text(xml.read_text().replace('port="5020"', f'port="{port}"'))
    plc = Running(app_dir)
    try:
        client = clients(port)
        assert not client.write_register(0, 900, device_id=1).isError()  # the setpoint
        assert not client.read_input_registers(0, count=2, device_id=1).isError()  # the level
        assert client.read_holding_registers(50, count=1, device_id=1).isError()  # not in the map
        time.sleep(2.2)  # a whole second without requests has been measured: req/s 0
        table, side = docs_examples()
        assert words(shown(plc.engine, 80), port) == words(table, 5020)
        assert words(shown(plc.engine, 46), port) == words(side, 5020)
    finally:
        plc.stop()


def test_softplc_watch_shows_the_server_in_a_real_terminal(tmux, tmp_path, clients):
    xml = server_xml()
    app_dir = write_app(tmp_path / "hmi", xml)
    port = int(xml.split('port="')[1].split('"')[0])
    tmux.start(f"{sys.executable} -m softplc_lite watch {app_dir} --fresh --state {tmp_path / 'state'}",
               width=100, height=30)
    screen = tmux.wait_for("servers", seconds=LIMIT_S)
    assert "not started" in screen and " up" not in screen
    tmux.keys("n")  # the first scan starts the server
    tmux.wait_for(f"MODBTCPS 127.0.0.1:{port} up", seconds=LIMIT_S)
    client = clients(port)
    assert client.read_holding_registers(NOT_SERVED, count=1, device_id=1).isError()
    tmux.keys("n")  # a scan: the view is redrawn (the counts come from the server, not the scan)
    screen = tmux.wait_for("1 (exception 02 1)", seconds=LIMIT_S)
    (row,) = [line for line in screen.splitlines() if "MODBTCPS" in line]
    assert row.split("│")[1].strip() == "1"  # one client connected
    client.close()
    tmux.keys("q")
    assert tmux.wait_gone(), "q did not end softplc watch"


def test_both_servers_of_an_app_each_in_its_row(tmp_path):
    """An app with MODBTCPS and ENIPS: each server its own row, ENIPS's
    refusals by EtherNet/IP's kinds."""
    from pylogix import PLC

    from helpers.apps import make_app
    from helpers.enips_apps import enips_xml

    app = make_app(tmp_path / "both", "ADD N11:0 1 N11:0\nMOV N7:19 N7:18\n", MODULES_LST="MODBTCPS\nENIPS\n",
                   MODBTCPS_XML=server_xml(), ENIPS_XML=enips_xml(""))
    plc = Running(app, module="ENIPS")
    try:
        modbus_server = next(m for m in plc.engine.modules if m.name == "MODBTCPS")
        assert modbus_server.wait_until_listening(LIMIT_S)
        with PLC("127.0.0.1") as comm:
            comm.Port = plc.port
            assert comm.Write("N11[0]", 5).Status == "Privilege violation"
            plc.wait_for(lambda: plc.module.server_status().refusals == 1 and plc.module.server_status().clients,
                         "the refusal and the client")
            plc.wait_for(lambda: "starting" not in shown(plc.engine, 110), "both servers' READY read by the scan")
            table = shown(plc.engine, 110)
        (modbus,) = lines_with(table, "MODBTCPS")
        (enip,) = lines_with(table, "ENIPS")
        assert f"ENIPS 127.0.0.1:{plc.port} up" in enip and "1 (read-only 1)" in enip
        assert [c.strip() for c in enip.split("│")][1] == "1"  # pylogix's connection
        assert "up" in modbus and "refusals" not in modbus
    finally:
        plc.stop()
