"""MODBTCPS.XML: the reader and checker of the Modbus TCP server's
configuration (docs/modbtcps.md, "The configuration file: MODBTCPS.XML").

Each rule of the file has a test here that fails when the rule is broken:
the root's attributes and their safe defaults, the allow-list, units, the
four region kinds and what each may map, the rules across regions (Modbus
address space, data table file end, overlaps, the status block), every
problem at once with line and column, encodings, the missing file, and the
data table addresses a region reaches. Expected lines and columns are
computed from the text each test writes (``locate``), never copied from the
checker's output."""

from __future__ import annotations

import ipaddress
import re
import subprocess
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from softplc_lite.datatable import parse_address
from softplc_lite.tlm.errors import ModuleError, ModuleErrors
from softplc_lite.tlm.modbtcps.config import (
    CONFIG_FILE,
    ELEMENT_OF_KIND,
    KINDS,
    STATUS_WORDS,
    Region,
    ServerConfig,
    Unit,
    config_path,
    config_references,
    item_address,
    load_config,
    parse_config,
)
from softplc_lite.tlm.xmlcheck import MAX_PROBLEMS

from helpers.cli import softplc_here
from helpers.located import locate, where

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "modbtcps.md"
PATH = "MODBTCPS.XML"
LOOPBACK = (ipaddress.ip_network("127.0.0.0/8"), ipaddress.ip_network("::1/128"))


# -- helpers ----------------------------------------------------------------------------------

def parse(xml: str | bytes, path: str = PATH) -> ServerConfig:
    return parse_config(xml.encode() if isinstance(xml, str) else xml, path)


def problems(xml: str | bytes) -> list[ModuleError]:
    with pytest.raises(ModuleErrors) as info:
        parse(xml)
    return info.value.problems


def only_problem(xml: str | bytes) -> ModuleError:
    found = problems(xml)
    assert len(found) == 1, ModuleErrors(found).report()
    return found[0]


UNIT = '<Unit id="1"><Coils start="0" count="1" address="B3/0"/></Unit>'  # a unit that maps something


def server(inner: str = UNIT, root: str = "") -> str:
    return f"<ModbusTcpServer{' ' + root if root else ''}>\n{inner}\n</ModbusTcpServer>\n"


def in_unit(*regions: str, root: str = "") -> str:
    body = "\n".join(regions)
    return server(f'<Unit id="1">\n{body}\n</Unit>', root)


def region(xml: str, root: str = "") -> Region:
    """The one region of unit 1."""
    (found,) = parse(in_unit(xml, root=root)).units[1].regions
    return found


def tag(element: str, start: int | str = 0, count: int | str = 1, address: str = "N7:0", **attrs: str) -> str:
    extra = "".join(f' {k}="{v}"' for k, v in attrs.items())
    return f'<{element} start="{start}" count="{count}" address="{address}"{extra}/>'


def doc_example() -> str:
    """The whole file shown in docs/modbtcps.md."""
    text = DOC.read_text(encoding="utf-8")
    section = text[text.index("## The configuration file: MODBTCPS.XML"):]
    return re.search(r"```xml\n(.*?)```", section, re.S).group(1)


# -- 1. the documented example ------------------------------------------------------------------

def test_the_doc_example_parses_to_the_model():
    text = doc_example()
    config = parse(text)
    assert (config.path, config.host, config.port, config.max_connections, config.max_requests_per_second,
            config.idle_timeout_ms, config.word_order, config.debug) == \
        (PATH, "127.0.0.1", 5020, 16, 100, 60000, "high-low", 0)
    assert config.status == parse_address("N40:0")
    assert config.allow == (ipaddress.ip_network("127.0.0.0/8"), ipaddress.ip_network("192.168.1.0/24"))
    assert config.warnings == []
    assert list(config.units) == [1, 2]

    def at(needle: str) -> tuple[int, int]:
        return locate(text, needle)

    expected_1 = (
        Region("coils", 0, 32, parse_address("B3/0"), True, "bit", "high-low", *at("<Coils")),
        Region("discrete_inputs", 0, 16, parse_address("I:0/0"), False, "bit", "high-low", *at("<DiscreteInputs")),
        Region("holding_registers", 0, 20, parse_address("N7:0"), True, "word", "high-low",
               *locate(text, "<HoldingRegisters", 1)),
        Region("holding_registers", 100, 4, parse_address("F8:0"), True, "float", "low-high",
               *locate(text, "<HoldingRegisters", 2)),
        Region("input_registers", 0, 2, parse_address("ST9:0"), False, "string", "high-low",
               *locate(text, "<InputRegisters", 1)),
    )
    assert config.units[1] == Unit(1, expected_1, at('<Unit id="1"')[0])
    assert config.units[2] == Unit(2, (Region("input_registers", 0, 10, parse_address("N11:0"), False, "word",
                                              "high-low", *locate(text, "<InputRegisters", 2)),),
                                   at('<Unit id="2"')[0])
    spans = [(r.registers_per_item, r.span, r.end) for r in expected_1]
    assert spans == [(1, 32, 32), (1, 16, 16), (1, 20, 20), (2, 8, 108), (83, 166, 166)]


