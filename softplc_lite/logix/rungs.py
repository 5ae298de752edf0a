"""Logix rungs translated into the ladder's syntax tree: each instruction
becomes the ladder instruction that has its rules (the PLC-5 one where
Logix's rules are the same, a Logix one from instructions.py where they
differ), each operand the data table address of its tag path (tags.py), a
constant, or an expression. Every problem of a routine is collected with its
place (the export's line, the column in the rung's text) and what was
expected; an instruction softplc_lite does not run is one of them, by name.

What each Logix instruction becomes (``PLAN``): the ladder mnemonic and a
letter an operand: ``b`` a bit, ``v`` a value (number, tag, or a CPT-style
expression where Logix allows one), ``d`` a destination, ``e`` an
expression, ``l`` a label, ``r`` a routine, ``p`` parameters (SBR, RET),
``T``/``C``/``R`` a TIMER, COUNTER or CONTROL (its CTL, and PRE and ACC), ``?`` an operand Logix keeps
in the structure (``TON(T1,?,?)``: written as ``?`` or a value, not used).

Instructions whose operands need more than a letter (``HANDLERS``: COP, CPS and
FLL by member, the string instructions, SIZE, compares and moves of strings,
BTD, SWPB, TRN, GSV and SSV, the function-block TONR ... OSFI) are translated
by copy.py, strings.py, bits.py, system.py and fbd.py.
"""

from __future__ import annotations

from ..ladder.ast import AddressRef, Branch, Const, Instruction, Pos, Rung
from . import bits, copy, fbd, model, strings, subroutines, system
from .expr import ExprError, number, parse_expression
from .neutral import NBranch, NeutralError, parse_rung
from .tags import NotRun, PathError, TagDirectory

PLAN: dict[str, tuple[str, str]] = {
    "XIC": ("XIC", "b"), "XIO": ("XIO", "b"), "OTE": ("OTE", "b"), "OTL": ("OTL", "b"), "OTU": ("OTU", "b"),
    "ONS": ("ONS", "b"), "OSR": ("OSR", "bb"), "OSF": ("OSF", "bb"),
    "NOP": ("NOP", ""), "AFI": ("AFI", ""), "TND": ("TND", ""), "MCR": ("MCR", ""),
    "MOV": ("MOV", "vd"), "MOVE": ("MOV", "vd"),
    "ADD": ("ADD", "vvd"), "SUB": ("SUB", "vvd"), "MUL": ("MUL", "vvd"), "DIV": ("LDIV", "vvd"),
    "MOD": ("MOD", "vvd"), "NEG": ("NEG", "vd"), "ABS": ("ABS", "vd"), "SQR": ("SQR", "vd"),
    "SQRT": ("SQR", "vd"), "CLR": ("CLR", "d"),
    "EQU": ("EQU", "vv"), "NEQ": ("NEQ", "vv"), "GRT": ("GRT", "vv"), "LES": ("LES", "vv"),
    "GEQ": ("GEQ", "vv"), "LEQ": ("LEQ", "vv"), "EQ": ("EQU", "vv"), "NE": ("NEQ", "vv"),
    "GT": ("GRT", "vv"), "LT": ("LES", "vv"), "GE": ("GEQ", "vv"), "LE": ("LEQ", "vv"),
    "LIM": ("LIM", "vvv"), "MEQ": ("LMEQ", "vvv"), "MVM": ("LMVM", "vvd"),
    "AND": ("LAND", "vvd"), "OR": ("LOR", "vvd"), "XOR": ("LXOR", "vvd"), "NOT": ("LNOT", "vd"),
    "BAND": ("LAND", "vvd"), "BOR": ("LOR", "vvd"), "BXOR": ("LXOR", "vvd"), "BNOT": ("LNOT", "vd"),
    "CPT": ("CPT", "de"), "CMP": ("CMP", "e"),
    "JMP": ("JMP", "l"), "LBL": ("LBL", "l"), "JSR": ("JSR", "r"), "RET": ("RET", "p"), "SBR": ("SBR", "p"),
    "TON": ("LTON", "T??"), "TOF": ("LTOF", "T??"), "RTO": ("LRTO", "T??"),
    "CTU": ("LCTU", "C??"), "CTD": ("LCTD", "C??"), "RES": ("LRES", "X"),
}
# Instructions Logix has and softplc_lite does not run yet, or cannot (MSG: a message to
# another device): said by name where they are used.
NOT_RUN_REASON = {"MSG": "a message to another device; softplc_lite has no network to send it on"}
# Instructions translated by a module of their own (operands of several kinds, or one ladder
# instruction per member): the handler returns the instruction, or NotImplemented for PLAN's.
HANDLERS = {**{m: copy.translate for m in ("COP", "CPS", "FLL")},
            **{m: strings.translate for m in (*strings.PLAN, "SIZE", *strings.COMPARES, "MOV", "MOVE")},
            "GSV": system.translate, "SSV": system.translate,
            **{m: bits.translate for m in ("BTD", "SWPB", "TRN")},
            **{m: fbd.translate for m in fbd.CALLS}}


