"""STRPRINT and STRSCAN: the COMGENIUS instructions that need no port.

``STRPRINT String Format Param...`` formats into a STRING element; it has
no CONTROL, executes to completion immediately (manual 4.3.6) and does so on
every scan its rung is true, as MOV or AIC do: with no CONTROL there is no
data table bit to remember the previous rung state, and a STRING that
follows its Params is what a ladder programmer expects (put an ONS in front
to format once). It keeps the first 82 characters and drops the rest. On a
bad format index, an illegal format or a bad Param it leaves the STRING as
it was and sets minor fault bit S:17/3 with code 4, 5 or 6 in S:102.

``STRSCAN Control String Format Param...`` matches the STRING against the
format on a false-to-true rung transition and reports like COMSCAN (4.3.5):
matched: DN, LEN characters read, POS specs matched; mismatch: DN ER, LEN
the offset where it failed, POS; a bad format index, illegal format or bad
Param: DN ER with LEN and POS 0. The end of the STRING is the end of the
input, so STRSCAN always completes on the scan it starts.
"""

from __future__ import annotations

from typing import Callable, Sequence

from ...datatable import STRING_CHARS, ValueKind
from ...ladder import status as S
from ...ladder.ast import AddressRef, Const, Instruction
from ...ladder.errors import LadderError
from ...ladder.instructions import InstructionSpec, K, OperandSpec
from ..api import BoundOperand, ControlElement, ControlledInstruction, InstructionContext
from .formats import FormatError, params_needed, parse_print, parse_scan
from .params import Param, ParamError, ParamKind, TableParam, ValueParam
from .printf import MAX_PARAMS, compile_print
from .scanf import MATCHED, compile_scan
from .strings import StringTable

MODULE = "COMGENIUS"
_PARAMS = tuple((f"param{k}", K.PARAM) for k in range(1, MAX_PARAMS + 1))
_PARAMS_OUT = tuple((f"param{k}", K.PARAM_OUT) for k in range(1, MAX_PARAMS + 1))


def spec(mnemonic: str, title: str, *operands: tuple[str, K], optional: int = 0) -> InstructionSpec:
    return InstructionSpec(mnemonic, title, tuple(OperandSpec(n, k) for n, k in operands), True, optional, MODULE)


STRPRINT = spec("STRPRINT", "format into a STRING", ("string", K.STRING), ("format", K.FORMAT), *_PARAMS,
                optional=MAX_PARAMS)
STRSCAN = spec("STRSCAN", "match a STRING", ("control", K.CONTROL), ("string", K.STRING), ("format", K.FORMAT),
               *_PARAMS_OUT, optional=MAX_PARAMS)

_KINDS = {ValueKind.WORD: ParamKind.INTEGER, ValueKind.FLOAT: ParamKind.FLOAT, ValueKind.STRING: ParamKind.STRING}


def param_sources(operands: Sequence[BoundOperand]) -> Callable[[], list[Param]]:
    """A function giving the Params of these operands for this scan: built
    once for constants and direct addresses, resolved each time otherwise."""
    fixed: list[Param | None] = []
    for op in operands:
        fixed.append(_param(op) if op.address is None or op.address.is_direct else None)
    if all(p is not None for p in fixed):
        params = list(fixed)
        return lambda: params
    return lambda: [p if p is not None else _param(op) for p, op in zip(fixed, operands)]


def _param(op: BoundOperand) -> Param:
    if op.address is None:
        return ValueParam(op.constant, name=op.text, writable=False)
    d, i, _ = op.location()
    return TableParam(_KINDS.get(op.address.kind, ParamKind.INTEGER), d, i, op.text)


def param_problem(items, params: Sequence[Param], scan: bool) -> str | None:
    """Too few Params, or one of the wrong kind, for a parsed format: what
    COMSCAN reports at its start, before any input could hide it."""
    needed = params_needed(items, scan)
    if len(needed) > len(params):
        return (f"too few Params: the format needs {len(needed)}, "
                f"{len(params)} {'was' if len(params) == 1 else 'were'} given")
    for k, ((item, kind), p) in enumerate(zip(needed, params), start=1):
        if p.kind.value != kind:
            return f"Param {k} ({p.name}) is a {p.kind.value} param; {item.text} needs a {kind}"
    return None


class FormatSource:
    """The format operand: a string table index, constant or from a word."""

    def __init__(self, operand: BoundOperand, strings: StringTable) -> None:
        self.operand = operand
        self.strings = strings

    def text(self) -> tuple[int, str | None]:
        index = int(self.operand.value())
        return index, self.strings.get(index)

    def problem(self, index: int) -> str:
        return f"format {index}: no such string (the string table has 1..{len(self.strings) - 1})"