def test_the_doc_example_loads_from_an_app_directory(tmp_path):
    (tmp_path / "modbtcps.xml").write_text(doc_example(), encoding="utf-8")  # the name in any case
    assert config_path(tmp_path) == tmp_path / "modbtcps.xml"
    config = load_config(tmp_path)
    assert config.path == str(tmp_path / "modbtcps.xml")
    assert sorted(config.units) == [1, 2]


# -- 2. the root ----------------------------------------------------------------------------

def test_defaults_are_safe():
    config = parse(server())
    assert (config.host, config.port, config.allow, config.max_connections, config.max_requests_per_second,
            config.idle_timeout_ms, config.status, config.word_order, config.debug) == \
        ("127.0.0.1", 502, LOOPBACK, 16, 100, 60000, None, "high-low", 0)
    assert config.warnings == []


@pytest.mark.parametrize("attr, field, low, high", [
    ("port", "port", 1, 65535),
    ("maxConnections", "max_connections", 1, 1000),
    ("maxRequestsPerSecond", "max_requests_per_second", 1, 100_000),
    ("idleTimeout", "idle_timeout_ms", 100, 3_600_000),
    ("debug", "debug", 0, 2),
])
def test_root_integer_ranges(attr, field, low, high):
    assert getattr(parse(server(root=f'{attr}="{low}"')), field) == low
    assert getattr(parse(server(root=f'{attr}="{high}"')), field) == high
    assert getattr(parse(server(root=f'{attr}="{hex(high)}"')), field) == high  # hex, as in MODBMAST.XML
    for bad in (low - 1, high + 1, "ten", ""):
        text = server(root=f'{attr}="{bad}"')
        problem = only_problem(text)
        assert problem.message == f"{attr}={str(bad)!r}: expected an integer {low}..{high}"
        assert where(problem) == locate(text, f'{attr}="')


def test_word_order_choices():
    assert parse(server(root='wordOrder="low-high"')).word_order == "low-high"
    assert parse(server(root='wordOrder="HIGH-LOW"')).word_order == "high-low"
    text = server(root='wordOrder="big"')
    problem = only_problem(text)
    assert problem.message == "wordOrder='big': expected 'high-low' or 'low-high'"
    assert where(problem) == locate(text, "wordOrder=")


@pytest.mark.parametrize("address, host", [
    ("127.0.0.1", "127.0.0.1"), ("0.0.0.0", "0.0.0.0"), ("192.168.1.5", "192.168.1.5"), ("::", "::"),
    ("::1", "::1"), ("[::1]", "::1"), ("fe80::1%eth0", "fe80::1%eth0"), ("localhost", "localhost"),
    ("plc-1.plant.example", "plc-1.plant.example"), ("plc1.", "plc1."),
])
def test_listen_address_accepted(address, host):
    assert parse(server(root=f'address="{address}"')).host == host


@pytest.mark.parametrize("address", ["300.1.1.1", "192.168.1", "a b", "-plc", "plc-", "plc..x", "[::1",
                                     "::g", "x" * 64, "under_score"])
def test_listen_address_refused(address):
    text = server(root=f'address="{address}"')
    problem = only_problem(text)
    assert problem.message.startswith(f"address={address!r}: expected an IPv4 or IPv6 address or a host name")
    assert where(problem) == locate(text, "address=")


def test_empty_listen_address():
    problem = only_problem(server(root='address=" "'))
    assert problem.message.startswith("address is empty; expected an IPv4 or IPv6 address or a host name")


def test_listening_wide_without_allow_warns():
    config = parse(server(root='address="0.0.0.0"'))
    assert config.allow == LOOPBACK
    assert len(config.warnings) == 1
    assert config.warnings[0].startswith(f"{PATH}:1: listening on 0.0.0.0 but no <Allow> is given")
    for quiet in (server(root='address="::1"'), server(root='address="localhost"'),
                  server('<Allow network="10.0.0.0/8"/>' + UNIT, root='address="0.0.0.0"')):
        assert parse(quiet).warnings == []


# -- 3. the allow-list ------------------------------------------------------------------------

@pytest.mark.parametrize("network, networks", [
    ("192.168.1.0/24", ["192.168.1.0/24"]),
    ("192.168.1.77/24", ["192.168.1.0/24"]),  # host bits are fine (strict=False)
    ("10.0.0.5", ["10.0.0.5/32"]),
    ("fd00::/8", ["fd00::/8"]),
    ("::1", ["::1/128"]),
    ("any", ["0.0.0.0/0", "::/0"]),
    ("ANY", ["0.0.0.0/0", "::/0"]),
])
def test_allow_networks(network, networks):
    config = parse(server(f'<Allow network="{network}"/>\n<Unit id="1"/>'))
    assert config.allow == tuple(ipaddress.ip_network(n) for n in networks)


def test_allow_list_keeps_order_and_replaces_the_default():
    config = parse(server('<Allow network="10.1.0.0/16"/><Allow network="fd00::/8"/><Unit id="1"/>'))
    assert config.allow == (ipaddress.ip_network("10.1.0.0/16"), ipaddress.ip_network("fd00::/8"))
    assert ipaddress.ip_network("127.0.0.0/8") not in config.allow


@pytest.mark.parametrize("network", ["10.0.0.0/33", "10.0.0", "everyone", "fd00::/129", "1.2.3.4/-1"])
def test_bad_allow_network(network):
    text = server(f'<Allow network="{network}"/>\n<Unit id="1"/>')
    problem = only_problem(text)
    assert problem.message.startswith(f"network={network!r}: expected a client network")
    assert where(problem) == locate(text, "network=")


