"""MODBTCPS refusals: a request answered with an exception changes nothing
and is counted, whoever would have refused it; the server starts only when
the engine scans; the shared memory a killed runtime leaves in /dev/shm is
removed; pymodbus is touched from one module only (docs/modbtcps.md).

Real runtimes (in a thread of this process, or `softplc run` processes),
real sockets, pymodbus's real client; every port a free one."""

from __future__ import annotations

import ast
import io
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest
from pymodbus.client import ModbusTcpClient
from rich.console import Console

from softplc_lite.app import load_app
from softplc_lite.ladder.engine import Engine
from softplc_lite.ladder.host import Mode
from softplc_lite.runner import RunOptions
from softplc_lite.tlm.modbtcps.protocol import SEGMENTS as shm
from softplc_lite.tlm.modbtcps import status as S
from softplc_lite.watch.snapshot import render
from softplc_lite.watch.serversview import ServersView
from softplc_lite.watch.session import WatchOptions, WatchSession

from helpers.cli import softplc
from helpers.modbtcps_apps import LIMIT_S, raw_request, server_xml, write_app
from helpers.modbus_peer import free_tcp_port, wait_for_tcp

pytestmark = pytest.mark.timeout(180)

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "softplc_lite" / "tlm" / "modbtcps"
# tests/helpers/modbtcps_apps.UNIT_1: coils 0..39 B3 (writable), holding 0..19 N7:0.. (writable), 50..54 N7:50..
# (read-only), 100..103 F8:0..1, 200..365 ST9:0..1 (ucs2, LEN at 200 and 283), 400..481 packed ST9:2..3


@pytest.fixture
def plc(tcp_plc):
    return tcp_plc


@pytest.fixture
def client(tcp_client):
    return tcp_client


def mapped(plc) -> dict:
    """Every word a client may write, and the float and string elements."""
    t = plc.engine.table
    return {"B3": [t.read(f"B3:{k}") for k in range(3)], "N7": [t.read(f"N7:{k}") for k in range(20)],
            "F8": [t.read(f"F8:{k}") for k in range(4)], "ST9": [t.read(f"ST9:{k}") for k in range(4)],
            "ST9.LEN": [t.read(f"ST9:{k}.LEN") for k in range(4)]}


def then_a_write_lands(plc, client) -> None:
    """A write answered once applied: whatever came before it has reached the scan, or never will
    (N7:19 is put back as it was)."""
    was = plc.read("N7:19")
    assert not client.write_register(19, 4321, device_id=1).isError()
    assert plc.read("N7:19") == 4321
    plc.engine.table.write("N7:19", was)


def wait_counted(plc, word: int, value: int) -> None:
    plc.wait_for(lambda: plc.status(word) == value, f"status word {word} = {value} (it is {plc.status(word)})")


def shown(engine, width: int = 100) -> str:
    console = Console(width=width, record=True, file=io.StringIO(), color_system=None)
    console.print(ServersView(engine))
    return console.export_text()


# -- 1. Write Single Coil: 0xFF00 or 0x0000, nothing else (Modbus spec 6.5) ----------------------


@pytest.mark.parametrize("value", [0x1234, 0x0001, 0x00FF, 0xFFFF, 0xFF01, 0x8000])
def test_write_single_coil_with_another_value_is_exception_03_and_changes_nothing(plc, client, value):
    before = mapped(plc)
    assert raw_request(plc.port, struct.pack(">BHH", 5, 0, value)) == bytes([0x85, 3])
    then_a_write_lands(plc, client)
    assert mapped(plc) == before and plc.read("B3/0") == 0
    wait_counted(plc, S.W_EXCEPTION_03, 1)
    wait_counted(plc, S.W_WRITES_APPLIED, 1)  # the landing write only


def test_write_single_coil_on_and_off_still_work(plc):
    assert raw_request(plc.port, struct.pack(">BHH", 5, 3, 0xFF00)) == struct.pack(">BHH", 5, 3, 0xFF00)
    assert plc.read("B3/3") == 1
    assert raw_request(plc.port, struct.pack(">BHH", 5, 3, 0x0000)) == struct.pack(">BHH", 5, 3, 0x0000)
    assert plc.read("B3/3") == 0


# -- 2. Read/Write Multiple Registers: the read part checked before the write -------------------


