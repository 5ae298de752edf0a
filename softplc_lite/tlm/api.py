"""What a plug-in module (TLM) implements, and the helpers it gets.

A TLM is a class registered in the entry-point group ``softplc_lite.tlms``
(see registry.py). An app enables it by naming it in its MODULES.LST. Then,
for that app:

1. ``configure(app_dir)`` reads the module's own config file (its
   ``config_file``, e.g. COMGENIUS.LST) and returns warnings;
2. ``instructions()`` declares its instructions (InstructionSpec, with
   operand kinds from ``ladder.instructions.K``); both rung syntaxes, the
   validator and ``fmt`` then know them like built-in ones;
3. ``check(instr)`` may return warnings about a use the module can judge
   before running (``softplc check`` prints them with their location);
4. ``attach(engine, options)`` is called once when an engine takes the
   module, before the first scan: open what it drives (ports). ``options``
   holds the run's module options, which the runner splits between
   modules with ``attach_options``: "ports" ({N: device} from ``softplc run --port``, only
   this module's ports), "recorder" (a ports.Recorder for ``--record``, or
   None) and "replay" (a trace path for ``--replay``, or None); a module
   ignores keys it does not use. Raise ModuleError to refuse to start. A
   module that drives serial ports lists them in ``port_claims()`` (after
   ``configure``), so that ``--port N=...`` finds its owner and no two ports
   open one device; one that serves a network (MODBTCPS) reports its
   servers in ``network_servers()``, for the watch view;
5. ``create(instr, ctx)`` makes one instance per instruction in the
   program (the engine asks through ``instance``). Each scan the engine calls the instance with the rung-in
   condition and takes its return value as the rung-out condition;
6. the driver hooks ``on_input``/``on_output`` run every scan at the
   engine's input and output points, ``on_mode`` on each mode change, and
   ``close`` when the run ends.

The engine has no special case for any module, and knows this package
only as ladder.host.Module, which TLM extends; COMGENIUS uses exactly this.
"""

from __future__ import annotations

import os
import sys
import time
from array import array
from pathlib import Path
from typing import TYPE_CHECKING, Mapping

from ..ladder.ast import Instruction
from ..ladder.bound import Access, BoundAccess, Operand
from ..ladder.errors import LadderError
from ..ladder.host import Instance, Module
from ..ladder.instructions import InstructionSpec
from ..ladder.semantics import R_DN, R_EM, R_EN, R_ER, Machine
from ..ports import PortClaim, Recorder, assign_port_overrides, claim_conflicts, physical_url
from .errors import ModuleError

if TYPE_CHECKING:  # pragma: no cover
    from ..ladder.engine import Engine


class TLM(Module):
    """Base class of a plug-in module. Subclasses set ``name`` (as written
    in MODULES.LST) and override what they need. What the engine calls
    (instructions, references, attach, the driver hooks, close) is
    ladder.host.Module's, documented there; this class adds the loader's
    and the tools' side, and runs ``create`` for the engine's ``instance``."""

    title: str = ""
    config_file: str | None = None  # read from the app directory by configure()

    def configure(self, app_dir: Path | None) -> list[str]:
        """Read the module's config from ``app_dir``; return warnings. Raise
        tlm.errors.ModuleError (with path, line, column) for a bad config."""
        return []

    def instructions(self) -> list[InstructionSpec]:
        return []

    def check(self, instr: Instruction) -> list[LadderError]:
        """Warnings about one (validated) instruction of this module."""
        return []

    def create(self, instr: Instruction, ctx: "InstructionContext") -> Instance:
        raise NotImplementedError(f"module {self.name} cannot run {instr.mnemonic}")

    def instance(self, engine: "Engine", instr: Instruction) -> Instance:
        return self.create(instr, InstructionContext(engine, instr))

    def bind(self, engine: "Engine", instr: Instruction, access: Access) -> Instance:
        if type(self).instance is not TLM.instance:  # a module that makes its instances itself
            return self.instance(engine, instr)
        return self.create(instr, InstructionContext(engine, instr, access))

    def port_claims(self) -> list[PortClaim]:
        """The serial ports the module will open, from its config."""
        return []

    def serial_ports(self) -> list:
        """The module's open ports (ports.SerialPort), for the watch view."""
        return []

    def network_servers(self) -> list:
        """The module's network servers, for the watch view: one item per
        server, with the fields of netserver.counters.ServerStatus
        (listening, up, clients, rate, requests, writes, refusals, refused)."""
        return []

    def log(self, message: str) -> None:
        """Diagnostics (a module's DEBUG output): standard error by default."""
        print(f"{self.name}: {message}", file=sys.stderr)

    def log_stamped(self, message: str, engine: "Engine | None" = None) -> None:
        """A diagnostic line stamped with the wall-clock time and the
        engine's time (the DEBUG output of the serial modules)."""
        t = time.time()
        stamp = time.strftime("%H:%M:%S", time.localtime(t)) + f".{int(t * 1000) % 1000:03d}"
        engine_ms = engine.clock.now_ms if engine is not None else 0
        self.log(f"{stamp} t={engine_ms}ms {message}")


