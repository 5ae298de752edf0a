"""The block code shapes: words held in locals are written back
wherever anything else can look at the table, on both executors alike
(docs/engine.md, "Compiled code")."""

from __future__ import annotations

import pytest

from helpers.instr_helpers import EXECUTORS
from softplc_lite.ladder import Engine, Mode, blocks, load_text
from softplc_lite.ladder import status as S


def _run(text: str, executor: str, scans: int = 1, values: dict | None = None) -> Engine:
    e = Engine(load_text(text, "t.lad"), executor=executor)
    for addr, v in (values or {}).items():
        e.table.write(addr, v)
    e.set_mode(Mode.RUN)
    e.run(scans)
    return e


def _both(text: str, scans: int = 1, values: dict | None = None) -> Engine:
    compiled, reference = (_run(text, ex, scans, values) for ex in EXECUTORS)
    assert compiled.table == reference.table
    assert (compiled.fault is None) == (reference.fault is None)
    if compiled.fault is not None:
        assert (compiled.fault.code, compiled.fault.rung, compiled.fault.instruction) == \
            (reference.fault.code, reference.fault.rung, reference.fault.instruction)
    return compiled


def test_a_fault_leaves_the_writes_of_earlier_rungs_of_its_block_in_the_table():
    e = _both("OTE B3/0\nXIC B3/0 OTL B3/1\nMOV N7:[N7:9] N7:1\nOTE B3/2\n", values={"N7:9": 500})
    assert e.mode is Mode.FAULTED and e.fault.rung == 2
    assert e.table.read("B3/0") == 1 and e.table.read("B3/1") == 1 and e.table.read("B3/2") == 0


def test_a_negative_timer_preset_faults_with_the_table_exact():
    e = _both("OTE B3/0\nMOV -5 T4:0.PRE\nXIC B3/0 TON T4:0 0.01 10 0\nOTE B3/9\n")
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_NEGATIVE_TIMER and e.fault.rung == 2
    assert e.table.read("B3/0") == 1 and e.table.read("T4:0.PRE") == -5 and e.table.read("B3/9") == 0


def test_a_jump_out_of_a_block_writes_its_words_back_first():
    text = "OTE B3/0\nXIC B3/0 OTL B3/1\nXIC B3/1 JMP 5\nOTE B3/2\nLBL 5 XIC B3/1 OTE B3/3\n"
    e = _both(text, scans=2)
    assert (e.table.read("B3/1"), e.table.read("B3/2"), e.table.read("B3/3")) == (1, 0, 1)


def test_cop_sees_and_overwrites_held_words():
    # N7:0 and N7:5 are held in locals around the COP, which reads and writes the table.
    text = ("XIC B3/0 OTE N7:0/1\nXIC N7:0/1 OTE N7:5/3\nCOP #N7:0 #N7:5 3\n"
            "XIC N7:5/1 OTE B3/1\nXIC N7:5/3 OTE B3/2\n")
    e = _both(text, values={"B3/0": 1})
    assert e.table.read("N7:5") == 2 and e.table.read("B3/1") == 1 and e.table.read("B3/2") == 0


def test_the_flags_held_in_a_local_follow_every_store():
    text = ("MOV 0 N7:0\nXIC S:0/2 OTE B3/0\nSUB N7:0 1 N7:1\nXIC S:0/3 OTE B3/1\n"
            "MUL N7:1 N7:1 N7:2\nXIC S:0/3 OTE B3/2\nXIC S:0/2 OTE B3/3\n"
            "ADD 32767 N7:1 N7:3\nXIC S:0/2 OTE B3/4\nADD 32767 1 N7:4\nXIC S:0/1 OTE B3/5\n")
    e = _both(text)
    bits = [e.table.read(f"B3/{k}") for k in range(6)]
    assert bits == [1, 1, 0, 0, 0, 1]  # zero, sign, 1*1 neither, 32766 neither, overflow
    assert e.table.read("S:10") & (1 << 14)  # the overflow minor fault, from the kernel path


def test_a_bit_the_program_sets_in_s0_survives_a_kernel_setting_the_flags():
    # S:0/5 is set through the block's local; the overflowing ADD's kernel keeps S:0's upper bits.
    e = _both("OTE S:0/5\nADD 32767 1 N7:4\nXIC S:0/5 OTE B3/0\nXIC S:0/1 OTE B3/1\n")
    assert e.table.read("S:0/5") == 1 and e.table.read("B3/0") == 1 and e.table.read("B3/1") == 1


