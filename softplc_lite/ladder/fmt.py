"""Print a program canonically, in mnemonic or neutral-text style.

Parsing what this prints gives back an equal AST (positions aside): the
tests check it on every program in programs/ and on generated programs.
"""

from __future__ import annotations

from .ast import (
    MAIN_FILE,
    AddressRef,
    BinOp,
    Branch,
    Call,
    Const,
    Element,
    Instruction,
    Program,
    Rung,
    SymbolRef,
    Text,
    UnaryOp,
    walk,
)
from .errors import LadderError
from .fmt_comments import Comments, attach_comments

STYLES = ("mnemonic", "neutral")

# Binding strength of expression operators (higher binds tighter), as in ladder.lark.
_PREC = {"=": 1, "<>": 1, "<": 1, "<=": 1, ">": 1, ">=": 1, "OR": 2, "XOR": 3, "AND": 4,
         "+": 5, "-": 5, "*": 6, "|": 6, "//": 6, "MOD": 6, "**": 7}
_UNARY, _ATOM = 8, 9


def _number(v: int | float) -> str:
    return repr(v) if isinstance(v, float) else str(v)


def _constant(c: Const) -> str:
    """A constant as written: hex ones in hex (a validated 0xFFFF holds -1)."""
    if c.hex and isinstance(c.value, int) and -0x8000 <= c.value <= 0xFFFF:
        return f"0x{c.value & 0xFFFF if c.value < 0 else c.value:X}"
    return _number(c.value)


def _prec(node) -> int:
    if isinstance(node, BinOp):
        return _PREC[node.op]
    if isinstance(node, UnaryOp):
        return _UNARY
    if isinstance(node, Const) and node.value < 0 and not node.hex:
        return _UNARY  # printed with a leading '-'
    return _ATOM


def format_expression(node, name_of=None, operators=None) -> str:
    """The expression as rung text; ``name_of(address)`` (optional) gives
    the name an address shows by (None: its address) and ``operators`` the
    text an operator shows as (Logix writes ``/`` for PLC-5's ``|``), so a
    view can show an expression its own way (a Logix app's) without the
    ladder core knowing how."""
    if isinstance(node, Const):
        return _constant(node)
    if isinstance(node, AddressRef):
        return (name_of(node.address) if name_of else None) or str(node.address)
    if isinstance(node, SymbolRef):
        return node.name
    if isinstance(node, Call):
        return f"{node.func}({format_expression(node.arg, name_of, operators)})"
    if isinstance(node, UnaryOp):
        inner = format_expression(node.operand, name_of, operators)
        if _prec(node.operand) < _UNARY:
            inner = f"({inner})"
        return f"-{inner}" if node.op == "NEG" else f"NOT {inner}"
    assert isinstance(node, BinOp)
    p = _PREC[node.op]
    left, right = format_expression(node.left, name_of, operators), format_expression(node.right, name_of, operators)
    if node.op == "**":
        # power takes unary operands on both sides and does not chain
        if _prec(node.left) < _UNARY:
            left = f"({left})"
        if _prec(node.right) < _UNARY:
            right = f"({right})"
    else:
        if _prec(node.left) < p or (p == 1 and _prec(node.left) == 1):
            left = f"({left})"
        if _prec(node.right) <= p:
            right = f"({right})"
    return f"{left} {operators.get(node.op, node.op) if operators else node.op} {right}"


def format_operand(op, style: str, file_operand: bool = False, name_of=None, operators=None) -> str:
    """``name_of`` and ``operators`` as for format_expression: a view's
    names for addresses (a Logix app's tag paths) and operators."""
    if isinstance(op, (BinOp, UnaryOp, Call)):
        text = format_expression(op, name_of, operators)
        return f'"{text}"' if style == "mnemonic" else text
    if isinstance(op, Const):
        return _constant(op)
    if isinstance(op, AddressRef):
        return (name_of(op.address) if name_of is not None else None) or str(op.address)
    if isinstance(op, SymbolRef):
        return op.name
    if isinstance(op, Text):
        escaped = op.value.replace("\\", "\\\\").replace('"', '\\"')
        return f'"{escaped}"'
    raise TypeError(f"cannot print operand {op!r}")


def format_instruction(ins: Instruction, style: str = "mnemonic", name_of=None, operators=None,
                       mnemonic_of=None) -> str:
    """``mnemonic_of``: the name a view gives the instruction (Logix's)."""
    operands = [format_operand(o, style, name_of=name_of, operators=operators) for o in ins.operands]
    mnemonic = mnemonic_of(ins.mnemonic) if mnemonic_of is not None else ins.mnemonic
    if style == "neutral":
        return f"{mnemonic}({','.join(operands)})"
    return " ".join([mnemonic, *operands])


def format_series(elements: list[Element], style: str, **names) -> str:
    """``names``: format_instruction's ``name_of``, ``operators`` and ``mnemonic_of``."""
    parts = []
    for el in elements:
        if isinstance(el, Branch):
            legs = [format_series(leg, style, **names) for leg in el.legs]
            if style == "neutral":
                parts.append("[" + ",".join(legs) + "]")
            else:
                parts.append("BST " + " NXB ".join(legs) + " BND")
        else:
            parts.append(format_instruction(el, style, **names))
    return ("" if style == "neutral" else " ").join(parts)


def format_rung(rung: Rung, style: str = "mnemonic") -> str:
    lines = [f"// {line}".rstrip() for line in (rung.comment or "").split("\n")] if rung.comment else []
    body = format_series(rung.elements, style)
    if not body and style == "mnemonic":
        body = "SOR EOR"  # an empty rung (check refuses it) stays a rung, not a blank line
    lines.append(body + ";" if style == "neutral" else body)
    return "\n".join(lines)