def test_allow_needs_a_network_and_comes_before_the_units():
    text = server('<Allow/>\n<Unit id="1"/>\n<Allow network="any"/>')
    first, second = problems(text)
    assert first.message.startswith("<Allow> needs the attribute network (")
    assert where(first) == locate(text, "<Allow/>")
    assert second.message == "<Allow> is not allowed here (<ModbusTcpServer> contains <Allow>*, <Unit>+)"
    assert where(second) == locate(text, '<Allow network="any"')


# -- 4. units -----------------------------------------------------------------------------------

def test_unit_ids_0_to_255():
    config = parse(server('<Unit id="0"/><Unit id="255"/><Unit id="0x10"/>'))
    assert sorted(config.units) == [0, 16, 255]
    text = server('<Unit id="256"/>')
    problem = only_problem(text)
    assert (problem.message, where(problem)) == ("id='256': expected an integer 0..255", locate(text, "id="))


def test_a_repeated_unit_id_names_the_first_line():
    text = server('<Unit id="7"/>\n<Unit id="8"/>\n<Unit id="7"><Coils/></Unit>')
    found = problems(text)
    repeated = [p for p in found if "used twice" in p.message]
    assert len(repeated) == 1  # (the repeat is reported even though its <Coils> has problems of its own)
    assert repeated[0].message == ("unit id 7 is used twice (first on line 2); a unit id is unique in the "
                                   "server")
    assert where(repeated[0]) == locate(text, 'id="7"', 2)


def test_at_least_one_unit_and_each_needs_an_id():
    text = server("")
    problem = only_problem(text)
    assert problem.message == "<ModbusTcpServer> needs <Unit> here (<Allow>*, <Unit>+)"
    text = server("<Unit/>")
    problem = only_problem(text)
    assert problem.message == "<Unit> needs the attribute id (an integer 0..255)"
    assert where(problem) == locate(text, "<Unit/>")


def test_an_empty_unit_is_warned_about():
    config = parse(server('<Unit id="1"><Coils start="0" count="1" address="B3/0"/></Unit>\n<Unit id="2"/>'))
    assert config.warnings == [f'{PATH}:3: <Unit id="2"> maps nothing: every request to it is refused '
                               "(exception 02)"]


def test_regions_in_any_order_and_number():
    config = parse(in_unit(tag("InputRegisters", 0), tag("Coils", 0, address="B3/0"),
                           tag("InputRegisters", 5), tag("HoldingRegisters", 0),
                           tag("DiscreteInputs", 0, address="I:0/0"), tag("Coils", 9, address="B3/9")))
    assert [r.kind for r in config.units[1].regions] == ["input_registers", "coils", "input_registers",
                                                         "holding_registers", "discrete_inputs", "coils"]
    assert set(ELEMENT_OF_KIND.values()) == set(KINDS)


def test_unknown_element_in_a_unit_gets_a_hint():
    text = in_unit('<HoldingRegister start="0" count="1" address="N7:0"/>', "<Allow/>")
    first, second = problems(text)
    assert first.message == ("unknown element <HoldingRegister> (<Unit> contains <Coils>, <DiscreteInputs>, "
                             "<HoldingRegisters>, <InputRegisters>: any number of each, in any order); did you "
                             "mean <HoldingRegisters>?")
    assert where(first) == locate(text, "<HoldingRegister ")
    assert second.message.startswith("<Allow> is not allowed here (<Unit> contains <Coils>")
    assert "did you mean" not in second.message


def test_wrong_root_and_malformed_xml():
    problem = only_problem("<ModbusSerial/>")
    assert problem.message == "the top element is <ModbusSerial>; expected <ModbusTcpServer> (docs/modbtcps.md)"
    problem = only_problem('<ModbusTcpServer>\n  <Unit id="1">\n</ModbusTcpServer>')
    assert problem.message.startswith("not well-formed XML")
    assert problem.line == 3


# -- 5. regions: attributes -------------------------------------------------------------------

@pytest.mark.parametrize("element", list(ELEMENT_OF_KIND))
def test_region_needs_start_count_and_address(element):
    text = in_unit(f"<{element}/>")
    found = problems(text)
    assert [p.message.split(" (")[0] for p in found] == [f"<{element}> needs the attribute start",
                                                        f"<{element}> needs the attribute count",
                                                        f"<{element}> needs the attribute address"]
    assert {where(p) for p in found} == {locate(text, f"<{element}/>")}


@pytest.mark.parametrize("attr, low, high", [("start", 0, 65535), ("count", 1, 65536)])
def test_start_and_count_ranges(attr, low, high):
    values = {"start": 0, "count": 1}
    for good in (low, high):
        values[attr] = good
        r = region(tag("Coils", values["start"], values["count"], "B3/0") if attr == "count" or good == 0
                   else tag("Coils", good, 1, "B3/0"))
        assert getattr(r, attr) == good
    for bad in (low - 1, high + 1):
        values[attr] = bad
        text = in_unit(tag("Coils", values["start"], values["count"], "B3/0"))
        problem = only_problem(text)
        assert problem.message == f"{attr}={str(bad)!r}: expected an integer {low}..{high}"
        assert where(problem) == locate(text, f"{attr}=")


