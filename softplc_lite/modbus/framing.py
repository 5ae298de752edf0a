"""Modbus serial-line framers: RTU and ASCII frames (ADUs) around a PDU.

Follows "Modbus over Serial Line Specification and Implementation Guide
V1.02": the serial ADU (address + PDU + check, 256 bytes at most), section
2.3; RTU framing and its silent intervals, section 2.5.1.1; the RTU CRC,
2.5.1.2; ASCII framing (':' + hex digits + CR LF), section 2.5.2.1; the
ASCII LRC, 2.5.2.2 (both check sums in ``crc``).

Framers know nothing of what a PDU means, except ``RtuFramer.response_length``,
which tells from the first bytes of a response how long it is (RTU has no end
marker). Pure functions of bytes: reading a port, timing the silences and
retrying are the caller's.

>>> RtuFramer.encode(2, bytes.fromhex("03 00 00 00 7D")).hex(" ")
'02 03 00 00 00 7d 85 d8'
>>> AsciiFramer.encode(0xF7, bytes.fromhex("03 13 89 00 0A"))
b':F7031389000A60\\r\\n'
>>> AsciiFramer.decode(b":F7031389000A60\\r\\n")
(247, b'\\x03\\x13\\x89\\x00\\n')
"""

from __future__ import annotations

import binascii
from collections.abc import Mapping
from types import MappingProxyType
from typing import ClassVar

from ._fields import MAX_PDU_LENGTH  # section 2.3: a 256-byte ADU - address - CRC
from .crc import crc16, lrc

__all__ = [
    "FrameError", "RtuFramer", "AsciiFramer", "FRAMERS", "rtu_intervals_ns",
    "RTU_FIXED_T1_5_NS", "RTU_FIXED_T3_5_NS", "RTU_FIXED_INTERVALS_ABOVE_BAUD",
]


class FrameError(ValueError):
    """A frame that cannot be taken apart; ``kind`` says why:

    - "crc": RTU CRC mismatch;
    - "lrc": ASCII LRC mismatch;
    - "short": too short to be a frame;
    - "format": ASCII frame not starting with ':' or not ending with CR LF,
      with characters other than hex digits, or with an odd number of them.
    """

    KINDS = ("crc", "lrc", "short", "format")

    def __init__(self, kind: str, message: str) -> None:
        if kind not in self.KINDS:
            raise ValueError(f"FrameError kind must be one of {', '.join(self.KINDS)}, not {kind!r}")
        super().__init__(f"{kind}: {message}")
        self.kind = kind


def _check_unit_and_pdu(unit: int, pdu: bytes) -> None:
    if not isinstance(unit, int) or not 0 <= unit <= 255:
        raise ValueError(f"unit must be an integer 0..255, not {unit!r}")
    if not 1 <= len(pdu) <= MAX_PDU_LENGTH:
        raise ValueError(f"a PDU has 1..{MAX_PDU_LENGTH} bytes, not {len(pdu)}")


def rtu_adu(unit: int, pdu: bytes) -> bytes:
    """Unit, PDU and CRC, unchecked: ``RtuFramer.encode`` after its checks,
    and a test peer's frames that a slave must refuse (a PDU too long)."""
    frame = bytes((unit,)) + bytes(pdu)
    return frame + crc16(frame).to_bytes(2, "little")


class RtuFramer:
    """RTU frames (section 2.5.1.1): unit address, PDU, CRC low byte first.

    >>> RtuFramer.decode(bytes.fromhex("02 03 00 00 00 7D 85 D8"))
    (2, b'\\x03\\x00\\x00\\x00}')
    >>> RtuFramer.response_length(bytes.fromhex("02 03 FA"))  # 250 data bytes
    255
    """

    name = "RTU"
    MIN_ADU_LENGTH = 4  # unit, function code, CRC
    MAX_ADU_LENGTH = 256

    # Response lengths (whole ADU): functions answering a byte count, then data ...
    BYTE_COUNT_FUNCTIONS = frozenset({1, 2, 3, 4, 23})
    # ... and functions whose response has a fixed length.
    FIXED_RESPONSE_LENGTHS: ClassVar[Mapping[int, int]] = MappingProxyType(
        {5: 8, 6: 8, 15: 8, 16: 8, 22: 10})
    EXCEPTION_RESPONSE_LENGTH = 5  # unit, function | 0x80, exception code, CRC

    @staticmethod
    def encode(unit: int, pdu: bytes) -> bytes:
        """The RTU ADU of ``pdu`` for ``unit`` (0 broadcast, 1..247, or up to 255)."""
        _check_unit_and_pdu(unit, pdu)
        return rtu_adu(unit, pdu)

    @staticmethod
    def decode(adu: bytes) -> tuple[int, bytes]:
        """(unit, PDU) of a whole RTU ADU; FrameError "short" below 4 bytes,
        "crc" when the CRC does not match."""
        if len(adu) < RtuFramer.MIN_ADU_LENGTH:
            raise FrameError("short", f"an RTU frame has at least 4 bytes, not {len(adu)}")
        sent = adu[-2] | adu[-1] << 8
        computed = crc16(adu[:-2])
        if sent != computed:
            raise FrameError("crc", f"CRC {sent:#06x} sent, {computed:#06x} computed")
        return adu[0], bytes(adu[1:-2])

    @staticmethod
    def response_length(prefix: bytes) -> int | None:
        """The length of the RTU *response* ADU starting with ``prefix`` (unit,
        function code, ...), or None while it cannot be told yet (fewer than 2
        bytes; a byte-count response before its byte count) or at all (a
        function not known here).

        >>> prefixes = ("02", "02 03", "02 03 04", "02 83", "02 10", "02 16", "02 2B")
        >>> [RtuFramer.response_length(bytes.fromhex(prefix)) for prefix in prefixes]
        [None, None, 9, 5, 8, 10, None]
        """
        if len(prefix) < 2:
            return None
        function = prefix[1]
        if function & 0x80:
            return RtuFramer.EXCEPTION_RESPONSE_LENGTH
        if function in RtuFramer.BYTE_COUNT_FUNCTIONS:
            return 5 + prefix[2] if len(prefix) >= 3 else None  # unit, function, count, data, CRC
        return RtuFramer.FIXED_RESPONSE_LENGTHS.get(function)


