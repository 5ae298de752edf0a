"""Ladder coverage: what the rungs did while scenarios ran, measured during
the real scan (one measurement; the reporters are testing/coverage_report.py).

A ``Coverage`` collects, over every scan of every run recorded into it:

* each rung (``RungKey``: program file number, rung index in that file):
  the scans that ended it true and false (its condition: the power at its
  end, as the scan left it); a rung never scanned (a JMP over it, a
  subroutine never called, a scan ended before it) is neither;
* each branch leg: the scans power flowed through it (to its end) or not;
* each instruction: the scans power reached it or not, and, when it did,
  whether it passed power on. A condition instruction (an instruction
  table entry that is not an output: XIC, XIO, the compares, ONS, AFI,
  ...) is "seen true" when power reached it and its test held, "seen false"
  when power reached it and its test failed: a softplc_lite choice, as
  branch coverage counts a condition only where it decides something (a
  contact that is open only while the rung is already off decides nothing).
  An output (OTE, timers, math, JSR, ...) is "on" when power reached it,
  "off" when it did not. LBL and SBR test nothing and are not counted.

A file made from Structured Text is measured the same way, rung by rung;
its reporters read the rungs as the text's statements and arms
(testing/coverage_st.py).

How: a run with coverage scans with the reference interpreter
(ladder/interpreter.py) through ``Recorder``, a subclass that counts as it
goes; the compiled executor, the fast path every other run takes, has no
instrumentation at all, so coverage costs nothing when it is off. The
counters are lists the recorder holds directly (an increment a rung and
two an instruction); ``Coverage.executor`` is the build function an Engine
takes as its executor.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..ladder.ast import Branch, Instruction, Listing, Program
from ..ladder.compiler import EndScan
from ..ladder.instructions import lookup
from ..ladder.interpreter import Interpreter, _Jump, interpret_file

RungKey = tuple[int, int]  # (program file number, rung index in that file)
ElementKey = tuple[int, int, int]  # (file, rung, element index in the rung: pre-order, branches included)
LegKey = tuple[int, int, int, int]  # (file, rung, the branch's element index, leg index)

NOT_COUNTED = frozenset({"LBL", "SBR", "NOP"})  # they test nothing and pass power through


@dataclass
class ElementInfo:
    index: int
    kind: str  # "branch", "condition", "output"
    text: str  # the mnemonic ("BST" for a branch)
    line: int
    column: int
    off_possible: bool = True  # an output: power into it can be off (something before it can block it)
    legs: int = 0  # a branch: how many legs
    leg_ranges: tuple = ()  # a branch: each leg's elements, as a range of element indices (pre-order)


@dataclass
class RungInfo:
    key: RungKey
    line: int
    column: int
    false_possible: bool = True  # something in the rung (or an MCR zone) can leave it false
    elements: list[ElementInfo] = field(default_factory=list)  # the counted ones
    starts: list[tuple[int, int]] = field(default_factory=list)  # (line, column) of every element


@dataclass
class FileInfo:
    number: int
    name: str | None
    source: str  # the .lad file it was read from
    rungs: list[RungInfo] = field(default_factory=list)
    listing: Listing | None = None  # the text the file was made from, when not ladder (testing/coverage_st.py)


def _elements(rung_elements, found: list) -> None:
    """Pre-order: a branch, then its legs' elements, leg by leg."""
    for el in rung_elements:
        found.append(el)
        if isinstance(el, Branch):
            for leg in el.legs:
                _elements(leg, found)


def _kind(ins: Instruction, outputs: dict[str, bool]) -> str | None:
    m = ins.mnemonic
    if m in NOT_COUNTED:
        return None
    spec = lookup(m)
    output = spec.output if spec is not None else outputs.get(m, True)
    return "output" if output else "condition"