def _data_value(v) -> str:
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return _number(v)


def unprintable(program: Program, style: str, instructions) -> list[LadderError]:
    """What ``style`` cannot print so that it parses back: in mnemonic
    style an instruction the set does not know (neutral text accepts any
    name, mnemonic text must tell instructions from symbols); in neutral
    style a quoted string operand (neutral text has no string operands)."""
    found = []
    for pfile in program.files.values():
        for rung in pfile.rungs:
            for ins in walk(rung.elements):
                if style == "mnemonic" and instructions.lookup(ins.mnemonic) is None:
                    found.append(LadderError(ins.pos, f"unknown instruction {ins.mnemonic!r}"
                                                      f"{instructions.hint(ins.mnemonic)}"))
                if style == "neutral":
                    found += [LadderError(op.pos, f"{ins.mnemonic} has a quoted string operand, which neutral "
                                                  "text cannot write") for op in ins.operands if isinstance(op, Text)]
    return found


def format_program(program: Program, style: str = "mnemonic") -> str:
    if style not in STYLES:
        raise ValueError(f"style must be one of {', '.join(STYLES)}")
    out: list[str] = []
    for decl in program.symbols.values():
        out.append(f"SYMBOL {decl.name} {decl.address}")
    for decl in program.data:
        values = " ".join(_data_value(v) for v in decl.values)
        out.append(f"DATA {decl.file} {decl.size}" + (f" = {values}" if decl.values else ""))
    for number in sorted(program.files):
        pfile = program.files[number]
        if out:
            out.append("")
        if number != MAIN_FILE or pfile.name or not pfile.rungs:  # an empty main file needs its header to stay
            out.append(f"FILE {number}" + (f" {pfile.name}" if pfile.name else ""))
        for rung in pfile.rungs:
            out.append(format_rung(rung, style))
    return "\n".join(out) + "\n"


# -- a whole source file, every comment kept (softplc fmt) ---------------------------

INDENT = "    "  # the elements of a multi-line rung


def _rung_lines(rung: Rung, style: str, comments: Comments) -> list[str]:
    """A rung with its own comment lines above, its trailing comment, and
    (when it had any) its inner comments between the same two top-level
    elements as in the source, the rung then spanning lines."""
    key = id(rung)
    lines = list(comments.above.get(key, ()))
    trailing = comments.trailing.get(key)
    if key not in comments.above and trailing is None and rung.comment:  # a rung built without its text
        lines = [f"// {line}".rstrip() for line in rung.comment.split("\n")]
    inner = comments.inner.get(key)
    end = f"  {trailing}" if trailing else ""
    if not inner:
        body = format_series(rung.elements, style)
        if not body and style == "mnemonic":
            body = "SOR EOR"
        lines.append((body + ";" if style == "neutral" else body) + end)
        return lines
    groups: list[list[str]] = [[] for _ in range(len(rung.elements) + 1)]
    for before, c in inner:
        groups[min(before, len(rung.elements))].append(c)
    if style == "neutral" and rung.elements:
        # a neutral rung opens at its first "(" or "[": a comment before its first element would be outside it
        groups[1][:0], groups[0] = groups[0], []
    out = ["SOR"] if style == "mnemonic" else []
    indent = INDENT if style == "mnemonic" else ""

    def add_comments(group) -> None:
        for c in group:
            if not c.own_line and out:
                out[-1] += f"  {c.text}"
            else:
                out.append(indent + c.text)

    add_comments(groups[0])
    for k, el in enumerate(rung.elements):
        out.append(indent + format_series([el], style))
        add_comments(groups[k + 1])
    if style == "mnemonic":
        out.append("EOR" + end)
    elif groups[-1] or not rung.elements:
        out.append(";" + end)  # after the last comments, so they stay inside the rung
    else:
        out[-1] += ";" + end
    return lines + out


def format_source(program: Program, text: str, style: str = "mnemonic") -> str:
    """``program`` (parsed from ``text``, one file) canonically, as
    format_program prints it, with every comment of ``text`` kept (see
    fmt_comments.py)."""
    if style not in STYLES:
        raise ValueError(f"style must be one of {', '.join(STYLES)}")
    comments = attach_comments(program, text)
    out: list[str] = []

    def blank() -> None:
        if out and out[-1] != "":
            out.append("")

    def blocks(found) -> None:
        for block in found:
            if block.blank_before:
                blank()
            out.extend(block.lines)
            if block.blank_after:
                blank()

    def statement(obj, line: str) -> None:
        blocks(comments.leading.get(id(obj), ()))
        trailing = comments.trailing.get(id(obj))
        out.append(f"{line}  {trailing}" if trailing else line)

    blocks(comments.header)
    for decl in program.symbols.values():
        statement(decl, f"SYMBOL {decl.name} {decl.address}")
    for decl in program.data:
        values = " ".join(_data_value(v) for v in decl.values)
        statement(decl, f"DATA {decl.file} {decl.size}" + (f" = {values}" if decl.values else ""))
    for number in sorted(program.files):
        pfile = program.files[number]
        if program.symbols or program.data or number != min(program.files):
            blank()
        if number != MAIN_FILE or pfile.name or not pfile.rungs:
            statement(pfile, f"FILE {number}" + (f" {pfile.name}" if pfile.name else ""))
        for rung in pfile.rungs:
            blocks(comments.leading.get(id(rung), ()))
            out.extend(_rung_lines(rung, style, comments))
    blocks(comments.footer)
    while out and out[-1] == "":
        out.pop()
    return "\n".join(out) + "\n"
