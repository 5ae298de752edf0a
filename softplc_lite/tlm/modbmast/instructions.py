"""MODBMAST's ladder instructions (manual 5.3), in both rung syntaxes:

``MBR_GETFAULTMAP Port Map``
    Copies the port's fault map into the 17 words at Map: bit n (counted
    across the words, B3/n when Map is #B3:0) is set while slave n is Not
    Present (Table 5); bit 0 is always 0. A conditional instruction: true
    when any bit is set (any slave not answering), false otherwise.
``MBR_GETSTATUS Result Port SlaveStart SlaveCount``
    Copies the five-word status block (Table 11) of each slave
    SlaveStart..SlaveStart+SlaveCount-1 into Result, one block after the
    other; a slave id the port does not configure gives five zeros.
``MBR_CLEARSTATUS Port SlaveStart SlaveCount``
    Zeroes the status blocks of those slaves.

They have no CONTROL: like COP they act on every scan their rung is true
(put an ONS in front to act once). A false rung does nothing (and
MBR_GETFAULTMAP is then false). What a PLC does with bad operands:

- a port that MODBMAST.XML does not configure, or a slave range outside
  1..247 (SlaveCount < 1, SlaveStart + SlaveCount - 1 > 247): minor fault
  S:17/3 with code 7 (port) or 8 (range) in S:102; nothing is copied;
- a Map or Result block that runs past the end of its file (an indirect
  address; a direct one grows its file, as COP's does): major fault 202.
"""

from __future__ import annotations

from array import array
from typing import TYPE_CHECKING

from ...datatable.address import Address
from ...ladder import status as S
from ...ladder.ast import AddressRef, Const, Instruction
from ...ladder.errors import LadderError
from ...ladder.instructions import InstructionSpec, K, OperandSpec
from ...ladder.semantics import MajorFault
from ..api import InstructionContext

if TYPE_CHECKING:  # pragma: no cover
    from .module import Modbmast

MODULE = "MODBMAST"
MAP_WORDS = 17  # 247 slaves + bit 0, 16 to a word
STATUS_WORDS = 5
MAX_SLAVE = 247


def _spec(mnemonic: str, title: str, output: bool, *operands: tuple[str, K]) -> InstructionSpec:
    return InstructionSpec(mnemonic, title, tuple(OperandSpec(n, k) for n, k in operands), output, 0, MODULE)


MBR_GETFAULTMAP = _spec("MBR_GETFAULTMAP", "fault map of a port's slaves (true when any has failed)", False,
                        ("port", K.PORT), ("map", K.WORD_FILE))
MBR_GETSTATUS = _spec("MBR_GETSTATUS", "five-word status blocks of a range of slaves", True,
                      ("result", K.WORD_FILE), ("port", K.PORT), ("slave_start", K.INT_SOURCE),
                      ("slave_count", K.INT_SOURCE))
MBR_CLEARSTATUS = _spec("MBR_CLEARSTATUS", "clear the status blocks of a range of slaves", True,
                        ("port", K.PORT), ("slave_start", K.INT_SOURCE), ("slave_count", K.INT_SOURCE))
SPECS = [MBR_GETFAULTMAP, MBR_GETSTATUS, MBR_CLEARSTATUS]


def block_words(instr: Instruction) -> tuple[int, int] | None:
    """(operand index, words) of the instruction's block operand, when its
    size is known before running (Map: 17; Result: 5 x a constant count)."""
    if instr.mnemonic == "MBR_GETFAULTMAP":
        return 1, MAP_WORDS
    if instr.mnemonic == "MBR_GETSTATUS":
        count = instr.operands[3]
        if isinstance(count, Const) and isinstance(count.value, int) and 1 <= count.value <= MAX_SLAVE:
            return 0, STATUS_WORDS * count.value
    return None


def references(instr: Instruction) -> list[Address]:
    """The last word of a direct block operand (the engine grows its file)."""
    found = block_words(instr)
    if found is None:
        return []
    index, words = found
    op = instr.operands[index]
    if not isinstance(op, AddressRef) or not op.address.is_direct or op.address.indexed:
        return []
    a = op.address
    last = a.element + words - 1
    from ...datatable.filetypes import MAX_ELEMENTS

    return [a.with_element(last)] if last < MAX_ELEMENTS else []


