"""A network server over the data table, shared by every protocol a module
serves (MODBTCPS's Modbus TCP; docs/modbtcps.md describes it as its users
see it).

What the layer gives a protocol:

- a server in a process of its own (process.py), so that a busy client
  never holds the scan;
- the shared image (image.py): the scan publishes the mapped words at its
  output point under a seqlock, so a read is always one whole scan's table
  and the scan never waits;
- writes applied at the scan's input point in arrival order, each answered
  only once applied (handle.py, messages.py);
- around every client (connection.py, server.py): the allow-list, the
  connection and request-rate limits, idle and malformed connections
  closed, requests answered in order, a client that leaves its replies
  unread no longer read; every refusal counted (counters.py) and logged;
- the counters copied into a status block the ladder reads, laid out by the
  protocol (``counters.StatusWords``), and the server as the watch view's
  servers panel shows it (``counters.ServerStatus``);
- a plain TCP listener (tcp.py) for a protocol whose handler writes its
  replies as bytes.

What a protocol writes (protocol.py):

- a ``Protocol``, picklable, built by its module from its configuration:
  the regions of the data table it maps (``regions``, ``image_bytes``), how
  the scan applies one of its writes (``apply``), why its process cannot
  serve (``unusable``: a library missing), the module its process runs as
  (``process_module``: a module that calls ``process.main``), the name of
  its image's file (``segments``: ``softplc-NAME-PID-RANDOM``), and
- the ``Handler`` it makes in the server process: the state it keeps per
  connection, if any (``opened``, ``closed``: an EtherNet/IP session), how long a frame is
  (``frame_length``; ``Malformed`` when it is not one), what a reply needs
  of a frame (``header``), the request a frame holds (``decode``), its
  reply (``serve``: reads of mapped regions through ``Server.read``,
  writes through ``Server.through_scan``), and the reply and counter of
  each kind of refusal (``refusal_reply``, ``counter``, ``code_words``).
  A handler whose library frames its replies brings its own ``listener``.

The module that serves it (a TLM) builds the Protocol and the ``Settings``
(address, port, allow-list, limits), holds a ``ServerHandle`` and calls its
``attach``, ``on_input``, ``on_output``, ``server_status`` and ``close``.

This package imports the data table, errors and textfile layers only: it
knows no module.
"""

from .counters import ServerStatus, StatusWords
from .handle import ServerHandle
from .protocol import APPLIED, IGNORED, REFUSED, Handler, Malformed, Protocol, Refusal, Settings

__all__ = ["APPLIED", "IGNORED", "REFUSED", "Handler", "Malformed", "Protocol", "Refusal", "ServerHandle",
           "ServerStatus", "Settings", "StatusWords"]
