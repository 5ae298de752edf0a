"""A JSR's parameters against its subroutine's SBR and RETs: a part of
validate.py's checker (its ``_Checker`` takes these methods), kept apart
for the checker's size; and the words for operands that its messages and
the checker's share."""

from __future__ import annotations

from .ast import AddressRef, Const, Instruction, Operand, Text, walk
from .instructions import MAX_PARAMETERS
from .limits import short_quote


class SubroutineChecks:
    """Needs ``self.error(pos, message)``, ``self.program`` and
    ``self._shapes`` (a dict), as validate._Checker has."""

    def jsr_parameters(self, instr: Instruction, operands: list, target: int) -> None:
        """A JSR's parameters against its subroutine: as many inputs as the
        target's SBR receives, return parameters that are addresses, and as
        many of them as each RET with values in the target returns."""
        count = operands[1] if len(operands) > 1 else Const(0, instr.pos)  # JSR file: no parameters
        if not (isinstance(count, Const) and isinstance(count.value, int) and 0 <= count.value <= MAX_PARAMETERS):
            return  # a count already reported
        inputs, params = count.value, operands[2:]
        if inputs > len(params):
            self.error(pos_of(count), f"JSR passes {inputs} input parameter{plural(inputs)} but lists "
                       f"{len(params)} parameter{plural(len(params))}")
            return
        returns = params[inputs:]
        if len(returns) > MAX_PARAMETERS:
            self.error(pos_of(returns[MAX_PARAMETERS]), f"JSR takes at most {MAX_PARAMETERS} return parameters, "
                       f"got {len(returns)}")
        for k, ret in enumerate(returns):
            if isinstance(ret, Const):
                self.error(pos_of(ret), f"JSR operand {inputs + 3 + k} (return parameter) must be a word or float "
                           f"address, not {describe(ret)}")
        sbr, rets = self.subroutine_shape(target)
        received = len(sbr.operands) if sbr is not None else 0
        if received != inputs:
            where = f"its SBR at {sbr.pos} receives {received}" if sbr is not None else "it has no SBR with parameters"
            self.error(pos_of(count), f"JSR passes {inputs} input parameter{plural(inputs)} to program file "
                       f"{target}, but {where}")
        if returns:
            if not rets:
                self.error(instr.pos, f"JSR expects {len(returns)} return parameter{plural(len(returns))} from program "
                           f"file {target}, which has no RET with values")
            for ret in rets:
                if len(ret.operands) != len(returns):
                    self.error(instr.pos, f"JSR expects {len(returns)} return parameter{plural(len(returns))} from "
                               f"program file {target}, but the RET at {ret.pos} returns {len(ret.operands)}")

    def subroutine_shape(self, number: int) -> tuple[Instruction | None, list[Instruction]]:
        """Program file ``number``'s SBR with parameters (the first instruction
        of its first rung) and its RETs with values, from the parsed text."""
        shape = self._shapes.get(number)  # every JSR to a file asks: walk it once
        if shape is None:
            shape = self._shapes[number] = subroutine_shape(self.program, number)
        return shape


def subroutine_shape(program, number: int) -> tuple[Instruction | None, list[Instruction]]:
    """Program file ``number``'s SBR with parameters (the first instruction
    of its first rung) and its RETs with values."""
    rungs = program.files[number].rungs
    first = rungs[0].elements[0] if rungs and rungs[0].elements else None
    sbr = first if isinstance(first, Instruction) and first.mnemonic == "SBR" and first.operands else None
    rets = [ins for rung in rungs for ins in walk(rung.elements) if ins.mnemonic == "RET" and ins.operands]
    return sbr, rets


def plural(n: int) -> str:
    return "" if n == 1 else "s"


def pos_of(operand):
    return getattr(operand, "pos")


def describe(operand: Operand) -> str:
    if isinstance(operand, AddressRef):
        return f"{operand.address} (a {operand.address.kind.value})"
    if isinstance(operand, Const):
        return f"the constant {operand.value}"
    if isinstance(operand, Text):
        return f"the string {short_quote(operand.value)}"
    return "an expression"
