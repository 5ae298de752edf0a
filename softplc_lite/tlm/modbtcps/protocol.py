"""Modbus TCP as the network-server layer (softplc_lite/netserver) serves it:
the map (layout.py) both processes hold, a client's write as the scan
applies it, and the handler (handler.py, pymodbus's framing) the server
process makes. Nothing here imports pymodbus: the runtime never does.
"""

from __future__ import annotations

import struct
from array import array

from ...netserver import APPLIED, IGNORED, REFUSED, Protocol
from ...netserver.image import Segments
from .config import ServerConfig
from .layout import Layout, string_lengths_fit

# A write as the scan gets it: a tag, then its fields.
WRITE, MASK = b"W", b"M"
_WRITE = struct.Struct("=BBHH")  # unit, kind (0 coils, 1 registers), address, count; the values follow
_MASK = struct.Struct("=BHHH")  # unit, address, and-mask, or-mask
KIND_CODES = {"coils": 0, "holding_registers": 1}
KINDS_BY_CODE = {v: k for k, v in KIND_CODES.items()}
SEGMENTS = Segments("modbtcps")  # the shared images' files: softplc-modbtcps-PID-RANDOM


def write_payload(unit: int, kind: str, address: int, values: list[int]) -> bytes:
    return WRITE + _WRITE.pack(unit, KIND_CODES[kind], address, len(values)) + array("H", values).tobytes()


def mask_payload(unit: int, address: int, and_mask: int, or_mask: int) -> bytes:
    return MASK + _MASK.pack(unit, address, and_mask, or_mask)


class ModbusProtocol(Protocol):
    name = "MODBTCPS"
    process_module = "softplc_lite.tlm.modbtcps.serverproc"
    segments = SEGMENTS

    def __init__(self, config: ServerConfig, layout: Layout) -> None:
        self.config = config
        self.layout = layout

    # -- the runtime's side --------------------------------------------------------------------------
    def regions(self) -> list[tuple[str, int, int, int]]:
        return [(s.file, s.index, s.words, s.offset) for s in self.layout.slots]

    @property
    def image_bytes(self) -> int:
        return self.layout.size

    def apply(self, payload: bytes, table) -> str:
        tag, rest = payload[:1], payload[1:]
        if tag == WRITE:
            unit, kind, address, _ = _WRITE.unpack_from(rest)
            kind, values = KINDS_BY_CODE[kind], array("H", rest[_WRITE.size:]).tolist()
        else:  # MASK: applied to the register as the table holds it now (Modbus spec 6.16)
            unit, address, and_mask, or_mask = _MASK.unpack(rest)
            kind, values = "holding_registers", None
        pieces = self.layout.find(unit, kind, address, 1 if values is None else len(values))
        if pieces is None:  # the server checked it against the same layout
            return IGNORED
        if values is None:
            current = Layout.load(pieces, table)[0]
            values = [(current & and_mask) | (or_mask & ~and_mask & 0xFFFF)]
            if not string_lengths_fit(pieces, values):  # the LEN check of 6, 16 and 23, on the result
                return REFUSED
        Layout.store(pieces, values, table)
        return APPLIED

    # -- the server process's side -------------------------------------------------------------------
    def unusable(self) -> str | None:
        """Why pymodbus cannot serve, in one line; None when it can."""
        try:
            from . import pymodbus_glue
        except ImportError as e:
            return str(e)
        return pymodbus_glue.missing()

    def handler(self, server):
        from .handler import ModbusHandler

        return ModbusHandler(server, self)
