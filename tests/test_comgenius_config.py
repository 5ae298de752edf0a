"""COMGENIUS.LST: the manual's sample files, its 11-string table, every
escape, and the errors (file, line, column, reason)."""

from __future__ import annotations

from pathlib import Path

import pytest

from softplc_lite.tlm.comgenius.config import PortConfig, load_config, parse_config
from softplc_lite.tlm.comgenius.strings import decode_escapes
from softplc_lite.tlm.errors import ModuleError

DATA = Path(__file__).parent / "data" / "comgenius"


def load(name: str):
    return parse_config((DATA / name).read_text(encoding="latin-1"), name)


def test_manual_sample_file_1():
    config = load("SAMPLE1.LST")
    assert config.debug == 0
    assert config.ports == {0: PortConfig(0, "0", "ISO-8859-1", 38400, 8, "N", 1, 500, line=29)}
    s = config.strings
    assert len(s) == 9  # string 0 and the 8 of the file
    assert s.get(0) == ""
    assert s.get(1) == "Rack no: %3o has %2d modules.\r\n"
    assert s.get(2) == "\x02\x03%.2C%.2C%#R"
    assert s.get(3) == "AK HM %.14s %.3d"
    assert s.get(4) == "\x02\x03\xfa%.250C%#R"
    assert s.get(5) == "\x02\x83%c%#R"
    assert s.get(6) == "A STRPRINT test: number:%2d float:%g ST:%s"
    assert s.get(7) == "A_STRing -3.14 -4555"
    assert s.get(8) == "%s %f %d"
    assert s.get(9) is None


def test_manual_sample_file_2_editor_usage():
    config = load("SAMPLE2.LST")
    assert config.ports == {}  # its one port line is commented out
    assert config.strings.strings == ["", "string C5:0.ACC=%04X F8:0=%g\n",
                                      "HELLO Mr. %s, This is your favorite PLC calling.\n", "%s"]


def test_manual_11_string_table():
    s = load("STRINGS11.LST").strings
    assert s.strings[1:] == [
        'Enter your "name:"',
        "Enter your access code:\a",
        "Thank you for being there.",  # text before the quotes is ignored
        "\x1b[%d;%dH",
        "",  # line 5 has no quotes: the null string, still numbered
        "\x10\x06",
        "NK %S\0",
        "HM %3d %d %S\0",
        "\b\b\b",
        "First line\r\nsecond line",
        "Here is a unicode character: \u124f",
    ]
    assert s.lines[5] == 6  # string 5 is the 6th line of the file ([STRINGS] is the 1st)


@pytest.mark.parametrize("escape,char", [
    (r"\a", "\x07"), (r"\b", "\x08"), (r"\f", "\x0c"), (r"\n", "\x0a"), (r"\r", "\x0d"), (r"\t", "\x09"),
    (r"\v", "\x0b"), (r"\\", "\\"), (r"\"", '"'), (r"\02", "\x02"), (r"\0", "\x00"), (r"\377", "\xff"),
    (r"\1234", "S4"), (r"\x1B", "\x1b"), (r"\xfa", "\xfa"), (r"\x7", "\x07"), (r"\xABC", "\xabC"),
    (r"\u124F", "\u124f"), (r"\u000a", "\n"), (r"\u41", "A"), (r"\uFFFFF", "\uffffF"),
])
def test_escape_table(escape, char):
    assert decode_escapes(escape) == char


def test_each_escape_is_one_character_in_a_string_line():
    s = parse_config('[STRINGS]\n"\\x02\\x03\\u0041\\101\\\\"\n').strings
    assert s.get(1) == "\x02\x03AA\\"


def test_semicolons_are_comments_outside_strings_only():
    config = parse_config("; top\n[DRIVER] \nDEBUG = 2 ; loud\n[PORTS]\n1, COM2, utf-8, 9600, 7, e, 2, 0 ; x\n"
                          '[STRINGS]\n"a;b" ; not a comment\n; this is string 2\n')
    assert config.debug == 2
    assert config.ports[1] == PortConfig(1, "COM2", "UTF-8", 9600, 7, "E", 2, 0, line=5)
    assert config.strings.strings == ["", "a;b", ""]
    assert config.warnings == ["COMGENIUS.LST:8: ';' does not start a comment in [STRINGS]: this line is "
                               "string 2, the empty string"]


def test_blank_lines_in_strings_take_no_number():
    assert parse_config('[strings]\n"one"\n\n   \n"two"\nno quotes\n\n').strings.strings == ["", "one", "two", ""]


def test_a_physical_port_may_be_a_url_with_commas():
    config = parse_config("[PORTS]\n35, spy:///dev/ttyS0?file=a,b.txt, US-ASCII, 115200, 8, O, 1, 2000\n")
    assert config.ports[35].physical == "spy:///dev/ttyS0?file=a,b.txt"
    assert config.ports[35].encoding == "US-ASCII"


def test_load_config_finds_the_file_in_any_case(tmp_path):
    (tmp_path / "comgenius.lst").write_text('[STRINGS]\n"x"\n')
    assert load_config(tmp_path).strings.get(1) == "x"


def test_a_missing_config_file_is_an_error(tmp_path):
    with pytest.raises(ModuleError, match="COMGENIUS is enabled in MODULES.LST but .*COMGENIUS.LST does not exist"):
        load_config(tmp_path)


def _error(text: str) -> ModuleError:
    with pytest.raises(ModuleError) as e:
        parse_config(text, "C.LST")
    return e.value


