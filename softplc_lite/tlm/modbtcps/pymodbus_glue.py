"""Every place MODBTCPS touches pymodbus, in one module.

Written and tested against pymodbus >=3.16.1,<3.17 (the range pyproject.toml
pins: pymodbus changes its API in minor releases). Beyond its documented
API (``ModbusTcpServer.serve_forever``/``shutdown``, the PDU classes of
``pymodbus.pdu``, ``ExceptionResponse``), MODBTCPS relies on these internals:

- ``pymodbus.server.requesthandler.ServerRequestHandler``, the object of
  one connection: its ``callback_connected``/``callback_disconnected``
  hooks, ``pdu_send`` (the MBAP framing of a reply), ``close`` and
  ``transport``; asyncio's ``data_received`` is taken over, so pymodbus's
  own receive buffer and request dispatch are never used;
- ``ModbusTcpServer.callback_new_connection``, ``transport`` (the
  listening sockets) and ``trace_packet``/``trace_pdu``/``trace_connect``;
- ``DecodePDU(True).decode``, the request decoder, and the attributes of
  the request PDUs it returns;
- a ``ModbusServerContext`` with ``old_simulator`` set, so that the server
  takes a datastore it never calls (requests are served by handler.py).

Nothing else in MODBTCPS imports pymodbus. ``missing()`` says, in one line,
what an installed pymodbus lacks of this; the server process reports it
instead of failing later with a traceback.
"""

from __future__ import annotations

PYMODBUS_RANGE = ">=3.16.1,<3.17"

try:
    import pymodbus
    from pymodbus.datastore import ModbusServerContext
    from pymodbus.pdu import DecodePDU, ExceptionResponse, bit_message as bits, register_message as regs
    from pymodbus.server import ModbusTcpServer
    from pymodbus.server.requesthandler import ServerRequestHandler
except ImportError as _exc:  # the server process says this line, not a traceback
    if isinstance(_exc, ModuleNotFoundError) and _exc.name == "pymodbus":
        raise ImportError(f"pymodbus is not installed: MODBTCPS needs pymodbus{PYMODBUS_RANGE} "
                          f"(pip install 'pymodbus{PYMODBUS_RANGE}')") from None
    raise ImportError(f"the installed pymodbus lacks what MODBTCPS uses ({_exc}): MODBTCPS is written for "
                      f"pymodbus {PYMODBUS_RANGE} (pip install 'pymodbus{PYMODBUS_RANGE}')") from None

from .rules import Request  # noqa: E402

_NEEDED = (
    (ServerRequestHandler, ("pdu_send", "close", "callback_connected", "callback_disconnected", "data_received")),
    (ModbusTcpServer, ("serve_forever", "shutdown", "callback_new_connection")),
    (DecodePDU, ("decode",)),
    (ModbusServerContext, ()),
    (bits, ("ReadCoilsResponse", "ReadDiscreteInputsResponse", "WriteSingleCoilResponse",
            "WriteMultipleCoilsResponse", "ReadCoilsRequest", "WriteSingleCoilRequest",
            "WriteMultipleCoilsRequest")),
    (regs, ("ReadHoldingRegistersResponse", "ReadInputRegistersResponse", "WriteSingleRegisterResponse",
            "WriteMultipleRegistersResponse", "MaskWriteRegisterResponse", "ReadWriteMultipleRegistersResponse",
            "ReadHoldingRegistersRequest", "WriteSingleRegisterRequest", "WriteMultipleRegistersRequest",
            "MaskWriteRegisterRequest", "ReadWriteMultipleRegistersRequest")),
)


def missing() -> str | None:
    """What the installed pymodbus lacks of what this module uses, in one
    line; None when it has everything."""
    lacking = [f"{getattr(owner, '__name__', owner)}.{name}" for owner, names in _NEEDED
               for name in names if not hasattr(owner, name)]
    if not lacking:
        return None
    return (f"pymodbus {getattr(pymodbus, '__version__', '?')} lacks {', '.join(lacking)}: MODBTCPS is written "
            f"for pymodbus {PYMODBUS_RANGE} (pip install 'pymodbus{PYMODBUS_RANGE}')")


class _NoDatastore(ModbusServerContext):
    """A datastore pymodbus's server accepts and never calls."""

    def __init__(self) -> None:  # no super().__init__: it would build pymodbus's own store
        self.old_simulator = True
        self.simdevices = []
        self._devices = {}