def attach_options(modules: list[TLM], options: Mapping[str, object]) -> tuple[dict[str, dict], Recorder | None]:
    """Each module's attach options, and the run's trace recorder.

    ``options``: "ports" ({N or (MODULE or None, N): device}, the run's
    ``--port`` items), "record" (a trace path) and "replay" (a trace path).
    Overrides go to the module that has the port (ModuleError when none or
    two do); ports that would share one device are refused."""
    raw = options.get("ports") or {}
    overrides = {(key if isinstance(key, tuple) else (None, key)): device for key, device in raw.items()}
    claims = {m.name: m.port_claims() for m in modules}
    split = assign_port_overrides(overrides, {name: [c.number for c in cs] for name, cs in claims.items() if cs})
    final = []
    for name, cs in claims.items():
        mine = split.get(name, {})
        for c in cs:
            device = mine.get(c.number)
            final.append(c if device is None else PortClaim(name, c.number, physical_url(device),
                                                            f"--port {name}:{c.number}={device}"))
    conflicts = claim_conflicts(final)
    if conflicts:
        raise ModuleError(conflicts[0])
    record = options.get("record")
    recorder = Recorder(str(record)) if record else None
    per_module = {m.name: {"ports": split.get(m.name, {}), "recorder": recorder, "replay": options.get("replay")}
                  for m in modules}
    return per_module, recorder


def read_module_file(path: Path) -> str:
    """A module's config file as text: a BOM or UTF-16 from a Windows
    editor is read, DOS-era bytes as latin-1 (textfile.py); a bad byte or an
    OS error is a ModuleError (located, or said in words)."""
    from ..errors import LocatedError
    from ..textfile import read_text

    try:
        return read_text(path, fallback="latin-1")
    except LocatedError as e:
        raise ModuleError(e.message, e.path, e.line, e.column) from None
    except OSError as e:  # errors.FileAccessError: "cannot read PATH: permission denied"
        raise ModuleError(str(e)) from None


def find_file(directory: Path, name: str) -> Path | None:
    """``name`` in ``directory``, matched without regard to case (SoftPLC
    config names are upper case; files copied from elsewhere may not be)."""
    exact = directory / name
    # Any entry but a directory: a FIFO, a device or a dangling link is found, and its reading says why it is refused.
    if os.path.lexists(exact) and not exact.is_dir():
        return exact
    if directory.is_dir():
        for p in sorted(directory.iterdir()):
            if p.name.upper() == name.upper() and not p.is_dir():
                return p
    return None


# -- operands --------------------------------------------------------------------------

# One operand of a module's instruction, bound to the data table through the
# executor's access: the protocol built-in instructions use (ladder/bound.py).
BoundOperand = Operand


class InstructionContext:
    """What ``TLM.create`` gets: the instruction, its operands bound through
    the executor's access (ladder.bound.Access; the compiled one when none is
    given) and the run-time machine (data table, status file, clock)."""

    def __init__(self, engine: "Engine", instr: Instruction, access: Access | None = None) -> None:
        self.engine = engine
        self.instr = instr
        self.table = engine.table
        self.machine: Machine = engine.machine
        if access is None:
            access = BoundAccess(engine.table, engine.machine)
        self.operands = [access.operand(op) for op in instr.operands]

    @property
    def now_ms(self) -> int:
        """The engine's clock (simulated or real), in ms."""
        return self.engine.clock.now_ms

    def where(self) -> str:
        from ..ladder.fmt import format_instruction

        return f"{format_instruction(self.instr)} at {self.instr.pos}"