class RoutineContext:
    """What translating one routine needs: the directory, the program's
    scope, the routine numbers by name, and the routine's labels."""

    def __init__(self, directory: TagDirectory, scope: str | None, routines: dict[str, int], source: str,
                 routine: str) -> None:
        self.directory = directory
        self.scope = scope
        self.routines = routines
        self.source = source
        self.routine = routine
        self.labels: dict[str, int] = {}
        self.problems: list[model.Problem] = []
        self.warnings: list[model.Problem] = []
        self.skip = False  # the rung being translated holds an instruction not run
        self.before: list[Instruction] = []  # LIDXs the instruction being translated needs before it
        self.parameters_not_run = False  # a JSR, SBR or RET of this routine has a parameter not passed
        self.aoi = None  # the project's Add-On Instructions (logix/aoi.py AoiCalls): calls to them
        self.calls = None  # the program's routines' parameter plans (logix/subroutines.py Subroutines)
        self.name = routine  # the routine's own name in its program
        self.language = "RLL"  # or "ST" (st_routine.py): the function-block instructions are ST's alone

    def warn(self, pos: Pos, message: str) -> None:
        self.warnings.append(model.Problem(pos, f"routine {self.routine}: {message}"))

    def label(self, name: str) -> int:
        return self.labels.setdefault(name.upper(), len(self.labels))

    def problem(self, pos: Pos, message: str) -> None:
        self.problems.append(model.Problem(pos, f"routine {self.routine}: {message}"))


def translate_rung(rung: model.Rung, ctx: RoutineContext) -> Rung | None:
    """The ladder rung of one Logix rung, or None (its problems added to
    ``ctx.problems``)."""
    try:
        elements = parse_rung(rung.text)
    except NeutralError as e:
        ctx.problem(_at(rung.pos, rung.text, e.column), f"rung {rung.number}: {e}")
        return None
    before = len(ctx.problems)
    ctx.skip = False
    out = _series(elements, rung, ctx)
    if len(ctx.problems) > before:
        return None
    if ctx.skip:  # kept in its place, running nothing (rung numbers stay the export's), its label kept
        label = out[:1] if out and isinstance(out[0], Instruction) and out[0].mnemonic == "LBL" else []
        out = label + [Instruction("NOP", [], rung.pos)]
    elif not out:
        out = [Instruction("NOP", [], rung.pos)]  # an empty rung of the export: Logix takes it, the ladder NOP
    return Rung(out, rung.comment, rung.pos)


def _at(pos: Pos, text: str, column: int) -> Pos:
    """The position of ``column`` of a rung's text that starts at ``pos``
    (a rung may span lines)."""
    head = text[:column]
    newlines = head.count("\n")
    if newlines:
        return Pos(pos.source, pos.line + newlines, column - head.rfind("\n"))
    return Pos(pos.source, pos.line, pos.column + column)


def _series(elements, rung, ctx) -> list:
    out = []
    for el in elements:
        if isinstance(el, NBranch):
            # An empty leg conducts (Logix takes ``[,]``); the ladder's tree wants an instruction there.
            legs = [_series(leg, rung, ctx) or [Instruction("NOP", [], _at(rung.pos, rung.text, el.column))]
                    for leg in el.legs]
            out.append(Branch(legs, _at(rung.pos, rung.text, el.column)))
        else:
            ctx.before = []
            ins = _instruction(el, rung, ctx)
            if ins is not None:
                out += ctx.before
                out += ins if isinstance(ins, list) else [ins]  # several: JSR, SBR, RET with copied parameters
    return out


