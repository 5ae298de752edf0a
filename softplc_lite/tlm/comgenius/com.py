"""The port instructions: COMPRINT, COMSCAN, COMRCVCLEAR, COMXMITCLEAR, COMRCVSTS
(manual 4.3.1-4.3.5).

``COMPRINT Control Port Format Param...`` starts on a false-to-true rung
transition: it formats its output once, then puts all of it into the
port's transmit buffer, or none of it while the buffer lacks room (no DN
while it waits, no timeout). Queued: DN, LEN = bytes. A bad format index,
bad or unconfigured port, a port that is down, an illegal format or a bad
Param: DN ER. A false rung clears EN DN ER; an output still waiting for
room is dropped.

``COMSCAN Control Port Format Param...`` starts on the transition and each
true scan matches the port's receive buffer against the format:

============================================  ===========================================================
matched                                       DN; LEN characters taken from the buffer; POS specs matched
cannot match                                  DN ER; LEN the offset of the mismatch; POS; nothing taken
more input needed, timeout expired            DN ER EM; LEN characters read; POS; nothing taken
more input needed, within the timeout         no DN; LEN, POS as far as it got; it tries again next scan
rung false before completion                  EN DN ER EM off; no completion
============================================  ===========================================================

The timeout is the port's ``[PORTS]`` timeout, measured on the engine's
clock from the transition. Params are written while matching, whether or
not the match completes (the manual's "staging areas").

``COMRCVCLEAR Port``, ``COMXMITCLEAR Port`` and ``COMRCVSTS Port Counter``
have no CONTROL: like STRPRINT they act on every scan their rung is true.
COMRCVSTS sets the counter's PRE to the receive buffer size, ACC to the
characters waiting, and OV while the buffer has overflowed. A bad port
makes them raise minor fault S:17/3 with code 7 and do nothing else.
"""

from __future__ import annotations

from typing import Callable

from ...ladder import status as S
from ...ladder.instructions import K
from ...ladder.semantics import OV
from ..api import BoundOperand, ControlElement, ControlledInstruction, InstructionContext, signed_word
from .formats import FormatError
from .instructions import _PARAMS, _PARAMS_OUT, FormatSource, param_problem, param_sources, spec
from .params import ParamError
from .ports import ComPort, PortSet
from .printf import MAX_PARAMS, compile_print
from .scanf import MATCHED, NEED_MORE, compile_scan
from .strings import StringTable

COMPRINT = spec("COMPRINT", "format and send to a port", ("control", K.CONTROL), ("port", K.PORT),
                ("format", K.FORMAT), *_PARAMS, optional=MAX_PARAMS)
COMSCAN = spec("COMSCAN", "receive and match from a port", ("control", K.CONTROL), ("port", K.PORT),
               ("format", K.FORMAT), *_PARAMS_OUT, optional=MAX_PARAMS)
COMRCVCLEAR = spec("COMRCVCLEAR", "clear a port's receive buffer", ("port", K.PORT))
COMXMITCLEAR = spec("COMXMITCLEAR", "clear a port's transmit buffer", ("port", K.PORT))
COMRCVSTS = spec("COMRCVSTS", "receive buffer status into a counter", ("port", K.PORT), ("counter", K.COUNTER))

Log = Callable[[int, str], None]


class _PortOperand:
    def __init__(self, operand: BoundOperand, ports: PortSet) -> None:
        self.operand = operand
        self.ports = ports

    def get(self) -> tuple[ComPort | None, str | None]:
        return self.ports.lookup(int(self.operand.value()))


