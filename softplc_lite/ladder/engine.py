"""Stage 4: the scan engine.

One scan: input hooks, the ladder (main file 2 and the files it JSRs to),
output hooks. Plug-in modules (TLMs) attach to exactly those points and to
mode changes. Modes: PROGRAM (no ladder), RUN, TEST (ladder runs, outputs
stay idle: output hooks are told outputs are disabled), FAULTED (after a
major fault; clear it to go back to PROGRAM).

Time is injectable (clocks.py); the table a program lays out before its
first scan is built by layout.py; what the engine needs of a module is
host.Module. A major fault is kept as ``engine.fault`` (the MajorFault,
its code, file, rung, instruction and message) until it is cleared.
"""

from __future__ import annotations

import time
import traceback
from typing import Callable

from ..datatable import DataTable
from ..datatable.errors import AddressRangeError
from ..datatable.table import to_signed
from . import status as S
from .ast import MAIN_FILE, AddressRef, Const, Instruction, Program
from .clocks import RealClock, SimulatedClock
from .compiler import RET, EndScan, compile_file, describe
from .host import TRANSITIONS, Mode, ModeError, overrides
from .interpreter import interpret_file
from .layout import initial_values, layout_problems, reference_module_blocks, reference_program
from .resolvers import address_fault
from .semantics import EN, STAMP, TT, Machine, MajorFault, Settings

# Importable from here too: the engine's own names (the modes, the clocks, the layout functions).
__all__ = ["Engine", "Mode", "ModeError", "RealClock", "SimulatedClock", "initial_values", "layout_problems",
           "reference_module_blocks", "reference_program"]

_EndScan = EndScan  # TND: end this scan now (defined with RET/TND so both executors let it through)


Hook = Callable[["Engine"], None]


def _builder(executor):
    """The function that builds a program file's code: "compiled",
    "reference" (the interpreter), or a build function of interpret_file's
    signature given as the executor itself (testing/coverage.py's recording
    interpreter)."""
    if callable(executor):
        return executor
    return compile_file if executor == "compiled" else interpret_file


