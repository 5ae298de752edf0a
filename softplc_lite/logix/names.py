"""What a view shows for a Logix app's operands and program files: an
operand's tag path in the scope of the routine it is in (a program's own
tags without ``Program:``), also for an element a tag indexes
(``Tanks[Active].Level`` for F12:[L15:0]); a program file by its routine
(``MainProgram.MainRoutine``) and that routine's program (its scope).
tags.TagNames does the direct addresses; docs/logix.md, "Watching a Logix
app", says what the view shows."""

from __future__ import annotations

from ..datatable import Address
from ..ladder.ast import Program
from .tags import TagDirectory, TagNames, TagSymbols, _path_text


class OperandNames:
    """Addresses of a Logix app's program back to tag paths, per scope:
    ``directory`` its tags, ``routines`` {program file: "Program.Routine"}."""

    def __init__(self, directory: TagDirectory, routines: dict[int, str]) -> None:
        self.names = TagNames(directory)
        self.routines = routines

    @classmethod
    def of(cls, program: Program) -> "OperandNames | None":
        """The names of ``program``, a Logix app's (its symbols are the tag
        directory's: tags.TagSymbols); None for another program. Its
        routines are the files project.py names ``Program.Routine``."""
        if not isinstance(program.symbols, TagSymbols):
            return None
        routines = {n: f.name for n, f in program.files.items() if f.name and "." in f.name}
        return cls(program.symbols.directory, routines)

    def scope_of(self, file_number: int | None) -> str | None:
        """The program whose tags a file's rungs name without ``Program:``
        (None for the continuous task: the controller's scope)."""
        name = self.routines.get(file_number) if file_number is not None else None
        return name.split(".", 1)[0] if name else None

    def routine_of(self, file_number: int) -> str | None:
        """``Program.Routine`` of a routine's file; None for another file."""
        return self.routines.get(file_number)

    def name_of(self, address: Address, scope: str | None = None) -> str | None:
        """The tag path of ``address`` seen from ``scope``, or None (not a
        tag's item, or an indirection a tag path does not say)."""
        if address.is_direct:
            return self.names.name_of(address, scope)
        return self._indexed(address, scope)

    def _indexed(self, address: Address, scope: str | None) -> str | None:
        """An element of a one-dimension array taken by an index tag
        (``Tanks[Active].Level``, ``Tanks[Active].Fill``): the path with the
        index tag's name as its subscript."""
        index = address.element
        if (address.indexed or not isinstance(address.file, int) or not isinstance(index, Address)
                or address.member or not (address.bit is None or isinstance(address.bit, int))
                or address.type_letter == "B"):
            return None
        index_name = self.names.name_of(index, scope)
        if index_name is None:
            return None
        for d, path, leaf in self.names.by_file.get(address.file, ()):
            if leaf.letter != address.type_letter or leaf.first != 0:
                continue
            text = _path_text(d, path, 0, address.bit)
            if text.count("[0]") != 1 or text.count("[") != 1:  # one dimension on the way: the one indexed
                return None
            text = text.replace("[0]", f"[{index_name}]")
            if d.scope and (scope or "").upper() != d.scope.upper():
                text = f"Program:{d.scope}.{text}"
            return text
        return None
