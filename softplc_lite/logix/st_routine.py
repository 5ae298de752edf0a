"""A Structured Text routine made into ladder rungs, so it runs on the same
engine, through the same compiler and reference interpreter, as the
export's ladder (docs/logix.md, "Structured Text").

Each statement becomes rungs in the routine's program file, each rung
placed at its statement's line (the watch view and coverage show the text
through the file's ladder/ast.py Listing):

- ``x := e`` is ``CPT(x, e)``; a BOOL ``b := e`` is ``LSTB(b, e)``; the
  non-retentive ``b [:=] e`` is the rung ``CMP(e) OTE(b)``; a string
  ``s := t`` is the string MOV (logix/strings.py).
- ``IF c THEN`` is ``CMP(c = 0) JMP(next arm)``; each arm but the last
  ends in ``JMP(end)``; ELSIF and ELSE start at a label.
- ``CASE`` stores its selector once (a hidden DINT unless it is a tag or a
  number), then tests each arm's list and ranges in order, as IF does.
- FOR, WHILE and REPEAT are a label, a test that jumps out and a backward
  JMP; EXIT jumps past the innermost loop; RETURN is RET. A loop that runs
  past the watchdog (S:28) is a major fault, as the ladder's backward JMP
  is (ladder/engine.py), where Logix faults with type 6 code 1.
- An instruction call (``JSR(Sub, 0);``, ``COP(a, b, 1);``, an Add-On
  Instruction ``Ramp(R1, x);``) is the same instruction as on a rung
  (logix/rungs.py), on a rung of its own that is always true.

Rules: 1756-PM007, Logix 5000 Controllers Structured Text ("Assignments",
"IF...THEN", "CASE...OF", "FOR...DO", "WHILE...DO", "REPEAT...UNTIL").

Choices of ours, each in docs/logix.md: a FOR's end value and step are
read at each test (PM007 does not say); ``[:=]``'s destinations are
cleared at the first scan the routine runs in after going to run (Logix
clears them in its prescan of every routine, called or not).
"""

from __future__ import annotations

from ..errors import Pos
from ..ladder.ast import AddressRef, Arm, Branch, Const, Instruction, Listing, Rung, BinOp
from ..st import ast as A
from ..st.parser import SourceLines, parse_routine
from . import model
from .neutral import NInstruction
from .rungs import NOT_RUN_REASON, PLAN, _instruction
from .st_expr import Expressions, StProblem, is_bool, render
from .tags import STATUS_FLAGS

# Instructions of the ladder that Structured Text does not have (1756-PM007, "Structured Text
# Instructions": ST reaches these through its own operators, functions and statements, and the
# timers and counters through their function-block forms TONR, CTUD...).
_LADDER_ONLY = set(PLAN) - {"JSR", "SBR", "RET", "MOD", "ABS", "SQRT", "NEG"}
_RUNG_MARK = -1  # the number a call's stand-in rung has: messages name the line instead