def test_read_write_multiple_whose_read_part_is_outside_the_map_is_02_and_writes_nothing(plc, client):
    before = mapped(plc)
    for read_address, read_count in ((1000, 1), (18, 5), (50, 6), (65535, 1)):
        r = client.readwrite_registers(read_address=read_address, read_count=read_count, write_address=0,
                                       values=[77, 78], device_id=1)
        assert r.isError() and r.exception_code == 2, (read_address, read_count, r)
    then_a_write_lands(plc, client)
    assert mapped(plc) == before and plc.read("N7:0") == 0
    wait_counted(plc, S.W_EXCEPTION_02, 4)
    wait_counted(plc, S.W_WRITES_APPLIED, 1)


def test_read_write_multiple_inside_the_map_writes_then_reads(plc, client):
    r = client.readwrite_registers(read_address=0, read_count=3, write_address=1, values=[5, 6], device_id=1)
    assert r.registers == [0, 5, 6]  # the write first, then the read (Modbus spec 6.17)


# -- 3. Mask Write Register: the LEN check of 6, 16 and 23 --------------------------------------


def test_mask_write_refuses_a_string_length_over_82_as_6_16_and_23_do(plc, client):
    plc.engine.table.write("ST9:0", "pump")
    then_a_write_lands(plc, client)
    before = mapped(plc)
    assert client.write_register(200, 65535, device_id=1).exception_code == 3
    assert client.write_registers(200, [83], device_id=1).exception_code == 3
    assert client.readwrite_registers(read_address=0, read_count=1, write_address=200, values=[65535],
                                      device_id=1).exception_code == 3
    r = client.mask_write_register(address=200, and_mask=0x0000, or_mask=0xFFFF, device_id=1)  # LEN 65535
    assert r.isError() and r.exception_code == 3, r
    r = client.mask_write_register(address=200, and_mask=0xFF7F, or_mask=0x0080, device_id=1)  # 4 | 0x80 = 132
    assert r.isError() and r.exception_code == 3, r
    then_a_write_lands(plc, client)
    assert mapped(plc) == before and plc.read("ST9:0") == "pump"
    wait_counted(plc, S.W_EXCEPTION_03, 5)
    # a result in range is applied: LEN 4 -> 2
    assert not client.mask_write_register(address=200, and_mask=0x0000, or_mask=0x0002, device_id=1).isError()
    assert plc.read("ST9:0") == "pu"
    # a character register is not a length
    assert not client.mask_write_register(address=201, and_mask=0x0000, or_mask=0xFFFF, device_id=1).isError()
    assert plc.read("ST9:0.LEN") == 2


# -- every write function: a refused request writes nothing ----------------------------------------

REFUSED_WRITES = {
    5: [(struct.pack(">BHH", 5, 0, 0x1234), 3), (struct.pack(">BHH", 5, 100, 0xFF00), 2),
        (struct.pack(">BHH", 5, 40, 0xFF00), 2), (struct.pack(">BHHB", 5, 0, 0xFF00, 0), 3)],
    6: [(struct.pack(">BHH", 6, 50, 9), 2), (struct.pack(">BHH", 6, 200, 83), 3), (struct.pack(">BHH", 6, 1000, 9), 2),
        (struct.pack(">BH", 6, 0), 3)],
    15: [(struct.pack(">BHHB", 15, 0, 8, 2) + b"\xff\xff", 3),  # byte count 2 for 8 coils
         (struct.pack(">BHHB", 15, 0, 16, 2) + b"\xff", 3),  # one byte short of its byte count
         (struct.pack(">BHHB", 15, 0, 0, 0), 3), (struct.pack(">BHHB", 15, 0, 1969, 247) + bytes(247), 3),
         (struct.pack(">BHHB", 15, 36, 8, 1) + b"\xff", 2),  # coils 36..43: 40.. are not mapped
         (struct.pack(">BHHB", 15, 100, 8, 1) + b"\xff", 2)],  # O:0 coils: read-only
    16: [(struct.pack(">BHHB", 16, 0, 2, 2) + b"\x00\x09\x00\x09", 3), (struct.pack(">BHHB", 16, 0, 2, 4) + b"\x00\x09", 3),
         (struct.pack(">BHHB", 16, 0, 124, 248) + bytes(248)[:240], 3),
         (struct.pack(">BHHB", 16, 18, 3, 6) + b"\x00\x09" * 3, 2), (struct.pack(">BHHB", 16, 199, 2, 4) + b"\x00\x09" * 2, 2),
         (struct.pack(">BHHB", 16, 200, 1, 2) + b"\xff\xff", 3)],
    22: [(struct.pack(">BHHH", 22, 50, 0, 0xFFFF), 2), (struct.pack(">BHHH", 22, 200, 0, 0xFFFF), 3),
         (struct.pack(">BHH", 22, 0, 0), 3)],
    23: [(struct.pack(">BHHHHB", 23, 0, 126, 0, 1, 2) + b"\x00\x09", 3),
         (struct.pack(">BHHHHB", 23, 0, 1, 0, 122, 2) + b"\x00\x09", 3),
         (struct.pack(">BHHHHB", 23, 0, 1, 0, 2, 2) + b"\x00\x09", 3),
         (struct.pack(">BHHHHB", 23, 0, 1, 0, 1, 2) + b"\x00\x09\x00", 3),
         (struct.pack(">BHHHHB", 23, 900, 1, 0, 1, 2) + b"\x00\x09", 2),
         (struct.pack(">BHHHHB", 23, 0, 1, 50, 1, 2) + b"\x00\x09", 2),
         (struct.pack(">BHHHHB", 23, 0, 1, 200, 1, 2) + b"\xff\xff", 3)],
}


