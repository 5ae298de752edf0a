"""The instruction table: every mnemonic, its operands and their kinds.

The validator checks operands against these specs, the parser uses the
mnemonic set to group mnemonic-form rungs, and ``fmt`` prints operands in
this order. Plug-in modules (TLMs) add their instructions through an
:class:`InstructionSet` built for the app that enables them.
"""

from __future__ import annotations

from collections.abc import Callable

from .ab_mnemonics import ab_instruction
from .instr import BOUND as _BOUND
from .spelling import closest
from .specs import K, OperandSpec, InstructionSpec, _spec  # noqa: F401 - re-exported

# Input parameters a JSR may pass, and return parameters it may receive (each).
MAX_PARAMETERS = 40

_BUILTIN = [
    # bit
    _spec("XIC", "examine if closed", False, ("bit", K.BIT)),
    _spec("XIO", "examine if open", False, ("bit", K.BIT)),
    _spec("OTE", "output energize", True, ("bit", K.BIT)),
    _spec("OTL", "output latch", True, ("bit", K.BIT)),
    _spec("OTU", "output unlatch", True, ("bit", K.BIT)),
    _spec("ONS", "one shot", False, ("storage", K.BIT)),
    _spec("OSR", "one shot rising", True, ("storage", K.BIT), ("output", K.BIT)),
    _spec("OSF", "one shot falling", True, ("storage", K.BIT), ("output", K.BIT)),
    # timers and counters
    _spec("TON", "timer on delay", True, ("timer", K.TIMER), ("base", K.TIMEBASE), ("preset", K.PRESET), ("accum", K.PRESET)),
    _spec("TOF", "timer off delay", True, ("timer", K.TIMER), ("base", K.TIMEBASE), ("preset", K.PRESET), ("accum", K.PRESET)),
    _spec("RTO", "retentive timer on", True, ("timer", K.TIMER), ("base", K.TIMEBASE), ("preset", K.PRESET), ("accum", K.PRESET)),
    _spec("CTU", "count up", True, ("counter", K.COUNTER), ("preset", K.PRESET), ("accum", K.PRESET)),
    _spec("CTD", "count down", True, ("counter", K.COUNTER), ("preset", K.PRESET), ("accum", K.PRESET)),
    _spec("RES", "reset", True, ("element", K.RESETTABLE)),
    # compare
    *[_spec(m, t, False, ("a", K.SOURCE), ("b", K.SOURCE)) for m, t in (
        ("EQU", "equal"), ("NEQ", "not equal"), ("LES", "less than"), ("LEQ", "less than or equal"),
        ("GRT", "greater than"), ("GEQ", "greater than or equal"))],
    _spec("LIM", "limit test", False, ("low", K.SOURCE), ("test", K.SOURCE), ("high", K.SOURCE)),
    _spec("MEQ", "masked equal", False, ("source", K.INT_SOURCE), ("mask", K.INT_SOURCE), ("compare", K.INT_SOURCE)),
    _spec("CMP", "compare expression", False, ("expression", K.EXPRESSION)),
    # math
    *[_spec(m, t, True, ("a", K.SOURCE), ("b", K.SOURCE), ("dest", K.DEST)) for m, t in (
        ("ADD", "add"), ("SUB", "subtract"), ("MUL", "multiply"), ("DIV", "divide"), ("MOD", "modulo"))],
    *[_spec(m, t, True, ("source", K.SOURCE), ("dest", K.DEST)) for m, t in (
        ("NEG", "negate"), ("ABS", "absolute value"), ("SQR", "square root"))],
    _spec("CPT", "compute", True, ("dest", K.DEST), ("expression", K.EXPRESSION)),
    _spec("CLR", "clear", True, ("dest", K.DEST)),
    *[_spec(m, t, True, ("a", K.INTEGER_SOURCE), ("b", K.INTEGER_SOURCE), ("dest", K.INTEGER_DEST)) for m, t in (
        ("AND", "bitwise and"), ("OR", "bitwise or"), ("XOR", "bitwise exclusive or"))],
    _spec("NOT", "bitwise not", True, ("source", K.INTEGER_SOURCE), ("dest", K.INTEGER_DEST)),
    # move and file
    _spec("MOV", "move", True, ("source", K.SOURCE), ("dest", K.DEST)),
    _spec("MVM", "masked move", True, ("source", K.INT_SOURCE), ("mask", K.INT_SOURCE), ("dest", K.WORD)),
    _spec("COP", "file copy", True, ("source", K.FILE), ("dest", K.FILE), ("length", K.LENGTH)),
    _spec("FLL", "file fill", True, ("source", K.FILE_SOURCE), ("dest", K.FILE), ("length", K.LENGTH)),
    _spec("BTD", "bit field distribute", True, ("source", K.INT_SOURCE), ("source_bit", K.BIT_NUMBER),
          ("dest", K.WORD), ("dest_bit", K.BIT_NUMBER), ("length", K.BIT_NUMBER)),
    # program control
    _spec("JMP", "jump to label", True, ("label", K.LABEL)),
    _spec("LBL", "label", False, ("label", K.LABEL)),
    # JSR file [inputs] [parameter...]: the first `inputs` parameters are passed to the SBR, the
    # rest receive RET's values (Logix's JSR(routine,count,in...,ret...) order, with a file number)
    _spec("JSR", "jump to subroutine", True, ("file", K.PROGRAM_FILE), ("inputs", K.PARAM_COUNT),
          ("parameter", K.SOURCE), optional=2, repeat=2 * MAX_PARAMETERS),
    _spec("SBR", "subroutine", False, ("parameter", K.DEST), optional=1, repeat=MAX_PARAMETERS),
    _spec("RET", "return", True, ("value", K.SOURCE), optional=1, repeat=MAX_PARAMETERS),
    _spec("MCR", "master control reset", True),
    _spec("AFI", "always false", False),
    _spec("TND", "temporary end", True),
    # strings
    _spec("ACI", "string to integer", True, ("source", K.STRING), ("dest", K.DEST)),
    _spec("AIC", "integer to string", True, ("source", K.INT_SOURCE), ("dest", K.STRING)),
    _spec("ACN", "string concatenate", True, ("a", K.STRING), ("b", K.STRING), ("dest", K.STRING)),
    _spec("AEX", "string extract", True, ("source", K.STRING), ("index", K.INT_SOURCE),
          ("count", K.INT_SOURCE), ("dest", K.STRING)),
    # AB order (1763-RM001 ASC): the string searched for, the start index, the string examined, the result
    _spec("ASC", "string search", True, ("source", K.STRING), ("index", K.INT_SOURCE),
          ("string_search", K.STRING), ("result", K.WORD)),
    _spec("ASR", "string compare", False, ("a", K.STRING), ("b", K.STRING)),
]