@pytest.mark.parametrize("chunk", [1, 3, 1000])
def test_words_used_once_or_often_give_the_same_table(monkeypatch, chunk):
    monkeypatch.setattr(blocks, "CHUNK_RUNGS", chunk)
    text = "".join(f"XIC B3/{k % 7} ADD N7:{k % 5} {k} N7:{k % 5}\nEQU N7:{k % 5} {k} OTE B3/{20 + k}\n"
                   for k in range(12))
    _both(text, scans=3, values={"B3/0": 1, "B3/3": 1})


def test_a_rung_made_a_block_of_its_own_runs_the_same(monkeypatch):
    text = "OTE B3/0\nXIC B3/0 TON T4:0 0.01 3 0\nXIC T4:0/DN CTU C5:0 5 0\nXIC C5:0/DN OTE B3/1\n"
    program = load_text(text)
    whole, split = Engine(program), Engine(program)
    split.files[2][0].isolate(2)
    assert len(split.files[2][0].blocks) == 3
    for e in (whole, split):
        e.set_mode(Mode.RUN)
        e.run(40)
    assert whole.table == split.table and whole.table.read("C5:0.ACC") > 0


def _rung_in_recorder():
    """A TLM whose instruction SEEN records the rung-in it is given."""
    from softplc_lite.ladder.instructions import InstructionSpec, K, OperandSpec
    from softplc_lite.tlm import TLM

    seen_spec = InstructionSpec("SEEN", "record the rung-in", (OperandSpec("dest", K.WORD),), True, 0, "REC")

    class Recorder(TLM):
        name = "REC"

        def __init__(self):
            self.rung_ins = []

        def instructions(self):
            return [seen_spec]

        def create(self, instr, ctx):
            def seen(c):
                self.rung_ins.append(c)
                return c
            return seen

    return Recorder()


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_contacts_give_a_module_instruction_a_bool_rung_in(executor):
    """Block code keeps a contact as ``word & mask`` (any value with the
    rung's truth); where the rung condition leaves block code it is a bool,
    True or False, as the reference interpreter gives it."""
    from softplc_lite.ladder import Mode, run_text

    rec = _rung_in_recorder()
    program = "\n".join([
        "XIC B3/4 SEEN N7:0",                       # bit 4 set: the word & mask is 16
        "XIC B3/5 SEEN N7:1",                       # clear: 0
        "BST XIC B3/4 NXB XIO B3/4 BND SEEN N7:2",  # a branch of truthy legs
        "XIC B3/4 XIC B3/15 SEEN N7:3",             # bit 15: the word & mask is negative
    ])
    engine = run_text(program, scans=0, executor=executor, modules=[rec],
                      values={"B3:0": -32768 | 16})
    engine.set_mode(Mode.RUN)
    engine.run(1)
    assert rec.rung_ins == [True, False, True, True]
    assert all(type(c) is bool for c in rec.rung_ins)


# TONs whose element only the TON itself uses: run in place, not held.
_TONS_ALONE = ("XIO B3/1 TON T4:3 0.01 25 0\n"
               "TON T4:4 1.0 1 0\n"
               "XIC B3/2 TON T4:5 0.01 7 3\n"
               "TON T4:6 0.01 0 0\n"
               "CTU C5:0 40 0\n"                      # B3/1 goes true at the 40th scan, B3/2 at the 60th
               "XIC C5:0/DN OTL B3/1\n"
               "GEQ C5:0.ACC 60 OTL B3/2\n"
               "XIC C5:0/DN MOV 3 T4:4.PRE\n")


@pytest.mark.parametrize("scan_ms", [3, 7, 10, 26])
def test_a_ton_alone_in_its_block_times_as_the_kernel(scan_ms):
    """The in-place TON: done, enabled now, timing with and without a whole
    tick, reset by a false rung, a preset raised under a done timer."""
    from softplc_lite.ladder import Settings

    engines = [Engine(load_text(_TONS_ALONE, "t.lad"), executor=ex, settings=Settings(scan_ms=scan_ms))
               for ex in EXECUTORS]
    assert "_tp = " in engines[0].files[2][0].source  # the in-place shape, not held locals
    for e in engines:
        e.set_mode(Mode.RUN)
    for _ in range(120):
        for e in engines:
            e.scan()
        compiled, reference = engines
        assert compiled.table.file(4).data[9:21] == reference.table.file(4).data[9:21]


