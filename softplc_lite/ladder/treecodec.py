"""A validated program as plain data for the code cache (ladder/codecache.py).

``encode`` turns a Program into tuples, ints and strings that ``marshal``
writes (and reads back in a fraction of the time pickle takes for the
same tree: pickle builds every node through its constructor and a dict of
state); ``decode`` builds the same tree again. Addresses and the rare
operand kinds (expressions, text, symbols) travel as one pickle beside it.
Positions keep their source, line and column. The cache keys this data by
the program text it came from, so decode never sees a tree that the
grammar and the validator did not make.
"""

from __future__ import annotations

import pickle

from ..gcpause import gc_paused
from . import ast as A
from .ast import AddressRef, Branch, Const, Instruction, Placeholder, Program, Rung

_new = object.__new__
_MASK = A._LINE_MASK
_BITS = A._LINE_BITS

# Node tags (first item of an encoded element or operand).
_INSTRUCTION, _BRANCH, _ADDRESS, _CONST, _OTHER = range(5)


class _Encoder:
    def __init__(self) -> None:
        self.sources: list[str] = []
        self.source_index: dict[int, int] = {}  # process source number -> index in self.sources
        self.addresses: list = []
        self.address_index: dict[int, int] = {}  # id(Address) -> index
        self.others: list = []  # operands pickled as they are

    def where(self, node) -> int:
        w = node._where
        number = w >> _BITS
        k = self.source_index.get(number)
        if k is None:
            k = self.source_index[number] = len(self.sources)
            self.sources.append(A._SOURCES[number])
        return k << _BITS | (w & _MASK)

    def operand(self, op):
        cls = op.__class__
        if cls is AddressRef:
            a = op.address
            k = self.address_index.get(id(a))
            if k is None:
                k = self.address_index[id(a)] = len(self.addresses)
                self.addresses.append(a)
            return (_ADDRESS, k, self.where(op), op._column)
        if cls is Const:
            return (_CONST, op.value, op.hex, self.where(op), op._column)
        self.others.append(op)
        return (_OTHER, len(self.others) - 1)

    def element(self, el):
        if el.__class__ is Instruction:
            return (_INSTRUCTION, el.mnemonic, tuple(self.operand(op) for op in el.operands), self.where(el), el._column)
        return (_BRANCH, tuple(tuple(self.element(e) for e in leg) for leg in el.legs), self.where(el), el._column)

    def rung(self, r: Rung):
        return (tuple(self.element(e) for e in r.elements), r.comment, self.where(r), r._column)


@gc_paused
def encode(program: Program) -> tuple:
    """(plain data, pickle bytes of the addresses and other objects)."""
    enc = _Encoder()
    files = tuple((f.number, tuple(enc.rung(r) for r in f.rungs)) for f in program.files.values())
    shell = Program({n: A.ProgramFile(f.number, f.name, [], f.pos, f.listing) for n, f in program.files.items()},
                    program.data, program.symbols)
    extra = pickle.dumps((enc.addresses, enc.others, shell), protocol=pickle.HIGHEST_PROTOCOL)
    return (tuple(enc.sources), files), extra


@gc_paused
def decode(data: tuple, extra: bytes) -> Program:
    sources, files = data
    addresses, others, program = pickle.loads(extra)
    # Each cached source's number in this process (positions keep it in their int).
    shift = [A._where_of(A.Pos(s, 0, 0)) >> _BITS << _BITS for s in sources]
    set_address = AddressRef.address.__set__
    set_value, set_hex = Const.value.__set__, Const.hex.__set__
    set_where, set_column = A._set_where, A._set_column

    memo: dict[int, int] = {}

    def where(w: int) -> int:
        # One int per line, shared by its nodes, as the parser makes them.
        here = memo.get(w)
        if here is None:
            here = memo[w] = shift[w >> _BITS] | (w & _MASK)
        return here

    def operand(e):
        tag = e[0]
        if tag == _ADDRESS:
            node = _new(AddressRef)
            set_address(node, addresses[e[1]])
            set_where(node, where(e[2]))
            set_column(node, e[3])
            return node
        if tag == _CONST:
            node = _new(Const)
            set_value(node, e[1])
            set_hex(node, e[2])
            set_where(node, where(e[3]))
            set_column(node, e[4])
            return node
        return others[e[1]]

    def element(e):
        if e[0] == _INSTRUCTION:
            node = _new(Instruction)
            node.mnemonic = e[1]
            ops = e[2]
            if len(ops) == 1:
                op = ops[0]
                if op[0] == _ADDRESS:  # the common instruction, XIC B3/0: written out
                    ref = _new(AddressRef)
                    set_address(ref, addresses[op[1]])
                    set_where(ref, where(op[2]))
                    set_column(ref, op[3])
                    node._operands = ref
                else:
                    node._operands = operand(op)
            else:
                node._operands = tuple([operand(op) for op in ops])
            node._where = where(e[3])
            node._column = e[4]
            return node
        node = _new(Branch)
        node.legs = tuple([tuple([element(x) for x in leg]) for leg in e[1]])
        node._where = where(e[2])
        node._column = e[3]
        return node

    for number, rungs in files:
        out = program.files[number].rungs
        for elements, comment, w, column in rungs:
            r = _new(Rung)
            r.elements = tuple([element(x) for x in elements])
            r.comment = comment
            r._where = where(w)
            r._column = column
            out.append(r)
    return program


__all__ = ["encode", "decode", "Placeholder"]
