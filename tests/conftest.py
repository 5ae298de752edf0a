"""Shared test helpers: random data tables built from raw contents, and
sim:// ports on a hand-moved clock."""

from __future__ import annotations

import gc
import math
from array import array

import pytest
import serial
from hypothesis import strategies as st

from softplc_lite.datatable import DataTable
from softplc_lite.datatable.filetypes import FILE_TYPES

from helpers.clocks import Clock
from helpers.isolation import bytecode_setup, hypothesis_setup, signals_setup, pytest_sessionfinish, pytest_sessionstart, pytest_terminal_summary  # noqa: F401
from helpers.tmux_helpers import tmux  # noqa: F401  (the fixture of the terminal tests)
from helpers.opcua_apps import register as register_opcuas

bytecode_setup()  # one bytecode cache for the run, outside the repository (tests/helpers/isolation.py)
hypothesis_setup()  # nothing of hypothesis's in the repository, no deadline (tests/helpers/isolation.py)
register_opcuas()  # OPCUAS's entry point where the installed metadata predates it (tests/helpers/opcua_apps.py)
signals_setup()  # Ctrl-C heard by the processes tests start, however the run was started (tests/helpers/isolation.py)


def pytest_collection_finish(session):
    # The collected tests and the modules they import live for the whole
    # run: moved out of the collector's reach, each full collection after
    # this scans only what the tests themselves make. Without it the
    # collector took about a tenth of a worker's time.
    gc.collect()
    gc.freeze()


@st.composite
def random_tables(draw, max_elements: int = 12) -> DataTable:
    """A table whose files hold arbitrary raw contents: any word pattern
    (unnamed control bits, ST LEN above 82, characters past LEN) and any
    non-NaN float32."""
    table = DataTable()
    numbers = draw(st.lists(st.integers(9, 60), unique=True, max_size=5))
    for n in numbers:
        table.create_file(draw(st.sampled_from(["B", "N", "T", "C", "R", "F", "ST"])), n, 0)
    for f in table.files():
        size = draw(st.integers(0 if f.number > 8 else f.size, max(f.size, max_elements)))
        f.grow(size)
        nbytes = len(f.data) * f.data.itemsize
        # Raw bytes are far cheaper to draw than thousands of integers.
        fresh = array(f.data.typecode, draw(st.binary(min_size=nbytes, max_size=nbytes)))
        if not f.is_words:
            # NaN payloads are not kept by JSON (documented); use plain values.
            fresh = array("f", [0.0 if math.isnan(x) else x for x in fresh])
        f.data[:] = fresh
    return table


FILE_LETTERS = list(FILE_TYPES)


@pytest.fixture
def clock() -> Clock:
    return Clock()


@pytest.fixture
def opened():
    """Opens sim:// (and replay://) ports, on ``clock`` when one is given,
    and closes them after the test."""
    import softplc_lite.ports.urlhandler  # noqa: F401  (registers the schemes)

    ports = []

    def open_(url: str, clock: Clock | None = None, **settings) -> serial.SerialBase:
        port = serial.serial_for_url(url, **settings)
        ports.append(port)
        if clock is not None:
            port.set_clock(clock)
        return port

    yield open_
    for port in ports:
        port.close()


@pytest.fixture(params=("compiled", "reference"))
def engine(request):
    """engine(text, values=None) -> an Engine in RUN that has not scanned
    yet, on each executor in turn (the bound instruction groups' tests)."""
    from softplc_lite.ladder import Engine, Mode, load_text

    def make(text: str, values: dict | None = None) -> Engine:
        table = DataTable()
        for address in values or {}:
            table.reference(address)
        e = Engine(load_text(text), table=table, executor=request.param)
        for address, value in (values or {}).items():
            e.table.write(address, value)
        e.set_mode(Mode.RUN)
        return e
    return make


@pytest.fixture(params=("compiled", "reference"))
def run(request):
    """run(text, scans=1, values=None, **kw) -> Engine, on one executor
    (the instruction tests). Every address in ``values`` is created first,
    so tests may preset words the program itself does not name."""
    from softplc_lite.ladder import run_text

    def _run(text: str, scans: int = 1, values: dict | None = None, **kw):
        table = kw.pop("table", None) or DataTable()
        for addr in values or {}:
            table.reference(addr)
        return run_text(text, scans=scans, executor=request.param, table=table, values=values, **kw)

    return _run


@pytest.fixture
def tcp_apps(tmp_path):
    """MODBTCPS apps started by the test (tests/helpers/modbtcps_apps.py), each
    stopped after it with its server process."""
    from helpers.modbtcps_apps import Apps

    apps = Apps(tmp_path)
    yield apps
    apps.close()


@pytest.fixture
def enips_apps(tmp_path):
    """ENIPS apps started by the test (tests/helpers/enips_apps.py), each
    stopped after it with its server process."""
    from helpers.enips_apps import EnipApps

    apps = EnipApps(tmp_path)
    yield apps
    apps.close()


@pytest.fixture
def tcp_plc(tcp_apps):
    """A MODBTCPS runtime of tests/helpers/modbtcps_apps.UNIT_1 on a free port."""
    return tcp_apps.start()


@pytest.fixture
def tcp_client(tcp_plc):
    """pymodbus's real client, connected to ``tcp_plc``."""
    from helpers.modbtcps_apps import LIMIT_S
    from pymodbus.client import ModbusTcpClient

    c = ModbusTcpClient("127.0.0.1", port=tcp_plc.port, timeout=LIMIT_S, retries=0)
    assert c.connect()
    yield c
    c.close()