class _Controlled(ControlledInstruction):
    """COMPRINT and COMSCAN: CONTROL, Port, Format, Params."""

    def __init__(self, ctx: InstructionContext, ports: PortSet, strings: StringTable, log: Log) -> None:
        super().__init__(ctx.operands[0])
        ops = ctx.operands
        self.port = _PortOperand(ops[1], ports)
        self.format = FormatSource(ops[2], strings)
        self.params = param_sources(ops[3:])
        self.where = ctx.where()
        self.log = log
        self.ctx = ctx

    def _port_and_format(self, ctl: ControlElement) -> tuple[ComPort, int, str] | None:
        """The port and the format text at the start, or None after
        finishing with ER (bad or down port, no such string)."""
        port, problem = self.port.get()
        if port is None:
            self._error(ctl, problem)
            return None
        index, fmt = self.format.text()
        if fmt is None:
            self._error(ctl, self.format.problem(index))
            return None
        return port, index, fmt

    def _error(self, ctl: ControlElement, message: str, empty: bool = False) -> bool:
        ctl.finish(error=True, empty=empty)
        self.log(1, f"{self.where}: {message} ({'ER EM' if empty else 'ER'})")
        return True


class ComPrint(_Controlled):
    pending: tuple[ComPort, bytes] | None = None

    def start(self, ctl: ControlElement) -> bool:
        ctl.len = 0
        found = self._port_and_format(ctl)
        if found is None:
            return True
        port, index, fmt = found
        try:
            out = compile_print(fmt).render(self.params(), port.tx_size)
        except FormatError as e:
            return self._error(ctl, f"format {index}: {e}")
        except ParamError as e:
            return self._error(ctl, f"format {index}: {e.reason}")
        data = port.encoding.encode(out)
        if len(data) > port.tx_size:
            size = f"{len(data)} bytes" if len(out) <= port.tx_size else f"more than {port.tx_size} bytes"
            return self._error(ctl, f"format {index}: {size} never fit the {port.tx_size}-byte "
                                    f"transmit buffer of port {port.number}")
        self.pending = (port, data)
        return self.step(ctl)

    def step(self, ctl: ControlElement) -> bool:
        port, data = self.pending
        if not port.up:
            self.pending = None
            return self._error(ctl, f"port {port.number} is down: {port.error}")
        if not port.queue(data):
            return False  # waits for room: no DN, no timeout
        self.pending = None
        ctl.len = len(data)
        ctl.finish()
        return True

    def cancel(self) -> None:
        self.pending = None  # rung went false while waiting: no output