@pytest.mark.parametrize("function", sorted(REFUSED_WRITES))
def test_every_write_function_answered_with_an_exception_writes_nothing(plc, client, function):
    plc.engine.table.write("ST9:0", "seal")
    writes = plc.status(S.W_WRITES_APPLIED)  # read before any write: the count of one may lag its answer
    then_a_write_lands(plc, client)
    before = mapped(plc)
    expected = {2: 0, 3: 0}
    for pdu, code in REFUSED_WRITES[function]:
        assert raw_request(plc.port, pdu) == bytes([0x80 | function, code]), pdu.hex()
        expected[code] += 1
    then_a_write_lands(plc, client)
    assert mapped(plc) == before
    wait_counted(plc, S.W_WRITES_APPLIED, writes + 2)  # the two writes that landed, none refused
    wait_counted(plc, S.W_EXCEPTION_02, expected[2])
    wait_counted(plc, S.W_EXCEPTION_03, expected[3])


# -- 4. exception 03 answers pymodbus would give are counted ------------------------------------------

ODD_BODIES = [
    struct.pack(">BHHHHB", 23, 0, 126, 0, 1, 2) + b"\x00\x01",  # read count 126
    struct.pack(">BHHHHB", 23, 0, 1, 0, 122, 2) + b"\x00\x01",  # write count 122 (decodes; pymodbus refused it later)
    struct.pack(">BHHHHB", 23, 0, 1, 0, 2, 2) + b"\x00\x01",  # byte count for 1 register, 2 said
    struct.pack(">BHHB", 15, 0, 8, 2) + b"\x01\x00",  # byte count 2 for 8 coils
    struct.pack(">BHHB", 16, 0, 2, 2) + b"\x00\x01",  # byte count 2 for 2 registers
    struct.pack(">BHHB", 16, 0, 124, 2) + b"\x00\x01",  # 124 registers
    struct.pack(">BHH", 1, 0, 2001), struct.pack(">BHH", 3, 0, 126), struct.pack(">BHH", 4, 0, 0),
    struct.pack(">BHH", 3, 0, 1) + b"\x00",  # a byte too many
]


def test_every_exception_03_is_counted_in_the_status_words_and_the_watch_view(plc):
    for k, pdu in enumerate(ODD_BODIES, 1):
        assert raw_request(plc.port, pdu) == bytes([0x80 | pdu[0], 3]), pdu.hex()
        wait_counted(plc, S.W_EXCEPTION_03, k)
        wait_counted(plc, S.W_REFUSALS, k)
    assert f"exception 03 {len(ODD_BODIES)}" in " ".join(shown(plc.engine).split())
    assert plc.status(S.W_WRITES_APPLIED) == 0


# -- fuzz: whatever the request, an exception answer means nothing was written ----------------------

EDGES = [0, 1, 18, 19, 20, 36, 39, 40, 50, 54, 99, 100, 103, 110, 199, 200, 201, 282, 283, 365, 399, 400, 481,
         1000, 65534, 65535]
VALUES = [0, 1, 82, 83, 0x7FFF, 0x8000, 0xFF00, 0xFFFF]