def _instruction(el, rung, ctx) -> Instruction | None:
    pos = _at(rung.pos, rung.text, el.column)
    handler = HANDLERS.get(el.mnemonic)
    if handler is not None:
        out = handler(el, pos, rung, ctx)
        if out is not NotImplemented:
            return out
    plan = PLAN.get(el.mnemonic)
    if plan is None:
        if ctx.aoi is not None and ctx.aoi.defines(el.mnemonic):
            return ctx.aoi.call(el, pos, rung, ctx)
        reason = NOT_RUN_REASON.get(el.mnemonic, "not an instruction softplc_lite runs yet")
        ctx.warn(pos, f"rung {rung.number}: {el.mnemonic}: {reason}; the rung is not run")
        ctx.skip = True
        return None
    mnemonic, letters = plan
    ops = el.operands
    if letters == "r":  # JSR(routine, count, parameters...)
        return _jsr(el, pos, rung, ctx)
    if letters == "p":  # SBR(parameters...) receives, RET(values...) returns
        plan = ctx.calls.plan(ctx.name) if ctx.calls is not None else None
        if plan is not None and plan.copies:
            return subroutines.sbr_ret(el, pos, rung, ctx, plan)
        params = _parameters(el, rung, ctx, 0, len(el.operands) if mnemonic == "RET" else 0)
        return None if params is None else Instruction(mnemonic, params, pos)
    if len(ops) != len(letters):
        ctx.problem(pos, f"rung {rung.number}: {el.mnemonic} takes {len(letters)} operand"
                         f"{'s' if len(letters) != 1 else ''}, found {len(ops)}")
        return None
    operands = []
    for letter, (text, column) in zip(letters, ops):
        where = _at(rung.pos, rung.text, column)
        try:
            operands += _operand(letter, text, where, ctx)
        except NotRun as e:
            ctx.warn(where, f"rung {rung.number}: {el.mnemonic} operand {text!r}: {e}; the rung is not run")
            ctx.skip = True
        except (PathError, ExprError) as e:
            ctx.problem(_at(rung.pos, rung.text, column + e.offset), f"rung {rung.number}: {el.mnemonic} "
                                                                     f"operand {text!r}: {e}")
    return Instruction(mnemonic, operands, pos)


def _jsr(el, pos, rung, ctx) -> Instruction | list | None:
    """JSR(routine, input count, inputs..., returns...): the ladder's JSR with
    the routine's file number, its operands in Logix's order (1756-RM003,
    JSR; docs/logix.md, "Subroutines with parameters")."""
    if not el.operands:
        ctx.problem(pos, f"rung {rung.number}: JSR takes the routine's name")
        return None
    name, column = el.operands[0]
    number_of = ctx.routines.get(name.upper())
    if number_of is None:
        ctx.problem(_at(rung.pos, rung.text, column), f"rung {rung.number}: JSR to {name!r}: no routine of that "
                                                      f"name in this program")
        return None
    if len(el.operands) < 2:
        return Instruction("JSR", [Const(number_of, pos)], pos)
    count_text, count_column = el.operands[1]
    count = number(count_text)
    if not isinstance(count, int) or not 0 <= count <= len(el.operands) - 2:
        ctx.problem(_at(rung.pos, rung.text, count_column), f"rung {rung.number}: JSR's input count "
                    f"{count_text!r}: expected a whole number from 0 to {len(el.operands) - 2}, the "
                    f"parameters listed")
        return None
    if len(el.operands) == 2:
        return Instruction("JSR", [Const(number_of, pos)], pos)
    plan = ctx.calls.plan(name) if ctx.calls is not None else None
    if plan is not None and plan.copies:
        return subroutines.jsr(el, pos, rung, ctx, plan, number_of, count)
    params = _parameters(el, rung, ctx, 2, count)
    return None if params is None else Instruction("JSR", [Const(number_of, pos), Const(count, pos)] + params, pos)