# Instructions with a fixed role in the language itself (not operand-driven).
BRANCH_KEYWORDS = ("BST", "NXB", "BND", "SOR", "EOR")


class InstructionSet:
    """The mnemonics a program may use: the built-in instructions plus those
    of the plug-in modules (TLMs) an app enables. The parser asks it which
    names are instructions, the validator for operand specs.

    ``unavailable`` maps mnemonics of installed but not enabled modules to
    their module name, so an unknown-instruction error can say what to add
    to MODULES.LST: a dict, or a function that makes it, called only when an
    error needs it (finding it loads every installed module's code, which
    a program without an unknown instruction never needs)."""

    def __init__(self, extra=(), unavailable: dict[str, str] | Callable[[], dict[str, str]] | None = None) -> None:
        self.table: dict[str, InstructionSpec] = dict(_BUILTIN_TABLE)
        self._unavailable = unavailable if callable(unavailable) else dict(unavailable or {})
        for spec in extra:
            existing = self.table.get(spec.mnemonic)
            if existing is not None and existing != spec:
                owner = f"module {existing.module}" if existing.module else "the built-in instruction set"
                raise ValueError(f"{spec.mnemonic} of module {spec.module} is already an instruction of {owner}")
            self.table[spec.mnemonic] = spec

    @property
    def unavailable(self) -> dict[str, str]:
        if callable(self._unavailable):
            self._unavailable = dict(self._unavailable())
        return self._unavailable

    def lookup(self, mnemonic: str) -> InstructionSpec | None:
        return self.table.get(mnemonic.upper())

    def is_mnemonic(self, name: str) -> bool:
        return name.upper() in self.table

    def all_specs(self) -> list[InstructionSpec]:
        return list(self.table.values())

    def suggest(self, name: str, output: bool | None = None) -> str | None:
        """The closest known mnemonic, for "did you mean" hints (spelling.py):
        ``output`` True where the name stands where an output instruction
        stands (last in its rung or branch leg), False where an input does
        (something follows it in series); among equally close mnemonics,
        those of that role are preferred."""
        prefer = None if output is None else (lambda m: self.table[m].output == output)
        return closest(name, self.table, prefer)

    def hint(self, name: str, output: bool | None = None) -> str:
        """What to say after "unknown instruction NAME" (``output``: as for
        ``suggest``)."""
        module = self.unavailable.get(name.upper())
        if module is not None:
            return f" ({name.upper()} is an instruction of the {module} module: add {module} to the app's MODULES.LST)"
        real = ab_instruction(name) if self.lookup(name) is None else None  # the live table decides
        if real is not None:
            return f" ({real} softplc_lite does not implement; docs/instructions.md lists those it does)"
        close = self.suggest(name, output)
        return f" (did you mean {close}?)" if close else ""


_BUILTIN_TABLE: dict[str, InstructionSpec] = {s.mnemonic: s for s in _BUILTIN}
_BUILTIN_TABLE.update((m, bi.spec) for m, bi in _BOUND.items())
BUILTIN = InstructionSet()


def lookup(mnemonic: str) -> InstructionSpec | None:
    return BUILTIN.lookup(mnemonic)


def is_mnemonic(name: str) -> bool:
    return BUILTIN.is_mnemonic(name)


def all_specs() -> list[InstructionSpec]:
    return BUILTIN.all_specs()


def suggest(name: str, output: bool | None = None) -> str | None:
    """The closest built-in mnemonic, for "did you mean" hints."""
    return BUILTIN.suggest(name, output)
