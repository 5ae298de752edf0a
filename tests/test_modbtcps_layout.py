"""MODBTCPS's one conversion between data table words and Modbus registers
(layout.py), without a server: what a client writes into any run of
registers or bits reads back the same, and changes nothing else, in every
kind of region."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from softplc_lite.datatable import DataTable
from softplc_lite.tlm.modbtcps.config import config_references, parse_config
from softplc_lite.tlm.modbtcps.layout import Layout

XML = b"""<ModbusTcpServer><Unit id="1">
  <Coils            start="0"   count="40" address="N7:0/5" writable="yes"/>
  <HoldingRegisters start="0"   count="10" address="N10:0"  writable="yes"/>
  <HoldingRegisters start="10"  count="3"  address="F8:0"   writable="yes"/>
  <HoldingRegisters start="16"  count="2"  address="F8:5"   writable="yes" wordOrder="low-high"/>
  <HoldingRegisters start="20"  count="2"  address="ST9:0"  writable="yes"/>
  <HoldingRegisters start="200" count="2"  address="ST9:4"  writable="yes" stringFormat="packed"/>
</Unit></ModbusTcpServer>"""

CONFIG = parse_config(XML)


def fresh() -> tuple[DataTable, Layout]:
    table = DataTable()
    for address in config_references(CONFIG):
        table.reference(address)
    return table, Layout.build(CONFIG, table)


def read(layout: Layout, table: DataTable, kind: str, address: int, count: int) -> list[int]:
    """What the server would answer from an image made of the table now."""
    return Layout.load(layout.find(1, kind, address, count), table)


def words(table: DataTable) -> dict[str, bytes]:
    return {f.name: f.data.tobytes() for f in table.files()}


REGIONS = [("coils", 0, 40, 1), ("holding_registers", 0, 10, 0xFFFF), ("holding_registers", 10, 6, 0xFFFF),
           ("holding_registers", 16, 4, 0xFFFF), ("holding_registers", 20, 166, 0xFFFF)]


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(REGIONS), st.data())
def test_what_is_written_reads_back_and_nothing_else_changes(region, data):
    kind, start, span, top = region
    table, layout = fresh()
    before = read(layout, table, kind, start, span)
    off = data.draw(st.integers(0, span - 1))
    n = data.draw(st.integers(1, span - off))
    values = data.draw(st.lists(st.integers(0, top), min_size=n, max_size=n))
    if kind == "holding_registers" and start == 20:  # a UCS-2 string's LEN registers take 0..82
        values = [v % 83 if (off + j) % 83 == 0 else v for j, v in enumerate(values)]
    other = words(table)
    Layout.store(layout.find(1, kind, start + off, n), values, table)
    after = read(layout, table, kind, start, span)
    assert after[off:off + n] == values
    assert after[:off] == before[:off] and after[off + n:] == before[off + n:]
    changed = {name for name, raw in words(table).items() if raw != other[name]}
    assert changed <= {"N7", "N10", "F8", "ST9"}


def test_coils_start_inside_a_word_and_run_on():
    table, layout = fresh()
    Layout.store(layout.find(1, "coils", 10, 3), [1, 1, 1], table)  # N7:0/15, N7:1/0, N7:1/1
    assert table.read("N7:0") == -32768 and table.read("N7:1") == 3


def test_floats_in_both_word_orders():
    table, layout = fresh()
    table.write("F8:0", 1.0)  # 0x3F800000
    table.write("F8:5", 1.0)
    assert read(layout, table, "holding_registers", 10, 2) == [0x3F80, 0]
    assert read(layout, table, "holding_registers", 16, 2) == [0, 0x3F80]


def test_packed_strings_round_trip_text_and_stop_at_nul():
    table, layout = fresh()
    table.write("ST9:4", "Level high")
    regs = read(layout, table, "holding_registers", 200, 41)
    assert regs[:5] == [0x4C65, 0x7665, 0x6C20, 0x6869, 0x6768] and regs[5:] == [0] * 36
    Layout.store(layout.find(1, "holding_registers", 241, 2), [0x4F4B, 0x0058], table)  # "OK", NUL, "X"
    assert table.read("ST9:5") == "OK"
    Layout.store(layout.find(1, "holding_registers", 200, 1), [0x4869], table)  # "Hi" over "Le"
    assert table.read("ST9:4") == "Hivel high"