class StrPrint:
    def __init__(self, ctx: InstructionContext, strings: StringTable, log: Callable[[int, str], None]) -> None:
        ops = ctx.operands
        self.machine = ctx.machine
        self.dest = ops[0]
        self.format = FormatSource(ops[1], strings)
        self.params = param_sources(ops[2:])
        self.where = ctx.where()
        self.log = log
        self.last: str | None = None  # the last output or problem logged (each is logged once, not every scan)

    def _fail(self, code: int, message: str) -> None:
        self.machine.minor(S.MINOR_MODULE_BIT, code)
        if message != self.last:
            self.last = message
            self.log(1, f"{self.where}: {message}; the STRING is left as it was (minor fault S:17/3, code {code})")

    def __call__(self, c: bool) -> bool:
        if not c:
            return c
        index, text = self.format.text()
        if text is None:
            self._fail(S.MINOR_CODE_FORMAT_INDEX, self.format.problem(index))
            return c
        try:
            out = compile_print(text).render(self.params(), STRING_CHARS)
        except FormatError as e:
            self._fail(S.MINOR_CODE_FORMAT, f"format {index}: {e}")
            return c
        except ParamError as e:
            self._fail(S.MINOR_CODE_PARAM, f"format {index}: {e.reason}")
            return c
        _param(self.dest).set_string(out)  # keeps the first 82 characters
        if out != self.last:
            self.last = out
            self.log(2, f"{self.where}: {out[:82]!r}")
        return c


class StrScan(ControlledInstruction):
    def __init__(self, ctx: InstructionContext, strings: StringTable, log: Callable[[int, str], None]) -> None:
        super().__init__(ctx.operands[0])
        ops = ctx.operands
        self.source = ops[1]
        self.format = FormatSource(ops[2], strings)
        self.params = param_sources(ops[3:])
        self.where = ctx.where()
        self.log = log

    def _error(self, ctl: ControlElement, message: str) -> bool:
        ctl.len = 0
        ctl.pos = 0
        ctl.finish(error=True)
        self.log(1, f"{self.where}: {message} (ER)")
        return True

    def start(self, ctl: ControlElement) -> bool:
        index, fmt = self.format.text()
        if fmt is None:
            return self._error(ctl, self.format.problem(index))
        try:
            result = compile_scan(fmt).match(_param(self.source).string(), self.params(), final=True)
        except FormatError as e:
            return self._error(ctl, f"format {index}: {e}")
        except ParamError as e:
            return self._error(ctl, f"format {index}: {e.reason}")
        ctl.len = result.used
        ctl.pos = result.specs
        ctl.finish(error=result.status != MATCHED)
        self.log(2, f"{self.where}: {result.status}, LEN={result.used} POS={result.specs}")
        return True


# -- softplc check ------------------------------------------------------------------------


def _operand_kind(op) -> str | None:
    if isinstance(op, Const):
        return "float" if isinstance(op.value, float) else "integer"
    if isinstance(op, AddressRef):
        return {ValueKind.WORD: "integer", ValueKind.FLOAT: "float", ValueKind.STRING: "STRING"}.get(op.address.kind)
    return None


def check_format_use(instr: Instruction, strings: StringTable, format_at: int, scan: bool) -> list[LadderError]:
    """What can be seen before running when the format index is a constant:
    a missing string, an illegal format, too few Params, a Param of the
    wrong kind. These are the run-time ER causes, reported as warnings."""
    fmt_op = instr.operands[format_at]
    if not isinstance(fmt_op, Const):
        return []
    index = fmt_op.value
    text = strings.get(index)
    if text is None:
        return [LadderError(fmt_op.pos, f"{instr.mnemonic}: format {index} is not in the string table "
                            f"(strings 1..{len(strings) - 1}); it will set {'ER' if scan else 'a minor fault'}")]
    try:
        items = parse_scan(text) if scan else parse_print(text)
    except FormatError as e:
        return [LadderError(fmt_op.pos, f"{instr.mnemonic}: format {index} {text!r}, {e}")]
    needed = params_needed(items, scan)
    given = instr.operands[format_at + 1:]
    found: list[LadderError] = []
    if len(needed) > len(given):
        found.append(LadderError(instr.pos, f"{instr.mnemonic}: format {index} {text!r} needs {len(needed)} "
                                 f"Param{'s' if len(needed) != 1 else ''}, {len(given)} given"))
    for k, ((item, kind), op) in enumerate(zip(needed, given), start=1):
        have = _operand_kind(op)
        if have is not None and have != kind:
            what = "a * width or precision" if kind == "integer" and item.kind() != "integer" else item.text
            found.append(LadderError(op.pos, f"{instr.mnemonic}: Param {k} is {_describe(op)}; {what} in format "
                                     f"{index} needs {'an' if kind == 'integer' else 'a'} {kind}"))
    return found


def _describe(op) -> str:
    if isinstance(op, Const):
        return f"the constant {op.value}"
    kind = _operand_kind(op)
    return f"{op.address} ({'an' if kind and kind[0] in 'aeiou' else 'a'} {kind})"
