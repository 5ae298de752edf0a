"""Simulated devices attached by the testing API (testing/devices.py,
PLC.load(devices=...), plc.device()), on the shipped apps (only read) with
real sim:// ports; the network server of a test on a port the system picks."""

import pytest
from pymodbus.client import ModbusTcpClient

from softplc_lite.ports.modbus_master import ModbusMaster, parse_requests
from softplc_lite.ports.modbus_slave import ModbusSlave
from softplc_lite.ports.scripted import ScriptedLine
from softplc_lite.ports import simlink
from softplc_lite.testing.devices import DeviceError
from softplc_lite.testing.plc import PLC

from helpers.apps import make_app
from helpers.shipped_apps import PROGRAMS, SHIPPED_PORT


def test_two_plcs_of_one_app_each_poll_their_own_master():
    with PLC.load(PROGRAMS / "modbus_slave", devices={0: ModbusMaster(1, period_ms=10)}) as fast, \
            PLC.load(PROGRAMS / "modbus_slave", devices={0: "sim://any?device=modbus_master&id=1"}) as shipped:
        fast.run(1)
        shipped.run(0.5)
        a, b = fast.device(0), shipped.device(0)
        assert a is not b and a.period_ns == 10_000_000 and b.period_ns == 20_000_000
        assert (a.bad, b.bad, a.timeouts, b.timeouts) == (0, 0, 0, 0)
        assert a.sent > 2 * b.sent > 0
        assert fast["Served.ACC"] - a.replies in (0, 1)  # a reply may be on the wire
        names = simlink.link_names()
        assert len([n for n in names if n.startswith("plc")]) == 2, names
    assert not [n for n in simlink.link_names() if n.startswith("plc")]


def test_the_apps_own_device_is_found_too():
    with PLC.load(PROGRAMS / "modbus_scada") as plc:
        plc.run(0.3)
        slaves = plc.device("MODBMAST:1")
        assert isinstance(slaves, ModbusSlave) and plc.device(1) is slaves
        assert slaves.unit(2).holding_registers[100] == plc["N11:20"] == 1500


def test_a_slave_object_with_a_fault_makes_the_master_count_timeouts():
    slave = ModbusSlave(2, registers=200)
    with PLC.load(PROGRAMS / "modbus_master", devices={0: slave}) as plc:
        plc.run(0.3)
        assert plc.device(0) is slave and plc["GoodReplies.ACC"] >= 2 and plc["Timeouts.ACC"] == 0
        slave.fault.silent = True
        plc.run(1)
        assert plc["Timeouts.ACC"] >= 2


def test_a_scripted_line_answers_the_loopback_app():
    line = ScriptedLine([(b"modules.\r\n", b"Rack no: 7 has 3 modules.\r\n")], delay_ms=5)
    with PLC.load(PROGRAMS / "loopback", devices={0: line}) as plc:
        plc.run(0.5)
        assert line.replies == plc["C5:0.ACC"] > 3
        assert (plc["GotRack"], plc["GotModules"]) == (7, 3)
        request, reply = line.log[0]
        assert request == b"Rack no:   5 has  2 modules.\r\n"


@pytest.mark.parametrize("devices, message", [
    ({5: ModbusMaster()}, "device on port 5: the app has no port 5 (its ports: COMGENIUS:0)"),
    ({"MODBMAST:0": ModbusMaster()}, "device on port MODBMAST:0: the app has no port MODBMAST:0"),
    ({"zero": ModbusMaster()}, "device on port zero: expected a port number or MODULE:N, not 'zero'"),
    ({0: "sim://x?device=nosuch"}, "device on port 0: unknown device kind 'nosuch'"),
    ({0: "sim://x?device=echo&speed=1"}, "device on port 0: echo device: unknown option 'speed' (known: delay_ms)"),
    ({0: "sim://x"}, "expected sim://NAME?device=KIND&... (a device, not a port-to-port link)"),
    ({0: "loop://"}, "expected a simulated device or sim://NAME?device=KIND&..."),
    ({0: 3}, "expected a simulated device (ModbusMaster, ModbusSlave, ScriptedLine, ...)"),
])
def test_each_mistake_is_a_device_error_naming_the_port(devices, message):
    with pytest.raises(DeviceError) as e:
        PLC.load(PROGRAMS / "loopback", devices=devices)
    assert message in str(e.value)