def test_unknown_region_attribute_gets_a_hint():
    text = in_unit('<Coils start="0" count="1" address="B3/0" writeable="yes"/>')
    problem = only_problem(text)
    assert problem.message == ("<Coils> has no attribute 'writeable' (its attributes: start, count, address, "
                               "writable); did you mean writable?")
    assert where(problem) == locate(text, "writeable")


def test_writable_defaults_to_no_and_takes_yes_or_no():
    assert region(tag("Coils", address="B3/0")).writable is False
    assert region(tag("Coils", address="B3/0", writable="YES")).writable is True
    assert region(tag("HoldingRegisters", writable="no")).writable is False
    text = in_unit(tag("HoldingRegisters", writable="true"))
    problem = only_problem(text)
    assert problem.message == "writable='true': expected 'yes' or 'no'"
    assert where(problem) == locate(text, "writable=")


@pytest.mark.parametrize("element, instead", [("DiscreteInputs", "Coils"), ("InputRegisters", "HoldingRegisters")])
def test_read_only_tables_cannot_be_writable(element, instead):
    address = "B3/0" if element == "DiscreteInputs" else "N7:0"
    assert region(tag(element, address=address, writable="no")).writable is False
    text = in_unit(tag(element, address=address, writable="yes"))
    problem = only_problem(text)
    assert problem.message == (f'writable="yes": <{element}> are read-only in Modbus (no function writes '
                               f"them); map them as <{instead}> to let clients write")
    assert where(problem) == locate(text, "writable=")


# -- 6. regions: what each maps ---------------------------------------------------------------------

@pytest.mark.parametrize("element", ["Coils", "DiscreteInputs"])
@pytest.mark.parametrize("address", ["B3/0", "B3/17", "B3:1/1", "N7:0/0", "N7:3/15", "I:0/0", "I:1/17",
                                     "I:1.0/3", "O:0/0", "S:1/15", "B10/5"])
def test_bit_regions_take_bit_addresses(element, address):
    r = region(tag(element, address=address))
    assert (r.value, r.address, r.registers_per_item) == ("bit", parse_address(address), 1)


@pytest.mark.parametrize("element", ["Coils", "DiscreteInputs"])
@pytest.mark.parametrize("address", ["N7:0", "B3:0", "I:0", "F8:0", "ST9:0", "T4:0/DN", "C5:0/CU", "R6:0/EN",
                                     "T4:0.ACC", "L9:0", "D10:0/1", "A11:0/1", "ST9:0.LEN"])
def test_bit_regions_refuse_other_addresses(element, address):
    text = in_unit(tag(element, address=address))
    problem = only_problem(text)
    assert problem.message == (f"address={address!r}: <{element}> map bits: a bit address of an O, I, S, B or N "
                               "file (B3/0, N7:0/0, I:0/0, O:0/0); the bits run on into the next words")
    assert where(problem) == locate(text, "address=")


@pytest.mark.parametrize("element", ["HoldingRegisters", "InputRegisters"])
@pytest.mark.parametrize("address, value, per_item", [
    ("N7:0", "word", 1), ("B3:2", "word", 1), ("O:0", "word", 1), ("I:7", "word", 1), ("S:3", "word", 1),
    ("N12:100", "word", 1), ("F8:0", "float", 2), ("F20:5", "float", 2), ("ST9:0", "string", 83),
])
def test_register_regions_take_words_floats_and_strings(element, address, value, per_item):
    r = region(tag(element, count=3, address=address))
    assert (r.value, r.address, r.registers_per_item, r.span) == (value, parse_address(address), per_item,
                                                                   3 * per_item)


@pytest.mark.parametrize("element", ["HoldingRegisters", "InputRegisters"])
@pytest.mark.parametrize("address", ["N7:0/3", "B3/17", "T4:0", "T4:0.ACC", "C5:0", "R6:0.POS", "ST9:0.LEN",
                                     "L9:0", "D10:0", "A11:0", "T4:0/DN", "SI12:0", "LI13:0"])
def test_register_regions_refuse_other_addresses(element, address):
    text = in_unit(tag(element, address=address))
    problem = only_problem(text)
    assert problem.message == (f"address={address!r}: <{element}> map whole elements: a word of an O, I, S, B "
                               "or N file (N7:0, B3:0, I:0), a float of an F file (F8:0) or a string of an ST "
                               "file (ST9:0)")
    assert where(problem) == locate(text, "address=")


@pytest.mark.parametrize("address", ["#N7:0", "N7:[N7:1]", "N[N7:2]:0", "B3/[N7:0]"])
def test_region_addresses_must_be_direct(address):
    element = "Coils" if "/" in address else "HoldingRegisters"
    text = in_unit(tag(element, address=address))
    problem = only_problem(text)
    assert problem.message == f"address={address!r}: a region's address must be direct (no [..] or #)"


@pytest.mark.parametrize("address, reason", [("X7:0", "unknown file type"), ("N7", "expected ':'"),
                                             ("N2:0", "file number 2 out of range"), ("", None)])
def test_bad_address_text_says_why(address, reason):
    text = in_unit(tag("HoldingRegisters", address=address))
    problem = only_problem(text)
    if reason is None:
        assert problem.message == "address is empty; expected a data table address"
    else:
        assert problem.message.startswith(f"address={address!r}: ") and reason in problem.message
    assert where(problem) == locate(text, "address=")