class Engine:
    def __init__(
        self,
        program: Program,
        table: DataTable | None = None,
        settings: Settings | None = None,
        clock=None,
        executor: str = "compiled",
        fresh: bool = True,
        modules=(),
        module_options=None,
        code: dict | None = None,
        recorder=None,
    ) -> None:
        """``modules``: the plug-in modules the program's instructions may
        belong to (ladder.host.Module); ``module_options``: module name ->
        the options its ``attach`` gets (the runner decides them: --port,
        --record, --replay); ``recorder``: what the modules' ports record
        into, opened once every module has attached (so an unwritable trace
        stops the start) and closed after them. ``code``: the program
        files' compiled code from the code cache (ladder/codecache.py), used
        instead of compiling them."""
        self.program = program
        self.modules = list(modules)
        self.table = table if table is not None else DataTable()
        self.settings = settings or Settings()
        self.clock = clock or SimulatedClock(self.settings.scan_ms)
        self.executor = executor
        if code is not None and executor != "compiled":
            code = None
        if code is not None:
            from .codecache import apply_layout

            try:
                apply_layout(self.table, code["layout"])  # what reference_program made when it was cached
            except Exception:  # not a layout after all: compile, as without a cache
                code = None
        if code is None:
            reference_program(program, self.table)
        if fresh:
            initial_values(program, self.table)
        self.machine = Machine(self.table, self.settings)
        self.s = self.machine.s
        if self.s[S.WATCHDOG_MS] == 0:
            self.s[S.WATCHDOG_MS] = self.settings.watchdog_ms
        self.mode = Mode.PROGRAM
        self.fault: MajorFault | None = None
        self.scans = 0
        self.input_hooks: list[Hook] = []
        self.output_hooks: list[Callable[["Engine", bool], None]] = []
        self.mode_hooks: list[Callable[["Engine", Mode, Mode], None]] = []
        self.last_scan_ms = 0.0
        self.max_scan_ms = 0.0
        self._clock_s4_ms = self.clock.now_ms  # the clock time S:4 has counted up to
        self._first_pass = False
        self._depth = 0
        self._deadline = 0.0
        self._owner = {spec.mnemonic: m for m in self.modules for spec in m.instructions()}
        self._instances: dict[int, object] = {}  # id(instruction) -> its module instance (online edit)
        self._kept_instances: dict[int, object] = {}  # while replace_program builds: instances kept
        self.module_warnings: list[str] = []
        self.recorder = recorder
        reference_module_blocks(program, self.table, self._owner)
        self._attach_modules(module_options or {})
        self._attach_hooks()
        build = _builder(executor)
        if code is not None:
            try:
                self._build_files(program, self._cached_build(code))
            except Exception:  # a cache that does not fit after all: compile, as without one
                reference_program(program, self.table)
                self._build_files(program, build)
        else:
            self._build_files(program, build)

    def _build_files(self, program: Program, build) -> None:
        self.files = {}
        for number in sorted(program.files):
            zone = [True]
            self.files[number] = (build(program, number, self.table, self.machine, self._jsr, zone,
                                        self._module_instance), zone)

    @staticmethod
    def _cached_build(code: dict):
        from .codecache import import_file

        def build(program, number, *args):
            return import_file(code["files"][number], program, number, *args)
        return build

    # -- plug-in modules ------------------------------------------------------------------
    def _attach_modules(self, per_module) -> None:
        attached = []
        try:
            for m in self.modules:
                self.module_warnings += m.attach(self, per_module.get(m.name, {}))
                attached.append(m)
            if self.recorder is not None:
                self.recorder.open()  # every port is described now; an unwritable TRACE stops the start
        except BaseException:
            for m in attached:  # a module refused to start: release what the others opened
                m.close()
            raise

    def _attach_hooks(self) -> None:
        for m in self.modules:
            if overrides(m, "on_input"):
                self.input_hooks.append(m.on_input)
            if overrides(m, "on_output"):
                self.output_hooks.append(m.on_output)
            if overrides(m, "on_mode"):
                self.mode_hooks.append(m.on_mode)

    def _module_instance(self, ins, access):
        """The run-time instance of a module instruction (called once per
        instruction by either executor, with the access it binds operands
        through: ladder/bound.py), or None for a built-in one."""
        module = self._owner.get(ins.mnemonic)
        if module is None:
            return None
        instance = self._kept_instances.get(id(ins))  # an online edit: the same instruction in an unchanged rung
        if instance is None:
            instance = module.bind(self, ins, access)
        self._instances[id(ins)] = instance
        return instance

    def close(self) -> None:
        """End of the run: modules release what they hold (ports, files)."""
        for m in self.modules:
            m.close()
        if self.recorder is not None:
            self.recorder.close()
            self.recorder = None

    # -- online program edit ---------------------------------------------------------------
    def replace_program(self, program: Program, code: dict | None = None):
        """Run ``program`` (validated) from the next scan on, the data table
        kept: call between scans, from the scan thread (``code``: its code
        from ladder/online.precompile, bound instead of compiled). Returns
        the ProgramChanges; raises EditRefused (nothing changed) if the table
        cannot take the program. What is kept and what is written:
        ladder/online.py, docs/engine.md "Online program edit"."""
        from .online import plan_edit

        return self.apply_edit(plan_edit(self, program, code))

    def apply_edit(self, plan):
        """Apply an online edit planned by ladder/online.plan_edit against
        this engine and its table as they still are: the table grows and
        takes the edit's values, the code is built anew (module
        instructions of unchanged rungs keep their instances). Returns the
        plan's ProgramChanges; raises EditRefused if the code cannot be
        built, the old code then running on in the grown table."""
        from .online import build_refused

        plan.apply_to(self.table)
        instances = self._instances
        kept = {id(new): instances[id(old)] for old, new in plan.kept if id(old) in instances}
        try:
            if plan.code is not None and self.executor == "compiled":
                try:  # bound to the live table, as the code cache's code is
                    self._rebuild(plan.program, kept, self._cached_build(plan.code))
                except Exception:  # code that does not fit after all: compile, as without it
                    self._rebuild(plan.program, kept)
            else:
                self._rebuild(plan.program, kept)
        except Exception as exc:
            raise build_refused(exc) from exc
        return plan.changes

    @property
    def module_owners(self) -> dict:
        """Mnemonic -> the module whose instruction it is."""
        return self._owner

    def _rebuild(self, program: Program, kept_instances: dict, build=None) -> None:
        """Build the code of ``program`` (with ``build``, else for the
        engine's executor); module instructions in ``kept_instances`` (id ->
        instance) keep theirs. If building fails, the old program and code
        stay and the error is raised."""
        saved = self.program, self.files, self._instances
        self.program, self._instances, self._kept_instances = program, {}, kept_instances
        if build is None:
            build = _builder(self.executor)
        try:
            self._build_files(program, build)
        except BaseException:
            self.program, self.files, self._instances = saved
            raise
        finally:
            self._kept_instances = {}

    # -- modes --------------------------------------------------------------------------
    def set_mode(self, mode: Mode) -> None:
        if mode is self.mode:
            if mode is Mode.PROGRAM:
                # SoftPLC: asking for PROGRAM while in PROGRAM tells the
                # modules to reload their configuration (MODBMAST manual 5.2).
                for hook in self.mode_hooks:
                    hook(self, mode, mode)
            return
        if mode not in TRANSITIONS[self.mode]:
            raise ModeError(f"cannot go from {self.mode.name} to {mode.name}"
                            + (" (clear the fault first: go to PROGRAM)" if self.mode is Mode.FAULTED else ""))
        old = self.mode
        if old is Mode.FAULTED:
            self.fault = None
            for w in (S.MAJOR_FAULT_BITS, S.MAJOR_FAULT_CODE, S.FAULT_FILE, S.FAULT_RUNG):
                self.s[w] = 0
        self.mode = mode
        self.s[S.MODE_WORD] = mode.value
        if mode in (Mode.RUN, Mode.TEST) and old is Mode.PROGRAM:
            self._first_pass = True
            # SLC 500's free-running clock S:4 is cleared on entering an executing mode (1763-RM001).
            self.s[S.FREE_RUNNING_CLOCK] = 0
            self._clock_s4_ms = self.clock.now_ms
            self._restamp_timers()
        for hook in self.mode_hooks:
            hook(self, old, mode)

    # -- one scan ------------------------------------------------------------------------------
    def scan(self) -> None:
        m = self.machine
        m.dt = self.clock.advance()
        m.now_ms = self.clock.now_ms
        self._free_running_clock()
        for hook in self.input_hooks:
            try:
                hook(self)
            except Exception as exc:  # a module's bug faults the PLC; it never ends the run with a traceback
                self._hook_failed(hook, exc)
        if self.mode in (Mode.RUN, Mode.TEST):
            self._ladder()
        enabled = self.mode is Mode.RUN
        for hook in self.output_hooks:
            try:
                hook(self, enabled)
            except Exception as exc:
                self._hook_failed(hook, exc)

    def _restamp_timers(self) -> None:
        """Timers left timing (EN or TT on) when the ladder starts again, from
        PROGRAM or from a restored table, time from now: the time in PROGRAM is
        not timed, and a stamp from another run of the clock means nothing."""
        now = self.clock.now_ms & STAMP
        for f in self.table.files():
            if f.ftype.letter == "T":
                d = f.data
                for i in range(0, len(d), f.ftype.words_per_element):
                    if d[i] & (EN | TT):
                        d[i] = (d[i] & ~STAMP) | now

    def _free_running_clock(self) -> None:
        """S:4 counts 10 ms steps of the engine's clock (simulated or real),
        16 bits, wrapping; a value the program writes counts on from there."""
        steps, _ = divmod(self.clock.now_ms - self._clock_s4_ms, S.FREE_RUNNING_CLOCK_MS)
        if steps:
            self._clock_s4_ms += steps * S.FREE_RUNNING_CLOCK_MS
            self.s[S.FREE_RUNNING_CLOCK] = to_signed((self.s[S.FREE_RUNNING_CLOCK] + steps) & 0xFFFF)

    def _hook_failed(self, hook, exc: Exception) -> None:
        owner = getattr(getattr(hook, "__self__", None), "name", None) or getattr(hook, "__qualname__", "a hook")
        message = f"internal error in {owner}'s {getattr(hook, '__name__', 'hook')}: {type(exc).__name__}: {exc}"
        if self.mode is Mode.FAULTED and self.fault is not None and self.fault.message == message:
            return  # the same failure again, scan after scan: the fault already says it
        self._major(MajorFault(S.FAULT_INTERNAL, message))

    def _ladder(self) -> None:
        s = self.s
        if self._first_pass:
            s[S.PROCESSOR_STATUS] |= -32768  # S:1/15 first pass
        start = time.perf_counter()
        watchdog_ms = s[S.WATCHDOG_MS] if s[S.WATCHDOG_MS] > 0 else self.settings.watchdog_ms
        self._deadline = start + watchdog_ms / 1000
        try:
            self._depth = 0
            if MAIN_FILE in self.files:  # a program with no rungs scans as an empty PLC does
                self.run_file(MAIN_FILE)
        except _EndScan:
            pass
        except MajorFault as fault:
            self._major(fault)
        except Exception as exc:  # a bug in softplc must not become a traceback for the user
            self._major(MajorFault(S.FAULT_INTERNAL, f"internal error: {type(exc).__name__}: {exc}"))
        elapsed_ms = (time.perf_counter() - start) * 1000
        self.last_scan_ms = elapsed_ms
        self.max_scan_ms = max(self.max_scan_ms, elapsed_ms)
        # S:8/S:9 hold the scan time in ms: simulated time per scan when the
        # clock is simulated (so runs are reproducible), measured otherwise.
        shown = elapsed_ms if self.clock.realtime else self.clock.scan_ms
        s[S.LAST_SCAN_MS] = min(int(round(shown)), 32767)
        s[S.MAX_SCAN_MS] = max(s[S.MAX_SCAN_MS], s[S.LAST_SCAN_MS])
        self.scans += 1
        s[S.SCAN_COUNT_LOW] = to_signed(self.scans & 0xFFFF)
        s[S.SCAN_COUNT_HIGH] = to_signed((self.scans >> 16) & 0xFFFF)
        if self._first_pass:
            s[S.PROCESSOR_STATUS] &= 0x7FFF
            self._first_pass = False
        if self.mode is not Mode.FAULTED and elapsed_ms > watchdog_ms:
            self._major(MajorFault(S.FAULT_WATCHDOG, f"scan took {elapsed_ms:.1f} ms, "
                                   f"more than the watchdog setpoint S:28 = {watchdog_ms} ms"))

    def run_file(self, number: int, inputs: list | None = None) -> list | None:
        """Scan program file ``number``; a JSR's ``inputs`` (values) go into
        the addresses of the file's SBR first. Returns the values of the RET
        that ended it, or None (a RET without values, the end of the file)."""
        compiled, zone = self.files[number]
        blocks = compiled.blocks  # one function per block of rungs (per rung in the reference executor)
        m = self.machine
        saved_zone = zone[0]
        # A JSR runs inside its caller's rung: where the caller stands is put
        # back on return, so a minor fault later in that rung names it.
        saved_at = (m.file, m.rung)
        zone[0] = True
        k = 0
        count = len(blocks)
        returned = None
        try:
            if inputs:
                m.file, m.rung = number, 0
                self._receive(number, inputs)
            while k < count:
                m.file = number
                m.rung = compiled.starts[k]
                r = blocks[k](zone[0])
                if r is None:
                    k += 1
                elif r.__class__ is not int:  # a RET with values: the instruction itself (m.rung: its rung)
                    returned = [self._parameter_value(op, r) for op in r.operands]
                    break
                elif r >= 0:  # a JMP to rung r (a label: a block starts there)
                    target = compiled.block_index(r)
                    if target <= k and time.perf_counter() > self._deadline:
                        raise MajorFault(S.FAULT_WATCHDOG, "watchdog: the scan is stuck in a backward JMP loop "
                                         f"(longer than S:28 = {self.s[S.WATCHDOG_MS]} ms)")
                    k = target
                    blocks = compiled.blocks  # a breakpoint set meanwhile may have split a block
                    count = len(blocks)
                elif r == RET:
                    break
                else:  # TND
                    raise _EndScan
        except MajorFault as fault:
            if fault.file is None:
                fault.file = number
                fault.rung, ins = self._which_instruction(compiled, fault)
                if fault.rung is None:
                    fault.rung = m.rung
                if fault.instruction is None and ins is not None:
                    fault.instruction = describe(ins)
            raise
        except (_EndScan, RecursionError):
            raise
        except Exception as exc:
            fault = MajorFault(S.FAULT_INTERNAL, f"internal error: {type(exc).__name__}: {exc}")
            fault.file = number
            fault.rung, ins = self._which_instruction(compiled, exc)
            if fault.rung is None:
                fault.rung = m.rung
            fault.instruction = describe(ins) if ins is not None else None
            raise fault from exc
        finally:
            zone[0] = saved_zone
            m.file, m.rung = saved_at
        return returned

    def _jsr(self, number: int, call: Instruction | None = None) -> None:
        """Run subroutine file ``number`` for a JSR; ``call`` is the JSR when
        it has parameters (1785-6.1 JSR/SBR/RET, docs/instructions.md): its
        inputs are read here, in the caller, all before any is written; the
        values of the RET that ends the subroutine go to its return
        parameters, pairwise, converted as MOV converts."""
        self._depth += 1
        try:
            if self._depth > self.settings.jsr_depth:
                raise MajorFault(S.FAULT_JSR_NESTING, f"JSR {number}: subroutines nested more than "
                                 f"{self.settings.jsr_depth} deep")
            if time.perf_counter() > self._deadline:
                raise MajorFault(S.FAULT_WATCHDOG, "watchdog: scan time exceeded S:28 in subroutine calls")
            if call is None:
                self.run_file(number)
                return
            ops = call.operands
            first_return = 2 + ops[1].value
            inputs = [self._parameter_value(op, call) for op in ops[2:first_return]]
            values = self.run_file(number, inputs)
            if values:
                self._store_parameters(ops[first_return:], values, call)
        finally:
            self._depth -= 1

    def _receive(self, number: int, inputs: list) -> None:
        """A JSR's input values into the addresses of file ``number``'s SBR
        (the first instruction of its first rung, as the validator requires)."""
        rungs = self.program.files[number].rungs
        sbr = rungs[0].elements[0] if rungs and rungs[0].elements else None
        if isinstance(sbr, Instruction) and sbr.mnemonic == "SBR":
            self._store_parameters(sbr.operands, inputs, sbr)

    def _store_parameters(self, refs, values: list, ins: Instruction) -> None:
        """Pairwise, as many as both lists have: each value stored as MOV
        stores it (float to integer rounds, overflow clamps or wraps, S:0)."""
        store = self.machine.store
        for ref, value in zip(refs, values):
            d, i = self._parameter_location(ref, ins)
            store(value, d, i)

    def _parameter_location(self, ref: AddressRef, ins: Instruction):
        try:
            f, index, _ = self.table.resolve(ref.address)
        except AddressRangeError as e:
            fault = address_fault(ref.address, e)
            fault.instruction = describe(ins)
            raise fault from None
        return f.data, index

    def _parameter_value(self, op, ins: Instruction):
        if isinstance(op, Const):
            return op.value
        d, i = self._parameter_location(op, ins)
        return d[i]

    @staticmethod
    def _which_instruction(compiled, exc: BaseException):
        """(rung, instruction) where it failed: the innermost generated line
        of this file in the traceback, through the block's line table."""
        found = (None, None)
        for frame, lineno in traceback.walk_tb(exc.__traceback__):
            rung, ins = compiled.where(frame.f_code.co_filename, lineno)
            if ins is not None:
                found = (rung, ins)
        return found

    def _major(self, fault: MajorFault) -> None:
        s = self.s
        # kept without its traceback and cause: they hold the frames of the scan that failed
        self.fault = fault.with_traceback(None)
        fault.__cause__ = fault.__context__ = None
        bit = S.MAJOR_WATCHDOG_BIT if fault.code == S.FAULT_WATCHDOG else S.MAJOR_RUNTIME_BIT
        s[S.MAJOR_FAULT_BITS] |= 1 << bit
        s[S.MAJOR_FAULT_CODE] = fault.code
        s[S.FAULT_FILE] = fault.file or 0
        s[S.FAULT_RUNG] = fault.rung or 0
        old = self.mode
        self.mode = Mode.FAULTED
        s[S.MODE_WORD] = Mode.FAULTED.value
        for hook in self.mode_hooks:
            hook(self, old, Mode.FAULTED)

    def module_fault(self, code: int, message: str) -> None:
        """A module's major fault outside the ladder (a driver whose
        configuration failed to reload): FAULTED, with S:11/S:12 set."""
        self._major(MajorFault(code, message))

    def run(self, scans: int) -> None:
        for _ in range(scans):
            self.scan()