def test_every_problem_at_once_and_a_port_without_a_device():
    with pytest.raises(DeviceError) as e:
        PLC.load(PROGRAMS / "loopback", devices={1: ModbusMaster(), 0: "sim://x?device=nosuch"})
    assert [key for key, _ in e.value.problems] == [1, 0]
    with PLC.load(PROGRAMS / "loopback") as plc, pytest.raises(DeviceError, match="no simulated device on it .loop://."):
        plc.device(0)


def test_the_network_server_listens_on_a_port_the_system_picks():
    with PLC.load(PROGRAMS / "hmi_server") as plc:
        assert plc.server_port() is None  # the first scan starts it
        plc["StartCmd"] = 1
        plc.scan(3)
        port = plc.server_port("MODBTCPS")
        assert port and port != SHIPPED_PORT
        client = ModbusTcpClient("127.0.0.1", port=port)
        try:
            assert client.connect()
            level = client.read_input_registers(0, count=2, device_id=1)
            assert level.registers == [plc["Level"], plc["Starts"]] == [3, 1]
        finally:
            client.close()


def test_a_master_with_its_own_requests_and_their_exception_codes():
    master = ModbusMaster(1, period_ms=20, requests=parse_requests("03 0000 0001, 06 03E8 0001,08 0000 0000"))
    with PLC.load(PROGRAMS / "modbus_slave", devices={0: master}) as plc:
        plc.run(0.2)
    assert (master.replies, master.exceptions, master.bad, master.timeouts) == (3, 6, 0, 0)
    assert master.last_exception == 1
    assert [request.hex(" ")[:8] for request, _ in list(master.log)[:3]] == ["01 03 00", "01 06 03", "01 08 00"]
    with pytest.raises(ValueError, match="requests must be hex PDUs separated by commas .* not '03 0x'"):
        parse_requests("03 0000,03 0x")
    with pytest.raises(DeviceError, match="requests must be hex PDUs separated by commas .* not ''"):
        PLC.load(PROGRAMS / "modbus_slave", devices={0: "sim://m?device=modbus_master&requests=03,"})


LINKED = """XIO T4:0/DN TON T4:0 0.01 5 0
XIC T4:0/DN COMPRINT R6:0 0 1 N7:0 N7:1
XIC T4:0/DN CTU C5:0 32767 0
"""


def test_an_apps_own_link_between_its_ports_is_the_plcs_own(tmp_path):
    """Port 0 and port 1 are the two ends of sim://line: two PLCs of the app
    at once each get a link of their own (a third end would be refused)."""
    app = make_app(tmp_path / "linked", LINKED, MODULES_LST="COMGENIUS\n", COMGENIUS_LST=(
        "[PORTS]\n0, sim://line, ISO-8859-1, 38400, 8, N, 1, 100\n1, sim://line, ISO-8859-1, 38400, 8, N, 1, 100\n"
        '[STRINGS]\n1 "%d %d\\r\\n"\n'))
    with PLC.load(app) as one, PLC.load(app) as two:
        one.run(0.5)
        two.run(0.5)
        names = [n for n in simlink.link_names() if n.endswith("-line")]
        assert len(names) == 2 and "line" not in simlink.link_names()
        for plc in (one, two):
            port0, port1 = plc.engine.modules[0].serial_ports()
            assert port0.up and port1.up and port0.serial.sim_link is port1.serial.sim_link
            assert port1.rx_bytes == port0.tx_bytes == plc["C5:0.ACC"] * len(b"0 0\r\n") > 0
    with pytest.raises(DeviceError, match="COMGENIUS:0 is given a device and a ports= override"):
        PLC.load(app, ports=("0=loop://",), devices={0: ModbusMaster()})
    with PLC.load(app, ports=("1=loop://",)) as plc:  # port 0 alone on its renamed link, port 1 as given
        plc.scan()
        port0, port1 = plc.engine.modules[0].serial_ports()
        assert port1.url == "loop://" and port0.url.startswith("sim://plc") and port0.url.endswith("-line")