# -- the CONTROL element pattern ---------------------------------------------------------


class ControlElement:
    """An R element seen by an instruction: status bits of word 0, LEN and
    POS. Bit masks are those of signed 16-bit words."""

    __slots__ = ("d", "i")

    def __init__(self, d: array, i: int) -> None:
        self.d = d
        self.i = i

    def _bit(self, mask: int) -> bool:
        return bool(self.d[self.i] & mask)

    en = property(lambda self: self._bit(R_EN))
    dn = property(lambda self: self._bit(R_DN))
    er = property(lambda self: self._bit(R_ER))
    em = property(lambda self: self._bit(R_EM))

    @property
    def len(self) -> int:
        return self.d[self.i + 1]

    @len.setter
    def len(self, value: int) -> None:
        self.d[self.i + 1] = signed_word(value)

    @property
    def pos(self) -> int:
        return self.d[self.i + 2]

    @pos.setter
    def pos(self, value: int) -> None:
        self.d[self.i + 2] = signed_word(value)

    def finish(self, error: bool = False, empty: bool = False) -> None:
        """Completion: DN, with ER on error and EM when ``empty`` (a timeout)."""
        w = (self.d[self.i] | R_DN) & ~(R_ER | R_EM)
        if error:
            w |= R_ER
        if empty:
            w |= R_EM
        self.d[self.i] = w


_R_BITS = R_EN | R_DN | R_ER | R_EM


def signed_word(value: int) -> int:
    """``value`` as a signed 16-bit word (its low 16 bits)."""
    value &= 0xFFFF
    return value - 0x10000 if value & 0x8000 else value


class ControlledInstruction:
    """The manual's pattern for instructions with a CONTROL operand.

    - Rung true with EN off (a false-to-true transition): EN on, DN ER EM
      off, ``start(ctl)``; from then on ``step(ctl)`` each true scan until it
      returns True (it calls ``ctl.finish`` to set DN/ER/EM).
    - Rung true and not started again: nothing, DN and ER stay as they are
      until the rung goes false ("allow the rung to go false").
    - Rung false: EN, DN, ER and EM off; an unfinished operation is dropped
      (``cancel()``): no completion.
    - Rung true, EN on but neither DN nor ER and nothing in progress (a
      data table restored from a snapshot taken mid-operation): started
      again, as if on a new transition.

    The EN bit is the memory of the previous rung state, as in PLC-5 file
    and message instructions, so the data table alone says what happens on
    the next scan. Subclasses implement ``start`` and ``step`` (``start``
    may finish at once and return True)."""

    def __init__(self, control: BoundOperand) -> None:
        self.control = control
        self.busy = False
        # A CONTROL address the access resolved once (a direct one, compiled):
        # its word and its ControlElement are kept, so a scan's call allocates
        # and looks up nothing. Otherwise it is resolved at every call.
        location = control.fixed
        self._d = location[0] if location is not None else None
        self._i = location[1] if location is not None else 0
        self._ctl = ControlElement(self._d, self._i) if location is not None else None

    def __call__(self, c: bool) -> bool:
        d = self._d
        if d is None:
            d, i, _ = self.control.location()
            ctl = None
        else:
            i = self._i
            ctl = self._ctl
        w = d[i]
        if not c:
            if self.busy:
                self.busy = False
                self.cancel()
            if w & _R_BITS:
                d[i] = w & ~_R_BITS
            return c
        if not w & R_EN:
            d[i] = (w | R_EN) & ~(R_DN | R_ER | R_EM)
            self.busy = not self.start(ctl or ControlElement(d, i))
        elif self.busy:
            self.busy = not self.step(ctl or ControlElement(d, i))
        elif not w & (R_DN | R_ER):
            # EN on, nothing in progress, no completion: the operation was
            # lost, e.g. the data table was restored from a retentive
            # snapshot taken mid-operation. Start it again, or the rung would
            # wait for a completion that can never come.
            d[i] = w & ~R_EM
            self.busy = not self.start(ctl or ControlElement(d, i))
        return c

    def start(self, ctl: ControlElement) -> bool:
        """Begin; return True when already finished."""
        return self.step(ctl)

    def step(self, ctl: ControlElement) -> bool:
        raise NotImplementedError

    def cancel(self) -> None:
        pass