class ComScan(_Controlled):
    port_obj: ComPort | None = None
    # The receive buffer (the str object itself) of the last attempt and its
    # result (status, used, specs), kept only when that attempt needed more
    # input and took no Param: matching the same buffer again would give the
    # same result and change nothing, so it is not repeated until the buffer
    # changes or the instruction starts again. With _tried_need (the length
    # the stopped field needs, 0 when unknown), a buffer that only grew at its
    # end and is still shorter gives NEED_MORE at its end, with the same specs.
    _tried_rx: str | None = None
    _tried_used = 0
    _tried_specs = 0
    _tried_need = 0

    def __init__(self, ctx: InstructionContext, ports: PortSet, strings: StringTable, log: Log) -> None:
        super().__init__(ctx, ports, strings, log)
        # Params of constants and direct addresses only: resolving them takes nothing from the table
        self._fixed_params = all(op.address is None or op.address.is_direct for op in ctx.operands[3:])
        self._clock = ctx.engine.clock  # the engine's clock object, read at every step (ctx.now_ms)
        self._deadline_ms = 0

    def start(self, ctl: ControlElement) -> bool:
        ctl.len = 0
        ctl.pos = 0
        self._tried_rx = None
        self.started_ms = self.ctx.now_ms
        found = self._port_and_format(ctl)
        if found is None:
            return True
        port, index, fmt = found
        try:
            self.matcher = compile_scan(fmt)
            problem = param_problem(self.matcher.items, self.params(), scan=True)  # parsed once, cached
        except FormatError as e:
            return self._error(ctl, f"format {index}: {e}")
        except ParamError as e:  # an indirect Param address that resolves nowhere
            return self._error(ctl, f"format {index}: {e.reason}")
        if problem:
            return self._error(ctl, f"format {index}: {problem}")
        self.index = index
        self.port_obj = port
        self._deadline_ms = self.started_ms + port.config.timeout_ms
        return self.step(ctl)

    def step(self, ctl: ControlElement) -> bool:
        # Run on every true scan while a reply arrives: the common outcome
        # (NEED_MORE on a buffer seen before, or one that only grew) is worked
        # out without a match, a result object or a property call.
        port = self.port_obj
        if port.error is not None:
            return self._error(ctl, f"port {port.number} is down: {port.error}")
        rx = port.rx
        tried = self._tried_rx
        if tried is not None and (rx is tried or (len(rx) < self._tried_need and rx.startswith(tried))):
            if rx is not tried:  # NEED_MORE at its end, with the same specs
                self._tried_rx = rx
                n = len(rx)
                self._tried_used = n if n <= 0x7FFF else signed_word(n)
            d, i = ctl.d, ctl.i
            d[i + 1] = self._tried_used  # LEN
            d[i + 2] = self._tried_specs  # POS
            if self._clock.now_ms < self._deadline_ms:
                return False
            return self._timeout(ctl, port)
        try:
            result, taken, need = self.matcher.match_counted(rx, self.params(), final=False)
        except ParamError as e:
            return self._error(ctl, f"format {self.index}: {e.reason}")
        status, used, specs = result
        d, i = ctl.d, ctl.i
        d[i + 1] = signed_word(used)  # LEN
        d[i + 2] = signed_word(specs)  # POS
        if status == NEED_MORE:
            if not taken and self._fixed_params:
                self._tried_rx, self._tried_used, self._tried_specs, self._tried_need = \
                    rx, d[i + 1], d[i + 2], need
            else:
                self._tried_rx = None
            if self._clock.now_ms < self._deadline_ms:
                return False
            return self._timeout(ctl, port)
        self._tried_rx = None
        if status == MATCHED:
            port.take(used)
            ctl.finish()
            self.log(2, f"{self.where}: matched {used} characters, {specs} specs")
            return True
        ctl.finish(error=True)  # MISMATCH
        self.log(2, f"{self.where}: mismatch at offset {used} after {specs} specs (ER)")
        return True

    def _timeout(self, ctl: ControlElement, port: ComPort) -> bool:
        return self._error(ctl, f"timeout after {port.config.timeout_ms} ms with {len(port.rx)} "
                                f"characters waiting", empty=True)


class _PortAction:
    """COMRCVCLEAR, COMXMITCLEAR, COMRCVSTS: every true scan."""

    def __init__(self, ctx: InstructionContext, ports: PortSet, log: Log) -> None:
        self.port = _PortOperand(ctx.operands[0], ports)
        self.machine = ctx.machine
        self.ctx = ctx
        self.where = ctx.where()
        self.log = log
        self.last_problem: str | None = None

    def __call__(self, c: bool) -> bool:
        if not c:
            return c
        port, problem = self.port.get()
        if port is None:
            self.machine.minor(S.MINOR_MODULE_BIT, S.MINOR_CODE_PORT)
            if problem != self.last_problem:  # logged once, not every scan
                self.log(1, f"{self.where}: {problem} (minor fault S:17/3, code {S.MINOR_CODE_PORT})")
            self.last_problem = problem
            return c
        self.last_problem = None
        self.act(port)
        return c

    def act(self, port: ComPort) -> None:
        raise NotImplementedError


class ComRcvClear(_PortAction):
    def act(self, port: ComPort) -> None:
        port.clear_rx()


class ComXmitClear(_PortAction):
    def act(self, port: ComPort) -> None:
        port.clear_tx()


class ComRcvSts(_PortAction):
    def act(self, port: ComPort) -> None:
        d, i, _ = self.ctx.operands[1].location()
        d[i + 1] = min(port.rx_size, 0x7FFF)  # PRE
        d[i + 2] = len(port.rx)  # ACC
        d[i] = (d[i] | OV) if port.overflow else (d[i] & ~OV)