def test_float_word_order_inherits_and_overrides():
    assert region(tag("HoldingRegisters", address="F8:0")).word_order == "high-low"
    assert region(tag("HoldingRegisters", address="F8:0"), root='wordOrder="low-high"').word_order == "low-high"
    assert region(tag("InputRegisters", address="F8:0", wordOrder="low-high")).word_order == "low-high"
    assert region(tag("InputRegisters", address="F8:0", wordOrder="high-low"),
                  root='wordOrder="low-high"').word_order == "high-low"


@pytest.mark.parametrize("address, value", [("N7:0", "word"), ("ST9:0", "string")])
def test_word_order_only_on_float_regions(address, value):
    text = in_unit(tag("HoldingRegisters", address=address, wordOrder="low-high"))
    problem = only_problem(text)
    assert problem.message == (f"wordOrder applies to a float region (an F file address); {address} holds "
                               f"{value}s")
    assert where(problem) == locate(text, "wordOrder=")
    problem = only_problem(in_unit(tag("Coils", address="B3/0", wordOrder="low-high")))
    assert problem.message.startswith("<Coils> has no attribute 'wordOrder'")


# -- 7. rules across regions ------------------------------------------------------------------------

@pytest.mark.parametrize("element, address, per_item", [
    ("Coils", "B3/0", 1), ("DiscreteInputs", "B3/0", 1), ("HoldingRegisters", "N7:0", 1),
    ("InputRegisters", "N7:0", 1), ("HoldingRegisters", "F8:0", 2), ("InputRegisters", "ST9:0", 83),
])
def test_a_region_stays_in_the_modbus_address_space(element, address, per_item):
    count = 3
    last_start = 65536 - count * per_item
    assert region(tag(element, last_start, count, address)).end == 65536
    text = in_unit(tag(element, last_start + 1, count, address))
    problem = only_problem(text)
    unit = "bits" if element in ("Coils", "DiscreteInputs") else "registers"
    assert problem.message == (f"<{element}> leaves the Modbus address space: {count * per_item} {unit} from "
                               f"start {last_start + 1} reach address 65536; the last is 65535")
    assert where(problem) == locate(text, "count=")


def test_all_65536_bits_fit_from_zero():
    r = region(tag("Coils", 0, 65536, "B3/0"))
    assert (r.span, r.end, item_address(r, 65535)) == (65536, 65536, parse_address("B3:4095/15"))


@pytest.mark.parametrize("element, address, fits, noun", [
    ("HoldingRegisters", "N7:9990", 10, "elements"),
    ("InputRegisters", "F8:9999", 1, "elements"),
    ("InputRegisters", "ST9:9998", 2, "elements"),
    ("Coils", "B3:9999/0", 16, "bits"),
    ("DiscreteInputs", "N7:9998/15", 17, "bits"),
])
def test_a_region_stays_inside_its_data_table_file(element, address, fits, noun):
    assert region(tag(element, 0, fits, address)).count == fits
    text = in_unit(tag(element, 0, fits + 1, address))
    problem = only_problem(text)
    assert problem.message == (f"address={address!r}: {fits + 1} {noun} from here run past the end of a file "
                               "(elements 0..9999)")
    assert where(problem) == locate(text, "address=")


@pytest.mark.parametrize("element, address", [("Coils", "B3/0"), ("DiscreteInputs", "I:0/0"),
                                              ("HoldingRegisters", "N7:0"), ("InputRegisters", "N7:0")])
def test_regions_of_one_kind_in_a_unit_may_not_overlap(element, address):
    text = in_unit(tag(element, 10, 10, address), tag(element, 0, 10, address), tag(element, 19, 1, address))
    problem = only_problem(text)  # 0..9 and 10..19 touch, and are fine; 19 is in 10..19
    assert problem.message == (f"<{element}> 19..19 overlaps <{element}> 10..19 on line 3; two regions of one "
                               "kind in a unit may not share an address")
    assert where(problem) == locate(text, 'start="19"')


def test_overlap_is_reported_at_the_later_region_naming_the_earlier():
    # The later one in the file starts lower: the report is still on it, naming the first.
    text = in_unit(tag("HoldingRegisters", 100, 4, "F8:0"), tag("HoldingRegisters", 90, 11, "N7:0"))
    problem = only_problem(text)
    assert problem.message.startswith("<HoldingRegisters> 90..100 overlaps <HoldingRegisters> 100..107 on line 3;")
    assert where(problem) == locate(text, 'start="90"')
    # A small region inside a large one that an earlier, shorter one does not reach.
    text = in_unit(tag("InputRegisters", 0, 100), tag("InputRegisters", 10, 1), tag("InputRegisters", 50, 1))
    assert [p.line for p in problems(text)] == [4, 5]


def test_floats_and_strings_overlap_by_their_registers():
    # F8:0 x 2 at 0 takes registers 0..3: a word at 3 overlaps, a word at 4 does not.
    assert len(parse(in_unit(tag("HoldingRegisters", 0, 2, "F8:0"), tag("HoldingRegisters", 4))).units[1].regions) == 2
    assert only_problem(in_unit(tag("HoldingRegisters", 0, 2, "F8:0"), tag("HoldingRegisters", 3))).line == 4
    assert only_problem(in_unit(tag("InputRegisters", 0, 1, "ST9:0"), tag("InputRegisters", 82))).line == 4
    assert len(parse(in_unit(tag("InputRegisters", 0, 1, "ST9:0"), tag("InputRegisters", 83))).units[1].regions) == 2


