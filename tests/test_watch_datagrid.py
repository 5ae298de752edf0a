"""The data-file monitor (softplc_lite/watch/datagrid.py): each file kind and
radix drawn into a fixed-width capture console, compared line for line."""

from __future__ import annotations

import pytest
from rich.console import Console

from softplc_lite.datatable import DataTable, DataTableError
from softplc_lite.watch.datagrid import (
    RADIXES,
    DataGrid,
    grid_for,
    next_radix,
    word_in_radix,
)


@pytest.fixture
def table() -> DataTable:
    t = DataTable()
    t.create_file("B", 3, 4)
    t.create_file("N", 7, 25)
    t.create_file("F", 8, 7)
    t.create_file("ST", 9, 3)
    t.create_file("A", 10, 2)
    t.create_file("L", 11, 2)
    t.write("N7:0", 150)
    t.write("N7:1", -1)
    t.write("N7:12", 0x4142)  # "AB"
    t.write("N7:13", 0x0A41)  # a line feed, then "A"
    t.write("B3/17", 1)
    t.write("F8:1", 3.14159265)
    t.write("F8:2", -1.0e-9)
    t.write("ST9:1", "HELLO")
    t.write("T4:0.PRE", 50)
    t.write("T4:0.ACC", 12)
    t.write("T4:0/DN", 1)
    t.write("C5:0.PRE", 10)
    t.write("C5:0/CU", 1)
    t.write("R6:0.LEN", 10)
    t.write("R6:0.POS", 3)
    t.write("A10:0", 0x4849)  # "HI"
    t.write("L11:1", -2)
    return t


def drawn(grid: DataGrid, width: int = 80) -> list[str]:
    console = Console(record=True, width=width, color_system=None)
    console.print(grid)
    return console.export_text().splitlines()


def test_integer_file_rows_of_ten_in_each_radix(table):
    assert drawn(DataGrid(table, "N7")) == [
        " N7  integer, 25 elements  radix decimal  N7:0..24",
        "N7:0      150     -1      0      0      0      0      0      0      0      0",
        "N7:10       0      0  16706   2625      0      0      0      0      0      0",
        "N7:20       0      0      0      0      0",
    ]
    assert drawn(DataGrid(table, "N7", radix="hex"))[1:3] == [
        "N7:0   0096 FFFF 0000 0000 0000 0000 0000 0000 0000 0000",
        "N7:10  0000 0000 4142 0A41 0000 0000 0000 0000 0000 0000",
    ]
    # ASCII: two characters a word, high byte first; what does not print is '.'
    assert drawn(DataGrid(table, "N7", radix="ascii"))[2] == "N7:10  .. .. AB .A .. .. .. .. .. .."


def test_binary_fits_the_width(table):
    lines = drawn(DataGrid(table, "N7", radix="binary", height=3), width=80)
    assert lines == [
        " N7  integer, 25 elements  radix binary  N7:0..3",
        "N7:0   0000000010010110 1111111111111111",
        "N7:2   0000000000000000 0000000000000000",
    ]
    wide = drawn(DataGrid(table, "N7", radix="binary", height=2), width=100)
    assert wide[1] == "N7:0   " + " ".join(["0000000010010110", "1111111111111111"] + ["0" * 16] * 3)
    narrow = drawn(DataGrid(table, "N7", height=3), width=30)
    assert narrow[1:] == ["N7:0      150     -1", "N7:2        0      0"]  # two words a row fit 30 columns
    assert all(len(line) <= 30 for line in narrow)


def test_b_file_starts_in_binary_bit_15_on_the_left(table):
    assert drawn(DataGrid(table, "B3")) == [
        " B3  binary, 4 elements  radix binary  B3:0..3",
        "B3:0  0000000000000000 0000000000000010",  # B3/17 is word 1 bit 1
        "B3:2  0000000000000000 0000000000000000",
    ]


def test_float_file_seven_significant_digits(table):
    assert drawn(DataGrid(table, "F8", radix="hex")) == [  # a radix does not apply to floats
        " F8  float, 7 elements  floats, 7 digits  F8:0..6",
        "F8:0            0.0      3.141593        -1e-09           0.0           0.0",
        "F8:5            0.0           0.0",
    ]


def test_timer_counter_control_one_element_a_row(table):
    assert drawn(DataGrid(table, "T4")) == [
        " T4  timer, 1 element  radix decimal  T4:0..0",
        "T4:0  EN 0 TT 0 DN 1  PRE     50  ACC     12",
    ]
    assert drawn(DataGrid(table, "C5"))[1] == "C5:0  CU 1 CD 0 DN 0 OV 0 UN 0  PRE     10  ACC      0"
    assert drawn(DataGrid(table, "R6", radix="hex"))[1] == \
        "R6:0  EN 0 EU 0 DN 0 EM 0 ER 0 UL 0 IN 0 FD 0  LEN 000A  POS 0003"


def test_string_file_length_and_quoted_text(table):
    assert drawn(DataGrid(table, "ST9")) == [
        " ST9  string, 3 elements  ST9:0..2",
        'ST9:0  LEN  0 ""',
        'ST9:1  LEN  5 "HELLO"',
        'ST9:2  LEN  0 ""',
    ]


def test_ascii_and_long_files(table):
    assert drawn(DataGrid(table, "A10"))[1] == "A10:0  HI .."  # an A file starts in ASCII
    assert drawn(DataGrid(table, "L11", radix="hex"))[1] == "L11:0  00000000 FFFFFFFE"
    assert drawn(DataGrid(table, "L11"))[1] == "L11:0            0          -2"


def test_paging_from_the_first_element_shown(table):
    grid = DataGrid(table, "N7", height=2)
    assert drawn(grid)[1].startswith("N7:0 ")
    grid.page(1)
    assert grid.first == 10
    assert drawn(grid)[0].endswith("N7:10..19") and drawn(grid)[1].startswith("N7:10 ")
    grid.page(5)  # not past the last element
    assert grid.first == 24
    grid.page(-10)
    assert grid.first == 0
    assert drawn(DataGrid(table, "T4", first=500))[1].startswith("T4:0 ")  # clamped to the file


def test_radix_cycle_and_word_text():
    assert [next_radix(r) for r in RADIXES] == ["hex", "binary", "ascii", "decimal"]
    assert word_in_radix(-1, "hex") == "FFFF"
    assert word_in_radix(0x4142, "ascii") == "AB"
    assert word_in_radix(0x7F20, "ascii") == ". "
    assert word_in_radix(5, "binary") == "0000000000000101"


def test_bad_file_and_radix_say_what_was_expected(table):
    with pytest.raises(DataTableError, match="there is no data file N70"):
        DataGrid(table, "N70")
    with pytest.raises(DataTableError, match="expected a type and number such as N7"):
        DataGrid(table, "7N")
    with pytest.raises(ValueError, match="expected one of decimal, hex, binary, ascii"):
        DataGrid(table, "N7", radix="octal")


def test_grid_for_the_d_prompt(table):
    grid = grid_for(table, " N7:20 ")
    assert (grid.file.name, grid.first, grid.radix) == ("N7", 20, "decimal")
    assert grid_for(table, "b3").radix == "binary"
    assert grid_for(table, "O").file.name == "O0"
    with pytest.raises(DataTableError, match=r"expected a file \(N7, T4, ST9\) or a file and an element"):
        grid_for(table, "N7:x")
    with pytest.raises(DataTableError, match="there is no data file N12"):
        grid_for(table, "N12")
