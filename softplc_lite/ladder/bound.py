"""Operand binding, the one protocol every instruction run by the engine
uses to reach its operands, and the built-in instructions written on it.

An :class:`Access` binds an operand once, at load, to a getter:

- ``access.location(op)`` -> ``get() -> (array, index, bit or None)``
- ``access.value(op)`` -> ``get() -> int | float`` (a constant, a word,
  a float, or 0/1 for a bit)
- ``access.expression(node)`` -> ``get() -> int | float`` (CPT-style
  expression; its ``#`` addresses follow S:24 at each call, which is how
  FAL and FSC step through files)
- ``access.operand(op)`` -> :class:`Operand`, the same getters as one
  object, with the operand's address or constant (what a plug-in module's
  instruction is given, ``InstructionContext.operands``)

Each executor binds through its own access: the compiled path resolves a
direct address once (:class:`BoundAccess`), the reference interpreter every
time it is used (:class:`ReferenceAccess`), so the executor differential
test compares two ways of finding operands for every instruction that
reads its operands through an access, built-in or a module's.

Built-in instructions with more state than a line of code (shift registers,
FIFOs, sequencers, file arithmetic, PID) are written on this protocol
rather than as a compiler template and an interpreter rule: one module per
group in ``ladder/instr/``, each declaring a :class:`BoundInstruction`
whose ``bind(instr, access)`` returns a callable taking the rung-in
condition and returning the rung-out one (as a module instruction's
instance does). The compiler emits ``c = _bN(c)``; the interpreter calls
the same object.

Faults: a bad indirect address raises the same MajorFault as built-in
instructions; a block past the end of its file raises FAULT_BLOCK_RANGE
(``block()`` below). The engine names the instruction in either case.
"""

from __future__ import annotations

from array import array
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Callable

from ..datatable import Address, DataTable, item_bit_mask
from ..datatable.errors import AddressRangeError
from .ast import AddressRef, Const, Instruction, address_refs
from .expr import evaluate, namespace, to_python
from .resolvers import address_fault, resolver
from .semantics import Machine, MajorFault
from . import status as S

if TYPE_CHECKING:  # pragma: no cover - type only
    from .specs import InstructionSpec

Location = tuple[array, int, "int | None"]
Run = Callable[[bool], bool]


@dataclass(frozen=True)
class BoundInstruction:
    """One built-in instruction implemented as a bound object.

    ``references(instr)``: addresses the instruction reaches beyond its
    operands (the last element of a file operand whose length is a
    constant), so the data table grows those files at load as it does for
    COP; the run still checks every block against its file.

    ``initial(instr)``: what a download writes for the instruction, as
    (address, value) pairs (the length and position operands of a shift
    register or sequencer go into its control's LEN and POS, as a timer's
    preset goes into PRE); only for a fresh table, like DATA values."""

    spec: "InstructionSpec"
    bind: Callable[[Instruction, "Access"], Run]
    references: Callable[[Instruction], list[Address]] | None = None
    initial: Callable[[Instruction], list[tuple[Address, int]]] | None = None


class Access:
    """How an instruction reaches its operands (see the module doc)."""

    cache_direct = False

    def __init__(self, table: DataTable, machine: Machine) -> None:
        self.table = table
        self.machine = machine

    def _resolve(self, address: Address) -> Location:
        try:
            f, index, bit = self.table.resolve(address)
        except AddressRangeError as e:
            raise address_fault(address, e) from None
        return f.data, index, bit

    def fixed(self, operand) -> Location | None:
        """The location of ``operand`` resolved once, now, when this access
        binds it so (a direct address on the compiled path); else None."""
        if self.cache_direct and isinstance(operand, AddressRef) and operand.address.is_direct:
            return self._resolve(operand.address)
        return None

    def location(self, operand) -> Callable[[], Location]:
        if not isinstance(operand, AddressRef):
            raise TypeError(f"{operand!r} is not an address")
        fixed = self.fixed(operand)
        if fixed is not None:
            return lambda: fixed
        resolve = self._resolve
        address = operand.address
        return lambda: resolve(address)

    def value(self, operand) -> Callable[[], int | float]:
        if isinstance(operand, Const):
            v = operand.value
            return lambda: v
        get = self.location(operand)

        def read():
            d, i, bit = get()
            return d[i] if bit is None else (d[i] >> bit) & 1
        return read

    def expression(self, node) -> Callable[[], int | float]:
        if isinstance(node, (Const, AddressRef)):
            return self.value(node)
        machine = self.machine
        getters = {id(leaf): self.location(leaf) for leaf in address_refs(node)}

        def compute():
            # Resolve every address first, in tree order (as compiled CPT
            # does), so an address fault comes before a minor fault.
            locs = {k: g() for k, g in getters.items()}

            def read(ref):
                d, i, bit = locs[id(ref)]
                return d[i] if bit is None else (d[i] >> bit) & 1
            return evaluate(node, read, machine)
        return compute

    def operand(self, operand) -> "Operand":
        return Operand(self, operand)


def _no_location() -> Location:
    raise TypeError("a constant operand has no location")


