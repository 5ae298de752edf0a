"""The PCCC codec (softplc_lite/cip/pccc.py): every command decoded from the
bytes 1770-6.5.16 lays out and encoded back, the PLC-5 address and the data
type/parameter fields, and what a malformed command is refused with."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from softplc_lite.cip import pccc as P

REQUESTOR = bytes.fromhex("07 0910 09101971")  # length 7, vendor, serial: what pycomm3 sends


def request(cmd: int, fnc: int, body: bytes, tns: int = 0x1234) -> P.PcccRequest:
    return P.PcccRequest.decode(REQUESTOR + bytes((cmd, 0)) + tns.to_bytes(2, "little") + bytes((fnc,)) + body)


def test_a_request_keeps_its_requestor_id_and_tns_for_the_reply():
    r = request(0x0F, 0xA2, bytes.fromhex("14 07 89 00 00"))
    assert (r.requestor, r.cmd, r.tns, r.fnc) == (REQUESTOR, 0x0F, 0x1234, 0xA2)
    assert P.PcccRequest.decode(r.encode()) == r
    ok = P.PcccReply(r.requestor, r.cmd, r.tns, data=b"\x01\x00").encode()
    assert ok[7:] == bytes.fromhex("4f 00 3412 0100")  # CMD | 0x40, STS, TNS, data
    refused = P.PcccReply(r.requestor, r.cmd, r.tns, P.STS_EXTENDED, P.EXT_ACCESS_DENIED, b"ignored").encode()
    assert refused[7:] == bytes.fromhex("4f f0 3412 0b")  # EXT STS after TNS, no data
    assert P.PcccReply.decode(refused).ext == P.EXT_ACCESS_DENIED


@pytest.mark.parametrize("raw", [b"", b"\x07\x01", REQUESTOR + b"\x0f\x00\x01", b"\x03\x01\x00\x0f\x00\x01\x00\xa2"])
def test_a_request_without_a_whole_requestor_id_and_header_is_refused(raw):
    with pytest.raises(P.PcccError) as info:
        P.PcccRequest.decode(raw)
    assert info.value.sts == P.STS_ILLEGAL


def test_slc_typed_read_and_write_with_two_and_three_address_fields():
    three = P.decode_command(request(0x0F, 0xA2, bytes.fromhex("06 04 86 ff 2c01 02")))
    assert three == P.SlcTypedRead(6, P.SlcAddress(4, "T", 300, 2), True)  # element 300: 0xFF then a word
    assert three.encode() == bytes.fromhex("06 04 86 ff 2c01 02")
    two = P.decode_command(request(0x0F, 0xA1, bytes.fromhex("02 07 89 05")))
    assert two == P.SlcTypedRead(2, P.SlcAddress(7, "N", 5, 0), False)
    write = P.decode_command(request(0x0F, 0xAA, bytes.fromhex("04 08 8a 00 00 0000c03f")))
    assert write == P.SlcTypedWrite(4, P.SlcAddress(8, "F", 0, 0), bytes.fromhex("0000c03f"), None, True)
    masked = P.decode_command(request(0x0F, 0xAB, bytes.fromhex("02 03 85 00 00 1000 1000")))
    assert masked.mask == 0x10 and masked.data == b"\x10\x00" and masked.encode() == bytes.fromhex(
        "02 03 85 00 00 1000 1000")
    assert P.decode_command(request(0x0F, 0xA9, bytes.fromhex("02 07 89 01 2a00"))).three_fields is False


def test_both_codes_of_output_and_input_files_are_taken():
    for code, kind in ((0x82, "O"), (0x8B, "O"), (0x83, "I"), (0x8C, "I")):
        assert P.decode_command(request(0x0F, 0xA2, bytes((2, 0, code, 0, 0)))).address.kind == kind
    with pytest.raises(P.PcccError) as info:
        P.decode_command(request(0x0F, 0xA2, bytes.fromhex("02 07 99 00 00")))
    assert (info.value.sts, info.value.ext) == (P.STS_EXTENDED, P.EXT_DATA_TYPE)


def test_plc5_addresses_by_level_mask():
    r = P.Reader(bytes.fromhex("0e 07 ff e803 02"))
    assert P.Plc5Address.read(r) == P.Plc5Address(7, 1000, 2)
    assert P.Plc5Address(7, 1000, 2).encode() == bytes.fromhex("0e 07 ff e803 02")
    assert P.Plc5Address(4, 0).encode() == bytes.fromhex("06 04 00")
    for raw, ext in ((bytes.fromhex("02 07"), P.EXT_TOO_FEW_LEVELS), (bytes.fromhex("16 07 00 00"),
                                                                        P.EXT_TOO_MANY_LEVELS),
                     (bytes.fromhex("07 01 07 00"), P.EXT_NOT_USABLE)):
        with pytest.raises(P.PcccError) as info:
            P.Plc5Address.read(P.Reader(raw))
        assert info.value.ext == ext, raw.hex()


def test_plc5_commands_round_trip():
    commands = [P.WordRangeRead(2, 10, P.Plc5Address(7, 0), 8),
                P.WordRangeWrite(0, 2, P.Plc5Address(7, 3), bytes.fromhex("01000200")),
                P.ReadModifyWrite(((P.Plc5Address(3, 1), 0xFFEF, 0x0010), (P.Plc5Address(3, 2), 0xFFFF, 0x0001))),
                P.TypedRead(0, 4, P.Plc5Address(8, 2), 4),
                P.TypedWrite(0, 1, P.Plc5Address(4, 0, 2), P.DT_INTEGER, 2, b"\x07\x00")]
    fncs = [0x01, 0x00, 0x26, 0x68, 0x67]
    for command, fnc in zip(commands, fncs):
        assert P.decode_command(request(0x0F, fnc, command.encode())) == command


def test_data_type_parameters_short_and_long():
    assert P.encode_type_param(P.DT_INTEGER, 2) == b"\x42"
    assert P.encode_type_param(P.DT_ARRAY, 21) == bytes.fromhex("99 09 15")
    assert P.encode_type_param(P.DT_BCD, 300) == bytes.fromhex("9a 10 2c01")
    for kind, size in ((1, 1), (9, 21), (16, 300), (4, 2)):
        assert P.read_type_param(P.Reader(P.encode_type_param(kind, size))) == (kind, size)


@given(st.integers(0, 0xFFFF), st.integers(0, 0xFFFF), st.integers(0, 0xFFFF))
def test_any_address_fields_round_trip(file, element, sub):
    address = P.Plc5Address(file, element, sub)
    assert P.Plc5Address.read(P.Reader(address.encode())) == address
    slc = P.SlcAddress(file, "N", element, sub)
    assert P.SlcAddress.read(P.Reader(slc.encode(True)), True) == slc


def test_echo_diagnostic_status_and_unknown_commands():
    assert P.decode_command(request(0x06, 0x00, b"ping")) == P.Echo(b"ping")
    assert P.decode_command(request(0x06, 0x03, b"")) == P.DiagnosticStatus()
    for cmd, fnc, body in ((0x0F, 0x99, b""), (0x01, 0x00, b""), (0x06, 0x03, b"x")):
        with pytest.raises(P.PcccError) as info:
            P.decode_command(request(cmd, fnc, body))
        assert info.value.sts == P.STS_ILLEGAL


@pytest.mark.parametrize("fnc, body", [(0xA2, bytes.fromhex("02 07 89 00")), (0xA1, bytes.fromhex("02 07 89 00 00 00")),
                                       (0x01, bytes.fromhex("0000 0100 06 07")), (0x68, bytes.fromhex("0000"))])
def test_a_truncated_or_overlong_command_is_an_illegal_format(fnc, body):
    with pytest.raises(P.PcccError) as info:
        P.decode_command(request(0x0F, fnc, body))
    assert info.value.sts in (P.STS_ILLEGAL, P.STS_EXTENDED)
