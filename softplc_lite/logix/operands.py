"""Operands of the Logix instructions translated outside rungs.py's PLAN
table (copy.py, strings.py, system.py): each resolved by kind, with the
problems and warnings placed at the operand as rungs.py places them.

A handler builds its instructions from an :class:`Operands`; ``translate``
runs it, turning a PathError into a located problem, a NotRun or a
:class:`Skip` into a warning that the rung is not run, and a handler's
``NotImplemented`` (not its case: a compare of numbers) into rungs.py's own
translation.
"""

from __future__ import annotations

from ..datatable import Address
from ..ladder.ast import AddressRef, Const, Instruction
from .expr import ExprError, number
from .tags import NotRun, PathError, Resolved


class Skip(Exception):
    """The rung is not run: the reason (a warning, not an error)."""


class Operands:
    def __init__(self, el, pos, rung, ctx) -> None:
        self.el, self.pos, self.rung, self.ctx = el, pos, rung, ctx
        self.current = 0

    def __len__(self) -> int:
        return len(self.el.operands)

    def text(self, k: int) -> str:
        return self.el.operands[k][0].strip()

    def where(self, k: int):
        from . import rungs

        self.current = k
        return rungs._at(self.rung.pos, self.rung.text, self.el.operands[k][1])

    def resolve(self, k: int) -> Resolved:
        from . import rungs

        where = self.where(k)
        text = self.text(k)
        if text == "?":
            raise NotRun("an operand left as ? (a rung not finished in the export)")
        if text[:1] in ("'", '"'):
            raise NotRun("a string literal is not yet taken by softplc_lite (a string tag is)")
        try:
            return rungs._resolve(text, where, self.ctx)
        except NotRun:
            raise
        except PathError as e:
            message = self._message_member(text)
            if message is not None:
                raise NotRun(message, e.offset) from None
            raise

    def _ref(self, k: int) -> AddressRef:
        """Operand k as one value's address (rungs.py's ``_resolve_ref``)."""
        r = self.resolve(k)
        if r.address is None:
            raise PathError(f"{self.text(k)} is a {r.type.name}{' array' if r.dims else ''}: expected a single "
                            f"value here")
        return AddressRef(r.address, self.where(k))

    def _message_member(self, text: str) -> str | None:
        """Why a path into a MESSAGE tag that does not resolve is not the
        export's mistake (its Path and the other members softplc_lite does
        not hold), or None."""
        name = text.split(".", 1)[0].split("[", 1)[0].strip()
        try:
            r = self.ctx.directory.resolve(name, self.ctx.scope, _no_index)
        except PathError:
            return None
        if r.type.name != "MESSAGE" or "." not in text:
            return None
        return f"{text.split('.', 1)[1]} of a MESSAGE is not held by softplc_lite"

    def value(self, k: int):
        """A number or a tag's value (Logix: immediate or tag)."""
        where = self.where(k)
        v = number(self.text(k))
        if v is not None:
            return Const(v, where)
        return self._ref(k)

    def dest(self, k: int) -> AddressRef:
        self.where(k)
        if number(self.text(k)) is not None:
            raise PathError("expected a tag to write, found a number")
        ref = self._ref(k)
        if ref.address.bit is not None:
            raise PathError("expected a number tag, found a BOOL")
        return ref

    def string(self, k: int) -> tuple[AddressRef, int]:
        """A string tag (an ST element) and its type's characters."""
        r = self.resolve(k)
        if r.type.kind != "string" or r.dims:
            raise PathError(f"expected a string, found {r.type.name}{' array' if r.dims else ''}")
        return AddressRef(r.address, self.where(k)), r.type.chars

    def is_string(self, k: int) -> bool:
        """Whether operand k names a string (False for a number, an
        expression, or a path that does not resolve: rungs.py says why)."""
        text = self.text(k)
        if number(text) is not None:
            return False
        try:
            r = self.ctx.directory.resolve(text, self.ctx.scope, _no_index)
        except PathError:
            return False
        return r.type.kind == "string"

    def count(self, n: int) -> None:
        if len(self) != n:
            raise _Count(f"{self.el.mnemonic} takes {n} operand{'s' if n != 1 else ''}, found {len(self)}")


class _Count(Exception):
    pass


def _no_index(terms, constant, count) -> Address:
    """A trial resolve's index made at run time: a stand-in, nothing laid out."""
    return Address("L", 0, 0)


def translate(el, pos, rung, ctx, build) -> Instruction | None:
    """``build(operands)`` -> a list of instructions (the last is the
    instruction, the others go before it), or NotImplemented."""
    from . import rungs

    ops = Operands(el, pos, rung, ctx)
    before = list(ctx.before)
    try:
        out = build(ops)
    except _Count as e:
        ctx.problem(pos, f"rung {rung.number}: {e}")
        return None
    except Skip as e:
        ctx.warn(pos, f"rung {rung.number}: {el.mnemonic}: {e}; the rung is not run")
        ctx.skip = True
        return None
    except NotRun as e:
        ctx.warn(ops.where(ops.current), f"rung {rung.number}: {el.mnemonic} operand {ops.text(ops.current)!r}: "
                                         f"{e}; the rung is not run")
        ctx.skip = True
        return None
    except (PathError, ExprError) as e:
        column = el.operands[ops.current][1] + getattr(e, "offset", 0)
        ctx.problem(rungs._at(rung.pos, rung.text, column), f"rung {rung.number}: {el.mnemonic} operand "
                                                            f"{ops.text(ops.current)!r}: {e}")
        return None
    if out is NotImplemented:
        ctx.before = before
        return NotImplemented
    ctx.before += out[:-1]
    return out[-1]
