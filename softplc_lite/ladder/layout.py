"""Load-time table work: the data table a program lays out.

Before the first scan (and for ``softplc check``, and for an online edit's
trial) the table grows to every file and element the program names
(``reference_program``, ``reference_module_blocks``) and takes what a
download writes (``initial_values``: DATA values, timer/counter presets,
the initial words of bound instructions). With a ``problems`` list each
function lists what the table refuses, located, instead of raising.
"""

from __future__ import annotations

from dataclasses import replace

from ..datatable import DataTable, DataTableError, parse_address
from ..datatable.filetypes import Storage, split_file_name
from .ast import AddressRef, Const, Pos, Program, address_refs, instructions_of, walk
from .errors import LadderError
from .instr import BOUND
from .semantics import source_units


def reference_program(program: Program, table: DataTable, problems: list | None = None) -> None:
    """Grow the table to everything the program names (and COP/FLL blocks).
    With ``problems``, what the table refuses is listed there, located at
    the declaration or instruction (softplc check), instead of raised."""
    for decl in program.data:
        ftype, digits = split_file_name(decl.file)
        with located(decl.pos, problems):
            table.create_file(ftype.letter, int(digits), decl.size)
    seen: set[int] = set()  # ids of addresses referenced: the parser makes one Address per text
    for pfile in program.files.values():
        for rung in pfile.rungs:
            for ins in instructions_of(rung.elements):
                try:
                    _reference_instruction(ins, table, seen)
                except DataTableError as e:  # (a try, not a with per instruction: load time)
                    with located(ins.pos, problems):
                        raise e from None


def _reference_instruction(ins, table: DataTable, seen: set[int]) -> None:
    for op in ins.operands:
        if op.__class__ is AddressRef:
            refs = (op,)
        elif op.__class__ is Const:
            continue
        else:
            refs = address_refs(op)
        for ref in refs:
            a = ref.address
            if id(a) not in seen:
                table.reference(a)
                seen.add(id(a))
    bound = BOUND.get(ins.mnemonic)
    if bound is not None and bound.references is not None:
        for address in bound.references(ins):
            table.reference(address)
    if ins.mnemonic in ("COP", "FLL") and ins.operands[1].address.is_direct:
        n = ins.operands[2].value
        dest = ins.operands[1].address
        for ref in ins.operands[:2]:
            if isinstance(ref, AddressRef) and ref.address.is_direct:
                # a COP source in another storage (F vs words) spans the same bytes
                count = source_units(n, ref.address.ftype, dest.ftype)
                table.reference(ref.address.with_element(ref.address.element + count - 1))


_PRESET = frozenset({"TON", "TOF", "RTO", "CTU", "CTD"})


def initial_values(program: Program, table: DataTable, problems: list | None = None) -> None:
    """What a download sets: DATA initial values, and the preset and
    accumulator operands of TON/TOF/RTO/CTU/CTD (as RSLogix 5 does)."""
    for decl in program.data:
        for k, (address, value) in enumerate(data_values(decl)):
            with located(decl.pos, problems, f"DATA {decl.file} value {k + 1}: "):
                write_data_value(table, address, value)
    for address, value, pos in instruction_writes(program):
        with located(pos, problems):
            table.write(address, value)


def data_values(decl):
    """(address, value) of each value of a DATA declaration, in order."""
    for k, value in enumerate(decl.values):
        yield parse_address(f"{decl.file}:0").with_element(k), value  # not text: O0 and I1 count in octal


def write_data_value(table: DataTable, address, value) -> None:
    """One DATA value written as a download writes it: an integer above
    32767 for a word file is stored as its 16 bits (0xFFFF, as RSLogix
    shows a word in hex), any other value as the table converts it."""
    if isinstance(value, int) and address.ftype.storage is Storage.WORD and value > 32767:
        table.write_word(address, value)
    else:
        table.write(address, value)


def instruction_writes(program: Program) -> list[tuple]:
    """(address, value, pos) that a download writes for the instructions:
    the preset and accumulator operands of TON/TOF/RTO/CTU/CTD into PRE and
    ACC, and each bound instruction's ``initial`` (a control's LEN, POS)."""
    out = []
    for pfile in program.files.values():
        for rung in pfile.rungs:
            for ins in instructions_of(rung.elements):
                if ins.mnemonic in _PRESET and ins.operands[0].address.is_direct:
                    pre, acc = ins.operands[-2], ins.operands[-1]
                    timer = ins.operands[0].address
                    out.append((replace(timer, member="PRE"), pre.value, ins.pos))
                    out.append((replace(timer, member="ACC"), acc.value, ins.pos))
                bound = BOUND.get(ins.mnemonic)
                if bound is not None and bound.initial is not None:
                    out += [(address, value, ins.pos) for address, value in bound.initial(ins)]
    return out


def layout_problems(program: Program, modules=()) -> tuple[DataTable, list[LadderError]]:
    """Build the data table a run would start with (files, sizes, initial
    values, module blocks) and list, located, everything it refuses: so that
    ``softplc check`` reports first whatever ``softplc run`` would refuse."""
    table = DataTable()
    problems: list[LadderError] = []
    reference_program(program, table, problems)
    initial_values(program, table, problems)
    for module in modules:
        where = Pos(f"{module.config_file or module.name} ({module.name})", 0, 0)
        for address in module.config_references():
            with located(where, problems):
                table.reference(address)
    reference_module_blocks(program, table, {spec.mnemonic: m for m in modules for spec in m.instructions()},
                            problems)
    return table, problems


def reference_module_blocks(program: Program, table: DataTable, owner: dict, problems: list | None = None) -> None:
    """Grow the table to what module instructions reach beyond their
    operands (``owner``: mnemonic -> module); ``problems`` as for
    reference_program."""
    if not owner:
        return
    for pfile in program.files.values():
        for rung in pfile.rungs:
            for ins in walk(rung.elements):
                module = owner.get(ins.mnemonic)
                if module is not None:
                    with located(ins.pos, problems):
                        for address in module.references(ins):
                            table.reference(address)


class located:
    """Raise a DataTableError as is, or (with a problems list) add it there
    as a LadderError at ``pos``."""

    def __init__(self, pos, problems: list | None, prefix: str = "") -> None:
        self.pos, self.problems, self.prefix = pos, problems, prefix

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind, exc, tb) -> bool:
        if exc is None or self.problems is None or not isinstance(exc, DataTableError):
            return False
        self.problems.append(LadderError(self.pos, f"{self.prefix}{exc}"))
        return True