@pytest.mark.parametrize("text,report", [
    ("DEBUG=1\n", "C.LST:1: 'DEBUG=1' is outside any section (start with [DRIVER], [PORTS] or [STRINGS])"),
    ("[DRIVERS]\n", "C.LST:1: unknown section [DRIVERS] (sections: [DRIVER], [PORTS], [STRINGS])"),
    ("[DRIVER]\nDEBUG=3\n", "C.LST:2: [DRIVER]: DEBUG must be 0, 1 or 2, not '3'"),
    ("[DRIVER]\nVERBOSE=1\n", "C.LST:2: [DRIVER]: unknown setting 'VERBOSE' (settings: DEBUG, PORT_ERRORS, "
                                "RETRY_MS, COM1..COM99)"),
    ("[DRIVER]\nDEBUG\n", "C.LST:2: [DRIVER]: expected KEY=VALUE (DEBUG=0, 1 or 2), found 'DEBUG'"),
    ("[DRIVER]\nPORT_ERRORS=maybe\n", "C.LST:2: [DRIVER]: PORT_ERRORS must be STOP (a port that cannot be "
                                       "opened stops the run) or RETRY (run on, retrying it), not 'maybe'"),
    ("[DRIVER]\nRETRY_MS=5\n", "C.LST:2: [DRIVER]: RETRY_MS must be at least 10, not 5"),
    ("[DRIVER]\nCOM3=\n", "C.LST:2: [DRIVER]: COM3= needs a device (e.g. COM3=/dev/ttyUSB0) or a URL"),
    ("[PORTS]\n0, COM1, ISO-8859-1, 38400, 8, N, 1\n",
     "C.LST:2: [PORTS]: expected 8 comma-separated fields (logical port, physical port, encoding, baud, "
     "data bits, parity, stop bits, timeout ms), found 7"),
    ("[PORTS]\n36, COM1, ISO-8859-1, 38400, 8, N, 1, 5\n", "C.LST:2: [PORTS]: logical port 36 is out of range (0..35)"),
    ("[PORTS]\nA, COM1, ISO-8859-1, 38400, 8, N, 1, 5\n", "C.LST:2: [PORTS]: logical port must be a number, not 'A'"),
    ("[PORTS]\n0, , ISO-8859-1, 38400, 8, N, 1, 5\n", "C.LST:2: [PORTS]: the physical port is empty"),
    ("[PORTS]\n0, COM1, EBCDIC, 38400, 8, N, 1, 5\n", "C.LST:2: [PORTS]: unknown encoding 'EBCDIC'"),
    ("[PORTS]\n0, COM1, UTF-8, 0, 8, N, 1, 5\n", "C.LST:2: [PORTS]: baud rate must be at least 1, not 0"),
    ("[PORTS]\n0, COM1, UTF-8, 9600, 9, N, 1, 5\n", "C.LST:2: [PORTS]: data bits 9 is out of range (5..8)"),
    ("[PORTS]\n0, COM1, UTF-8, 9600, 8, M, 1, 5\n", "C.LST:2: [PORTS]: parity must be N, E or O, not 'M'"),
    ("[PORTS]\n0, COM1, UTF-8, 9600, 8, N, 3, 5\n", "C.LST:2: [PORTS]: stop bits 3 is out of range (1..2)"),
    ("[PORTS]\n0, COM1, UTF-8, 9600, 8, N, 1, -5\n", "C.LST:2: [PORTS]: timeout must be a number, not '-5'"),
    ("[PORTS]\n0, COM1, UTF-8, 9600, 8, N, 1, 5\n0, COM2, UTF-8, 9600, 8, N, 1, 5\n",
     "C.LST:3: [PORTS]: logical port 0 is defined twice (first on line 2)"),
    ('[STRINGS]\n"ok"\n1 "abc\n', "C.LST:3:3: [STRINGS]: only one double quote"),
    ('[STRINGS]\n1 "ab\\qc"\n', "C.LST:2:6: [STRINGS]: unknown escape \\q"),
    ('[STRINGS]\n"\\x"\n', "C.LST:2:2: [STRINGS]: \\x needs 1 to 2 hex digits"),
    ('[STRINGS]\n"\\u"\n', "C.LST:2:2: [STRINGS]: \\u needs 1 to 4 hex digits"),
    ('[STRINGS]\n"\\400"\n', "C.LST:2:2: [STRINGS]: the octal escape \\400 is 256, more than 8 bits"),
    ('[STRINGS]\n"abc\\"\n', "C.LST:2:5: [STRINGS]: a backslash at the end of the string"),
    ('[STRINGS]\n"' + "x" * 256 + '"\n', "C.LST:2:1: [STRINGS]: string 1 has 256 characters; at most 255"),
])
def test_errors_give_the_line_and_the_reason(text, report):
    assert _error(text).report().startswith(report)


def test_255_characters_after_escapes_is_the_limit():
    assert len(parse_config('[STRINGS]\n"' + "\\x41" * 255 + '"\n').strings.get(1)) == 255


def test_at_most_32000_strings():
    ok = "[STRINGS]\n" + '"s"\n' * 32000
    assert len(parse_config(ok).strings) == 32001
    assert _error(ok + '"one too many"\n').report() == "C.LST:32002: [STRINGS]: more than 32000 strings"


def test_driver_extensions_port_errors_retry_and_com_devices():
    config = parse_config("[DRIVER]\nDEBUG=1\nport_errors = retry\nRETRY_MS=250\ncom1=/dev/ttyUSB0\n"
                          "COM12 = socket://127.0.0.1:5020 ; a TCP bridge\n")
    assert (config.debug, config.port_errors, config.retry_ms) == (1, "RETRY", 250)
    assert config.com_devices == {1: "/dev/ttyUSB0", 12: "socket://127.0.0.1:5020"}
    defaults = parse_config("[DRIVER]\nDEBUG=0\n")
    assert (defaults.port_errors, defaults.retry_ms, defaults.com_devices) == ("STOP", 1000, {})