class Link(ServerRequestHandler):
    """pymodbus's object of one client connection, as the network-server
    layer's Connection uses it (netserver.protocol.Link): pymodbus and
    asyncio's calls go to the connection, which replies in pymodbus PDUs
    that ``pdu_send`` frames."""

    def __init__(self, listener: "Listener", server) -> None:
        super().__init__(listener, listener.trace_packet, listener.trace_pdu, listener.trace_connect)
        self.connection = server.connect(self)

    # pymodbus and asyncio -> the connection
    def callback_connected(self) -> None:
        self.connection.connected()

    def callback_disconnected(self, exc) -> None:
        super().callback_disconnected(exc)
        self.connection.ended()

    def data_received(self, data: bytes) -> None:
        # asyncio's call, taken over: pymodbus's own buffer drops everything when more than 264 bytes
        # arrive at once (pipelined requests) and is cleared by every reply sent.
        if self.transport is not None:
            self.connection.received(data)

    def callback_data(self, data: bytes, addr=None) -> int:
        return len(data)  # not reached: data_received does not pass data on

    def pause_writing(self) -> None:
        self.connection.pause_writing()

    def resume_writing(self) -> None:
        self.connection.resume_writing()

    # the connection -> pymodbus
    @property
    def is_open(self) -> bool:
        return self.transport is not None

    def peername(self):
        return self.transport.get_extra_info("peername") if self.transport is not None else None

    def reply(self, response) -> None:
        self.pdu_send(response)

    def pause_reading(self) -> None:
        if self.transport is not None:
            self.transport.pause_reading()

    def resume_reading(self) -> None:
        if self.transport is not None:
            self.transport.resume_reading()

    def abort(self) -> None:
        """Close now, dropping the replies not yet sent (a client that stops
        reading must not keep its socket and their memory: close() waits)."""
        if self.transport is not None:
            self.transport.abort()
        self.close()

    def close(self, reconnect: bool = False) -> None:
        super().close(reconnect)
        self.connection.ended()


class Listener(ModbusTcpServer):
    """pymodbus's TCP server, as the network-server layer's listener
    (netserver.protocol.Listener): each connection a Link."""

    def __init__(self, server) -> None:
        self.plc_server = server
        super().__init__(_NoDatastore(), address=(server.settings.host, server.settings.port))

    def callback_new_connection(self):
        return Link(self, self.plc_server)

    async def start(self) -> int:
        """Listen; the port bound."""
        await self.serve_forever(background=True)
        return self.transport.sockets[0].getsockname()[1]

    async def stop(self) -> None:
        await self.shutdown()


_decoder = DecodePDU(True)


def decode(pdu: bytes, unit: int, tid: int) -> Request | None:
    """A request PDU (function code first) as a Request; None when pymodbus
    cannot decode it."""
    p = _decoder.decode(pdu)
    if p is None or p.function_code != pdu[0]:
        return None
    f = p.function_code
    r = Request(f, unit, tid, address=p.address)
    if f in (1, 2, 3, 4):
        r.count = p.count
    elif f == 5:
        r.values = [1 if p.bits[0] else 0]
    elif f == 6:
        r.values = [int(p.registers[0])]
    elif f == 15:
        r.values = [1 if b else 0 for b in p.bits[:p.count]]
    elif f == 16:
        r.values = [int(v) for v in p.registers[:p.count]]
    elif f == 22:
        r.and_mask, r.or_mask = p.and_mask, p.or_mask
    elif f == 23:
        r.address, r.values = p.write_address, [int(v) for v in p.write_registers[:p.write_count]]
        r.read_address, r.read_count = p.read_address, p.read_count
    else:
        return None
    if f in (5, 6, 15, 16, 22, 23):
        r.count = len(r.values) if f != 22 else 1
    return r


def response(r: Request, values: list[int] | None = None):
    """The normal response to ``r``; ``values``: the items read (1-4, 23),
    or the item as it reads after the write (5, 6)."""
    f, ids = r.function, {"dev_id": r.unit, "transaction_id": r.tid}
    if f in (1, 2):
        cls = bits.ReadCoilsResponse if f == 1 else bits.ReadDiscreteInputsResponse
        return cls(bits=[bool(v) for v in values], **ids)
    if f in (3, 4):
        cls = regs.ReadHoldingRegistersResponse if f == 3 else regs.ReadInputRegistersResponse
        return cls(registers=list(values), **ids)
    if f == 5:
        return bits.WriteSingleCoilResponse(address=r.address, bits=[bool(values[0])], **ids)
    if f == 6:
        return regs.WriteSingleRegisterResponse(address=r.address, registers=list(values), **ids)
    if f == 15:
        return bits.WriteMultipleCoilsResponse(address=r.address, count=r.count, **ids)
    if f == 16:
        return regs.WriteMultipleRegistersResponse(address=r.address, count=r.count, **ids)
    if f == 22:
        return regs.MaskWriteRegisterResponse(address=r.address, and_mask=r.and_mask, or_mask=r.or_mask, **ids)
    return regs.ReadWriteMultipleRegistersResponse(registers=list(values), **ids)


def exception_response(function: int, code: int, unit: int, tid: int):
    return ExceptionResponse(function & 0x7F, code, device_id=unit, transaction=tid)
