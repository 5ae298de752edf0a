"""Operand kinds and instruction specs: what the instruction table is made
of. instructions.py builds the table from these; the bound instruction
groups (ladder/instr/) declare their specs with them too.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum


class K(Enum):
    """Operand kinds."""

    BIT = "bit address"
    SOURCE = "number or word/float address"  # read-only numeric operand
    DEST = "word or float address"  # numeric destination
    INT_SOURCE = "integer or word address"
    WORD = "word address"
    TIMER = "timer element (T)"
    COUNTER = "counter element (C)"
    CONTROL = "control element (R)"
    RESETTABLE = "timer, counter or control element"
    TIMEBASE = "time base 1.0, 0.01 or 0.001"
    PRESET = "integer constant"
    LABEL = "label number 0..999"
    PROGRAM_FILE = "program file number 3..999"
    EXPRESSION = "expression"
    FILE = "file address (#N7:0)"
    WORD_FILE = "word file address (#B3:0)"  # a block of 16-bit words (module instructions)
    FILE_SOURCE = "number, or file address (#N7:0)"
    LENGTH = "length 1..1000"
    STRING = "string element (ST)"
    BIT_NUMBER = "bit number 0..15"
    ANY = "operand"  # TLM parameters: validated by the TLM
    # TLM parameter kinds (COMGENIUS and third-party modules)
    PORT = "port number 0..35 or word address"
    FORMAT = "format index (integer or word address)"
    PARAM = "number, or word, float or STRING element"  # read by a conversion
    PARAM_OUT = "word, float or STRING element"  # written by a conversion
    PARAM_COUNT = "input parameter count 0..40"  # JSR: how many of the parameters after it are inputs
    # shift registers and sequencers (ladder/instr/shift.py, sequencer.py)
    BIT_LENGTH = "length 1..16000 bits"  # a bit array: at most a 1000-word file
    POSITION = "position 0..1000"
    # FAL / FSC (ladder/instr/filemath.py): ALL and INC are words of the instruction, never symbols
    FILE_MODE = "mode ALL, INC or a number of elements per scan"
    # bitwise instructions on SLC/MicroLogix L files (32-bit, 1763-RM001)
    INTEGER_SOURCE = "integer, or word or long address"
    INTEGER_DEST = "word or long address"


@dataclass(frozen=True)
class OperandSpec:
    name: str
    kind: K


@dataclass(frozen=True)
class InstructionSpec:
    mnemonic: str
    title: str
    operands: tuple[OperandSpec, ...]
    output: bool  # output instructions are last in a series (informational)
    optional: int = 0  # how many trailing operands may be left out
    module: str | None = None  # the TLM that provides it; None = built in
    repeat: int = 0  # > 0: the last operand may be given up to this many times (JSR, SBR, RET parameters)

    @property
    def min_operands(self) -> int:
        return len(self.operands) - self.optional

    @property
    def max_operands(self) -> int:
        return len(self.operands) - 1 + self.repeat if self.repeat else len(self.operands)

    def operand_at(self, index: int) -> OperandSpec:
        """The spec of operand ``index``: a repeated last operand covers every
        position from its own on."""
        return self.operands[min(index, len(self.operands) - 1)]

    def signature(self) -> str:
        names = [o.name if i < self.min_operands else f"[{o.name}]" for i, o in enumerate(self.operands)]
        if self.repeat and names:
            names[-1] = names[-1][:-1] + "...]" if names[-1].startswith("[") else names[-1] + "..."
        return f"{self.mnemonic} {' '.join(names)}".strip()


def _spec(mnemonic: str, title: str, output: bool, *operands: tuple[str, K], optional: int = 0,
          repeat: int = 0) -> InstructionSpec:
    return InstructionSpec(mnemonic, title, tuple(OperandSpec(n, k) for n, k in operands), output, optional,
                           repeat=repeat)
