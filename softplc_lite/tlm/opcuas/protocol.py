"""OPC UA as the network-server layer (softplc_lite/netserver) serves it:
the whole data table in the shared image (space.py lays it out), and the
handler the server process makes, whose listener is asyncua's server
(asyncua_glue.py). Nothing here imports asyncua: the runtime never does.

A client's write of a variable a ``<Writable>`` opens reaches the scan as
writes.py's bytes, applied at the input point.
"""

from __future__ import annotations

from ...netserver import Handler, Protocol
from ...netserver.image import Segments
from . import status as S
from . import writes
from .config import ServerConfig
from .space import Space

SEGMENTS = Segments("opcuas")  # the shared images' files: softplc-opcuas-PID-RANDOM


class OpcUaProtocol(Protocol):
    name = "OPCUAS"
    process_module = "softplc_lite.tlm.opcuas.serverproc"
    segments = SEGMENTS

    def __init__(self, config: ServerConfig, space: Space) -> None:
        self.config = config
        self.space = space

    def regions(self) -> list[tuple[str, int, int, int]]:
        return self.space.regions()

    @property
    def image_bytes(self) -> int:
        return self.space.image_bytes

    def apply(self, payload: bytes, table) -> str:
        return writes.apply(self.space, payload, table)

    def unusable(self) -> str | None:
        """Why asyncua cannot serve, in one line; None when it can."""
        try:
            from . import asyncua_glue
        except ImportError as e:
            return str(e)
        return asyncua_glue.missing()

    def handler(self, server):
        return OpcUaHandler(server, self)


class OpcUaHandler(Handler):
    """asyncua frames, decodes and answers every request (its listener is
    asyncua's server); the layer's per-frame hooks are never called."""

    busy = "BadTooManyOperations"
    failure = "BadInternalError"

    def __init__(self, server, protocol: OpcUaProtocol) -> None:
        super().__init__(server)
        self.protocol = protocol

    def listener(self):
        from .asyncua_glue import Listener

        return Listener(self.server, self.protocol.space, self.protocol.config,
                        (S.REFUSED_WRITES, S.REFUSED_ITEMS, S.REFUSED_SUBSCRIPTIONS, S.REFUSED_IDENTITIES))

    def frame_length(self, data, at):  # pragma: no cover - asyncua frames
        raise NotImplementedError

    def header(self, frame, state):  # pragma: no cover
        raise NotImplementedError

    def decode(self, frame, header):  # pragma: no cover
        raise NotImplementedError

    async def serve(self, request):  # pragma: no cover
        raise NotImplementedError

    def refusal_reply(self, code, header):  # pragma: no cover
        raise NotImplementedError

    def counter(self, code) -> int:
        return S.REFUSED_WRITES
