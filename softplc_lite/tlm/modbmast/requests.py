"""The ten request kinds of MODBMAST (manual Table 3 and Table 8): which
Modbus function each is, which reference region its refNum must be in, what
it contains, and the quantities the Modbus specification allows.

A request's quantity is the sum of its blocks' counts, in the request's own
units: coils or discretes for the bit functions (a block of fmt "i2" stands
for 16 of them per word), registers for the others.
"""

from __future__ import annotations

from dataclasses import dataclass

from ...modbus.pdu import (ReadCoilsRequest, ReadHoldingRegistersRequest, ReadWriteMultipleRegistersRequest,
                           WriteMultipleCoilsRequest, WriteMultipleRegistersRequest)

MANY = 10**9

COILS, DISCRETES, INPUT_REGISTERS, HOLDING_REGISTERS = 0, 1, 3, 4  # Table 7 region digits


@dataclass(frozen=True)
class RequestKind:
    element: str  # the XML element name
    function: int
    regions: tuple[int, ...]  # the refNum region, per refNum
    reads: bool
    writes: bool
    bits: bool  # coils or discretes (else registers)
    counts: tuple[tuple[int, int], ...]  # allowed quantity, per refNum
    model: tuple[tuple[str, int, int], ...]  # Table 8 content: (element, min, max) in order

    def region(self, k: int = 0) -> int:
        return self.regions[k]

    def limits(self) -> tuple[tuple[int, int], ...]:
        return self.counts

    def units(self, block) -> int:
        """How many of the request's items (bits or registers) a block holds."""
        return block.bits if self.bits else block.count

    def noun(self, k: int = 0) -> str:
        if not self.bits:
            return "registers"
        return "discretes" if self.region(k) == DISCRETES else "coils"

    def verb(self, k: int = 0) -> str:
        """"reads" or "writes" for refNum ``k``."""
        return "reads" if self.reads and k == 0 else "writes"


def _kind(element: str, function: int, region: int, reads: bool, bits: bool, count: tuple[int, int],
          many: bool, extra: tuple[tuple[str, int, int], ...] = ()) -> RequestKind:
    block = "toBlock" if reads else "fromBlock"
    model = (("refNum", 1, 1), *extra, (block, 1, MANY if many else 1))
    return RequestKind(element, function, (region,), reads, not reads, bits, (count,), model)


_READ_BITS = (1, ReadCoilsRequest.MAX_COUNT)
_READ_REGISTERS = (1, ReadHoldingRegistersRequest.MAX_COUNT)

KINDS = (
    _kind("ReadCoils", 1, COILS, True, True, _READ_BITS, many=False),
    _kind("ReadInputDiscretes", 2, DISCRETES, True, True, _READ_BITS, many=False),
    _kind("ReadMultipleRegisters", 3, HOLDING_REGISTERS, True, False, _READ_REGISTERS, many=True),
    _kind("ReadInputRegisters", 4, INPUT_REGISTERS, True, False, _READ_REGISTERS, many=True),
    _kind("WriteCoil", 5, COILS, False, True, (1, 1), many=False),
    _kind("WriteSingleRegister", 6, HOLDING_REGISTERS, False, False, (1, 1), many=False),
    _kind("ForceMultipleCoils", 15, COILS, False, True, (1, WriteMultipleCoilsRequest.MAX_COUNT), many=False),
    _kind("WriteMultipleRegisters", 16, HOLDING_REGISTERS, False, False,
          (1, WriteMultipleRegistersRequest.MAX_COUNT), many=True),
    _kind("MaskWriteRegister", 22, HOLDING_REGISTERS, False, False, (1, 1), many=False,
          extra=(("andMask", 1, 1),)),
    RequestKind("ReadWriteRegisters", 23, (HOLDING_REGISTERS, HOLDING_REGISTERS), True, True, False,
                ((1, ReadWriteMultipleRegistersRequest.MAX_READ_COUNT),
                 (1, ReadWriteMultipleRegistersRequest.MAX_WRITE_COUNT)),
                (("refNum", 1, 1), ("toBlock", 1, MANY), ("refNum", 1, 1), ("fromBlock", 1, MANY))),
)

REQUEST_KINDS: dict[str, RequestKind] = {k.element: k for k in KINDS}
