"""The watch view's ladder drawing (watch/rungs.py) and power flow
(watch/power.py): rungs rendered into a fixed-width console without colour
and compared as text (trailing spaces dropped), power checked directly."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from rich.console import Console

from softplc_lite.app import load_app
from softplc_lite.datatable import DataTable
from softplc_lite.ladder import load_text
from softplc_lite.ladder.ast import address_refs, walk
from softplc_lite.runner import Runner, RunOptions
from softplc_lite.watch.power import rung_power
from softplc_lite.watch.rungs import ENERGIZED, FAULT, ProgramFileView, RungView

from helpers.shipped_apps import copy_app

ROOT = Path(__file__).resolve().parent.parent
PROGRAMS = ROOT / "programs"


def program_and_table(text: str, values: dict | None = None):
    """A validated program and a table holding every address it names."""
    program = load_text(text)
    table = DataTable()
    for pfile in program.files.values():
        for rung in pfile.rungs:
            for ins in walk(rung.elements):
                for op in ins.operands:
                    for ref in address_refs(op):
                        table.reference(ref.address)
    for address, value in (values or {}).items():
        table.write(address, value)
    return program, table


def render(renderable, width: int) -> str:
    console = Console(width=width, record=True, color_system=None, file=io.StringIO())
    console.print(renderable)
    return "\n".join(line.rstrip() for line in console.export_text().splitlines())


def rung_text(text: str, width: int, values: dict | None = None, **view) -> str:
    program, table = program_and_table(text, values)
    return render(RungView(program.main.rungs[0], 0, table, symbols=program.symbols, **view), width)


def lines(*rows: str) -> str:
    return "\n".join(rows)


# -- drawing ----------------------------------------------------------------------------------


def test_contacts_and_coil_with_bit_values():
    assert rung_text("XIC B3/1 XIO B3/2 OTE O:0/0\n", 40, {"B3/1": 1}) == lines(
        "   Rung 0",
        "| B3/1  B3/2                     O:0/0 |",
        "|-] [---]/[-----------------------( )--|",
        "|  1     0                         0   |",
    )


def test_nested_branch():
    text = "BST XIC B3/1 NXB BST XIC B3/2 NXB XIO B3/3 BND BND OTE B3/0\n"
    assert rung_text(text, 50, {"B3/2": 1}) == lines(
        "   Rung 0",
        "|   B3/1                                    B3/0 |",
        "|-+-] [------+------------------------------( )--|",
        "| |  0       |                               0   |",
        "| |   B3/2   |                                   |",
        "| +-+-] [--+-+                                   |",
        "|   |  1   |                                     |",
        "|   | B3/3 |                                     |",
        "|   +-]/[--+                                     |",
        "|      0                                         |",
    )


def test_timer_box_shows_live_preset_accumulator_and_status_bits():
    values = {"B3/1": 1, "T4:0": {"EN": 1, "TT": 1, "PRE": 5, "ACC": 3}}
    assert rung_text("XIC B3/1 TON T4:0 0.01 5 0\n", 50, values) == lines(
        "   Rung 0",
        "| B3/1                     +-TON---------------+ |",
        "|-] [----------------------|T4:0 base 0.01     |-|",
        "|  1                       |EN TT . PRE 5 ACC 3| |",
        "|                          +-------------------+ |",
    )


def test_mov_box_shows_operand_values():
    assert rung_text("MOV N7:0 N7:1\n", 40, {"N7:0": 42, "N7:1": 42}) == lines(
        "   Rung 0",
        "|                 +-MOV--------------+ |",
        "|-----------------|N7:0=42 -> N7:1=42|-|",
        "|                 +------------------+ |",
    )


def test_comment_symbols_and_forced_marker():
    text = "SYMBOL Start I:0/0\nSYMBOL Motor O:0/0\n// Start the motor while the button is held.\nXIC Start OTE Motor\n"
    assert rung_text(text, 44, {"I:0/0": 1}, forced={"I:0/0"}, selected=True, breakpoint=True) == lines(
        ">* Rung 0",
        "    Start the motor while the button is",
        "    held.",
        "| Start                              Motor |",
        "| I:0/0                              O:0/0 |",
        "|--] [--------------------------------( )--|",
        "|  1 F                                 0   |",
    )


def test_compare_and_compute_boxes_wrap_between_instructions():
    text = 'XIC B3/1 EQU N7:0 5 LIM 0 N7:1 10 CPT N7:2 "N7:0 * 2 + N7:1"\n'
    values = {"N7:0": 5, "N7:1": 3, "N7:2": 13}
    assert rung_text(text, 80, values) == lines(
        "   Rung 0",
        "| B3/1  +-EQU-------+  +-LIM-------------+        +-CPT----------------------+ |",
        "|-] [---|N7:0=5 == 5|--|0 <= N7:1=3 <= 10|--------|N7:0 * 2 + N7:1 -> N7:2=13|-|",
        "|  0    +-----------+  +-----------------+        |N7:0=5 N7:1=3             | |",
        "|                                                 +--------------------------+ |",
    )
    assert rung_text(text, 40, values) == lines(
        "   Rung 0",
        "| B3/1  +-EQU-------+",
        "|-] [---|N7:0=5 == 5|----------------->>",
        "|  0    +-----------+",
        "   +-LIM-------------+",
        ">>-|0 <= N7:1=3 <= 10|---------------->>",
        "   +-----------------+",
        "          +-CPT----------------------+ |",
        ">>--------|N7:0 * 2 + N7:1 -> N7:2=13|-|",
        "          |N7:0=5 N7:1=3             | |",
        "          +--------------------------+ |",
    )


def test_unresolvable_indirect_address_is_drawn_as_a_fault():
    text = "XIC N7:[N7:1]/0 MOV N7:0 N7:[N7:1] OTE B3/0\n"
    assert rung_text(text, 60, {"N7:1": 99}) == lines(
        "   Rung 0",
        "    ! N7:[N7:1]/0: element 99 (from N7:1) is past the end of",
        "    N7 (2 elements)",
        "    ! N7:[N7:1]: element 99 (from N7:1) is past the end of",
        "    N7 (2 elements)",
        "| N7:[N7:1]/0                +-MOV-----------------+  B3/0 |",
        "|-----] [--------------------|N7:0=0 -> N7:[N7:1]=?|--( )--|",
        "|      ?                     +---------------------+   0   |",
    )


def test_true_instructions_and_energized_wires_are_highlighted():
    program, table = program_and_table("XIC B3/1 XIC B3/2 OTE B3/0\n", {"B3/1": 1})
    console = Console(width=40, color_system="truecolor", force_terminal=True, file=io.StringIO())
    segments = list(console.render(RungView(program.main.rungs[0], 0, table), console.options))
    contacts = [s for s in segments if s.text == "] ["]
    assert [s.style for s in contacts] == [ENERGIZED, None]  # B3/1 true, B3/2 false
    wires = [s for s in segments if s.text.startswith("-")]
    assert wires[0].style == ENERGIZED and wires[-1].style is None  # power stops at B3/2

    program, table = program_and_table("XIC N7:[N7:1]/0 OTE B3/0\n", {"N7:1": 99})
    segments = list(console.render(RungView(program.main.rungs[0], 0, table), console.options))
    assert next(s for s in segments if s.text == "] [").style == FAULT


# -- the Modbus master -------------------------------------------------------------------------


@pytest.fixture(scope="module")
def modbus():
    """programs/modbus_master after 121 scans: the first reply has just been
    matched (R6:1 EN DN, LEN 255, POS 2)."""
    app = load_app(PROGRAMS / "modbus_master", use_cache=False)
    app.state_dir = None
    runner = Runner(app, RunOptions(fresh=True), log=lambda msg: None)
    runner.run(121)
    yield app, runner.table
    runner.engine.close()


def modbus_rung(modbus, number: int, width: int, **view) -> str:
    app, table = modbus
    rung = app.program.main.rungs[number]
    return render(RungView(rung, number, table, symbols=app.program.symbols, instructions=app.instructions,
                           **view), width)


def test_comprint_rung_shows_control_bits_and_symbols(modbus):
    assert modbus_rung(modbus, 1, 80, forced={"B3/0"}) == lines(
        "   Rung 1",
        "    Rung 1. Poll: when the timer is done, send the query of example 2 (slave 2,",
        "    function 3, Start and Count big endian, CRC-16 preloaded 0xFFFF) and mark",
        "    the transaction Busy. COMPRINT starts on this rung's false-to-true",
        "    transition, so it sends once per poll; R6:0 DN means the query is queued.",
        "| PollTimer/DN  Busy                                                           |",
        "|   T4:0/DN     B3/0                         +-COMPRINT--------------------+   |",
        "|-----] [-------]/[------------------------+-|Query(R6:0) port 0 format 2  |-+-|",
        "|      0        0 F                        | |Start(N7:0)=0 Count(N7:1)=125| | |",
        "|                                          | |. . . . LEN 8 POS 0          | | |",
        "|                                          | +-----------------------------+ | |",
        "|                                          | Busy                            | |",
        "|                                          | B3/0                            | |",
        "|                                          +-(L)-----------------------------+ |",
        "|                                            0 F                               |",
    )


def test_comscan_rung_shows_en_dn_len_pos(modbus):
    assert modbus_rung(modbus, 3, 80, selected=True) == lines(
        ">  Rung 3",
        "    Rung 3. While Busy, look for the normal reply (example 4): 02 03 FA, 125",
        "    big-endian registers into the staging area N10, and the CRC. COMSCAN waits",
        "    scan after scan until the reply is complete, cannot match (DN ER) or the",
        "    port's timeout (250 ms, COMGENIUS.LST) expires (DN ER EM).",
        "| Busy                                                                         |",
        "| B3/0                                           +-COMSCAN-------------------+ |",
        "|-] [--------------------------------------------|Reply(R6:1) port 0 format 4|-|",
        "|  0                                             |N10:0=1                    | |",
        "|                                                |EN DN . . LEN 255 POS 2    | |",
        "|                                                +---------------------------+ |",
    )
    without_status = modbus_rung(modbus, 3, 80, tli_status=False)
    assert "LEN 255" not in without_status and "|N10:0=1 " in without_status


def test_long_rung_wraps_at_60_and_80_but_not_at_200(modbus):
    assert modbus_rung(modbus, 8, 60) == lines(
        "   Rung 8",
        "    Rung 8. Both COMSCANs failed to match without a timeout:",
        "    the input is garbage. Clear the receive buffer",
        "    (COMRCVCLEAR), count it, end the transaction.",
        "| Reply/DN  Reply/ER  Reply/EM  Exception/DN",
        "| R6:1/DN   R6:1/ER   R6:1/EM     R6:2/DN",
        "|---] [-------] [-------]/[---------] [------------------->>",
        "|    1         0         0           1",
        "   Exception/ER  Exception/EM",
        "     R6:2/ER       R6:2/EM",
        ">>-----] [-----------]/[---------------------------------->>",
        "        1             0",
        "                             +-COMRCVCLEAR-+               |",
        ">>-------------------------+-|port 0       |-------------+-|",
        "                           | +-------------+             | |",
        "                           | +-CTU---------------------+ | |",
        "                           +-|GarbageClears(C5:4)      |-+ |",
        "                           | |. . . . . PRE 32767 ACC 0| | |",
        "                           | +-------------------------+ | |",
        "                           | Busy                        | |",
        "                           | B3/0                        | |",
        "                           +-(U)-------------------------+ |",
        "                              0                            |",
    )
    at_80 = modbus_rung(modbus, 8, 80).splitlines()
    assert sum(line.endswith(">>") for line in at_80) == 1
    assert sum(line.startswith(">>") for line in at_80) == 1
    at_200 = modbus_rung(modbus, 8, 200)
    assert ">>" not in at_200
    wire_row = [line for line in at_200.splitlines() if "] [" in line]
    assert len(wire_row) == 1 and wire_row[0].count("] [") == 4 and "+-|port 0" in wire_row[0]
    assert len(wire_row[0]) == 200


def test_program_file_view_draws_a_window_of_rungs(modbus):
    app, table = modbus
    main = app.program.main
    view = ProgramFileView(main, table, app.program.symbols, first=2, selected=3, breakpoints={(2, 5)},
                           height=30, instructions=app.instructions)
    text = render(view, 80)
    assert len(text.splitlines()) == 30  # the space left is filled with the top of rung 5...
    assert (view.drawn, view.last_drawn) == (3, 4)  # ...which does not count as drawn
    assert text.startswith("   Rung 2") and ">  Rung 3" in text and " * Rung 5" in text and "Rung 6" not in text
    assert view.rungs_that_fit(80, 60) == 5 and view.rungs_that_fit(80, 12) == 1
    assert (view.drawn, view.last_drawn, view.height) == (3, 4, 30)  # the view is left as it was
    tall = ProgramFileView(main, table, first=1, height=5)
    assert len(render(tall, 80).splitlines()) == 5 and (tall.drawn, tall.last_drawn) == (1, 1)
    everything = ProgramFileView(main, table, breakpoints={5})
    headers = [line for line in render(everything, 80).splitlines() if line[:3] in ("   ", " * ") and
               line[3:].startswith("Rung ")]
    assert headers == [f"{' * ' if n == 5 else '   '}Rung {n}" for n in range(len(main.rungs))]
    assert everything.last_drawn == len(main.rungs) - 1


@pytest.mark.parametrize("app_dir", sorted(p.name for p in PROGRAMS.iterdir() if (p / "main.lad").exists()))
def test_every_example_program_renders_at_80_and_120(app_dir, tmp_path):
    app = load_app(copy_app(app_dir, tmp_path))  # its server, if it has one, on a free port
    runner = Runner(app, RunOptions(fresh=True), log=lambda msg: None)
    try:
        runner.run(5)
        for pfile in app.program.files.values():
            for width in (80, 120):
                view = ProgramFileView(pfile, runner.table, app.program.symbols, instructions=app.instructions)
                text = render(view, width)
                assert view.drawn == len(pfile.rungs)
                assert max(len(line) for line in text.splitlines()) <= width
    finally:
        runner.engine.close()


# -- power flow -------------------------------------------------------------------------------


def power_of(text: str, values: dict | None = None):
    program, table = program_and_table(text, values)
    rung = program.main.rungs[0]
    return rung, rung_power(rung, table), table


def test_contacts_are_true_on_their_bit_and_in_series_make_an_and():
    rung, power, _ = power_of("XIC B3/1 XIO B3/2 XIC B3/3 OTE B3/0\n", {"B3/1": 1})
    xic1, xio2, xic3, ote = rung.elements
    assert (power[xic1].is_true, power[xio2].is_true, power[xic3].is_true) == (True, True, False)
    assert (power[xio2].power_in, power[xio2].power_out) == (True, True)
    assert (power[xic3].power_in, power[xic3].power_out) == (True, False)
    assert (power[ote].power_in, power[ote].power_out, power[ote].is_true) == (False, False, False)
    assert power.out is False
    _, power, _ = power_of("XIC B3/1 XIO B3/2 OTE B3/0\n", {"B3/1": 1})
    assert power.out is True


def test_a_branch_is_an_or_of_its_legs():
    text = "BST XIC B3/1 NXB BST XIC B3/2 NXB XIC B3/3 BND BND OTE B3/0\n"
    rung, power, _ = power_of(text, {"B3/3": 1})
    outer = rung.elements[0]
    inner = outer.legs[1][0]
    assert power[outer].legs == (False, True) and power[inner].legs == (False, True)
    assert power.out is True
    _, power, _ = power_of(text)
    assert power.out is False
    rung, power, _ = power_of("XIO B3/1 BST XIC B3/2 NXB XIC B3/3 BND OTE B3/0\n", {"B3/1": 1, "B3/2": 1})
    branch = rung.elements[1]
    assert power[branch].power_in is False and power[branch.legs[0][0]].is_true is True
    assert power[branch].legs == (False, False) and power.out is False


@pytest.mark.parametrize("condition,values,expected", [
    ("EQU N7:0 5", {"N7:0": 5}, True),
    ("NEQ N7:0 5", {"N7:0": 5}, False),
    ("LES N7:0 F8:0", {"N7:0": 1, "F8:0": 1.5}, True),
    ("LEQ N7:0 1", {"N7:0": 2}, False),
    ("GRT N7:0 1", {"N7:0": 2}, True),
    ("GEQ N7:0 3", {"N7:0": 2}, False),
    ("LIM 0 N7:0 10", {"N7:0": 10}, True),
    ("LIM 10 N7:0 0", {"N7:0": 5}, False),  # low > high: true outside
    ("MEQ N7:0 255 N7:1", {"N7:0": 0x1234, "N7:1": 0x34}, True),
    ('CMP "N7:0 * 2 > N7:1"', {"N7:0": 3, "N7:1": 5}, True),
    ("AFI", {}, False),
    ("ONS B3/5", {"B3/5": 1}, True),  # one-shots pass their input through
])
def test_conditions_follow_the_interpreter(condition, values, expected):
    rung, power, _ = power_of(f"{condition} OTE B3/0\n", values)
    assert power[rung.elements[0]].is_true is expected
    assert power.out is expected


def test_power_has_no_side_effects():
    text = 'ONS B3/5 CMP "N7:0 | N7:1 > 0" OTE B3/0\n'
    program, table = program_and_table(text, {"N7:0": 5})
    before = table.file("S2").data.tolist(), table.file("B3").data.tolist()
    power = rung_power(program.main.rungs[0], table)
    assert power.out is True  # division by zero gives the overflow result
    assert (table.file("S2").data.tolist(), table.file("B3").data.tolist()) == before


def test_bad_indirect_address_is_a_fault_not_an_exception():
    text = "XIC B3/1 XIC N7:[N7:1]/0 MOV N7:0 N7:[N7:2] OTE B3/0\n"
    rung, power, _ = power_of(text, {"B3/1": 1, "N7:1": 99, "N7:2": 500})
    ok, bad, mov, ote = rung.elements
    assert power[ok].power_out is True
    assert power[bad].fault and "element 99" in power[bad].fault and power[bad].power_out is False
    assert power[mov].fault and power[ote].power_in is False and power.out is False
    assert len(power.faults()) == 2
    rung, power, _ = power_of("XIC N7:[N7:1]/0 OTE B3/0\n", {"N7:1": 0})
    assert power.faults() == [] and power[rung.elements[0]].fault is None