def _parameters(el, rung, ctx, first: int, inputs: int) -> list | None:
    """The operands of JSR, SBR or RET from ``first``: the first ``inputs``
    of them values (a number or a tag), the rest tags that receive. An
    atomic number tag (SINT, INT, DINT, LINT, REAL) is passed; a BOOL, a
    string, a structure or an array is copied around them (subroutines.py),
    so one here is not passed (the rung is not run)."""
    out = []
    for k, (text, column) in enumerate(el.operands[first:]):
        where = _at(rung.pos, rung.text, column)
        value = number(text)
        try:
            if value is not None:
                if k >= inputs:
                    raise PathError("expected a tag to receive the parameter, found a number")
                out.append(Const(value, where))
                continue
            r = _resolve(text, where, ctx)
            if r.address is None or r.address.bit is not None or r.type.name == "BOOL":
                kind = "BOOL" if r.address is not None else (f"{r.type.name} array" if r.dims else r.type.name)
                raise NotRun(f"a {kind} where the routine's SBR or RET has a number: softplc_lite passes a "
                             f"BOOL, string, structure or array to a parameter of its own kind")
            out.append(AddressRef(r.address, where))
        except NotRun as e:
            ctx.warn(where, f"rung {rung.number}: {el.mnemonic} parameter {text!r}: {e}; the rung is not run")
            ctx.skip = True
            ctx.parameters_not_run = ctx.parameters_not_run or el.mnemonic != "JSR"
        except (PathError, ExprError) as e:
            ctx.problem(_at(rung.pos, rung.text, column + e.offset), f"rung {rung.number}: {el.mnemonic} "
                                                                     f"parameter {text!r}: {e}")
            return None
    return out


def _indexer(pos: Pos, ctx):
    """How a path's run-time index is made (tags.py's ``index_of``): one tag
    that is the whole index of an array in a file of its own is that tag's
    item (the file's end checks it); anything else (an expression, several
    dimensions, a constant part) is a hidden DINT that an LIDX, put just
    before the instruction, computes and checks dimension by dimension."""
    def index_of(terms, constant, count):
        if len(terms) == 1 and constant == 0 and terms[0][2] == 1 and terms[0][1] == count:
            try:
                r = ctx.directory.resolve(terms[0][0], ctx.scope)
            except PathError:
                r = None
            if r is not None and r.address is not None and r.type.name in ("SINT", "INT", "DINT") \
                    and r.address.is_direct:
                return r.address
        hidden = ctx.directory.hidden_index()
        operands = [AddressRef(hidden, pos), Const(constant, pos)]
        for text, size, stride in terms:
            operands += [parse_expression(text, pos, lambda path, offset: _resolve_ref(path, pos, ctx)),
                         Const(size, pos), Const(stride, pos)]
        ctx.before.append(Instruction("LIDX", operands, pos))
        return hidden
    return index_of


def _resolve(text: str, pos: Pos, ctx):
    return ctx.directory.resolve(text, ctx.scope, _indexer(pos, ctx))


def _resolve_ref(text: str, pos: Pos, ctx) -> AddressRef:
    r = _resolve(text, pos, ctx)
    if r.address is None:
        raise PathError(f"{text} is a {r.type.name}{' array' if r.dims else ''}: expected a single value here")
    return AddressRef(r.address, pos)


def _operand(letter: str, text: str, pos: Pos, ctx) -> list:
    if letter == "?":
        return []
    if letter in "vde":
        value = number(text)
        if value is not None:
            if letter == "d":
                raise PathError("expected a tag to write, found a number")
            return [Const(value, pos)]
        if letter == "d":
            return [_resolve_ref(text, pos, ctx)]
        return [parse_expression(text, pos, lambda path, offset: _resolve_ref(path, Pos(
            pos.source, pos.line, pos.column + offset), ctx))]
    if letter == "b":
        ref = _resolve_ref(text, pos, ctx)
        if ref.address.bit is None:
            raise PathError("expected a BOOL or a bit (Tag.5)")
        return [ref]
    if letter == "l":
        return [Const(ctx.label(text), pos)]
    if letter in "TCRX":
        r = _resolve(text, pos, ctx)
        kind = r.type.name if r.address is None and not r.dims else None
        wanted = {"T": ("TIMER",), "C": ("COUNTER",), "R": ("CONTROL",),
                  "X": ("TIMER", "COUNTER", "CONTROL")}[letter]
        if kind not in wanted:
            raise PathError(f"expected a {' or '.join(wanted)}, found "
                            f"{r.type.name}{' array' if r.dims else ''}")
        members = ("CTL", "PRE", "ACC") if letter != "X" else ("CTL", "POS" if kind == "CONTROL" else "ACC")
        return [_resolve_ref(f"{text}.{m}", pos, ctx) for m in members]
    raise AssertionError(letter)