def test_different_kinds_and_different_units_may_share_addresses():
    config = parse(server('<Unit id="1">' + tag("Coils", 0, 16, "B3/0") + tag("DiscreteInputs", 0, 16, "B3/0")
                          + tag("HoldingRegisters", 0, 1, "B3:0") + tag("InputRegisters", 0, 1, "B3:0")
                          + '</Unit><Unit id="2">' + tag("Coils", 0, 16, "B3/0") + "</Unit>"))
    assert [len(u.regions) for u in config.units.values()] == [4, 1]


def test_writable_regions_may_map_the_same_words():
    config = parse(in_unit(tag("Coils", 0, 16, "B3/0", writable="yes"),
                           tag("HoldingRegisters", 0, 1, "B3:0", writable="yes"),
                           tag("HoldingRegisters", 10, 1, "B3:0", writable="yes")))
    assert [r.writable for r in config.units[1].regions] == [True, True, True]


# -- 8. the status block --------------------------------------------------------------------------

@pytest.mark.parametrize("address", ["N40:0", "B3:0", "N7:9984"])
def test_status_is_a_word_of_an_n_or_b_file(address):
    assert parse(server(root=f'status="{address}"')).status == parse_address(address)


@pytest.mark.parametrize("address, reason", [
    ("F8:0", "expected a direct word address of an N or B file"),
    ("O:0", "expected a direct word address of an N or B file"),
    ("N7:0/1", "expected a direct word address of an N or B file"),
    ("B3/16", "expected a direct word address of an N or B file"),
    ("#N7:0", "expected a direct word address of an N or B file"),
    ("T4:0.ACC", "expected a direct word address of an N or B file"),
    ("N7:9985", "the 16 status words from here run past the end of a file (elements 0..9999)"),
    ("N7", "expected ':'"),
])
def test_bad_status_address(address, reason):
    text = server(root=f'status="{address}"')
    problem = only_problem(text)
    assert problem.message.startswith(f"status={address!r}: ") and reason in problem.message
    assert where(problem) == locate(text, "status=")


@pytest.mark.parametrize("writable_region", [
    tag("HoldingRegisters", 0, 10, "N40:0", writable="yes"),  # N40:0..9 covers N40:5
    tag("HoldingRegisters", 0, 1, "N40:20", writable="yes"),  # the last status word
    tag("Coils", 0, 1, "N40:5/15", writable="yes"),  # one bit of the first status word
    tag("Coils", 0, 2, "N40:4/15", writable="yes"),  # runs on into N40:5
])
def test_a_writable_region_over_the_status_words_is_an_error(writable_region):
    text = in_unit(writable_region, root='status="N40:5"')
    problem = only_problem(text)
    assert "is writable and maps" in problem.message
    assert "over the status words N40:5..N40:20 (status= on line 1): a client must not write the server's " \
           "counters" in problem.message
    assert where(problem) == locate(text, "address=")


@pytest.mark.parametrize("fine_region", [
    tag("InputRegisters", 0, 16, "N40:5"),  # read-only: a client may read the counters
    tag("HoldingRegisters", 0, 16, "N40:5"),
    tag("HoldingRegisters", 0, 5, "N40:0", writable="yes"),  # N40:0..4: just before
    tag("HoldingRegisters", 0, 5, "N40:21", writable="yes"),  # just after
    tag("HoldingRegisters", 0, 16, "N41:5", writable="yes"),  # another file
    tag("Coils", 0, 16, "N40:4/0", writable="yes"),  # the 16 bits of N40:4, the word before
    tag("Coils", 0, 16, "N40:21/0", writable="yes"),  # the word after
])
def test_regions_beside_the_status_words_are_fine(fine_region):
    assert len(parse(in_unit(fine_region, root='status="N40:5"')).units[1].regions) == 1


def test_status_words_are_sixteen():
    assert STATUS_WORDS == 16
    config = parse(server(root='status="N40:0"'))
    assert config_references(config)[-2:] == [parse_address("N40:0"), parse_address("N40:15")]


# -- 9. every problem at once ---------------------------------------------------------------------

MANY_PROBLEMS = """\
<ModbusTcpServer port="70000" colour="red" status="F8:0">
  <Allow network="10.0.0.0/40"/>
  <Unit id="1">
    <Coils start="0" count="8" address="N7:0"/>
    <HoldingRegisters start="0" count="10" address="N7:0"/>
    <HoldingRegisters start="5" count="10" address="N7:20"/>
    <InputRegisters start="0" count="1" address="T4:0" writable="yes"/>
    <DiscreteInput start="0" count="1" address="I:0/0"/>
  </Unit>
  <Unit id="1"/>
  <Unit id="999"/>
</ModbusTcpServer>
"""