class AsciiFramer:
    """ASCII frames (section 2.5.2.1): ':', then unit, PDU and LRC as two
    upper-case hex digits a byte, then CR LF. ``decode`` also accepts
    lower-case hex digits.

    >>> AsciiFramer.frame_end(b"..:0103\\r\\n:01")
    9
    """

    name = "ASCII"
    START = b":"
    END = b"\r\n"
    MAX_FRAME_LENGTH = 513  # ':' + 2 * (unit + 253-byte PDU + LRC) + CR LF

    @staticmethod
    def encode(unit: int, pdu: bytes) -> bytes:
        """The ASCII frame of ``pdu`` for ``unit``, ':' to CR LF."""
        _check_unit_and_pdu(unit, pdu)
        data = bytes((unit,)) + bytes(pdu)
        return b":" + (data + bytes((lrc(data),))).hex().upper().encode("ascii") + b"\r\n"

    @staticmethod
    def decode(frame: bytes) -> tuple[int, bytes]:
        """(unit, PDU) of a whole frame, ':' to CR LF inclusive. FrameError
        "short" for an empty frame or fewer than 3 bytes (unit, function
        code, LRC) between the delimiters, "format" for a missing ':' or CR
        LF, odd or non-hex digits (checked in that order, before the length),
        "lrc" when the LRC does not match."""
        frame = bytes(frame)
        if not frame:
            raise FrameError("short", "empty frame")
        if not frame.startswith(b":"):
            raise FrameError("format", f"an ASCII frame starts with ':', not {frame[:1]!r}")
        if not frame.endswith(b"\r\n"):
            raise FrameError("format", f"an ASCII frame ends with CR LF, not {frame[-2:]!r}")
        digits = frame[1:-2]
        if len(digits) % 2:
            raise FrameError("format", f"odd number of hex digits ({len(digits)})")
        try:
            data = binascii.a2b_hex(digits)
        except binascii.Error:
            raise FrameError("format", f"characters other than hex digits in {digits!r}") from None
        if len(data) < 3:
            raise FrameError("short", f"an ASCII frame holds at least 3 bytes, not {len(data)}")
        computed = lrc(data[:-1])
        if data[-1] != computed:
            raise FrameError("lrc", f"LRC {data[-1]:#04x} sent, {computed:#04x} computed")
        return data[0], data[1:-1]

    @staticmethod
    def frame_start(buffer: bytes) -> int | None:
        """The index of the first ':' in ``buffer``, or None."""
        index = buffer.find(b":")
        return None if index < 0 else index

    @staticmethod
    def frame_end(buffer: bytes) -> int | None:
        """The index just past the first CR LF after a ':' in ``buffer``
        (``buffer[frame_start(buffer):frame_end(buffer)]`` is a frame), or
        None while no whole frame has arrived."""
        start = buffer.find(b":")
        if start < 0:
            return None
        end = buffer.find(b"\r\n", start + 1)
        return None if end < 0 else end + 2


# Section 2.5.1.1: above 19200 baud the two timers have fixed recommended
# values, 750 µs for the inter-character time-out (t1.5) and 1.750 ms for the
# inter-frame delay (t3.5); at 19200 baud and below, 1.5 and 3.5 character times.
RTU_FIXED_INTERVALS_ABOVE_BAUD = 19200
RTU_FIXED_T1_5_NS = 750_000
RTU_FIXED_T3_5_NS = 1_750_000


def rtu_intervals_ns(baudrate: int, char_ns: int) -> tuple[int, int]:
    """(t1.5, t3.5) in ns, the RTU silent intervals of section 2.5.1.1: inside
    a frame, no more than 1.5 character times between two characters; between
    frames, at least 3.5. ``char_ns`` is the time of one character (start,
    data, parity and stop bits: 11 bits in the spec's 8E1; 10 for 8N1),
    rounded half up to whole ns. Above 19200 baud the spec's fixed values
    apply: 750 µs and 1750 µs.

    >>> rtu_intervals_ns(9600, 1_041_667)  # 10 bits at 9600 baud
    (1562501, 3645835)
    >>> rtu_intervals_ns(115200, 86_806)
    (750000, 1750000)
    """
    if not isinstance(baudrate, int) or baudrate <= 0:
        raise ValueError(f"baudrate must be a positive integer, not {baudrate!r}")
    if not isinstance(char_ns, int) or char_ns <= 0:
        raise ValueError(f"char_ns must be a positive integer, not {char_ns!r}")
    if baudrate > RTU_FIXED_INTERVALS_ABOVE_BAUD:
        return RTU_FIXED_T1_5_NS, RTU_FIXED_T3_5_NS
    return (3 * char_ns + 1) // 2, (7 * char_ns + 1) // 2  # 1.5 and 3.5 times, half up


FRAMERS: dict[str, type[RtuFramer | AsciiFramer]] = {"RTU": RtuFramer, "ASCII": AsciiFramer}
