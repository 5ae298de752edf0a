"""The Modbus codec (``softplc_lite.modbus``): PDUs, RTU and ASCII framers,
CRC and LRC, checked byte for byte against pymodbus 3.16.1.

A. Every PDU of functions 1, 2, 3, 4, 5, 6, 15, 16, 22, 23 and the exception
   response, requests and responses, with fields drawn by hypothesis within
   the spec's limits: our ``encode()`` equals pymodbus's PDU (function code +
   ``encode()``); our ``decode()`` of pymodbus's bytes gives the fields back;
   pymodbus's decoder reads the same fields from our bytes. The same PDUs in
   whole RTU and ASCII frames for any unit 0..255, both ways; the RTU
   response length from growing prefixes; each request's expected response
   length against the length of pymodbus's normal response.
B. Known vectors: the CRC examples, the ASCII example of the serial-line
   spec (unit 0xF7, read 10 registers from 0x1389), exception responses for
   codes 1..4 of every function; the CRC against a bit-by-bit reference and
   pymodbus's, the LRC against its definition and pymodbus's.
C. Errors: each FrameError kind, each ModbusDecodeError case with its
   exception code, constructors refusing illegal fields.
D. The RTU silent intervals (serial-line spec 2.5.1.1).
E. Where pymodbus departs from the Modbus specification: each case states
   what the specification wants (what we do) and what pymodbus 3.16.1 does.
"""

from __future__ import annotations

import doctest
import importlib
import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from decimal import ROUND_HALF_UP, Decimal

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pymodbus.framer import FramerAscii, FramerRTU
from pymodbus.pdu import DecodePDU, ModbusPDU
from pymodbus.pdu import ExceptionResponse as PmExceptionResponse
from pymodbus.pdu import bit_message as pm_bit
from pymodbus.pdu import register_message as pm_reg

from softplc_lite.modbus import (
    FRAMERS, REQUESTS, RESPONSES, AsciiFramer, ExceptionResponse, FrameError,
    MaskWriteRegisterRequest, MaskWriteRegisterResponse, ModbusDecodeError, ReadCoilsRequest,
    ReadCoilsResponse, ReadDiscreteInputsRequest, ReadDiscreteInputsResponse,
    ReadHoldingRegistersRequest, ReadHoldingRegistersResponse, ReadInputRegistersRequest,
    ReadInputRegistersResponse, ReadWriteMultipleRegistersRequest,
    ReadWriteMultipleRegistersResponse, RtuFramer, WriteMultipleCoilsRequest,
    WriteMultipleCoilsResponse, WriteMultipleRegistersRequest, WriteMultipleRegistersResponse,
    WriteSingleCoilRequest, WriteSingleCoilResponse, WriteSingleRegisterRequest,
    WriteSingleRegisterResponse, bytes_to_registers, crc16, decode_request, decode_response, lrc,
    pack_bits, registers_to_bytes, rtu_intervals_ns, unpack_bits,
)

logging.getLogger("pymodbus").setLevel(logging.CRITICAL)

EXAMPLES = settings(max_examples=60, deadline=None)
FUNCTIONS = (1, 2, 3, 4, 5, 6, 15, 16, 22, 23)
BYTE_COUNT_RESPONSES = (1, 2, 3, 4, 23)  # response: unit, function, byte count, data, CRC

PYMODBUS_DECODERS = {"request": DecodePDU(is_server=True), "response": DecodePDU(is_server=False)}
OUR_DECODERS = {"request": decode_request, "response": decode_response}


def pymodbus_pdu(message: ModbusPDU) -> bytes:
    """pymodbus's PDU: function code + ``encode()`` (what its framers send)."""
    return bytes((message.function_code,)) + message.encode()


# --- A. PDUs and frames against pymodbus -------------------------------------

@dataclass
class Pair:
    """One PDU as ours and as pymodbus's, with the same fields."""

    ours: object
    theirs: ModbusPDU
    their_fields: dict  # what pymodbus's decoder must find in our bytes
    decoded: object = None  # what our decode() gives for pymodbus's bytes, when not ``ours``
    their_response: ModbusPDU | None = None  # for a request: pymodbus's normal response to it


@dataclass
class Case:
    name: str
    side: str  # "request" or "response"
    pairs: Callable[[], st.SearchStrategy[Pair]] = field(repr=False)


REGISTER = st.integers(0, 0xFFFF)


def blocks(max_count: int) -> st.SearchStrategy[tuple[int, int]]:
    """(address, count): 1..max_count items, all within 0..65535."""
    return st.integers(1, max_count).flatmap(lambda n: st.tuples(st.integers(0, 0x10000 - n), st.just(n)))