class Coverage:
    """The measurement over one or more runs of one program, merged: every
    run recorded into it adds its scans to the same counters."""

    def __init__(self) -> None:
        self.files: dict[int, FileInfo] = {}
        self.rungs: dict[RungKey, list[int]] = {}  # [scans ending true, scans ending false]
        self.legs: dict[LegKey, list[int]] = {}  # [powered, not powered]
        # [power reached it, did not, passed power on (when reached), did not (when reached)]
        self.instructions: dict[ElementKey, list[int]] = {}
        self.kinds: dict[ElementKey, str] = {}
        self.module_outputs: dict[str, bool] = {}  # module mnemonic -> its spec's output flag

    # -- recording --------------------------------------------------------------------------
    def learn_modules(self, modules) -> None:
        """The output flag of the plug-in modules' instructions (their specs)."""
        for m in modules:
            for spec in m.instructions():
                self.module_outputs[spec.mnemonic] = spec.output

    def executor(self, program: Program, number: int, *args, **kw):
        """Engine build function: program file ``number`` on a recording
        interpreter that counts into this Coverage."""
        pfile = program.files[number]
        self._describe(number, pfile)
        counters = {}  # id(node) -> its counter list
        for r, rung in enumerate(pfile.rungs):
            counters[id(rung.elements)] = self.rungs[(number, r)]
            found: list = []
            _elements(rung.elements, found)
            for e, el in enumerate(found):
                if isinstance(el, Branch):
                    for k, leg in enumerate(el.legs):
                        if len(leg):  # an empty leg has no identity of its own (and passes its input)
                            counters[id(leg)] = self.legs[(number, r, e, k)]
                elif (number, r, e) in self.kinds:
                    counters[id(el)] = self.instructions[(number, r, e)]
        rung_lists = {id(rung.elements) for rung in pfile.rungs}

        class _Bound(Recorder):
            pass
        _Bound.counters = counters
        _Bound.rung_lists = rung_lists
        return interpret_file(program, number, *args, interpreter=_Bound, **kw)

    def _describe(self, number: int, pfile) -> None:
        if number in self.files:
            if _shape(self.files[number]) != [len(_flat(r.elements)) for r in pfile.rungs]:
                raise ValueError(f"coverage of program file {number}: another program was recorded into it")
            return
        info = FileInfo(number, pfile.name, pfile.pos.source, [], pfile.listing)
        has_mcr = any(isinstance(el, Instruction) and el.mnemonic == "MCR" for r in pfile.rungs for el in r.elements)
        for r, rung in enumerate(pfile.rungs):
            pos = rung.pos
            may_be_off: dict[int, bool] = {}
            false_possible = _may_end_off(rung.elements, has_mcr, lambda el: _kind(el, self.module_outputs),
                                          may_be_off)
            rinfo = RungInfo((number, r), pos.line, pos.column, false_possible)
            self.rungs[(number, r)] = [0, 0]
            found: list = []
            _elements(rung.elements, found)
            ranges = _leg_ranges(rung.elements)
            for e, el in enumerate(found):
                p = el.pos
                rinfo.starts.append((p.line, p.column))
                if isinstance(el, Branch):
                    rinfo.elements.append(ElementInfo(e, "branch", "BST", p.line, p.column, legs=len(el.legs),
                                                      leg_ranges=ranges[id(el)]))
                    for k, leg in enumerate(el.legs):
                        self.legs[(number, r, e, k)] = [0, 0]
                    continue
                kind = _kind(el, self.module_outputs)
                if kind is None:
                    continue
                rinfo.elements.append(ElementInfo(e, kind, el.mnemonic, p.line, p.column, may_be_off[id(el)]))
                self.kinds[(number, r, e)] = kind
                self.instructions[(number, r, e)] = [0, 0, 0, 0]
            info.rungs.append(rinfo)
        self.files[number] = info

    # -- reading ----------------------------------------------------------------------------
    def executed(self, key: RungKey) -> bool:
        """The rung was scanned (to its end) at least once."""
        counts = self.rungs.get(key)
        return counts is not None and (counts[0] > 0 or counts[1] > 0)

    def scans(self, key: RungKey) -> int:
        counts = self.rungs.get(key)
        return 0 if counts is None else counts[0] + counts[1]

    def rung_outcomes(self, key: RungKey) -> tuple[bool, bool]:
        """(ever true, ever false)."""
        t, f = self.rungs.get(key, (0, 0))
        return t > 0, f > 0

    def leg_powered(self, key: LegKey) -> bool:
        return self.legs.get(key, (0, 0))[0] > 0

    def element_outcomes(self, key: ElementKey) -> tuple[bool, bool]:
        """A condition: (seen true, seen false); an output: (seen on, seen off)."""
        counts = self.instructions.get(key)
        if counts is None:
            return False, False
        if self.kinds[key] == "condition":
            return counts[2] > 0, counts[3] > 0
        return counts[0] > 0, counts[1] > 0

    def merge(self, other: "Coverage") -> None:
        """Add ``other``'s counts (a measurement of the same program) to these."""
        for number, info in other.files.items():
            if number not in self.files:
                self.files[number] = info
                self.kinds.update({k: v for k, v in other.kinds.items() if k[0] == number})
            elif _shape(self.files[number]) != _shape(info):
                raise ValueError(f"coverage of program file {number}: another program was recorded into it")
        for mine, theirs in ((self.rungs, other.rungs), (self.legs, other.legs),
                             (self.instructions, other.instructions)):
            for key, counts in theirs.items():
                into = mine.setdefault(key, [0] * len(counts))
                for i, n in enumerate(counts):
                    into[i] += n