@pytest.mark.parametrize("scan_ms", [3, 7, 10, 26])
def test_a_held_ton_times_as_the_kernel_through_every_outcome(scan_ms):
    """TON on held words sets its whole control word per outcome (done,
    enabled now, still timing with the stamp its time counts from): scan
    times that are not a multiple of the time base leave a remainder that
    the stamp must carry; the rung goes false and true again, and a preset
    is raised under a done timer. Both executors, every scan."""
    from softplc_lite.ladder import Settings

    text = ("XIO B3/0 TON T4:0 0.01 25 0\n"          # times out, then reset by B3/0
            "XIC T4:0/DN OTL B3/0\n"
            "XIC B3/0 XIO T4:1/DN TON T4:1 0.01 40 0\n"
            "TON T4:2 1.0 1 0\n"                    # a 1 s base: ACC counts seconds
            "XIC T4:2/DN MOV 3 T4:2.PRE\n"           # a preset raised under a done timer
            "XIC T4:1/DN OTU B3/0\n")
    engines = [Engine(load_text(text, "t.lad"), executor=ex, settings=Settings(scan_ms=scan_ms))
               for ex in EXECUTORS]
    for e in engines:
        e.set_mode(Mode.RUN)
    seen_done = set()
    for _ in range(900 // scan_ms + 200):
        for e in engines:
            e.scan()
        compiled, reference = engines
        assert compiled.table.file(4).data[:9] == reference.table.file(4).data[:9]
        assert compiled.table.read("B3:0") == reference.table.read("B3:0")
        seen_done.update(k for k in range(3) if compiled.table.read(f"T4:{k}/DN"))
    assert seen_done == {0, 1, 2}


@pytest.mark.parametrize("reader", [
    "XIC S:0/2 OTE B3/9",            # a contact
    "MOV S:0 N7:9",                   # a word read inline
    "COP #S:0 #N7:9 1",               # a block copy of S
    "JSR 3",                          # code that is not block code (a barrier)
    "ADD S:0 0 N7:9",                 # a store reading S:0 as its operand
    "",                               # the end of the scan
])
def test_flags_a_held_store_leaves_pending_are_set_before_anything_reads_s0(reader):
    """A word store on held words leaves S:0's flags pending (its value and
    carry) until something reads S:0: each reader, after stores whose rungs
    are true or false, sees the flags of the last store that ran."""
    text = ("XIC B3/0 MOV 0 N7:1\n"          # runs: Z
            "XIC B3/1 MOV -5 N7:2\n"         # rung false: flags stay Z
            f"{reader}\n"
            "XIC B3/0 ADD 32767 1 N7:3\n"    # overflow: the kernel sets V in the table
            f"{reader}\n"
            "XIC B3/0 ADD -1 -1 N7:4\n"      # carry and sign, in range
            "XIC B3/0 MOV 1 N7:5\n"          # clears them: only the last store counts
            f"{reader}\n"
            "OTE B3/15\n"
            "FILE 3\nRET\n")
    if not reader:
        text = text.replace("\n\n", "\n")
    e = _both(text, scans=2, values={"B3:0": 1})
    if not reader.startswith(("MOV", "ADD")):  # (a reader that stores sets the flags itself)
        assert e.table.read("S:0") & 15 == 0  # MOV 1: no flag
    assert e.table.read("N7:3") == 32767 and e.table.read("N7:4") == -2


def test_flags_pending_survive_a_breakpoint_split():
    """A rung isolated for a breakpoint is a block of its own: the flags
    pending at the end of the block before it are written with it."""
    text = "XIC B3/0 ADD -1 -1 N7:4\nXIC B3/0 MOV -3 N7:5\nXIC S:0/3 OTE B3/1\nXIC S:0/0 OTE B3/2\n"
    for isolate in (False, True):
        e = Engine(load_text(text, "t.lad"))
        if isolate:
            e.files[2][0].isolate(2)
        e.table.write("B3/0", 1)
        e.set_mode(Mode.RUN)
        e.run(1)
        assert (e.table.read("B3/1"), e.table.read("B3/2")) == (1, 0)  # sign from MOV -3, carry cleared


def test_counters_alone_and_held_count_as_the_kernel():
    """A counter whose control word nothing else in its block uses works on
    a temporary written back at the end of its rung; one read elsewhere is
    held. Both count, wrap (OV, UN), reset and set DN as the kernel."""
    text = ("XIC S:1/15 MOV 32765 C5:0.ACC\nXIC S:1/15 MOV -32766 C5:1.ACC\n"
            "XIC B3/0 CTU C5:0 5 32765\n"       # alone: wraps to -32768, OV
            "XIC B3/0 CTD C5:1 -1 -32766\n"     # alone: wraps to 32767, UN
            "XIC B3/0 CTU C5:2 3 0\nXIC C5:2/DN OTE B3/5\n"  # held: read by the next rung
            "XIC B3/0 CTU C5:4 3 0\n"          # alone: DN from ACC = PRE on
            "XIC B3/0 CTU C5:3 2 0\n"
            "XIC C5:3/DN RES C5:3\n"            # RES in the same block: held around a kernel
            "XIC S:1/15 OTL B3/0\n")
    engines = [Engine(load_text(text, "t.lad"), executor=ex) for ex in EXECUTORS]
    assert "_tw = _tw_was = f5[0]" in engines[0].files[2][0].source and "w5_6 = f5[6]" in engines[0].files[2][0].source
    for e in engines:
        e.set_mode(Mode.RUN)
    for scan in range(12):
        for e in engines:
            e.table.write("B3/0", scan % 2)  # a counting edge every other scan
            e.scan()
        compiled, reference = engines
        assert compiled.table.file(5).data == reference.table.file(5).data
        assert compiled.table.read("B3:0") == reference.table.read("B3:0")
    assert compiled.table.read("C5:0/OV") == 1 and compiled.table.read("C5:1/UN") == 1
    assert compiled.table.read("B3/5") == 1 and compiled.table.read("C5:4/DN") == 1


def test_a_rung_condition_used_once_is_folded_into_its_use():
    """c = EXPR whose one use is the rung's "if c:" or "... if c else ...":
    EXPR moves there (compiler.fold_condition); with two uses, or anything
    but loads between, it stays. Both executors agree either way."""
    text = ("XIC B3/0 OTU B3/0\n"                 # reads and writes the same bit: folded
            "XIC B3/1 OTE B3/2\n"                 # folded into the conditional expression
            "XIC B3/3 OTE B3/4 OTE B3/5\n"        # two uses: kept
            "CTU C5:0 5 0\n"                      # no contact: "if True:" compiles to nothing
            "XIC B3/6 TON T4:0 0.01 3 0\n")       # the TON's fault path uses c too: kept
    e = _both(text, scans=4, values={"B3:0": 0b1001011})
    source = e.files[2][0].source
    assert "if w3_0 & 1:" in source or "if f3[0] & 1:" in source
    assert source.count("\n        c = ") == 2 and "if True:" in source
    assert e.table.read("B3/0") == 0 and e.table.read("B3/2") == 1 and e.table.read("B3/4") == 1


@pytest.mark.parametrize("text", [
    "SUB N7:4 1 N7:4\n",                                  # a borrow from the operand that is the destination
    "XIC B3/0 SUB N7:4 1 N7:4\nXIC S:0/0 OTE B3/1\n",       # S:0 held: the carry left pending
    "ADD N7:5 N7:4 N7:4\nADD N7:4 N7:5 N7:4\nXIC S:0/0 OTE B3/2\n",
])
def test_add_and_sub_into_their_own_operand_set_the_carry_from_the_operand(text):
    """ADD/SUB whose destination is also an operand held in a local: the
    carry (borrow) is worked out from the operand as it was, not from the
    stored result (found by the differential test: SUB Start 1 Start)."""
    e = _both("DATA N7 10\n" + text, values={"B3/0": 1, "N7:5": -1})
    assert e.table.read("S:0") & 1 == 1  # 0 - 1 borrows; -1 + -1 and -1 + -2 carry
