"""The straight-line baseline for the engine targets: a boolean ladder
program written as the Python one would write by hand for that one program.

ONE function for the whole main file: every data-table word the program
uses is read once into a local at the top; the rungs follow in order as
plain expressions on those locals (XIC/XIO a mask test, OTE/OTL/OTU a mask
set or clear, branches an ``or`` of their legs); every word written is
stored back once at the end. It is generated from the same validated rungs
the engine compiles, with the PLC semantics the engine has (1785-6.1 and
docs/instructions.md): each rung starts true; a series of contacts is the
``and`` of them; a branch passes power if any leg does; OTE writes its bit
from the rung condition; OTL/OTU write only when it is true; a write is seen
by every later rung (they read the same local).

It is a yardstick, not an executor: it covers XIC, XIO, OTE, OTL, OTU on
direct bit addresses and branches of them (the boolean benchmark program),
and raises ValueError on anything else. It has none of the engine's duties
(faults naming the rung, the watch view's power flow, breakpoints, module
instructions): the issue's target is the engine within 2x of it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

CONTACTS = ("XIC", "XIO")
COILS = ("OTE", "OTL", "OTU")


@dataclass
class StraightLine:
    scan: Callable[[], None]  # one pass over the main file on the table it was built for
    source: str  # the generated Python text
    words_read: int  # locals loaded at the top
    words_written: int  # words stored back at the end
    instructions: int


def _is_branch(element) -> bool:
    return getattr(element, "legs", None) is not None  # duck-typed: a baseline commit's AST classes differ


def _contacts_only(elements) -> bool:
    for el in elements:
        if _is_branch(el):
            if not all(_contacts_only(leg) for leg in el.legs):
                return False
        elif el.mnemonic not in CONTACTS:
            return False
    return True


class _Writer:
    def __init__(self, table) -> None:
        self.table = table
        self.lines: list[str] = []
        self.words: dict[tuple[int, int], str] = {}  # (file number, word index) -> local name
        self.written: set[tuple[int, int]] = set()
        self.instructions = 0

    def bit(self, instruction) -> tuple[str, int, tuple[int, int]]:
        """(local name, mask, word key) of the instruction's one bit operand."""
        operands = instruction.operands
        if len(operands) != 1:
            raise ValueError(f"{instruction.mnemonic}: expected one operand, got {len(operands)}")
        address = getattr(operands[0], "address", None)
        if address is None or not address.is_direct or address.bit is None:
            raise ValueError(f"{instruction.mnemonic} {operands[0]}: the baseline takes direct bit addresses only")
        data_file, index, bit = self.table.resolve(address)
        key = (data_file.number, index)
        name = self.words.setdefault(key, f"w{data_file.number}_{index}")
        # bit 15 is -32768 in a signed word (datatable.bit_mask): | and & ~ keep it in range
        return name, (-32768 if bit == 15 else 1 << bit), key

    def term(self, element) -> str:
        """A Python boolean expression for a contact or a contacts-only branch."""
        if _is_branch(element):
            legs = []
            for leg in element.legs:
                terms = [self.term(e) for e in leg]
                legs.append("True" if not terms else terms[0] if len(terms) == 1 else "(" + " and ".join(terms) + ")")
            return "(" + " or ".join(legs) + ")"
        self.instructions += 1
        name, mask, _ = self.bit(element)
        return f"{name} & {mask}" if element.mnemonic == "XIC" else f"not {name} & {mask}"

    def emit(self, text: str) -> None:
        self.lines.append("    " + text)

    def series(self, elements, depth: int, c_is_true: bool) -> bool:
        """Emit one series; returns whether ``c`` is still the constant True."""
        terms: list[str] = []

        def flush(c_true: bool) -> bool:
            if terms:
                self.emit(("c = " if c_true else "c = c and ") + " and ".join(terms))
                terms.clear()
                return False
            if c_true:
                self.emit("c = True")
            return False

        for el in elements:
            if _contacts_only([el]):  # a contact, or a branch of contacts only: one term of an `and`
                terms.append(self.term(el))
            elif _is_branch(el):
                c_is_true = flush(c_is_true)
                if all(not _is_branch(e) and e.mnemonic in COILS for leg in el.legs for e in leg):
                    for leg in el.legs:  # parallel coils: each leg passes the rung-in on unchanged
                        self.series(leg, depth + 1, False)
                    continue
                self.emit(f"b{depth} = c")
                self.emit(f"o{depth} = False")
                for leg in el.legs:
                    self.emit(f"c = b{depth}")
                    self.series(leg, depth + 1, False)
                    self.emit(f"o{depth} = o{depth} or c")
                self.emit(f"c = o{depth}")
            elif el.mnemonic in COILS:
                c_is_true = flush(c_is_true)
                self.instructions += 1
                name, mask, key = self.bit(el)
                self.written.add(key)
                if el.mnemonic == "OTE":
                    self.emit(f"{name} = ({name} | {mask}) if c else ({name} & {~mask})")
                elif el.mnemonic == "OTL":
                    self.emit(f"if c: {name} |= {mask}")
                else:
                    self.emit(f"if c: {name} &= {~mask}")
            else:
                raise ValueError(f"{el.mnemonic}: the straight-line baseline covers XIC XIO OTE OTL OTU and branches")
        # contacts after the last coil still end the rung (its rung-out), as in the engine
        if terms:
            c_is_true = flush(c_is_true)
        return c_is_true


def build(program, table, file_number: int = 2) -> StraightLine:
    """The straight-line function for ``program``'s file ``file_number``,
    reading and writing ``table`` (its own table: give it a copy of the
    engine's initial one)."""
    writer = _Writer(table)
    for k, rung in enumerate(program.files[file_number].rungs):
        writer.lines.append(f"    # rung {k}")
        writer.series(rung.elements, 0, True)
    files = sorted({number for number, _ in writer.words})
    params = ", ".join(f"f{n}=f{n}" for n in files)
    head = [f"def straight_line_scan({params}):"]
    head += [f"    {name} = f{n}[{i}]" for (n, i), name in sorted(writer.words.items())]
    tail = [f"    f{n}[{i}] = {writer.words[(n, i)]}" for n, i in sorted(writer.written)]
    source = "\n".join(head + writer.lines + tail) + "\n"
    namespace = {f"f{n}": table.file(n).data for n in files}
    exec(compile(source, "<straight-line baseline>", "exec"), namespace)  # noqa: S102 - source built from validated bit addresses only
    return StraightLine(namespace["straight_line_scan"], source, len(writer.words), len(writer.written),
                        writer.instructions)
