"""What a protocol writes to serve through this layer (see the package's
docstring): a ``Protocol``, picklable, that both processes hold, and the
``Handler`` it makes in the server process.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol as Interface

from .image import Segments

if TYPE_CHECKING:
    from .server import Server

# What the scan did with a write (Protocol.apply).
APPLIED = "applied"  # in the data table: counted in the writes applied
IGNORED = "ignored"  # nothing to do (the server checked it against the same map): answered all the same
REFUSED = "refused"  # not applied: ``Server.through_scan`` returns False to the handler


@dataclass(frozen=True)
class Settings:
    """Where the server listens, who may connect, and its limits."""

    host: str
    port: int
    allow: tuple  # ipaddress networks
    max_connections: int
    max_requests_per_second: int
    idle_timeout_ms: int
    debug: int = 0  # 1: refusals logged; 2: every connection and request too


@dataclass(frozen=True)
class Refusal:
    """A request answered with an error, and why (for the log); ``code`` is
    the protocol's (a Modbus exception code)."""

    code: Any
    why: str


class Malformed(Exception):
    """Bytes that are not a frame of the protocol: their connection closes,
    counted; the message says what they were."""


class Protocol(abc.ABC):
    """A protocol as both processes know it: built by its module in the
    runtime from its configuration, pickled to the server process."""

    name: str = "NETSERVER"  # the log's prefix, and the server process's messages
    process_module: str = "softplc_lite.netserver.process"  # run as ``python -m``: names the process
    segments: Segments = Segments("netserver")  # the image's file name, for someone who lists /dev/shm

    # -- the runtime's side --------------------------------------------------------------------------
    @abc.abstractmethod
    def regions(self) -> list[tuple[str, int, int, int]]:
        """The data table words the image holds: (file name, first index in
        the file's array, items, byte offset in the image), one a region.
        The scan publishes them at its output point."""

    @property
    @abc.abstractmethod
    def image_bytes(self) -> int:
        """The bytes the regions take in the image."""

    @abc.abstractmethod
    def apply(self, payload: bytes, table) -> str:
        """Apply a client's write (the bytes the handler passed to
        ``Server.through_scan``) to the data table, at the scan's input
        point: APPLIED, IGNORED or REFUSED."""

    # -- the server process's side -------------------------------------------------------------------
    def unusable(self) -> str | None:
        """Why this process cannot serve (a library missing), in one line;
        asked before anything is imported that needs it."""
        return None

    @abc.abstractmethod
    def handler(self, server: Server) -> Handler:
        """The protocol's side of ``server``."""


class Handler(abc.ABC):
    """A protocol in the server process: frames, decodes and answers
    requests, reading mapped regions from the image (``Server.read``) and
    passing writes to the scan (``Server.through_scan``)."""

    busy: Any  # the refusal code of a busy server: over the request rate, too many writes waiting
    failure: Any  # the refusal code of a request whose serving failed (a bug: logged, not counted)

    def __init__(self, server: Server) -> None:
        self.server = server

    def listener(self) -> Listener:
        """What accepts the connections: plain TCP (tcp.py) unless the
        protocol's library brings its own."""
        from .tcp import TcpListener

        return TcpListener(self.server)

    @abc.abstractmethod
    def frame_length(self, data: bytearray, at: int) -> int | None:
        """The length of the frame that starts at ``data[at]``, or None
        until it is all received; raises Malformed."""

    def opened(self, link: Link) -> Any:
        """The state a protocol keeps per connection (an EtherNet/IP session),
        made when ``link`` is accepted; None for a protocol that keeps none."""
        return None

    def closed(self, state) -> None:
        """The connection that held ``state`` ended, however it ended: what
        the protocol opened for it (a CIP connection) goes with it."""

    @abc.abstractmethod
    def header(self, frame: bytes, state) -> Any:
        """What a reply to ``frame`` needs of it (a transaction id; the
        connection's ``state`` if the reply needs that too), so that a frame
        refused before it is decoded is answered too."""

    @abc.abstractmethod
    def decode(self, frame: bytes, header) -> Any:
        """The request a whole frame holds, or the Refusal that answers it.
        A request's ``str`` is its debug log line."""

    @abc.abstractmethod
    async def serve(self, request) -> Any:
        """The reply to a request, or the Refusal that answers it."""

    @abc.abstractmethod
    def refusal_reply(self, code, header) -> Any:
        """The reply that refuses a request with ``code``."""

    @abc.abstractmethod
    def counter(self, code) -> int:
        """The counter (counters.py) a refusal with ``code`` counts in."""

    def code_words(self, code) -> str:
        """A refusal's code as the log says it."""
        return str(code)


class Link(Interface):
    """One client's connection as the listener holds it (tcp.py's, or a
    protocol library's): the layer's Connection calls these."""

    @property
    def is_open(self) -> bool: ...

    def peername(self): ...

    def reply(self, response) -> None: ...

    def pause_reading(self) -> None: ...

    def resume_reading(self) -> None: ...

    def abort(self) -> None: ...


class Listener(Interface):
    """Accepts connections; each new one is given to ``Server.connect``."""

    async def start(self) -> int: ...  # listen; the port bound

    async def stop(self) -> None: ...