def _may_end_off(elements, off_in: bool, kind_of, may_be_off: dict[int, bool]) -> bool:
    """Whether the power out of a series can be off, given whether the power
    into it can (``off_in``); ``may_be_off`` gets, for each element, whether
    the power into it can be off. A condition can block power, an output
    passes it on, a branch blocks when all its legs can. An outcome that
    cannot happen is not counted: an unconditional rung never ends false,
    a coil with nothing before it is never off (unless an MCR zone in the
    file can turn the rung off)."""
    off = off_in
    for el in elements:
        may_be_off[id(el)] = off
        if isinstance(el, Branch):
            off = all([_may_end_off(leg, off, kind_of, may_be_off) for leg in el.legs])
        elif kind_of(el) == "condition":
            off = True
    return off


def _leg_ranges(rung_elements) -> dict[int, tuple[range, ...]]:
    """id(branch) -> the element indices of each of its legs (pre-order
    numbering, as _elements gives: a leg's elements, nested ones included,
    are consecutive)."""
    ranges: dict[int, tuple[range, ...]] = {}
    counter = [0]

    def visit(elements) -> None:
        for el in elements:
            counter[0] += 1
            if isinstance(el, Branch):
                legs = []
                for leg in el.legs:
                    start = counter[0]
                    visit(leg)
                    legs.append(range(start, counter[0]))
                ranges[id(el)] = tuple(legs)
    visit(rung_elements)
    return ranges


def _shape(info: FileInfo) -> list[int]:
    """Elements a rung: what tells a measurement of another program apart."""
    return [len(rung.starts) for rung in info.rungs]


def _flat(elements) -> list:
    found: list = []
    _elements(elements, found)
    return found


class Recorder(Interpreter):
    """The reference interpreter, counting as it scans. ``counters`` (id of a
    rung's element list, of a leg, of an instruction -> its counter list)
    and ``rung_lists`` (the ids that are whole rungs) are set on a subclass
    made per program file (Coverage.executor)."""

    counters: dict[int, list[int]] = {}
    rung_lists: frozenset | set = frozenset()

    def series(self, elements, c, rung, pfile):
        counts = self.counters.get(id(elements))
        if counts is None:
            return Interpreter.series(self, elements, c, rung, pfile)
        if id(elements) in self.rung_lists:
            try:
                out = Interpreter.series(self, elements, c, rung, pfile)
            except (_Jump, EndScan):  # a JMP, RET or TND (here or in a subroutine) fired: power reached it
                counts[0] += 1
                raise
        else:
            out = Interpreter.series(self, elements, c, rung, pfile)
        counts[0 if out else 1] += 1
        return out

    def instruction(self, ins, c, rung, pfile):
        counts = self.counters.get(id(ins))
        if counts is None:
            return Interpreter.instruction(self, ins, c, rung, pfile)
        if c:
            counts[0] += 1
            out = Interpreter.instruction(self, ins, c, rung, pfile)
            counts[2 if out else 3] += 1
            return out
        counts[1] += 1
        return Interpreter.instruction(self, ins, c, rung, pfile)