@st.composite
def bit_lists(draw, min_count: int = 1, max_count: int = 2000) -> list[bool]:
    """Bits drawn as raw bytes (fast for 2000 bits), lowest bit first."""
    count = draw(st.integers(min_count, max_count))
    raw = draw(st.binary(min_size=(count + 7) // 8, max_size=(count + 7) // 8))
    return [bool(raw[i // 8] >> (i % 8) & 1) for i in range(count)]


def register_lists(count: int) -> st.SearchStrategy[list[int]]:
    """``count`` register values, drawn as raw bytes (fast for 125 registers)."""
    return st.binary(min_size=2 * count, max_size=2 * count).map(
        lambda raw: [raw[i] << 8 | raw[i + 1] for i in range(0, len(raw), 2)])


def padded(bits: list[bool]) -> list[bool]:
    """``bits`` and the zero bits up to the end of the last byte."""
    return list(bits) + [False] * (-len(bits) % 8)


@st.composite
def read_requests(draw, ours_class, their_class, max_count, their_response):
    address, count = draw(blocks(max_count))
    return Pair(ours_class(address, count), their_class(address=address, count=count),
                {"address": address, "count": count}, their_response=their_response(count))


@st.composite
def single_coils(draw, ours_class, their_class, their_response=None):
    address, value = draw(st.integers(0, 0xFFFF)), draw(st.booleans())
    return Pair(ours_class(address, value), their_class(address=address, bits=[value]),
                {"address": address, "bits": [value]},
                their_response=their_response and their_response(address=address, bits=[value]))


@st.composite
def single_registers(draw, ours_class, their_class, their_response=None):
    address, value = draw(st.integers(0, 0xFFFF)), draw(REGISTER)
    return Pair(ours_class(address, value), their_class(address=address, registers=[value]),
                {"address": address, "registers": [value]},
                their_response=their_response and their_response(address=address, registers=[value]))


@st.composite
def multiple_coils_requests(draw):
    address, count = draw(blocks(1968))
    bits = draw(bit_lists(count, count))
    return Pair(WriteMultipleCoilsRequest(address, bits),
                pm_bit.WriteMultipleCoilsRequest(address=address, bits=bits),
                {"address": address, "count": count, "bits": bits},
                their_response=pm_bit.WriteMultipleCoilsResponse(address=address, count=count))


@st.composite
def multiple_registers_requests(draw):
    address, count = draw(blocks(123))
    values = draw(register_lists(count))
    return Pair(WriteMultipleRegistersRequest(address, values),
                pm_reg.WriteMultipleRegistersRequest(address=address, registers=values),
                {"address": address, "count": count, "registers": values},
                their_response=pm_reg.WriteMultipleRegistersResponse(address=address, count=count))


@st.composite
def mask_writes(draw, ours_class, their_class, their_response=None):
    address, and_mask, or_mask = draw(st.integers(0, 0xFFFF)), draw(REGISTER), draw(REGISTER)
    fields = {"address": address, "and_mask": and_mask, "or_mask": or_mask}
    return Pair(ours_class(address, and_mask, or_mask), their_class(**fields), fields,
                their_response=their_response and their_response(**fields))


@st.composite
def read_write_requests(draw):
    read_address, read_count = draw(blocks(125))
    write_address, write_count = draw(blocks(121))
    values = draw(register_lists(write_count))
    return Pair(ReadWriteMultipleRegistersRequest(read_address, read_count, write_address, values),
                pm_reg.ReadWriteMultipleRegistersRequest(read_address=read_address, read_count=read_count,
                                                         write_address=write_address, write_registers=values),
                {"read_address": read_address, "read_count": read_count, "write_address": write_address,
                 "write_count": write_count, "write_registers": values},
                their_response=pm_reg.ReadWriteMultipleRegistersResponse(registers=[0] * read_count))


@st.composite
def bits_responses(draw, ours_class, their_class):
    bits = draw(bit_lists())
    return Pair(ours_class(bits), their_class(bits=bits), {"bits": padded(bits)},
                decoded=ours_class(padded(bits)))  # decode gives whole bytes of bits


@st.composite
def registers_responses(draw, ours_class, their_class):
    values = draw(st.integers(1, 125).flatmap(register_lists))
    return Pair(ours_class(values), their_class(registers=values), {"registers": values})


@st.composite
def write_multiple_responses(draw, ours_class, their_class, max_count):
    address, count = draw(blocks(max_count))
    return Pair(ours_class(address, count), their_class(address=address, count=count),
                {"address": address, "count": count})


@st.composite
def exception_responses(draw):
    function, code = draw(st.integers(1, 0x7F)), draw(st.integers(1, 0xFF))
    return Pair(ExceptionResponse(function, code), PmExceptionResponse(function, code),
                {"function_code": function | 0x80, "exception_code": code})


def _zero_bits(cls):
    return lambda count: cls(bits=[False] * count)


def _zero_registers(cls):
    return lambda count: cls(registers=[0] * count)


CASES = [
    Case("fc01 request", "request", lambda: read_requests(
        ReadCoilsRequest, pm_bit.ReadCoilsRequest, 2000, _zero_bits(pm_bit.ReadCoilsResponse))),
    Case("fc02 request", "request", lambda: read_requests(
        ReadDiscreteInputsRequest, pm_bit.ReadDiscreteInputsRequest, 2000,
        _zero_bits(pm_bit.ReadDiscreteInputsResponse))),
    Case("fc03 request", "request", lambda: read_requests(
        ReadHoldingRegistersRequest, pm_reg.ReadHoldingRegistersRequest, 125,
        _zero_registers(pm_reg.ReadHoldingRegistersResponse))),
    Case("fc04 request", "request", lambda: read_requests(
        ReadInputRegistersRequest, pm_reg.ReadInputRegistersRequest, 125,
        _zero_registers(pm_reg.ReadInputRegistersResponse))),
    Case("fc05 request", "request", lambda: single_coils(
        WriteSingleCoilRequest, pm_bit.WriteSingleCoilRequest, pm_bit.WriteSingleCoilResponse)),
    Case("fc06 request", "request", lambda: single_registers(
        WriteSingleRegisterRequest, pm_reg.WriteSingleRegisterRequest, pm_reg.WriteSingleRegisterResponse)),
    Case("fc15 request", "request", multiple_coils_requests),
    Case("fc16 request", "request", multiple_registers_requests),
    Case("fc22 request", "request", lambda: mask_writes(
        MaskWriteRegisterRequest, pm_reg.MaskWriteRegisterRequest, pm_reg.MaskWriteRegisterResponse)),
    Case("fc23 request", "request", read_write_requests),
    Case("fc01 response", "response", lambda: bits_responses(ReadCoilsResponse, pm_bit.ReadCoilsResponse)),
    Case("fc02 response", "response", lambda: bits_responses(
        ReadDiscreteInputsResponse, pm_bit.ReadDiscreteInputsResponse)),
    Case("fc03 response", "response", lambda: registers_responses(
        ReadHoldingRegistersResponse, pm_reg.ReadHoldingRegistersResponse)),
    Case("fc04 response", "response", lambda: registers_responses(
        ReadInputRegistersResponse, pm_reg.ReadInputRegistersResponse)),
    Case("fc05 response", "response", lambda: single_coils(
        WriteSingleCoilResponse, pm_bit.WriteSingleCoilResponse)),
    Case("fc06 response", "response", lambda: single_registers(
        WriteSingleRegisterResponse, pm_reg.WriteSingleRegisterResponse)),
    Case("fc15 response", "response", lambda: write_multiple_responses(
        WriteMultipleCoilsResponse, pm_bit.WriteMultipleCoilsResponse, 1968)),
    Case("fc16 response", "response", lambda: write_multiple_responses(
        WriteMultipleRegistersResponse, pm_reg.WriteMultipleRegistersResponse, 123)),
    Case("fc22 response", "response", lambda: mask_writes(
        MaskWriteRegisterResponse, pm_reg.MaskWriteRegisterResponse)),
    Case("fc23 response", "response", lambda: registers_responses(
        ReadWriteMultipleRegistersResponse, pm_reg.ReadWriteMultipleRegistersResponse)),
    Case("exception response", "response", exception_responses),
]
REQUEST_CASES = [case for case in CASES if case.side == "request"]
RESPONSE_CASES = [case for case in CASES if case.side == "response"]


def test_cases_cover_every_pdu_class():
    covered = {case.name for case in CASES}
    assert covered == {f"fc{fc:02d} {side}" for fc in FUNCTIONS for side in ("request", "response")} | {
        "exception response"}
    assert sorted(REQUESTS) == sorted(RESPONSES) == list(FUNCTIONS)


@pytest.mark.parametrize("case", CASES, ids=lambda case: case.name)
@EXAMPLES
@given(data=st.data())
def test_pdu_matches_pymodbus_both_ways(case, data):
    pair = data.draw(case.pairs())
    theirs = pymodbus_pdu(pair.theirs)
    ours = pair.ours.encode()
    assert ours.hex(" ") == theirs.hex(" ")
    decoded = pair.ours if pair.decoded is None else pair.decoded
    assert type(pair.ours).decode(theirs) == decoded
    assert OUR_DECODERS[case.side](theirs) == decoded
    parsed = PYMODBUS_DECODERS[case.side].decode(ours)
    assert type(parsed).__name__ == type(pair.ours).__name__
    assert {name: getattr(parsed, name) for name in pair.their_fields} == pair.their_fields


@pytest.mark.parametrize("case", CASES, ids=lambda case: case.name)
@EXAMPLES
@given(data=st.data())
def test_frames_match_pymodbus_both_ways(case, data):
    pair, unit = data.draw(case.pairs()), data.draw(st.integers(0, 255))
    pair.theirs.dev_id = unit
    pdu = pair.ours.encode()
    decoder = PYMODBUS_DECODERS[case.side]

    rtu = FramerRTU(decoder).buildFrame(pair.theirs)
    assert RtuFramer.encode(unit, pdu).hex(" ") == rtu.hex(" ")
    assert RtuFramer.decode(rtu) == (unit, pdu)
    assert FramerRTU(decoder).decode(RtuFramer.encode(unit, pdu)) == (len(rtu), unit, 0, pdu)

    ascii_frame = FramerAscii(decoder).buildFrame(pair.theirs)
    assert AsciiFramer.encode(unit, pdu) == ascii_frame  # same case of hex digits, same CR LF
    assert AsciiFramer.decode(ascii_frame) == (unit, pdu)
    assert FramerAscii(decoder).decode(AsciiFramer.encode(unit, pdu)) == (len(ascii_frame), unit, 0, pdu)
    assert AsciiFramer.frame_start(b"\x00" + ascii_frame) == 1
    assert AsciiFramer.frame_end(b"\x00" + ascii_frame + b":01") == len(ascii_frame) + 1


@pytest.mark.parametrize("case", RESPONSE_CASES, ids=lambda case: case.name)
@EXAMPLES
@given(data=st.data())
def test_rtu_response_length_from_growing_prefixes(case, data):
    pair, unit = data.draw(case.pairs()), data.draw(st.integers(0, 255))
    frame = RtuFramer.encode(unit, pair.ours.encode())
    function = frame[1]
    known_from = 3 if function in BYTE_COUNT_RESPONSES else 2  # the byte count, or the function code
    lengths = [RtuFramer.response_length(frame[:k]) for k in range(len(frame) + 1)]
    assert lengths == [None] * known_from + [len(frame)] * (len(frame) + 1 - known_from)
    assert type(pair.theirs).calculateRtuFrameSize(frame) == len(frame)  # pymodbus's own count agrees


@pytest.mark.parametrize("case", REQUEST_CASES, ids=lambda case: case.name)
@EXAMPLES
@given(data=st.data())
def test_expected_response_length_is_pymodbus_normal_response(case, data):
    pair = data.draw(case.pairs())
    response = pymodbus_pdu(pair.their_response)
    assert pair.ours.expected_response_length() == len(response)
    frame = FramerRTU(PYMODBUS_DECODERS["response"]).buildFrame(pair.their_response)
    assert RtuFramer.response_length(frame[:3]) == len(frame) == 3 + len(response)


def test_expected_response_length_examples():
    assert ReadHoldingRegistersRequest(0, 125).expected_response_length() == 2 + 250
    assert ReadCoilsRequest(0, 2000).expected_response_length() == 2 + 250
    assert ReadCoilsRequest(0, 9).expected_response_length() == 2 + 2
    assert WriteSingleCoilRequest(0, True).expected_response_length() == 5
    assert WriteMultipleRegistersRequest(0, [1, 2]).expected_response_length() == 5
    assert MaskWriteRegisterRequest(0, 0xF2, 0x25).expected_response_length() == 7
    assert ReadWriteMultipleRegistersRequest(3, 6, 14, [0xFF] * 3).expected_response_length() == 14


@pytest.mark.parametrize("function", FUNCTIONS)
@pytest.mark.parametrize("code", [1, 2, 3, 4])
def test_exception_responses_both_ways(function, code):
    theirs = PmExceptionResponse(function, code)
    theirs.dev_id = 7
    ours = ExceptionResponse(function, code)
    assert ours.encode() == pymodbus_pdu(theirs) == bytes((function | 0x80, code))
    assert decode_response(pymodbus_pdu(theirs)) == ours
    parsed = PYMODBUS_DECODERS["response"].decode(ours.encode())
    assert (parsed.function_code, parsed.exception_code) == (function | 0x80, code)
    frame = FramerRTU(PYMODBUS_DECODERS["response"]).buildFrame(theirs)
    assert RtuFramer.encode(7, ours.encode()) == frame and len(frame) == 5
    assert RtuFramer.response_length(frame[:2]) == 5
    ascii_frame = FramerAscii(PYMODBUS_DECODERS["response"]).buildFrame(theirs)
    assert ascii_frame == AsciiFramer.encode(7, ours.encode())
    assert ours.name == ("ILLEGAL FUNCTION", "ILLEGAL DATA ADDRESS", "ILLEGAL DATA VALUE",
                         "SLAVE DEVICE FAILURE")[code - 1]


# --- B. known vectors and check sums --------------------------------------------

def test_known_rtu_vectors():
    request = ReadHoldingRegistersRequest(0, 0x7D)
    assert crc16(bytes.fromhex("02 03 00 00 00 7D")) == 0xD885
    assert RtuFramer.encode(2, request.encode()) == bytes.fromhex("02 03 00 00 00 7D 85 D8")
    assert RtuFramer.decode(bytes.fromhex("02 03 00 00 00 7D 85 D8")) == (2, bytes.fromhex("03 00 00 00 7D"))
    theirs = pm_reg.ReadHoldingRegistersRequest(address=0, count=0x7D, dev_id=2)
    assert FramerRTU(PYMODBUS_DECODERS["request"]).buildFrame(theirs) == bytes.fromhex(
        "02 03 00 00 00 7D 85 D8")
    assert RtuFramer.encode(1, ReadHoldingRegistersRequest(0, 10).encode()) == bytes.fromhex(
        "01 03 00 00 00 0A C5 CD")


def test_serial_line_spec_ascii_example():
    data = bytes.fromhex("F7 03 13 89 00 0A")
    total = 0xF7 + 0x03 + 0x13 + 0x89 + 0x00 + 0x0A
    assert total == 0x1A0 and (0x100 - (total & 0xFF)) & 0xFF == 0x60  # the LRC by hand
    assert lrc(data) == 0x60
    frame = b":F7031389000A60\r\n"
    request = ReadHoldingRegistersRequest(0x1389, 10)
    assert AsciiFramer.encode(0xF7, request.encode()) == frame
    assert AsciiFramer.decode(frame) == (0xF7, request.encode())
    assert AsciiFramer.decode(frame.lower()) == (0xF7, request.encode())  # lower-case hex accepted
    theirs = pm_reg.ReadHoldingRegistersRequest(address=0x1389, count=10, dev_id=0xF7)
    assert FramerAscii(PYMODBUS_DECODERS["request"]).buildFrame(theirs) == frame


def bitwise_crc16(data: bytes) -> int:
    """The CRC as the serial-line spec's Appendix B describes it, bit by bit."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


@EXAMPLES
@given(data=st.binary(max_size=300), split=st.integers(0, 300))
def test_crc16_against_bitwise_reference_and_pymodbus(data, split):
    assert crc16(data) == bitwise_crc16(data)
    swapped = FramerRTU.compute_CRC(data)  # pymodbus gives the CRC byte-swapped
    assert crc16(data) == ((swapped & 0xFF) << 8 | swapped >> 8)
    assert crc16(data[split:], crc16(data[:split])) == crc16(data)


@EXAMPLES
@given(data=st.binary(max_size=300))
def test_lrc_against_definition_and_pymodbus(data):
    assert lrc(data) == (256 - sum(data) % 256) % 256
    assert (sum(data) + lrc(data)) % 256 == 0
    assert lrc(data) == FramerAscii.compute_LRC(data)


@EXAMPLES
@given(bits=bit_lists(0, 2000), extra=st.integers(0, 7))
def test_pack_and_unpack_bits(bits, extra):
    packed = pack_bits(bits)
    assert packed == pm_bit.pack_bitstring(bits)
    assert unpack_bits(packed, len(bits)) == bits
    assert unpack_bits(packed, 8 * len(packed)) == padded(bits)
    with pytest.raises(ValueError):
        unpack_bits(packed, 8 * len(packed) + 1 + extra)


@EXAMPLES
@given(values=st.lists(st.integers(-0x8000, 0xFFFF), max_size=130))
def test_registers_to_and_from_bytes(values):
    unsigned = [value & 0xFFFF for value in values]
    data = registers_to_bytes(values)
    assert data == b"".join(value.to_bytes(2, "big") for value in unsigned)
    assert list(bytes_to_registers(data)) == unsigned
    assert bytes_to_registers(data).typecode == "H"
    assert registers_to_bytes(iter(values)) == data


def test_packing_refuses_bad_input():
    with pytest.raises(ValueError):
        registers_to_bytes([0x10000])
    with pytest.raises(ValueError):
        registers_to_bytes([-0x8001, 5])
    with pytest.raises(ValueError):
        bytes_to_registers(b"\x00\x01\x02")
    with pytest.raises(ValueError):
        unpack_bits(b"\x00", -1)


@pytest.mark.parametrize("name", ["crc", "errors", "packing", "request_pdus", "response_pdus", "pdu",
                                  "framing", ""])
def test_module_doctests(name):
    module = importlib.import_module("softplc_lite.modbus" + (f".{name}" if name else ""))
    assert module.__doc__ and "Specification" in module.__doc__
    result = doctest.testmod(module)
    assert result.attempted > 0 and result.failed == 0


# --- C. errors ------------------------------------------------------------------------

FRAME_ERRORS = [
    pytest.param(RtuFramer.decode, b"\x02\x03\x85", "short", "at least 4", id="rtu 3 bytes"),
    pytest.param(RtuFramer.decode, b"", "short", "at least 4", id="rtu empty"),
    pytest.param(RtuFramer.decode, bytes.fromhex("02 03 00 00 00 7D 85 D9"), "crc", "0xd985 sent, 0xd885",
                 id="rtu crc"),
    pytest.param(RtuFramer.decode, bytes.fromhex("02 03 00 00 00 7D D8 85"), "crc", "0x85d8 sent",
                 id="rtu crc high byte first"),
    pytest.param(AsciiFramer.decode, b":F7031389000A61\r\n", "lrc", "0x61 sent, 0x60", id="ascii lrc"),
    pytest.param(AsciiFramer.decode, b":0103\r\n", "short", "at least 3", id="ascii 2 bytes"),
    pytest.param(AsciiFramer.decode, b":\r\n", "short", "at least 3", id="ascii nothing"),
    pytest.param(AsciiFramer.decode, b"", "short", "empty", id="ascii empty"),
    pytest.param(AsciiFramer.decode, b"F7031389000A60\r\n", "format", "starts with ':'", id="ascii no colon"),
    pytest.param(AsciiFramer.decode, b":F7031389000A60\r", "format", "CR LF", id="ascii no LF"),
    pytest.param(AsciiFramer.decode, b":F7031389000A60\n", "format", "CR LF", id="ascii no CR"),
    pytest.param(AsciiFramer.decode, b":F7031389000A60", "format", "CR LF", id="ascii no CR LF"),
    pytest.param(AsciiFramer.decode, b":F7031389000G60\r\n", "format", "other than hex", id="ascii non-hex"),
    pytest.param(AsciiFramer.decode, b":F7 03 13 89 00 0A 60\r\n", "format", "other than hex",
                 id="ascii spaces"),
    pytest.param(AsciiFramer.decode, b":F7031389000A600\r\n", "format", "odd number", id="ascii odd digits"),
]


@pytest.mark.parametrize("decode,frame,kind,words", FRAME_ERRORS)
def test_frame_errors(decode, frame, kind, words):
    with pytest.raises(FrameError) as caught:
        decode(frame)
    assert caught.value.kind == kind
    assert isinstance(caught.value, ValueError) and str(caught.value).startswith(kind)
    assert words in str(caught.value)


def test_frame_error_kinds():
    assert FrameError.KINDS == ("crc", "lrc", "short", "format")
    with pytest.raises(ValueError):
        FrameError("parity", "not a kind of ours")


def test_ascii_frame_start_and_end_wait_for_a_whole_frame():
    assert AsciiFramer.frame_start(b"garbage") is None
    assert AsciiFramer.frame_start(b"ab:01") == 2
    assert AsciiFramer.frame_end(b"\r\n:0103") is None  # a CR LF before the ':' does not count
    assert AsciiFramer.frame_end(b"ab:0103\r") is None
    assert AsciiFramer.frame_end(b"ab:0103\r\n:02") == 9
    assert AsciiFramer.frame_end(b"") is None


def ten(n: int) -> str:
    return " 00" * n


DECODE_ERRORS = [
    # quantity 0
    ("01 0000 0000", decode_request, 3), ("02 0000 0000", decode_request, 3),
    ("03 0000 0000", decode_request, 3), ("04 0000 0000", decode_request, 3),
    ("0F 0000 0000 00", decode_request, 3), ("10 0000 0000 00", decode_request, 3),
    ("17 0000 0000 0000 0001 02 0000", decode_request, 3), ("17 0000 0001 0000 0000 00", decode_request, 3),
    ("0F 0000 0000 00", decode_response, 3), ("10 0000 0000", decode_response, 3),
    # quantity above the limit
    ("01 0000 07D1", decode_request, 3), ("02 0000 07D1", decode_request, 3),
    ("03 0000 007E", decode_request, 3), ("04 0000 007E", decode_request, 3),
    ("0F 0000 07B1 F7" + ten(247), decode_request, 3), ("10 0000 007C F8" + ten(248), decode_request, 3),
    ("17 0000 007E 0000 0001 02 0000", decode_request, 3),
    ("17 0000 0001 0000 007A F4" + ten(244), decode_request, 3),
    ("0F 0000 07B1", decode_response, 3), ("10 0000 007C", decode_response, 3),
    ("01 FB" + ten(251), decode_response, 3), ("03 FC" + ten(252), decode_response, 3),
    # byte count that does not match the quantity, or the bytes sent
    ("0F 0000 000A 01 FF", decode_request, 3), ("0F 0000 000A 03 FF 03 00", decode_request, 3),
    ("0F 0000 000A 02 FF", decode_request, 3), ("10 0000 0002 03 0001 00", decode_request, 3),
    ("10 0000 0002 04 0001", decode_request, 3), ("17 0000 0001 0000 0002 02 0001", decode_request, 3),
    ("17 0000 0001 0000 0001 02 0001 00", decode_request, 3),
    ("01 02 05", decode_response, 3), ("01 00", decode_response, 3), ("01 01 05 00", decode_response, 3),
    ("03 03 0001 02", decode_response, 3), ("03 00", decode_response, 3), ("03 04 0001", decode_response, 3),
    ("17 02 0001 02", decode_response, 3),
    # wrong length
    ("03 0000 0001 00", decode_request, 3), ("03 0000 00", decode_request, 3),
    ("06 0001 00", decode_request, 3), ("05", decode_request, 3), ("16 0000 00F2", decode_request, 3),
    ("10 0000 0001 02 0001 00", decode_request, 3), ("0F 0000 0008", decode_request, 3),
    ("05 0000 FF00 00", decode_response, 3), ("10 0000 0001 00", decode_response, 3),
    ("83 02 00", decode_response, 3), ("83", decode_response, 3), ("01", decode_response, 3),
    # coil value neither 0xFF00 nor 0x0000
    ("05 0000 1234", decode_request, 3), ("05 0000 00FF", decode_request, 3),
    ("05 0000 0001", decode_request, 3), ("05 0000 1234", decode_response, 3),
    # exception code 0
    ("83 00", decode_response, 3),
    # unknown function (or none)
    ("07", decode_request, 1), ("2B 0E 01 00", decode_request, 1), ("41 0000", decode_request, 1),
    ("00", decode_request, 1), ("83 02", decode_request, 1), ("", decode_request, 1),
    ("07 00", decode_response, 1), ("80 01", decode_response, 1), ("", decode_response, 1),
    # address + quantity past 65535
    ("01 FFFF 0002", decode_request, 2), ("03 FF84 007D", decode_request, 2),
    ("0F F851 07B0 F6" + ten(246), decode_request, 2), ("10 FFFF 0002 04 0001 0002", decode_request, 2),
    ("17 FFFF 0002 0000 0001 02 0001", decode_request, 2),
    ("17 0000 0001 FFFF 0002 04 0001 0002", decode_request, 2),
    ("0F FFFF 0002", decode_response, 2),
]


@pytest.mark.parametrize("pdu_hex,decode,code", DECODE_ERRORS,
                         ids=[f"{decode.__name__} {pdu_hex[:24]}" for pdu_hex, decode, _ in DECODE_ERRORS])
def test_decode_errors(pdu_hex, decode, code):
    with pytest.raises(ModbusDecodeError) as caught:
        decode(bytes.fromhex(pdu_hex))
    assert caught.value.exception_code == code
    assert isinstance(caught.value, ValueError) and f"(exception {code:02X} " in str(caught.value)


def test_decode_limits_are_inclusive():
    assert decode_request(bytes.fromhex("01 0000 07D0")) == ReadCoilsRequest(0, 2000)
    assert decode_request(bytes.fromhex("03 FF83 007D")) == ReadHoldingRegistersRequest(0xFF83, 125)
    assert decode_request(bytes.fromhex("0F 0000 07B0 F6" + ten(246))) == WriteMultipleCoilsRequest(
        0, [False] * 1968)
    assert decode_request(bytes.fromhex("10 0000 007B F6" + ten(246))) == WriteMultipleRegistersRequest(
        0, [0] * 123)
    assert decode_request(bytes.fromhex("17 0000 007D 0000 0079 F2" + ten(242))) == (
        ReadWriteMultipleRegistersRequest(0, 125, 0, [0] * 121))
    assert decode_response(bytes.fromhex("01 FA" + ten(250))) == ReadCoilsResponse([False] * 2000)
    assert decode_response(bytes.fromhex("03 FA" + ten(250))) == ReadHoldingRegistersResponse([0] * 125)


CONSTRUCTOR_ERRORS = [
    lambda: ReadCoilsRequest(0, 0), lambda: ReadCoilsRequest(0, 2001), lambda: ReadCoilsRequest(-1, 1),
    lambda: ReadCoilsRequest(0x10000, 1), lambda: ReadCoilsRequest(0xFFFF, 2),
    lambda: ReadDiscreteInputsRequest(0, 2001), lambda: ReadHoldingRegistersRequest(0, 126),
    lambda: ReadInputRegistersRequest(0, 0), lambda: ReadHoldingRegistersRequest(1.0, 1),
    lambda: WriteSingleCoilRequest(0, 2), lambda: WriteSingleCoilRequest(0x10000, True),
    lambda: WriteSingleCoilResponse(0, 0xFF00),
    lambda: WriteSingleRegisterRequest(0, 0x10000), lambda: WriteSingleRegisterRequest(0, -1),
    lambda: WriteSingleRegisterResponse(-1, 0),
    lambda: WriteMultipleCoilsRequest(0, ()), lambda: WriteMultipleCoilsRequest(0, [True] * 1969),
    lambda: WriteMultipleCoilsRequest(0xFFFF, [True, True]),
    lambda: WriteMultipleRegistersRequest(0, ()), lambda: WriteMultipleRegistersRequest(0, [0] * 124),
    lambda: WriteMultipleRegistersRequest(0, [0x10000]), lambda: WriteMultipleRegistersRequest(0, [-1]),
    lambda: WriteMultipleRegistersRequest(0, [1.5]),
    lambda: MaskWriteRegisterRequest(0, 0x10000, 0), lambda: MaskWriteRegisterResponse(0, 0, -1),
    lambda: ReadWriteMultipleRegistersRequest(0, 0, 0, [1]),
    lambda: ReadWriteMultipleRegistersRequest(0, 126, 0, [1]),
    lambda: ReadWriteMultipleRegistersRequest(0, 1, 0, ()),
    lambda: ReadWriteMultipleRegistersRequest(0, 1, 0, [1] * 122),
    lambda: ReadWriteMultipleRegistersRequest(0, 1, 0xFFFF, [1, 2]),
    lambda: ReadCoilsResponse(()), lambda: ReadCoilsResponse([True] * 2001),
    lambda: ReadHoldingRegistersResponse(()), lambda: ReadInputRegistersResponse([0] * 126),
    lambda: ReadWriteMultipleRegistersResponse([0x10000]),
    lambda: WriteMultipleCoilsResponse(0, 1969), lambda: WriteMultipleRegistersResponse(0, 124),
    lambda: WriteMultipleRegistersResponse(0xFFFF, 2),
    lambda: ExceptionResponse(0, 1), lambda: ExceptionResponse(0x80, 1), lambda: ExceptionResponse(3, 0),
    lambda: ExceptionResponse(3, 256),
    lambda: RtuFramer.encode(256, b"\x03"), lambda: RtuFramer.encode(-1, b"\x03"),
    lambda: RtuFramer.encode(1, b""), lambda: RtuFramer.encode(1, b"\x03" * 254),
    lambda: AsciiFramer.encode(256, b"\x03"), lambda: AsciiFramer.encode(1, b""),
]


@pytest.mark.parametrize("build", CONSTRUCTOR_ERRORS, ids=range(len(CONSTRUCTOR_ERRORS)))
def test_constructors_refuse_illegal_fields(build):
    with pytest.raises(ValueError) as caught:
        build()
    assert not isinstance(caught.value, (ModbusDecodeError, FrameError))


def test_constructor_limits_are_inclusive_and_pdus_are_values():
    assert len(WriteMultipleCoilsRequest(0xFFFF - 1967, [True] * 1968).encode()) == 6 + 246
    assert len(WriteMultipleRegistersRequest(0, [0xFFFF] * 123).encode()) == 6 + 246
    assert len(ReadWriteMultipleRegistersRequest(0xFF83, 125, 0xFF87, [1] * 121).encode()) == 10 + 242
    assert len(RtuFramer.encode(255, b"\x03" * 253)) == 256
    request = WriteMultipleRegistersRequest(5, [1, 2, 3])
    assert request.values == (1, 2, 3) and request.count == 3
    assert request == WriteMultipleRegistersRequest(5, (1, 2, 3)) and hash(request) == hash(
        WriteMultipleRegistersRequest(5, (1, 2, 3)))
    assert WriteSingleCoilRequest(1, True) != WriteSingleCoilResponse(1, True)  # same fields, other PDU
    with pytest.raises(AttributeError):
        request.address = 6  # frozen


def test_class_constants_and_tables():
    assert (ReadCoilsRequest.MAX_COUNT, ReadHoldingRegistersRequest.MAX_COUNT) == (2000, 125)
    assert (WriteMultipleCoilsRequest.MAX_COUNT, WriteMultipleRegistersRequest.MAX_COUNT) == (1968, 123)
    assert (ReadWriteMultipleRegistersRequest.MAX_READ_COUNT,
            ReadWriteMultipleRegistersRequest.MAX_WRITE_COUNT) == (125, 121)
    assert all(cls.function_code == fc for table in (REQUESTS, RESPONSES) for fc, cls in table.items())
    assert all(cls.__name__.endswith("Request") for cls in REQUESTS.values())
    assert all(cls.__name__.endswith("Response") for cls in RESPONSES.values())
    assert FRAMERS == {"RTU": RtuFramer, "ASCII": AsciiFramer}
    assert (RtuFramer.name, AsciiFramer.name) == ("RTU", "ASCII")


@pytest.mark.parametrize("prefix_hex,length", [
    ("", None), ("02", None), ("02 01", None), ("02 03", None), ("02 17", None),
    ("02 01 01", 6), ("02 02 FA", 255), ("02 03 02", 7), ("02 04 FA", 255), ("02 17 04", 9),
    ("02 05", 8), ("02 06", 8), ("02 0F", 8), ("02 10", 8), ("02 16", 10),
    ("02 81", 5), ("02 83 02", 5), ("02 90", 5), ("02 96", 5), ("02 FF", 5),
    ("02 07", None), ("02 2B 0E", None), ("02 00", None),
])
def test_rtu_response_length_examples(prefix_hex, length):
    assert RtuFramer.response_length(bytes.fromhex(prefix_hex)) == length


# --- D. RTU silent intervals ------------------------------------------------------------

def half_up(value: Decimal) -> int:
    return int(value.quantize(Decimal(1), rounding=ROUND_HALF_UP))


def char_time_ns(baudrate: int, bits: int) -> int:
    return half_up(Decimal(bits * 10**9) / baudrate)


def test_rtu_intervals_at_9600():
    char_ns = char_time_ns(9600, 10)
    assert char_ns == 1_041_667
    t15, t35 = half_up(Decimal(char_ns) * Decimal("1.5")), half_up(Decimal(char_ns) * Decimal("3.5"))
    assert (t15, t35) == (1_562_501, 3_645_835)  # 1562500.5 and 3645834.5, rounded up
    assert rtu_intervals_ns(9600, char_ns) == (t15, t35)


@pytest.mark.parametrize("baudrate", [1200, 2400, 4800, 9600, 19200])
@pytest.mark.parametrize("bits", [10, 11])
def test_rtu_intervals_use_character_times_up_to_19200(baudrate, bits):
    char_ns = char_time_ns(baudrate, bits)
    expected = (half_up(Decimal(char_ns) * Decimal("1.5")), half_up(Decimal(char_ns) * Decimal("3.5")))
    assert rtu_intervals_ns(baudrate, char_ns) == expected
    assert expected != (750_000, 1_750_000)


@pytest.mark.parametrize("baudrate", [19201, 38400, 57600, 115200, 921600])
def test_rtu_intervals_are_fixed_above_19200(baudrate):
    assert rtu_intervals_ns(baudrate, char_time_ns(baudrate, 11)) == (750_000, 1_750_000)


@EXAMPLES
@given(char_ns=st.integers(1, 10**10))
def test_rtu_intervals_round_half_up(char_ns):
    t15, t35 = rtu_intervals_ns(19200, char_ns)
    assert t15 == half_up(Decimal(char_ns) * Decimal("1.5"))
    assert t35 == half_up(Decimal(char_ns) * Decimal("3.5"))


@pytest.mark.parametrize("baudrate,char_ns", [(0, 1000), (-9600, 1000), (9600, 0), (9600, 1.5)])
def test_rtu_intervals_refuse_nonsense(baudrate, char_ns):
    with pytest.raises(ValueError):
        rtu_intervals_ns(baudrate, char_ns)


# --- E. where pymodbus 3.16.1 departs from the specification -------------------------------

def test_fc15_quantity_limit_is_1968_pymodbus_encodes_up_to_2000():
    # Spec 6.11: quantity of outputs 1..0x07B0 (1968), so that the PDU stays within 253 bytes.
    with pytest.raises(ValueError):
        WriteMultipleCoilsRequest(0, [True] * 1969)
    # pymodbus: MAX_COUNT = 2000; 2000 coils make a 256-byte PDU (a 259-byte RTU frame).
    theirs = pymodbus_pdu(pm_bit.WriteMultipleCoilsRequest(address=0, bits=[True] * 2000))
    assert len(theirs) == 256
    # Decoding pymodbus's 1969 coils: exception 03 (spec); pymodbus's decoder accepts it.
    theirs = pymodbus_pdu(pm_bit.WriteMultipleCoilsRequest(address=0, bits=[True] * 1969))
    with pytest.raises(ModbusDecodeError) as caught:
        decode_request(theirs)
    assert caught.value.exception_code == 3
    assert PYMODBUS_DECODERS["request"].decode(theirs).count == 1969


def test_fc16_quantity_limit_is_1_to_123_pymodbus_encodes_0_and_124():
    # Spec 6.12: quantity of registers 1..0x007B (123).
    for values in ([], [1] * 124):
        with pytest.raises(ValueError):
            WriteMultipleRegistersRequest(0, values)
    # pymodbus encodes both without complaint (its decoder takes them too; its
    # server answers exception 03 later, when executing).
    assert pymodbus_pdu(pm_reg.WriteMultipleRegistersRequest(address=0, registers=[])) == bytes.fromhex(
        "10 0000 0000 00")
    theirs = pymodbus_pdu(pm_reg.WriteMultipleRegistersRequest(address=0, registers=[1] * 124))
    assert len(theirs) == 254
    with pytest.raises(ModbusDecodeError) as caught:
        decode_request(theirs)
    assert caught.value.exception_code == 3
    assert PYMODBUS_DECODERS["request"].decode(theirs).count == 124


def test_fc05_value_must_be_ff00_or_0000_pymodbus_takes_any_nonzero_as_on():
    # Spec 6.5: the output value is 0xFF00 (ON) or 0x0000 (OFF); anything else is exception 03.
    pdu = bytes.fromhex("05 0000 1234")
    with pytest.raises(ModbusDecodeError) as caught:
        decode_request(pdu)
    assert caught.value.exception_code == 3
    # pymodbus decodes it as ON (and its server writes the coil ON).
    assert PYMODBUS_DECODERS["request"].decode(pdu).bits == [True]


def test_fc23_write_quantity_limit_is_121_pymodbus_decoder_checks_125():
    # Spec 6.17: quantity to write 1..0x0079 (121).
    pdu = bytes.fromhex("17 0000 0001 0000 007A F4") + bytes(244)
    with pytest.raises(ModbusDecodeError) as caught:
        decode_request(pdu)
    assert caught.value.exception_code == 3
    # pymodbus's decode() checks the write count against MAX_READ_COUNT (125) and accepts 122.
    assert PYMODBUS_DECODERS["request"].decode(pdu).write_count == 122


def test_address_plus_quantity_past_65535_pymodbus_encodes_and_decodes_it():
    # Spec 4.4 / flow chart of 6.1: addresses 0..65535; start + quantity past the end
    # is exception 02. We refuse to build it and answer 02 when decoding it.
    with pytest.raises(ValueError):
        ReadCoilsRequest(0xFFFF, 2)
    theirs = pymodbus_pdu(pm_bit.ReadCoilsRequest(address=0xFFFF, count=2))
    assert theirs == bytes.fromhex("01 FFFF 0002")  # pymodbus builds it
    with pytest.raises(ModbusDecodeError) as caught:
        decode_request(theirs)
    assert caught.value.exception_code == 2
    parsed = PYMODBUS_DECODERS["request"].decode(theirs)
    assert (parsed.address, parsed.count) == (0xFFFF, 2)


def test_pdu_length_is_exact_pymodbus_ignores_trailing_bytes():
    # Spec 6.3: a read request is exactly 5 bytes; a longer one is malformed (exception 03).
    pdu = bytes.fromhex("03 0000 0001 00")
    with pytest.raises(ModbusDecodeError) as caught:
        decode_request(pdu)
    assert caught.value.exception_code == 3
    parsed = PYMODBUS_DECODERS["request"].decode(pdu)  # pymodbus reads the first 5 bytes
    assert (parsed.address, parsed.count) == (0, 1)


def test_response_byte_count_must_match_pymodbus_does_not_check():
    # Spec 6.3 / 6.1: byte count 2 x N registers, and N bytes of bits follow the byte count.
    odd = bytes.fromhex("03 03 0001 02")
    short = bytes.fromhex("01 02 05")
    for pdu in (odd, short):
        with pytest.raises(ModbusDecodeError):
            decode_response(pdu)
    assert PYMODBUS_DECODERS["response"].decode(odd).registers == [1]  # the odd byte dropped
    assert PYMODBUS_DECODERS["response"].decode(short).bits == [True, False, True] + [False] * 5