class StRoutine:
    """The translation of one ST routine; ``rungs`` and ``listing`` when
    done, counts in ``statements`` (how many, run, not run, with errors)."""

    def __init__(self, routine: model.Routine, ctx) -> None:
        self.routine = routine
        self.ctx = ctx
        ctx.language = "ST"
        self.x = Expressions(ctx)
        self.rungs: list[Rung] = []
        self.rung_lines: list[int] = []
        self.starts: list[int] = []
        self.arms: list[Arm] = []
        self.loops: list[int] = []  # the exit label of each loop the statement is in
        self.pending: int | None = None  # a label the next rung starts at
        self.clear_first: list = []  # [:=] destinations, cleared on the first scan
        self.statements = {"total": 0, "run": 0, "not run": 0, "errors": 0}
        self.lines: list[tuple[Pos, str]] = []
        self.line_of: dict[int, int] = {}

    # -- output ----------------------------------------------------------------------------
    def translate(self) -> tuple[list[Rung], Listing]:
        lines = self.routine.lines
        first = lines[0].pos.line if lines and lines[0].pos.line else 1
        where = SourceLines(lines, self.ctx.source, first)
        for pos, part in zip(where.starts, where.texts):
            self.line_of.setdefault(pos.line, len(self.lines))
            self.lines.append((pos, part))
        errors = []
        statements = parse_routine(where, self.ctx.source, first, errors)
        for e in errors:
            self.ctx.problem(e.pos, f"{e.message}")
        self.block(statements)
        self.flush(self.routine.pos)
        if self.clear_first:
            self.first_scan_clears()
        return self.rungs, Listing(self.lines, self.rung_lines, self.starts, self.arms)

    def line(self, pos: Pos) -> int:
        return self.line_of.get(pos.line, 0)

    def emit(self, elements: list, pos: Pos) -> int:
        """Add a rung (at the pending label, if any); its index."""
        if self.pending is not None:
            elements = [Instruction("LBL", [Const(self.pending, pos)], pos)] + elements
            self.pending = None
        self.rungs.append(Rung(elements or [Instruction("NOP", [], pos)], None, pos))
        self.rung_lines.append(self.line(pos))
        return len(self.rungs) - 1

    def land(self, label: int, pos: Pos) -> int:
        """Put ``label`` before the next rung; the index that rung will have."""
        if self.pending is not None:
            self.emit([], pos)
        self.pending = label
        return len(self.rungs)

    def flush(self, pos: Pos) -> None:
        if self.pending is not None:
            self.emit([], pos)

    def new_label(self) -> int:
        return self.ctx.label(f"__ST{len(self.ctx.labels)}")

    def jump(self, label: int, pos: Pos) -> Instruction:
        return Instruction("JMP", [Const(label, pos)], pos)

    def unless(self, node, pos: Pos) -> list:
        """Elements true when ``node`` is zero (a condition that fails)."""
        if isinstance(node, AddressRef) and node.address.bit is not None:
            return [Instruction("XIO", [node], pos)]
        return [Instruction("CMP", [BinOp("=", node, Const(0, pos), pos)], pos)]

    def when(self, node, pos: Pos) -> list:
        if isinstance(node, AddressRef) and node.address.bit is not None:
            return [Instruction("XIC", [node], pos)]
        return [Instruction("CMP", [BinOp("<>", node, Const(0, pos), pos)], pos)]

    # -- statements ------------------------------------------------------------------------
    def block(self, statements) -> None:
        for s in statements:
            self.statement(s)

    def statement(self, s) -> None:
        self.statements["total"] += 1
        problems, warnings = len(self.ctx.problems), len(self.ctx.warnings)
        self.ctx.skip = False
        self.ctx.before = []
        mark = len(self.rungs)
        saved = (len(self.arms), len(self.starts), len(self.clear_first), self.pending)
        compound = isinstance(s, (A.If, A.Case, A.For, A.While, A.Repeat))
        failed = None
        try:
            getattr(self, f"st_{type(s).__name__.lower()}")(s)
        except StProblem as e:
            failed = e
            (self.ctx.warn if e.not_run else self.ctx.problem)(e.pos, f"{e}" +
                                                                ("; the statement is not run" if e.not_run else ""))
            # What the statement made before the problem goes with it (an IF whose ELSIF fails
            # would leave a JMP to a label never placed); what came before it stays.
            del self.rungs[mark:], self.rung_lines[mark:]
            del self.arms[saved[0]:], self.starts[saved[1]:], self.clear_first[saved[2]:]
            self.pending = saved[3]
        self._name_lines(problems, warnings, s.pos)
        if failed is not None:
            self.statements["not run" if failed.not_run else "errors"] += 1
        elif compound:  # its own statements counted themselves
            self.statements["run"] += 1
        elif len(self.ctx.problems) > problems:
            self.statements["errors"] += 1
        elif self.ctx.skip:
            self.statements["not run"] += 1
        else:
            self.statements["run"] += 1
        if len(self.rungs) > mark and (not self.starts or self.starts[-1] != mark):
            self.starts.append(mark)

    def _name_lines(self, problems: int, warnings: int, pos: Pos) -> None:
        """A call's messages say "rung -1": the place they give is enough."""
        for found, first in ((self.ctx.problems, problems), (self.ctx.warnings, warnings)):
            for k in range(first, len(found)):
                p = found[k]
                found[k] = model.Problem(p.pos, p.message.replace(f"rung {_RUNG_MARK}: ", ""))

    def simple(self, elements: list, pos: Pos) -> None:
        """One statement's rung, unless a problem or a warning stops it."""
        if self.ctx.skip:
            return
        self.emit(self.ctx.before + elements, pos)

    def st_assign(self, s: A.Assign) -> None:
        target = self.x.tag(s.target)
        if target.type.kind == "string" and not target.dims:
            if isinstance(s.value, A.TagRef):
                return self.instruction(A.Call("MOV", (s.value, s.target), s.pos))
            raise StProblem(s.pos, f"{s.target.text} is a {target.type.name}: a string takes a string tag (a "
                                   f"string constant or expression is not run by softplc_lite)", not_run=True)
        if target.address is None:
            kind = f"{target.type.name} array" if target.dims else target.type.name
            raise StProblem(s.target.pos, f"{s.target.text} is a {kind}: an assignment writes a number or a BOOL "
                                          f"(COP copies structures and arrays; 1756-PM007, \"Assignments\")")
        dest = AddressRef(target.address, s.target.pos)
        node, _ = self.x.value(s.value)
        if not s.retentive:
            self.clear_first.append(dest)
        if is_bool(target):
            if s.retentive:
                return self.simple([Instruction("LSTB", [dest, node], s.pos)], s.pos)
            return self.simple(self.when(node, s.pos) + [Instruction("OTE", [dest], s.pos)], s.pos)
        self.simple([Instruction("CPT", [dest, node], s.pos)], s.pos)

    def st_call(self, s: A.Call) -> None:
        name = s.name.upper()
        if name in _LADDER_ONLY and name not in NOT_RUN_REASON and not (self.ctx.aoi and self.ctx.aoi.defines(name)):
            raise StProblem(s.pos, f"{s.name} is a ladder instruction Structured Text does not have (1756-PM007, "
                                   f"\"Structured Text Instructions\"): expected an assignment, a function, or the "
                                   f"instruction's function-block form")
        if self.ctx.aoi is not None and self.ctx.aoi.defines(name):
            for a in s.args[1:]:
                if a is not None and not isinstance(a, (A.TagRef, A.Const)):
                    raise StProblem(a.pos, f"{s.name}: an expression as an argument ({render(a)}): softplc_lite "
                                           f"passes a tag or a number to an Add-On Instruction", not_run=True)
        self.instruction(s)

    def instruction(self, s: A.Call) -> None:
        """The rung of a call, as logix/rungs.py makes the instruction."""
        name = s.name.upper()
        texts = [render(a) for a in s.args]
        places = [a.pos if a is not None else s.pos for a in s.args]
        text, columns = _placed(s.pos, places)
        stand_in = model.Rung(_RUNG_MARK, text, pos=s.pos)
        el = NInstruction(name, list(zip(texts, columns)), 0)
        out = _instruction(el, stand_in, self.ctx)
        if out is None or self.ctx.skip:
            return
        self.simple(out if isinstance(out, list) else [out], s.pos)

    def st_return(self, s: A.Return) -> None:
        self.emit([Instruction("RET", [], s.pos)], s.pos)

    def st_exit(self, s: A.Exit) -> None:
        if not self.loops:
            raise StProblem(s.pos, "EXIT outside a FOR, WHILE or REPEAT loop")
        self.emit([self.jump(self.loops[-1], s.pos)], s.pos)

    def test(self, cond, pos: Pos, label: int) -> int:
        """A rung that jumps to ``label`` when ``cond`` fails; its index."""
        self.ctx.before = []
        node = self.x.condition(cond)
        return self.emit(self.ctx.before + self.unless(node, pos) + [self.jump(label, pos)], pos)

    def choose(self, tests, else_, pos: Pos) -> None:
        """IF and CASE alike: ``tests`` is [(make_test(label) -> rung, body,
        label text, line)]; ``else_`` the ELSE body or None."""
        end = self.new_label()
        last = len(tests) - 1
        for k, (make_test, body, what, where) in enumerate(tests):
            final = k == last and else_ is None
            following = end if final else self.new_label()
            rung = make_test(following)
            self.arms.append(Arm(rung, False, what, self.line(where)))
            self.block(body)
            if final:
                self.arms.append(Arm(rung, True, "no arm", self.line(pos)))
            else:
                self.emit([self.jump(end, where)], where)
                at = self.land(following, where)
                if k == last:
                    self.arms.append(Arm(at, None, "ELSE", self.line(where)))
        if else_ is not None:
            self.block(else_)
        self.land(end, pos)

    def st_if(self, s: A.If) -> None:
        tests = []
        for k, (cond, body) in enumerate(s.branches):
            where = s.pos if k == 0 else getattr(cond, "pos", s.pos)
            tests.append((lambda label, c=cond, w=where: self.test(c, w, label), body, "IF" if k == 0 else "ELSIF",
                          where))
        self.choose(tests, s.else_, s.pos)

    def st_case(self, s: A.Case) -> None:
        node, t = self.x.value(s.selector)
        if t not in ("SINT", "INT", "DINT", "LINT", "BOOL"):
            raise StProblem(s.selector.pos if hasattr(s.selector, "pos") else s.pos,
                            f"a CASE selector of type {t}: expected an integer (1756-PM007, \"CASE...OF\")")
        before = self.ctx.before
        if not isinstance(node, (AddressRef, Const)) or before:
            hidden = AddressRef(self.ctx.directory.hidden_index(), s.pos)
            self.emit(before + [Instruction("CPT", [hidden, node], s.pos)], s.pos)
            node = hidden
        self.ctx.before = []
        tests = []
        for arm in s.arms:
            match = None
            for lab in arm.labels:
                if isinstance(lab, A.CaseRange):
                    one = BinOp("AND", BinOp(">=", node, Const(lab.low.value, lab.pos), lab.pos),
                                BinOp("<=", node, Const(lab.high.value, lab.pos), lab.pos), lab.pos)
                else:
                    one = BinOp("=", node, Const(lab.value, lab.pos), lab.pos)
                match = one if match is None else BinOp("OR", match, one, arm.pos)
            label_text = "CASE " + ", ".join(f"{x.low.value}..{x.high.value}" if isinstance(x, A.CaseRange)
                                             else str(x.value) for x in arm.labels)

            def make(label, m=match, p=arm.pos):
                return self.emit(self.unless(m, p) + [self.jump(label, p)], p)
            tests.append((make, arm.body, label_text, arm.pos))
        if not tests:
            if s.else_:
                self.block(s.else_)
            return
        self.choose(tests, s.else_, s.pos)

    def loop(self, exit_: int, body) -> None:
        self.loops.append(exit_)
        try:
            self.block(body)
        finally:
            self.loops.pop()

    def st_for(self, s: A.For) -> None:
        var = self.x.tag(s.var)
        if var.address is None or is_bool(var) or var.type.name not in ("SINT", "INT", "DINT", "LINT"):
            raise StProblem(s.var.pos, f"{s.var.text}: a FOR's count is a SINT, INT or DINT tag (1756-PM007, "
                                       f"\"FOR...DO\")")
        count = AddressRef(var.address, s.var.pos)
        head = self.ctx.before
        start, _ = self.x.value(s.start)
        self.emit(self.ctx.before + [Instruction("CPT", [count, start], s.pos)], s.pos)
        top, exit_ = self.new_label(), self.new_label()
        self.land(top, s.pos)
        self.ctx.before = list(head)
        stop, _ = self.x.value(s.stop)
        step = Const(1, s.pos)
        if s.step is not None:
            step, _ = self.x.value(s.step)
        if isinstance(step, Const):
            past = BinOp("<" if step.value < 0 else ">", count, stop, s.pos)
        else:
            past = BinOp("OR", BinOp("AND", BinOp(">=", step, Const(0, s.pos), s.pos), BinOp(">", count, stop, s.pos),
                                     s.pos),
                         BinOp("AND", BinOp("<", step, Const(0, s.pos), s.pos), BinOp("<", count, stop, s.pos),
                               s.pos), s.pos)
        test = self.emit(self.ctx.before + self.when(past, s.pos) + [self.jump(exit_, s.pos)], s.pos)
        self.arms.append(Arm(test, False, "FOR body", self.line(s.pos)))
        self.loop(exit_, s.body)
        self.ctx.before = list(head)
        self.emit(self.ctx.before + [Instruction("CPT", [count, BinOp("+", count, step, s.pos)], s.pos),
                                     self.jump(top, s.pos)], s.pos)
        self.land(exit_, s.pos)

    def st_while(self, s: A.While) -> None:
        top, exit_ = self.new_label(), self.new_label()
        self.land(top, s.pos)
        test = self.test(s.cond, s.pos, exit_)
        self.arms.append(Arm(test, False, "WHILE body", self.line(s.pos)))
        self.loop(exit_, s.body)
        self.emit([self.jump(top, s.pos)], s.pos)
        self.land(exit_, s.pos)

    def st_repeat(self, s: A.Repeat) -> None:
        top, exit_ = self.new_label(), self.new_label()
        self.land(top, s.pos)
        self.loop(exit_, s.body)
        where = getattr(s.until, "pos", s.pos)
        test = self.test(s.until, where, top)
        self.arms.append(Arm(test, True, "REPEAT again", self.line(where)))
        self.land(exit_, s.pos)

    # -- [:=] ------------------------------------------------------------------------------
    def first_scan_clears(self) -> None:
        """One rung first: on the first scan, each [:=] destination cleared."""
        pos = self.routine.pos
        first = AddressRef(STATUS_FLAGS["S:FS"], pos)
        legs = [[Instruction("OTU" if d.address.bit is not None else "CLR", [d], d.pos)] for d in self.clear_first]
        out = legs[0] if len(legs) == 1 else [Branch(legs, pos)]
        self.rungs.insert(0, Rung([Instruction("XIC", [first], pos)] + out, None, pos))
        self.rung_lines.insert(0, 0)
        self.starts = [k + 1 for k in self.starts]
        self.arms = [Arm(a.rung + 1, a.taken_when, a.label, a.line) for a in self.arms]


def _placed(start: Pos, places: list[Pos]) -> tuple[str, list[int]]:
    """A stand-in rung text and each operand's column in it, such that
    logix/rungs.py's ``_at(start, text, column)`` is the operand's place in
    the export (the ladder side's messages then point into the ST text)."""
    text = ""
    line, column = start.line, start.column
    columns = []
    for p in places:
        if p.line > line:
            text += "\n" * (p.line - line) + " " * (p.column - 1)
            line, column = p.line, p.column
        elif p.line == line and p.column > column:
            text += " " * (p.column - column)
            column = p.column
        columns.append(len(text))
    return text, columns


def translate_st(routine: model.Routine, ctx) -> tuple[list[Rung], Listing, dict[str, int]]:
    """The rungs of ST ``routine``, its Listing, and its statement counts."""
    st = StRoutine(routine, ctx)
    rungs, listing = st.translate()
    return rungs, listing, st.statements