def check(instr: Instruction, ports: dict) -> list[LadderError]:
    """Warnings ``softplc check`` prints: a constant port MODBMAST.XML does
    not configure, a constant slave range outside 1..247, a block that
    cannot fit its file."""
    found = []
    port_at = 0 if instr.mnemonic != "MBR_GETSTATUS" else 1
    port = instr.operands[port_at]
    if isinstance(port, Const) and port.value not in ports:
        have = ", ".join(map(str, sorted(ports))) or "none"
        found.append(LadderError(port.pos, f"{instr.mnemonic}: port {port.value} is not configured in "
                                           f"MODBMAST.XML (ports: {have}); it will raise a minor fault"))
    if instr.mnemonic != "MBR_GETFAULTMAP":
        start, count = instr.operands[port_at + 1], instr.operands[port_at + 2]
        if isinstance(start, Const) and isinstance(count, Const):
            if count.value < 1 or start.value < 1 or start.value + count.value - 1 > MAX_SLAVE:
                found.append(LadderError(start.pos, f"{instr.mnemonic}: slaves {start.value}.."
                                                    f"{start.value + count.value - 1} are outside 1..{MAX_SLAVE}; "
                                                    "it will raise a minor fault"))
    blocks = block_words(instr)
    if blocks is not None:
        op = instr.operands[blocks[0]]
        if isinstance(op, AddressRef) and op.address.is_direct and not references(instr):
            found.append(LadderError(op.pos, f"{instr.mnemonic}: {blocks[1]} words from {op.address} run past the "
                                             "largest file (elements 0..9999); it will fault"))
    return found


class _Mbr:
    def __init__(self, ctx: InstructionContext, module: "Modbmast", port_at: int) -> None:
        self.module = module
        self.machine = ctx.machine
        self.port = ctx.operands[port_at]
        self.where = ctx.where()
        self.last_problem: str | None = None

    def _minor(self, code: int, problem: str) -> None:
        self.machine.minor(S.MINOR_MODULE_BIT, code)
        if problem != self.last_problem:  # logged once, not every scan
            self.module.debug(1, f"{self.where}: {problem} (minor fault S:17/3, code {code})")
        self.last_problem = problem

    def _statuses(self) -> dict | None:
        number = int(self.port.value())
        statuses = self.module.port_status(number)
        if statuses is None:
            have = ", ".join(map(str, self.module.port_numbers())) or "none"
            self._minor(S.MINOR_CODE_PORT, f"port {number} is not configured in MODBMAST.XML (ports: {have})")
        return statuses

    def _slaves(self, start_op, count_op) -> tuple[dict, range] | None:
        """The port's statuses and the slave ids SlaveStart..; None after
        raising the minor fault a bad port or range gives."""
        statuses = self._statuses()
        if statuses is None:
            return None
        start, count = int(start_op.value()), int(count_op.value())
        if count < 1 or start < 1 or start + count - 1 > MAX_SLAVE:
            self._minor(S.MINOR_CODE_OPERAND, f"slaves {start}..{start + count - 1} (SlaveStart {start}, "
                                              f"SlaveCount {count}) are outside 1..{MAX_SLAVE}")
            return None
        return statuses, range(start, start + count)

    @staticmethod
    def _block(operand, words: int) -> tuple[array, int]:
        d, i, _ = operand.location()
        if i + words > len(d):
            raise MajorFault(S.FAULT_BLOCK_RANGE, f"{words} words from {operand.text} run past the end of the file "
                                                  f"({len(d)} words)")
        return d, i


class GetFaultMap(_Mbr):
    def __init__(self, ctx: InstructionContext, module: "Modbmast") -> None:
        super().__init__(ctx, module, 0)
        self.map = ctx.operands[1]

    def __call__(self, c: bool) -> bool:
        if not c:
            return False
        statuses = self._statuses()
        if statuses is None:
            return False
        bits = 0
        for slave, s in statuses.items():
            if not s.present:
                bits |= 1 << slave
        d, i = self._block(self.map, MAP_WORDS)
        words = array("H", bits.to_bytes(2 * MAP_WORDS, "little"))
        d[i:i + MAP_WORDS] = array("h", words.tobytes())
        self.last_problem = None
        return bits != 0


class GetStatus(_Mbr):
    def __init__(self, ctx: InstructionContext, module: "Modbmast") -> None:
        super().__init__(ctx, module, 1)
        self.result, _, self.start, self.count = ctx.operands

    def __call__(self, c: bool) -> bool:
        found = self._slaves(self.start, self.count) if c else None
        if found is None:
            return c
        statuses, slaves = found
        d, i = self._block(self.result, STATUS_WORDS * len(slaves))
        out = []
        for slave in slaves:
            s = statuses.get(slave)
            out += s.words() if s is not None else (0,) * STATUS_WORDS
        d[i:i + len(out)] = array("h", out)
        self.last_problem = None
        return c


class ClearStatus(_Mbr):
    def __init__(self, ctx: InstructionContext, module: "Modbmast") -> None:
        super().__init__(ctx, module, 0)
        _, self.start, self.count = ctx.operands

    def __call__(self, c: bool) -> bool:
        found = self._slaves(self.start, self.count) if c else None
        if found is None:
            return c
        statuses, slaves = found
        for slave in slaves:
            s = statuses.get(slave)
            if s is not None:
                s.clear()
        self.last_problem = None
        return c


INSTANCES = {"MBR_GETFAULTMAP": GetFaultMap, "MBR_GETSTATUS": GetStatus, "MBR_CLEARSTATUS": ClearStatus}
