"""How the watch view names what it shows: operands, instructions and
program files. A PLC-5 app shows each operand's address, with its symbol
above or before it when the program declares one; a Logix app (a Studio
5000 export, docs/logix.md) shows its operands by tag path alone, in the
scope of the routine shown, its instructions by their Logix names and its
program files as routines. The rung drawing (cells.py) asks the names
object of the file it draws and knows nothing of Logix.
"""

from __future__ import annotations

from collections.abc import Mapping

from ..datatable import Address
from ..ladder.ast import MAIN_FILE
from ..ladder.fmt import format_expression
from ..ladder.instr.logix import LOGIX_NAMES
from ..logix.names import OperandNames
from ..logix.tags import TagSymbols

LOGIX_OPERATORS = {"|": "/", "//": "/"}  # the ladder's operators Logix writes otherwise (1756-RM003, "CPT")


class SymbolNames:
    """Address -> symbol name; a bit or word of a named element is named
    after it (``Reply/DN`` for R6:1/DN when Reply is R6:1). The address is
    shown too (``replaces_address`` False)."""

    replaces_address = False

    def __init__(self, symbols: Mapping[str, object] | None) -> None:
        self.by_address: dict[str, str] = {}
        for name, target in (symbols or {}).items():
            address = getattr(target, "address", target)
            self.by_address.setdefault(str(address), name)

    def name(self, address: Address) -> str | None:
        if not self.by_address or not address.is_direct:
            return None
        text = str(address)
        found = self.by_address.get(text)
        if found is not None or (address.bit is None and address.member is None) or address.element is None:
            return found
        element = str(Address(address.type_letter, address.file, address.element))
        owner = self.by_address.get(element)
        if owner is not None and text.startswith(element):
            return owner + text[len(element):]
        return None

    def mnemonic(self, mnemonic: str) -> str:
        return mnemonic

    def expression(self, node) -> str:
        return format_expression(node)

    def file_name(self, number: int) -> str | None:
        """What a JSR to file ``number`` names (None: the file's number)."""
        return None


class TagPathNames:
    """A Logix app's operands as tag paths seen from one routine's program
    (``scope``); the address only where no tag path says it."""

    replaces_address = True

    def __init__(self, operands, scope: str | None) -> None:
        self.operands = operands  # logix.names.OperandNames
        self.scope = scope
        self.cache: dict[Address, str | None] = {}

    def name(self, address: Address) -> str | None:
        try:
            return self.cache[address]
        except KeyError:
            found = self.operands.name_of(address, self.scope)
            if found and found.upper().endswith(".CTL"):  # a TIMER's, COUNTER's or CONTROL's hidden word: the tag
                found = found[:-4]
            self.cache[address] = found
            return found

    def mnemonic(self, mnemonic: str) -> str:
        return LOGIX_NAMES.get(mnemonic, mnemonic)

    def expression(self, node) -> str:
        return format_expression(node, self.name, LOGIX_OPERATORS)

    def file_name(self, number: int) -> str | None:
        routine = self.operands.routine_of(number)
        if routine is None:
            return None
        program, _, name = routine.partition(".")
        return name if (program or "").upper() == (self.scope or "").upper() else routine


def routines_of(program) -> tuple[tuple[int, str], ...]:
    """A Logix app's routines, (program file, ``Program.Routine``): what a
    report keeps to name a few rungs later (names_in_file); () for another
    app."""
    operands = OperandNames.of(program)
    return tuple(sorted(operands.routines.items())) if operands is not None else ()


def names_in_file(symbols, routines: tuple[tuple[int, str], ...], number: int | None):
    """The operand names of program file ``number`` for a report's drawing
    of a few rungs, and what the file is called: a Logix app's (its
    ``routines``, routines_of) by tag path in its routine's scope, another's
    by symbol and address."""
    if routines and isinstance(symbols, TagSymbols):
        operands = OperandNames(symbols.directory, dict(routines))
        names = TagPathNames(operands, operands.scope_of(number))
        routine = operands.routine_of(number) if number is not None else None
        return names, (f"routine {routine}" if routine else f"program file {number}")
    return SymbolNames(symbols), f"program file {number}"


class Naming:
    """The names of one app: ``for_file(n)`` the operand names of program
    file ``n``'s rungs; ``file_label`` what the file list calls a file;
    ``what_files`` what the files are (``program file``, ``routine``)."""

    def __init__(self, app) -> None:
        self.app = app
        self._learn()

    def _learn(self) -> None:
        """The names of the app's program as it is now."""
        program = self.app.program
        self.symbols = program.symbols
        self.plain = SymbolNames(self.symbols)
        self.by_file: dict[int | None, TagPathNames] = {}
        self.operands = OperandNames.of(program)

    def _current(self) -> None:
        if self.app.program.symbols is not self.symbols:  # an online edit put a new program (and tags) in place
            self._learn()

    @property
    def is_logix(self) -> bool:
        return self.operands is not None

    def for_file(self, number: int | None):
        self._current()
        if self.operands is None:
            return self.plain
        names = self.by_file.get(number)
        if names is None:
            names = self.by_file[number] = TagPathNames(self.operands, self.operands.scope_of(number))
        return names

    def where(self, number: int) -> str:
        """A file as a list of uses names it: ``file 3``; a Logix app's by
        its routine (``MainProgram.FillTank``) or task."""
        self._current()
        pfile = self.app.program.files.get(number)
        if self.operands is not None and pfile is not None and pfile.name:
            return pfile.name
        return f"file {number}"

    def file_label(self, pfile) -> str:
        if self.operands is not None and pfile.name:
            return pfile.name
        return f"{pfile.number} {pfile.name}" if pfile.name else str(pfile.number)

    def tag_grid(self, table, text: str):
        """The tag monitor ``d TEXT`` shows in a Logix app (tagbrowser.py);
        None when TEXT names no tag (or the app is not a Logix app)."""
        self._current()
        if self.operands is None:
            return None
        from .tagbrowser import tag_grid_for

        return tag_grid_for(self.app.program.symbols.directory, table, text)

    @property
    def what_files(self) -> tuple[str, str]:
        """The shown file's title and the list's: a Logix app's files are routines."""
        return ("routine", "routines") if self.operands is not None else ("program file", "files")

    def first_file(self, files: list[int]) -> int | None:
        """The file shown at start: the main file (2); for a Logix app the
        routine the continuous task runs first, where its rungs are (a
        choice: file 2 holds only the tasks' JSRs)."""
        program = self.app.program
        if self.operands is not None and MAIN_FILE in program.files:
            for rung in program.files[MAIN_FILE].rungs:
                for el in rung.elements:
                    target = getattr(el, "operands", [None])[0] if getattr(el, "mnemonic", None) == "JSR" else None
                    number = getattr(target, "value", None)
                    if number in files and self.operands.routine_of(number) is not None:  # not a periodic task's file
                        return number
        return MAIN_FILE if MAIN_FILE in files else files[0] if files else None