def test_every_problem_is_reported_with_its_line_and_column():
    text = MANY_PROBLEMS
    found = problems(text)
    expected = [
        (locate(text, "port="), "port='70000': expected an integer 1..65535"),
        (locate(text, "colour="), "<ModbusTcpServer> has no attribute 'colour'"),
        (locate(text, "status="), "status='F8:0': expected a direct word address"),
        (locate(text, "network="), "network='10.0.0.0/40': expected a client network"),
        (locate(text, 'address="N7:0"'), "address='N7:0': <Coils> map bits"),
        (locate(text, 'start="5"'), "<HoldingRegisters> 5..14 overlaps <HoldingRegisters> 0..9 on line 5"),
        (locate(text, 'address="T4:0"'), "address='T4:0': <InputRegisters> map whole elements"),
        (locate(text, "writable="), 'writable="yes": <InputRegisters> are read-only in Modbus'),
        (locate(text, "<DiscreteInput "), "unknown element <DiscreteInput>"),
        (locate(text, 'id="1"', 2), "unit id 1 is used twice (first on line 3)"),
        (locate(text, 'id="999"'), "id='999': expected an integer 0..255"),
    ]
    assert [(where(p), p.message[:len(m)]) for p, (_, m) in zip(found, expected)] == expected
    assert len(found) == len(expected)
    assert all(p.path == PATH for p in found)
    report = ModuleErrors(found).report()
    assert report.splitlines()[0] == f"{PATH}:1:{locate(text, 'port=')[1]}: port='70000': expected an integer " \
                                     "1..65535"


def test_a_file_with_very_many_problems_lists_the_first_and_counts_the_rest():
    units = "\n".join(f'<Unit id="{n}" x="1"/>' for n in range(MAX_PROBLEMS + 30))
    found = problems(server(units))
    assert len(found) == MAX_PROBLEMS + 1
    assert found[-1].message.startswith("... and ")
    # One unknown attribute a unit: 230 problems, 200 listed.
    assert found[-1].message == f"... and 30 more problems (the first {MAX_PROBLEMS} are listed)"
    assert [p.line for p in found[:-1]] == list(range(2, MAX_PROBLEMS + 2))


# -- 10. encodings and the file itself ------------------------------------------------------------

SMALL = '<?xml version="1.0" encoding="{enc}"?>\n<ModbusTcpServer port="5020">\n  <Unit id="1">\n' \
        '    <HoldingRegisters start="0" count="2" address="N7:0"/>\n  </Unit>\n</ModbusTcpServer>\n'


@pytest.mark.parametrize("encoding, codec, bom", [
    ("UTF-8", "utf-8", b""),
    ("UTF-8", "utf-8", b"\xef\xbb\xbf"),
    ("UTF-16", "utf-16", b""),  # Python's utf-16 writes a BOM
    ("UTF-16", "utf-16-le", b"\xff\xfe"),
    ("UTF-16", "utf-16-be", b"\xfe\xff"),
    ("ISO-8859-1", "latin-1", b""),
])
def test_encodings_read_from_a_file(tmp_path, encoding, codec, bom):
    (tmp_path / CONFIG_FILE).write_bytes(bom + SMALL.replace("{enc}", encoding).encode(codec))
    config = load_config(tmp_path)
    assert config.port == 5020
    assert config.units[1].regions[0].address == parse_address("N7:0")
    assert config.units[1].regions[0].line == 4


def test_positions_in_a_utf16_file_are_those_of_the_text(tmp_path):
    text = SMALL.replace("{enc}", "UTF-16").replace('address="N7:0"', 'address="N7:0/1"')
    (tmp_path / CONFIG_FILE).write_bytes(text.encode("utf-16"))
    with pytest.raises(ModuleErrors) as info:
        load_config(tmp_path)
    (problem,) = info.value.problems
    assert (problem.path, where(problem)) == (str(tmp_path / CONFIG_FILE), locate(text, "address="))


def test_a_missing_file_says_what_it_holds(tmp_path):
    assert config_path(tmp_path) is None
    with pytest.raises(ModuleError) as info:
        load_config(tmp_path)
    message = str(info.value.message)
    assert not isinstance(info.value, ModuleErrors)
    assert str(tmp_path / CONFIG_FILE) in message
    assert "does not exist" in message and "<ModbusTcpServer>" in message and "docs/modbtcps.md" in message


def test_a_directory_named_like_the_file_is_not_the_file(tmp_path):
    (tmp_path / CONFIG_FILE).mkdir()
    with pytest.raises(ModuleError, match="does not exist"):
        load_config(tmp_path)


def test_a_dtd_is_refused():
    text = '<?xml version="1.0"?>\n<!DOCTYPE x [<!ENTITY a "b">]>\n<ModbusTcpServer><Unit id="1"/></ModbusTcpServer>'
    problem = only_problem(text)
    assert "document type declaration" in problem.message and problem.line == 2


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=300) | st.text(max_size=300).map(lambda t: server(t).encode()))
def test_garbage_never_raises_anything_but_module_errors(data):
    try:
        config = parse_config(data)
    except ModuleErrors as e:
        assert e.problems and all(p.line >= 1 and p.column >= 1 for p in e.problems)
    else:
        assert isinstance(config, ServerConfig)


# -- 11. addresses a region reaches ---------------------------------------------------------------

@pytest.mark.parametrize("address, k, expected", [
    ("B3/0", 0, "B3/0"), ("B3/0", 17, "B3/17"), ("B3/15", 1, "B3/16"), ("B3:1/15", 1, "B3/32"),
    ("N7:0/0", 17, "N7:1/1"), ("N7:0/15", 1, "N7:1/0"), ("N7:4/14", 3, "N7:5/1"),
    ("I:0/17", 1, "I:1/0"), ("I:0/0", 16, "I:1/0"), ("O:7/17", 1, "O:10/0"),  # I/O numbers are octal
])
def test_item_address_of_bits_runs_on_across_words(address, k, expected):
    r = region(tag("Coils", 0, k + 1, address))
    assert item_address(r, k) == parse_address(expected)
    assert str(item_address(r, k)) == expected


