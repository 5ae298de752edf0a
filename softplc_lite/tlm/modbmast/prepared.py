"""A request made ready to go: its frame (built once for a read), where its
data comes from and goes to, and what its reply must look like.

Frames are built by the one Modbus codec (softplc_lite.modbus): its PDU
classes and its RTU or ASCII framer.
"""

from __future__ import annotations

from ...datatable import DataTable
from ...modbus.pdu import (MaskWriteRegisterRequest, ReadCoilsRequest, ReadDiscreteInputsRequest,
                           ReadHoldingRegistersRequest, ReadInputRegistersRequest,
                           ReadWriteMultipleRegistersRequest, WriteMultipleCoilsRequest,
                           WriteMultipleRegistersRequest, WriteSingleCoilRequest, WriteSingleRegisterRequest)
from .config import Request
from .status import BAD_REPLY
from .transfer import Gather, Scatter

_READS = {1: ReadCoilsRequest, 2: ReadDiscreteInputsRequest, 3: ReadHoldingRegistersRequest,
          4: ReadInputRegistersRequest}


class Prepared:
    """One configured request, bound to the data table and the framer."""

    __slots__ = ("request", "function", "slave", "framer", "scatter", "gather", "fixed", "idle", "reply_length",
                 "echo_length", "sent_pdu")

    def __init__(self, request: Request, framer, table: DataTable) -> None:
        self.request = request
        self.function = request.kind.function
        self.slave = request.slave
        self.framer = framer
        bits = request.kind.bits
        self.scatter = Scatter(table, request.to_blocks, bits) if request.to_blocks else None
        self.gather = Gather(table, request.from_blocks, bits) if request.from_blocks else None
        idle = self._message(idle=True)
        pdu = idle.encode()
        self.idle = (pdu, framer.encode(self.slave, pdu))  # a write's request with idle (zero) data
        self.fixed = self.idle if self.gather is None else None  # a read's request never changes
        self.reply_length = idle.expected_response_length()  # the normal reply's PDU length
        # Writes other than 23 answer with an echo: all of the request (5, 6,
        # 22) or its address and quantity (15, 16).
        self.echo_length = {5: 5, 6: 5, 22: 7, 15: 5, 16: 5}.get(self.function, 0)
        self.sent_pdu = pdu

    def frame(self, idle: bool) -> bytes:
        """The request ADU: a read's is always the same; a write's data is
        gathered now (zeros when ``idle``: outputs idle outside RUN)."""
        fixed = self.fixed or (self.idle if idle else None)
        if fixed is not None:
            self.sent_pdu = fixed[0]
            return fixed[1]
        pdu = self._message(idle=False).encode()
        self.sent_pdu = pdu
        return self.framer.encode(self.slave, pdu)

    def _message(self, idle: bool):
        r = self.request
        f = self.function
        if f in _READS:
            return _READS[f](r.address, r.count)
        if f == 5:
            return WriteSingleCoilRequest(r.address, False if idle else bool(self.gather.coils() & 1))
        if f == 6:
            return WriteSingleRegisterRequest(r.address, 0 if idle else self.gather.registers()[0])
        if f == 15:
            stream = 0 if idle else self.gather.coils()
            return WriteMultipleCoilsRequest(r.address, tuple(bool(stream >> k & 1) for k in range(r.count)))
        if f == 16:
            return WriteMultipleRegistersRequest(r.address, (0,) * r.count if idle else tuple(self.gather.registers()))
        if f == 22:
            return MaskWriteRegisterRequest(r.address, r.and_mask, 0 if idle else self.gather.registers()[0])
        values = (0,) * r.write_count if idle else tuple(self.gather.registers())  # 23
        return ReadWriteMultipleRegistersRequest(r.address, r.count, r.write_address, values)

    def check_reply(self, pdu: bytes) -> tuple[int, bytes]:
        """(0, data) for the normal reply to what was sent (data: a read's
        payload), (code, b"") for an exception reply, (BAD_REPLY, b"") for
        anything else."""
        f = self.function
        if len(pdu) == 2 and pdu[0] == f | 0x80:
            return pdu[1], b""
        if pdu[0] != f or len(pdu) != self.reply_length:
            return BAD_REPLY, b""
        if self.echo_length:
            return (0, b"") if pdu[:self.echo_length] == self.sent_pdu[:self.echo_length] else (BAD_REPLY, b"")
        if pdu[1] != len(pdu) - 2:  # the byte count of a read
            return BAD_REPLY, b""
        return 0, pdu[2:]

    def store(self, data: bytes) -> None:
        """Put a read's payload where its toBlocks say."""
        if self.scatter is not None and data:
            self.scatter.store(data)
