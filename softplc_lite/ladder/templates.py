"""The compiler's instruction templates that work on the data table in
place (after a barrier: every held word written back, ladder/held_words.py),
and program control. Each ``i_MNEMONIC`` emits the code of one instruction;
kernels with real logic are Machine methods (semantics.py), shared with the
reference interpreter.
"""

from __future__ import annotations

from . import status as S
from .ast import AddressRef
from .blocks import RET, RUNG_BOOL, TND
from .held_words import _SIMPLE, _is_word, _word_valued
from .semantics import BASE_MS, MajorFault, lim, source_units


class TableTemplates:
    """Mixin of _FileCompiler: one method per instruction."""

    # Bit instructions on indirect or indexed addresses, on the table.
    def i_XIC(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, f"c = c and {d}[{i}] & {mk} != 0")

    def i_XIO(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, f"c = c and not {d}[{i}] & {mk}")

    def i_OTE(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, f"{d}[{i}] = ({d}[{i}] | {mk}) if c else ({d}[{i}] & ~{mk})")

    def i_OTL(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, f"if c: {d}[{i}] |= {mk}")

    def i_OTU(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, f"if c: {d}[{i}] &= ~{mk}")

    def i_ONS(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, "if c:")
        self.emit(ind + 1, f"if {d}[{i}] & {mk}: c = False")
        self.emit(ind + 1, f"else: {d}[{i}] |= {mk}")
        self.emit(ind, f"else: {d}[{i}] &= ~{mk}")

    def _one_shot(self, ind, ops, rising: bool):
        sd, si, sm = self.location(ind, ops[0])
        od, oi, om = self.location(ind, ops[1])
        stored = f"{sd}[{si}] & {sm}"
        fire = f"c and not {stored}" if rising else f"not c and {stored}"
        self.emit(ind, f"{od}[{oi}] = ({od}[{oi}] | {om}) if ({fire}) else ({od}[{oi}] & ~{om})")
        self.emit(ind, f"{sd}[{si}] = ({sd}[{si}] | {sm}) if c else ({sd}[{si}] & ~{sm})")

    def i_OSR(self, ind, ops):
        self._one_shot(ind, ops, True)

    def i_OSF(self, ind, ops):
        self._one_shot(ind, ops, False)

    def _timer(self, ind, ops, kernel: str):
        d, i, _ = self.location(ind, ops[0])
        fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
        self.emit(ind, f"{fn}({d}, {i}, {RUNG_BOOL}, {BASE_MS[ops[1].value]!r})")

    def i_TON(self, ind, ops):
        self._timer(ind, ops, "ton")

    def i_TOF(self, ind, ops):
        self._timer(ind, ops, "tof")

    def i_RTO(self, ind, ops):
        self._timer(ind, ops, "rto")

    def _counter(self, ind, ops, kernel: str):
        d, i, _ = self.location(ind, ops[0])
        fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
        self.emit(ind, f"{fn}({d}, {i}, {RUNG_BOOL})")

    def i_CTU(self, ind, ops):
        self._counter(ind, ops, "ctu")

    def i_CTD(self, ind, ops):
        self._counter(ind, ops, "ctd")

    def i_RES(self, ind, ops):
        self.emit(ind, "if c:")
        d, i, _ = self.location(ind + 1, ops[0])
        self.emit(ind + 1, f"{self.bind('_res', self.machine.res)}({d}, {i})")

    def i_LIM(self, ind, ops):
        lo, t, hi = (self.value(ind, o) for o in ops)
        self.emit(ind, f"c = c and {self.bind('_lim', lim)}({lo}, {t}, {hi})")

    def i_MEQ(self, ind, ops):
        src, mask, cmp_ = (self.value(ind, o) for o in ops)
        self.emit(ind, f"c = c and ({src} & {mask}) == ({cmp_} & {mask})")

    def i_CMP(self, ind, ops):
        self.emit(ind, "if c:")
        self.emit(ind + 1, f"c = bool({self.expression(ind + 1, ops[0])})")

    def _store(self, ind, dest, value_code: str, kernel: str = "store", value=None):
        if self.inline_dest is not None:  # MOV/CPT of a word value into a held word (in_place)
            self.bind("_s", self.machine.s)
            fn = self.bind("_store", self.machine.store)
            self.store_in_local(ind + 1, dest, value_code, f"{fn}(_v, _D_)", in_range=_is_word(value))
            return
        d, i, _ = self.location(ind + 1, dest)
        if kernel == "store" and value is not None and _is_word(dest) and _word_valued(value):
            kernel = "store_word"
        fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
        self.emit(ind + 1, f"{fn}({value_code}, {d}, {i})")

    def _math2(self, ind, ops, kernel: str):
        self.emit(ind, "if c:")
        a, b = self.value(ind + 1, ops[0]), self.value(ind + 1, ops[1])
        if self.inline_dest is not None:  # ADD/SUB of words into a held word (in_place)
            # Operands read in place are read once (the sum, the carry and a fallback use them);
            # an operand that is the destination's local too (SUB N7:4 1 N7:4) is copied, as the
            # carry is worked out after the store.
            if not _SIMPLE.match(a) or a == self.inline_dest:
                self.emit(ind + 1, f"_a = {a}")
                a = "_a"
            if not _SIMPLE.match(b) or b == self.inline_dest:
                self.emit(ind + 1, f"_b = {b}")
                b = "_b"
            self.bind("_s", self.machine.s)
            fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
            a16, b16 = (repr(int(x) & 65535) if x.lstrip("-").isdigit() else f"({x} & 65535)" for x in (a, b))
            symbol, carry = ("+", f"{a16} + {b16} > 65535") if kernel == "add" else ("-", f"{a16} < {b16}")
            self.store_in_local(ind + 1, ops[2], f"{a} {symbol} {b}", f"{fn}({a}, {b}, _D_)", carry=carry)
            return
        d, i, _ = self.location(ind + 1, ops[2])
        if kernel in ("add", "sub") and all(_is_word(op) for op in ops):
            kernel += "_words"
        fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
        self.emit(ind + 1, f"{fn}({a}, {b}, {d}, {i})")

    def i_ADD(self, ind, ops):
        self._math2(ind, ops, "add")

    def i_SUB(self, ind, ops):
        self._math2(ind, ops, "sub")

    def i_DIV(self, ind, ops):
        self._math2(ind, ops, "div")

    def i_MOD(self, ind, ops):
        self._math2(ind, ops, "mod")

    def i_MUL(self, ind, ops):
        self.emit(ind, "if c:")
        a, b = self.value(ind + 1, ops[0]), self.value(ind + 1, ops[1])
        self._store(ind, ops[2], f"{a} * {b}")

    def i_NEG(self, ind, ops):
        self.emit(ind, "if c:")
        v = self.value(ind + 1, ops[0])
        d, i, _ = self.location(ind + 1, ops[1])
        self.emit(ind + 1, f"{self.bind('_neg', self.machine.neg)}({v}, {d}, {i})")

    def i_ABS(self, ind, ops):
        self.emit(ind, "if c:")
        self._store(ind, ops[1], f"abs({self.value(ind + 1, ops[0])})")

    def i_SQR(self, ind, ops):
        self.emit(ind, "if c:")
        v = self.value(ind + 1, ops[0])
        d, i, _ = self.location(ind + 1, ops[1])
        self.emit(ind + 1, f"{self.bind('_sqr', self.machine.sqr)}({v}, {d}, {i})")

    def i_MOV(self, ind, ops):
        self.emit(ind, "if c:")
        self._store(ind, ops[1], self.value(ind + 1, ops[0]), value=ops[0])

    def i_CPT(self, ind, ops):
        self.emit(ind, "if c:")
        self._store(ind, ops[0], self.expression(ind + 1, ops[1]), value=ops[1])

    def i_CLR(self, ind, ops):
        self.emit(ind, "if c:")
        d, i, _ = self.location(ind + 1, ops[0])
        self.emit(ind + 1, f"{self.bind('_clear', self.machine.clear)}({d}, {i})")

    def _logic(self, ind, ops, symbol: str):
        self.emit(ind, "if c:")
        a, b = self.value(ind + 1, ops[0]), self.value(ind + 1, ops[1])
        self._store(ind, ops[2], f"{a} {symbol} {b}", "logic")

    def i_AND(self, ind, ops):
        self._logic(ind, ops, "&")

    def i_OR(self, ind, ops):
        self._logic(ind, ops, "|")

    def i_XOR(self, ind, ops):
        self._logic(ind, ops, "^")

    def i_NOT(self, ind, ops):
        self.emit(ind, "if c:")
        self._store(ind, ops[1], f"~{self.value(ind + 1, ops[0])}", "logic")

    def i_MVM(self, ind, ops):
        self.emit(ind, "if c:")
        src, mask = self.value(ind + 1, ops[0]), self.value(ind + 1, ops[1])
        d, i, _ = self.location(ind + 1, ops[2])
        self.emit(ind + 1, f"{self.bind('_logic', self.machine.logic)}(({d}[{i}] & ~{mask}) | ({src} & {mask}), {d}, {i})")

    def _block(self, ind, ref: AddressRef, length: int, dest_ref: AddressRef) -> tuple[str, str, str]:
        """A block operand of a file instruction: array, start, word count.
        The element count comes from the destination's element size; a COP
        source of another storage (F vs words) spans the same bytes."""
        wpe = dest_ref.address.ftype.words_per_element
        needed = source_units(length * wpe, ref.address.ftype, dest_ref.address.ftype)
        d, i, _ = self.location(ind, ref)
        check = self.bind("_block_check", _block_check)
        self.emit(ind, f"{check}({d}, {i}, {needed!r}, {str(ref.address)!r})")
        return d, i, repr(length * wpe)

    def i_COP(self, ind, ops):
        self.emit(ind, "if c:")
        n = ops[2].value
        sd, si, count = self._block(ind + 1, ops[0], n, ops[1])
        dd, di, _ = self._block(ind + 1, ops[1], n, ops[1])
        self.emit(ind + 1, f"{self.bind('_cop', self.machine.cop)}({sd}, {si}, {dd}, {di}, {count})")

    def i_FLL(self, ind, ops):
        self.emit(ind, "if c:")
        v = self.value(ind + 1, ops[0])
        dd, di, count = self._block(ind + 1, ops[1], ops[2].value, ops[1])
        self.emit(ind + 1, f"{self.bind('_fll', self.machine.fll)}({v}, {dd}, {di}, {count})")

    def i_BTD(self, ind, ops):
        self.emit(ind, "if c:")
        src = self.value(ind + 1, ops[0])
        d, i, _ = self.location(ind + 1, ops[2])
        self.emit(ind + 1, f"{self.bind('_btd', self.machine.btd)}({src}, {ops[1].value!r}, {d}, {i}, "
                  f"{ops[3].value!r}, {ops[4].value!r})")

    # program control: leaving the block writes its locals back first
    def leave(self, ind: int, value: str) -> None:
        self.emit(ind, "if c:")
        self.flush_lines(ind + 1)
        self.emit(ind + 1, f"return {value}")

    def i_JMP(self, ind, ops):
        self.leave(ind, repr(self.labels[ops[0].value]))

    def i_LBL(self, ind, ops):
        pass

    def i_SBR(self, ind, ops):
        pass  # its parameters are written by the engine when a JSR enters the file (Engine.run_file)

    def _call(self) -> str:
        """``_calls[k]``: the instruction being compiled, for the engine to
        move its parameters (JSR inputs and returns, RET values)."""
        calls = self.env.setdefault("_calls", [])
        key = (id(self.current), "call")
        if key not in self.named:
            self.named[key] = f"_calls[{len(calls)}]"
            calls.append(self.current)
        return self.named[key]

    def i_JSR(self, ind, ops):
        if len(ops) > 1:
            self.emit(ind, f"if c: _jsr({ops[0].value!r}, {self._call()})")
        else:
            self.emit(ind, f"if c: _jsr({ops[0].value!r})")

    def i_RET(self, ind, ops):
        # A RET with values returns itself: run_file reads them (a fault there names this rung), the JSR stores them.
        if ops:
            self.mark_rung(ind)
        self.leave(ind, self._call() if ops else repr(RET))

    def i_TND(self, ind, ops):
        self.leave(ind, repr(TND))

    def i_MCR(self, ind, ops):
        # An MCR alone on its rung ends the zone; with conditions before it, it starts one.
        conditional = self.rung_elements[0] is not self.current
        self.emit(ind, f"z = {RUNG_BOOL if conditional else 'True'}")
        self.emit(ind, "_zone[0] = z")

    def i_AFI(self, ind, ops):
        self.emit(ind, "c = False")

    # strings
    def _strings(self, ind, kernel: str, ops, values=()):
        self.emit(ind, "if c:")
        args = []
        for k, op in enumerate(ops):
            if k in values:
                args.append(self.value(ind + 1, op))
            else:
                d, i, _ = self.location(ind + 1, op)
                args += [d, i]
        self.emit(ind + 1, f"{self.bind('_' + kernel, getattr(self.machine, kernel))}({', '.join(args)})")

    def i_ACI(self, ind, ops):
        self._strings(ind, "aci", ops)

    def i_AIC(self, ind, ops):
        self._strings(ind, "aic", ops, values=(0,))

    def i_ACN(self, ind, ops):
        self._strings(ind, "acn", ops)

    def i_AEX(self, ind, ops):
        self._strings(ind, "aex", ops, values=(1, 2))

    def i_ASC(self, ind, ops):
        # operands in AB order, as the kernel takes them: source (sought), index, string search, result
        self._strings(ind, "asc", ops, values=(1,))

    def i_ASR(self, ind, ops):
        self.emit(ind, "if c:")
        (ad, ai, _), (bd, bi, _) = self.location(ind + 1, ops[0]), self.location(ind + 1, ops[1])
        self.emit(ind + 1, f"c = {self.bind('_asr', self.machine.asr)}({ad}, {ai}, {bd}, {bi})")


def _block_check(d, i, n, text) -> None:
    if i + n > len(d):
        raise MajorFault(S.FAULT_BLOCK_RANGE, f"{n} words from {text} run past the end of the file ({len(d)} words)")


_COMPARE = {"EQU": "==", "NEQ": "!=", "LES": "<", "LEQ": "<=", "GRT": ">", "GEQ": ">="}
