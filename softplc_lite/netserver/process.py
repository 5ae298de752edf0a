"""The server process: a protocol's server over the shared image.

Run by the runtime (``python -m MODULE OUT_FD IMAGE_FD``, MODULE the
protocol's ``process_module``, which calls ``main``): its own process, so
that however busy the clients keep it, the scan never waits for it (no
shared interpreter lock). It reads the protocol and the settings from
standard input, answers reads from the image the scan publishes (the shared
memory open on IMAGE_FD), and passes writes to the scan through the pipe
OUT_FD, answering a write once the scan has applied it (so a read that
follows sees it). It exits when standard input closes: when the runtime
stops, or dies.

The protocol's handler frames, decodes and answers requests; server.py and
connection.py add what a PLC's server needs around each client: the
allow-list, the connection and request-rate limits, idle connections closed,
malformed frames closing their connection, and every refusal counted
(counters.py). The protocol's libraries are imported only once it has said
it can serve (``Protocol.unusable``), so that a missing or unusable library
is said to the runtime in one line.
"""

from __future__ import annotations

import asyncio
import errno
import os
import pickle
import signal
import socket
import sys

from ..fdio import read_exactly
from ..errors import os_error_words
from . import counters as C
from . import messages as msg
from .image import SharedImage
from .server import Server

_WHY = {errno.EADDRINUSE: "the address is in use (another program listens there)",
        errno.EACCES: "no permission (a port below 1024 needs privileges)",
        errno.EADDRNOTAVAIL: "no such address on this machine"}


def _bind_problem(host: str, port: int) -> str | None:
    """Why the address cannot be listened on, in words (a library's listener may only log it)."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except OSError:
        return f"cannot listen on {host}:{port}: no such host"
    family, kind, proto, _, sockaddr = infos[0]
    with socket.socket(family, kind, proto) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(sockaddr)
        except OSError as e:
            why = _WHY.get(e.errno) or os_error_words(e)  # a listen's own words first, then the common ones
            return f"cannot listen on {host}:{port}: {why}"
    return None


async def serve(init: dict, image, out_fd: int) -> None:
    settings = init["settings"]
    problem = _bind_problem(settings.host, settings.port)
    if problem is not None:
        os.write(out_fd, msg.failed(problem))  # blocking still: a few bytes into an empty pipe
        return
    server = Server(init["protocol"], settings, image, out_fd)
    port = await server.start()
    image.set(C.PORT, port)
    image.set(C.LISTENING, 1)
    server.log(1, f"listening on {settings.host}:{port}")
    os.set_blocking(out_fd, False)
    server.send(msg.ready(port))

    loop = asyncio.get_running_loop()
    done = loop.create_future()
    reader = msg.Reader()
    stdin = 0
    os.set_blocking(stdin, False)

    def from_runtime() -> None:
        try:
            data = os.read(stdin, 65536)
        except BlockingIOError:
            return
        if not data:  # the runtime closed the pipe: stopped, or gone
            if not done.done():
                done.set_result(None)
            return
        for m in reader.feed(data):
            if m[0] == msg.REFUSED:
                server.refused_by_scan(m[1])
            elif m[0] == msg.ACK:
                server.acked(m[1])

    loop.add_reader(stdin, from_runtime)
    await done
    loop.remove_reader(stdin)
    image.set(C.LISTENING, 0)
    await server.stop()


def main() -> int:
    # Ctrl-C reaches the whole terminal's process group: the runtime decides when this process ends
    # (it closes standard input after its final scan), so a Ctrl-C does not end it first.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    out_fd, image_fd = int(sys.argv[1]), int(sys.argv[2])
    name = "server process"

    def fail(why: str) -> int:  # one line, no traceback: the runtime says it; if it is gone, this process does
        try:
            os.write(out_fd, msg.failed(why))
        except OSError:
            print(f"{name}: {why}", file=sys.stderr, flush=True)
        return 1

    try:
        header = read_exactly(0, 4)
        if len(header) < 4:
            return 1
        init = pickle.loads(read_exactly(0, msg.LENGTH.unpack(header)[0]))
        name = init["protocol"].name
        problem = init["protocol"].unusable()
        if problem is not None:
            return fail(problem)
        asyncio.run(serve(init, SharedImage.attach(image_fd, init["size"]), out_fd))
    except Exception as exc:  # noqa: BLE001 - a bug: one line, never a traceback
        return fail(f"the server process failed: {exc or exc.__class__.__doc__}")
    return 0


def run_and_exit() -> None:
    """``main``, then the process ends at once. Python's own teardown would
    free the protocol library's objects one by one (asyncua's address space:
    over a second) while the runtime waits for this process to end; there is
    nothing left to finalize: the image is the runtime's, the pipe is
    written, standard error is flushed here."""
    code = main()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(code)


if __name__ == "__main__":
    run_and_exit()