class Operand:
    """One operand bound through an :class:`Access`.

    ``constant`` (a Const's value) or ``address`` (an AddressRef's) is set,
    the other None; ``location()`` and ``value()`` are the access's getters;
    ``fixed`` is the location when the access resolved it once at bind
    (what an instance may keep instead of calling ``location()`` every
    scan), else None. A bad indirect address raises the same major fault as
    a built-in instruction's."""

    __slots__ = ("operand", "constant", "address", "fixed", "location", "value")

    def __init__(self, access: Access, operand) -> None:
        self.operand = operand
        self.constant = operand.value if isinstance(operand, Const) else None
        self.address = operand.address if isinstance(operand, AddressRef) else None
        if self.address is not None:
            self.fixed = access.fixed(operand)
            self.location = (lambda fixed=self.fixed: fixed) if self.fixed is not None else access.location(operand)
            self.value = access.value(operand)
        else:
            self.fixed = None
            self.location = _no_location
            constant = self.constant
            self.value = lambda: constant

    @property
    def text(self) -> str:
        return str(self.address) if self.address is not None else repr(self.constant)


# A bit's mask in an item of any width (what resolvers.resolver gives) -> the bit's number: the
# masks of the widths differ only in their top bit, negative (-128, -32768, -2**31, -2**63).
_BIT_OF_MASK = {item_bit_mask(b, size): b for size in (1, 2, 4, 8) for b in range(8 * size)}


class BoundAccess(Access):
    """The compiled path: a direct address is resolved once, at load, and an
    expression is made Python code once (the compiler's form of CPT's,
    expr.to_python) instead of a tree walked at each call."""

    cache_direct = True

    def location(self, operand) -> Callable[[], Location]:
        """An indirect or indexed address through the compiler's resolver
        (resolvers.resolver: fast paths for the common shapes), its bit mask
        given back as the bit's number."""
        if not isinstance(operand, AddressRef) or self.fixed(operand) is not None:
            return super().location(operand)
        locate = resolver(self.table, operand.address)
        bit_of = _BIT_OF_MASK

        def get() -> Location:
            d, i, mask = locate()
            return d, i, (None if mask is None else bit_of[mask])
        return get

    def expression(self, node) -> Callable[[], int | float]:
        if isinstance(node, (Const, AddressRef)):
            return self.value(node)
        ns: dict[str, object] = namespace(self.machine)
        names: dict[int, str] = {}
        resolve = []  # every address that is not fixed resolved first, in tree order, as Access.expression does
        for leaf in address_refs(node):
            if id(leaf) in names:
                continue
            k = len(names)
            fixed = self.fixed(leaf)
            if fixed is not None:
                d, i, bit = fixed
                ns[f"_d{k}"] = d
                names[id(leaf)] = f"_d{k}[{i}]" if bit is None else f"((_d{k}[{i}] >> {bit}) & 1)"
            else:
                ns[f"_g{k}"] = self.location(leaf)
                resolve.append(f"    _d{k}, _i{k}, _b{k} = _g{k}()\n")
                names[id(leaf)] = f"(_d{k}[_i{k}] if _b{k} is None else (_d{k}[_i{k}] >> _b{k}) & 1)"
        body = to_python(node, lambda ref: names[id(ref)])
        exec(compile(f"def compute():\n{''.join(resolve)}    return {body}\n", "<bound expression>", "exec"), ns)
        return ns["compute"]


class ReferenceAccess(Access):
    """The reference interpreter: every address resolved each time."""


def unary_store(fn: Callable[[int | float], int | float], after: Callable[[Machine], None] | None = None):
    """The bind of an instruction ``MNEM source dest`` that stores
    ``fn(source)`` the way math instructions do (``Machine.store``: float
    or word, overflow, S:0 flags) on a true rung; ``after(machine)`` may
    adjust the flags an instruction sets differently (TOD resets S)."""

    def bind(instr: Instruction, access: Access) -> Run:
        source = access.value(instr.operands[0])
        dest = access.location(instr.operands[1])
        m = access.machine

        def run(c: bool) -> bool:
            if c:
                d, i, _ = dest()
                m.store(fn(source()), d, i)
                if after is not None:
                    after(m)
            return c
        return run
    return bind


def block(d: array, i: int, words: int, what: str) -> None:
    """A file operand of ``words`` words from index ``i``: a major fault
    when it runs past the end of its file (as COP and FLL)."""
    if i < 0 or i + words > len(d):
        raise MajorFault(S.FAULT_BLOCK_RANGE, f"{words} words from {what} run past the end of the file "
                         f"({len(d)} words)")


def file_references(instr: Instruction, operand: int, length: int | None) -> list[Address]:
    """The last element of file operand ``operand`` when ``length`` (a
    constant element count) is known and the address is direct."""
    if length is None or length < 1 or operand >= len(instr.operands):
        return []
    op = instr.operands[operand]
    if not isinstance(op, AddressRef) or not op.address.is_direct or op.address.element is None:
        return []
    return [op.address.with_element(op.address.element + length - 1)]


LEN, POS = 1, 2  # words of a control (R) element after its status word


def control_words(instr: Instruction, control: int, length: int, position: int | None = None
                  ) -> list[tuple[Address, int]]:
    """What a download writes for an instruction with a control: the length
    (and position) operands into the control's LEN (and POS); nothing for a
    control reached indirectly."""
    address = instr.operands[control].address
    if not address.is_direct:
        return []
    out = [(replace(address, member="LEN"), constant(instr, length))]
    if position is not None:
        out.append((replace(address, member="POS"), constant(instr, position)))
    return out


def constant(instr: Instruction, operand: int) -> int | float | None:
    """Operand ``operand`` when it is a constant, else None."""
    if operand < len(instr.operands) and isinstance(instr.operands[operand], Const):
        return instr.operands[operand].value
    return None