@pytest.mark.parametrize("address, k, expected", [
    ("N7:0", 5, "N7:5"), ("F8:0", 1, "F8:1"), ("F8:10", 3, "F8:13"), ("ST9:0", 1, "ST9:1"), ("I:7", 1, "I:10"),
])
def test_item_address_of_elements(address, k, expected):
    r = region(tag("HoldingRegisters", 0, k + 1, address))
    assert item_address(r, k) == parse_address(expected)


def test_config_references_reach_the_last_item_of_every_region_and_the_status_block():
    config = parse(server('<Unit id="1">' + tag("Coils", 0, 20, "B3/10") + tag("HoldingRegisters", 0, 4, "F8:0")
                          + tag("InputRegisters", 0, 2, "ST9:0") + '</Unit><Unit id="2">'
                          + tag("DiscreteInputs", 0, 2, "N7:0/15") + "</Unit>", root='status="N40:0"'))
    assert [str(a) for a in config_references(config)] == ["B3/10", "B3/29", "F8:0", "F8:3", "ST9:0", "ST9:1",
                                                           "N7:0/15", "N7:1/0", "N40:0", "N40:15"]


def test_config_references_create_the_words_in_a_data_table():
    from softplc_lite.datatable import DataTable, DataTableError

    config = parse(doc_example())
    table = DataTable()
    reached = ("B3/31", "N7:19", "F8:3", "ST9:1", "N11:9", "N40:15")
    for a in reached:
        with pytest.raises(DataTableError):
            table.read(a)
    for address in config_references(config):
        table.reference(address)
    for a in reached:
        table.read(a)  # now it exists


@given(st.integers(0, 9998 * 16), st.integers(0, 31))
def test_item_address_is_the_bit_k_places_on(first_bit, k):
    r = Region("coils", 0, k + 1, parse_address(f"B3/{first_bit}"), False, "bit", "high-low", 1, 1)
    assert item_address(r, k) == parse_address(f"B3/{first_bit + k}")


# -- 12. softplc check reports it all (its main(), the module registered by its entry point) -------------

def check_app(tmp_path: Path, xml: str | None) -> subprocess.CompletedProcess:
    (tmp_path / "MODULES.LST").write_text("MODBTCPS\n")
    (tmp_path / "main.lad").write_text("ADD N11:0 1 N11:0\n")
    if xml is not None:
        (tmp_path / CONFIG_FILE).write_text(xml)
    return softplc_here("check", str(tmp_path), cwd=tmp_path)


def test_check_reports_every_problem_with_file_line_and_column(tmp_path):
    proc = check_app(tmp_path, MANY_PROBLEMS)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stdout + proc.stderr
    path = tmp_path / CONFIG_FILE
    lines = [line for line in (proc.stdout + proc.stderr).splitlines() if line.startswith(str(path))]
    expected = [f"{path}:{p.line}:{p.column}: {p.message}" for p in problems(MANY_PROBLEMS)]
    assert lines == expected and len(lines) == 11


def test_check_says_what_a_missing_file_holds(tmp_path):
    proc = check_app(tmp_path, None)
    assert proc.returncode == 1
    out = proc.stdout + proc.stderr
    assert "Traceback" not in out
    assert f"{tmp_path / CONFIG_FILE} does not exist: it holds the <ModbusTcpServer> configuration" in out
    assert "docs/modbtcps.md" in out


def test_check_passes_the_doc_example_and_shows_warnings(tmp_path):
    proc = check_app(tmp_path, doc_example())
    assert (proc.returncode, proc.stderr) == (0, "")
    assert "module MODBTCPS" in proc.stdout and "warning" not in proc.stdout
    proc = check_app(tmp_path, server(root='address="0.0.0.0"'))
    assert proc.returncode == 0
    assert f"warning: {tmp_path / CONFIG_FILE}:1: listening on 0.0.0.0 but no <Allow> is given" in \
        proc.stdout + proc.stderr


def test_string_format_packed_takes_41_registers_an_element():
    r = region(tag("HoldingRegisters", address="ST9:0", count="2", stringFormat="packed"))
    assert (r.string_format, r.registers_per_item, r.span) == ("packed", 41, 82)
    assert region(tag("InputRegisters", address="ST9:0")).string_format == "ucs2"  # the default
    assert region(tag("InputRegisters", address="ST9:0", stringFormat="UCS2")).registers_per_item == 83


@pytest.mark.parametrize("address, value", [("N7:0", "word"), ("F8:0", "float")])
def test_string_format_only_on_string_regions(address, value):
    text = in_unit(tag("InputRegisters", address=address, stringFormat="packed"))
    problem = only_problem(text)
    assert problem.message == (f"stringFormat applies to a string region (an ST file address); {address} holds "
                               f"{value}s")
    assert where(problem) == locate(text, "stringFormat=")
    problem = only_problem(in_unit(tag("HoldingRegisters", address="ST9:0", stringFormat="ascii")))
    assert problem.message == "stringFormat='ascii': expected 'ucs2' or 'packed'"