def random_write(rnd) -> bytes:
    """A write request near the map's edges and the functions' limits, its
    quantities, byte counts and length sometimes wrong."""
    f = rnd.choice([5, 6, 15, 16, 22, 23])
    address = rnd.choice(EDGES) if rnd.random() < 0.8 else rnd.randrange(65536)
    value = lambda: rnd.choice(VALUES) if rnd.random() < 0.7 else rnd.randrange(65536)  # noqa: E731
    if f in (5, 6):
        body = struct.pack(">HH", address, value())
    elif f == 22:
        body = struct.pack(">HHH", address, value(), value())
    elif f == 15:
        count = rnd.choice([1, 8, 9, 40, 1968, 1969, 0]) if rnd.random() < 0.7 else rnd.randrange(2100)
        byte_count = (count + 7) // 8 if rnd.random() < 0.7 else rnd.randrange(256)
        body = struct.pack(">HHB", address, count, byte_count & 0xFF) + bytes(rnd.randrange(256)
                                                                             for _ in range(min(byte_count, 240)))
    else:
        count = rnd.choice([1, 2, 83, 121, 122, 123, 124, 0]) if rnd.random() < 0.7 else rnd.randrange(130)
        byte_count = 2 * count if rnd.random() < 0.7 else rnd.randrange(256)
        data = b"".join(struct.pack(">H", value()) for _ in range(min(byte_count, 240) // 2))
        if f == 16:
            body = struct.pack(">HHB", address, count, byte_count & 0xFF) + data
        else:
            read = rnd.choice(EDGES), rnd.choice([1, 2, 20, 125, 126, 0])
            body = struct.pack(">HHHHB", *read, address, count, byte_count & 0xFF) + data
    if rnd.random() < 0.1:
        body = body[:-1] if rnd.random() < 0.5 else body + b"\0"
    return bytes([f]) + body[:252]


def test_fuzz_a_write_answered_with_an_exception_changes_nothing(tcp_apps):
    import random

    plc = tcp_apps.start(server_xml(maxRequestsPerSecond=100000))
    rnd = random.Random(27)
    with ModbusTcpClient("127.0.0.1", port=plc.port, timeout=LIMIT_S, retries=0) as client:
        refused = 0
        for _ in range(300):
            pdu = random_write(rnd)
            before = mapped(plc)
            reply = raw_request(plc.port, pdu)
            if reply[0] & 0x80:
                refused += 1
                then_a_write_lands(plc, client)
                after = mapped(plc)
                changed = [(k, i, before[k][i], after[k][i]) for k in before for i in range(len(before[k]))
                           if before[k][i] != after[k][i]]
                assert not changed, f"request {pdu.hex()} answered {reply.hex()} wrote {changed}"
        assert refused > 100  # most of them are refused: the edges are where the rules are
    wait_counted(plc, S.W_REFUSALS, refused)


# -- 7. a program only compiled or drawn starts no server ---------------------------------------------


def hmi_copy(tmp_path: Path, port: int) -> Path:
    app = tmp_path / "hmi_server"
    shutil.copytree(ROOT / "programs" / "hmi_server", app, ignore=shutil.ignore_patterns(".softplc"))
    xml = app / "MODBTCPS.XML"
    xml.write_text(xml.read_text().replace('port="5020"', f'port="{port}"'))
    return app


def server_processes() -> list[int]:
    """This process's children that are MODBTCPS server processes."""
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
                cmd = (entry / "cmdline").read_bytes()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == os.getpid() and b"modbtcps.serverproc" in cmd:
                out.append(int(entry.name))
    return out


def test_compiling_or_drawing_hmi_server_starts_no_server_even_with_its_port_taken(tmp_path):
    with socket.socket() as taken:  # a user's running PLC on the app's port
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        app = load_app(hmi_copy(tmp_path, port), state_dir=None)
        engine = Engine(app.program, modules=app.modules)  # what the code cache and the compile tests build
        try:
            (module,) = [m for m in engine.modules if m.name == "MODBTCPS"]
            assert module.process is None and not module.started and server_processes() == []
        finally:
            engine.close()
        session = WatchSession(load_app(hmi_copy(tmp_path / "w", port), state_dir=None),
                               WatchOptions(run=RunOptions(fresh=True)))
        try:
            assert "not started" in render(session, 130, 30).export_text() and server_processes() == []
            panel = " ".join(shown(session.engine, 46).split())
            assert "MODBTCPS 127.0.0.1:" in panel and "not started" in panel and "down" not in panel
        finally:
            session.quit()
        check = softplc("check", str(tmp_path / "hmi_server"))
        assert check.returncode == 0 and "ok" in check.stdout, check.stderr


def test_the_first_scan_starts_the_server_and_a_taken_port_fails_it_not_the_run(tmp_path):
    port = free_tcp_port()
    app = load_app(hmi_copy(tmp_path, port), state_dir=None)
    engine = Engine(app.program, modules=app.modules)
    try:
        (module,) = [m for m in engine.modules if m.name == "MODBTCPS"]
        engine.scan()  # simulated time: it waits until the server listens
        assert module.port == port and len(server_processes()) == 1
        wait_for_tcp(port, LIMIT_S)
    finally:
        engine.close()
    assert server_processes() == []
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        app = load_app(hmi_copy(tmp_path / "taken", taken.getsockname()[1]), state_dir=None)
        engine = Engine(app.program, modules=app.modules)
        engine.set_mode(Mode.RUN)
        try:
            for _ in range(3):
                engine.scan()
            (module,) = [m for m in engine.modules if m.name == "MODBTCPS"]
            assert "the address is in use" in module.failed and engine.fault is None and engine.scans == 3
        finally:
            engine.close()


# -- 5. /dev/shm after kill -9 ------------------------------------------------------------------------


def segments_of(pid: int) -> list[str]:
    return [n for n in os.listdir(shm.segment_directory()) if n.startswith(f"{shm.PREFIX}{pid}-")]


HOLD_A_SEGMENT = """
import sys, time
from softplc_lite.tlm.modbtcps.protocol import SEGMENTS as image
fd, path = image.create_named(4096)   # named, as a runtime's is for a moment
print(path, flush=True)
time.sleep(60)
"""


def test_a_segment_left_by_a_killed_runtime_is_removed_at_the_next_start_and_a_live_one_kept(tcp_apps):
    dead = subprocess.Popen([sys.executable, "-c", HOLD_A_SEGMENT], stdout=subprocess.PIPE, text=True)
    live = subprocess.Popen([sys.executable, "-c", HOLD_A_SEGMENT], stdout=subprocess.PIPE, text=True)
    try:
        dead_path, live_path = dead.stdout.readline().strip(), live.stdout.readline().strip()
        assert os.path.exists(dead_path) and os.path.exists(live_path)
        dead.send_signal(signal.SIGKILL)
        dead.wait(LIMIT_S)
        assert os.path.exists(dead_path)  # kill -9: nothing of it ran
        plc = tcp_apps.start()
        assert plc.port
        assert not os.path.exists(dead_path), "the next start removes the dead runtime's segment"
        assert os.path.exists(live_path), "a live process's segment is never touched"
        assert segments_of(os.getpid()) == []  # the running server's is unlinked already
    finally:
        live.kill()
        live.wait(LIMIT_S)
        if os.path.exists(live_path):
            os.unlink(live_path)


def left_behind(before: set[str], killed: list[int]) -> list[str]:
    """Segments that appeared since ``before``, of the killed runtimes or
    named after no process at all."""
    left = []
    for name in set(os.listdir(shm.segment_directory())) - before:
        if name.startswith(shm.PREFIX):
            pid = name[len(shm.PREFIX):].split("-")[0]
            if not pid.isdigit() or int(pid) in killed:
                left.append(name)
    return left


def test_kill_9_of_a_runtime_while_its_server_starts_leaves_nothing_in_dev_shm(tmp_path):
    app = write_app(tmp_path / "app", server_xml())
    before = set(os.listdir(shm.segment_directory()))
    killed = []
    for delay in (0.05, 0.15, 0.3, 0.5, 0.8, 1.2):
        p = subprocess.Popen([sys.executable, "-m", "softplc_lite", "run", str(app), "--realtime", "--fresh"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(delay)
        p.send_signal(signal.SIGKILL)
        p.wait(LIMIT_S)
        killed.append(p.pid)
    second = softplc("run", str(app), "--scans", "3", "--fresh", "--print", "N40:0")
    assert second.returncode == 0 and second.stdout.strip() == "N40:0 = 1", second.stderr
    assert left_behind(before, killed) == []


# -- 6. pymodbus from one module ------------------------------------------------------------------------


def test_only_the_glue_module_imports_pymodbus():
    importers = []
    for path in sorted(PACKAGE.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            if any(n.split(".")[0] == "pymodbus" for n in names):
                importers.append(path.name)
    assert sorted(set(importers)) == ["pymodbus_glue.py"]


LACKING = """
import pymodbus.transaction.transaction as transaction
del transaction.TransactionManager.pdu_send  # what ServerRequestHandler inherits
"""


def test_a_pymodbus_lacking_what_the_glue_needs_fails_the_server_in_one_line(tmp_path):
    (tmp_path / "site").mkdir()
    (tmp_path / "site" / "sitecustomize.py").write_text(LACKING)
    app = write_app(tmp_path / "app", server_xml())
    env = {**os.environ, "PYTHONPATH": f"{tmp_path / 'site'}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    p = softplc("run", str(app), "--scans", "3", "--fresh", "--print", "N40:0", env=env)
    assert p.returncode == 0 and p.stdout.strip() == "N40:0 = 2", p.stderr  # the failed bit; the scan went on
    assert "Traceback" not in p.stderr
    (line,) = [line for line in p.stderr.splitlines() if "lacks" in line]
    assert "ServerRequestHandler.pdu_send" in line and "pymodbus >=3.16.1,<3.17" in line
