"""Ctrl-C while the ``softplc`` command starts (docs/cli.md, "Signals").

Loading softplc's modules takes the first 0.2 s or so of every command; a
KeyboardInterrupt there would escape as a Python traceback, before main()
can catch anything. The entry module (``console``, which the console script
and ``python -m`` load first) calls ``quit_while_loading`` before its first
heavy import: until main() takes the signals over, Ctrl-C ends the process
quietly with exit status 130, what an interrupted command exits with. Only
Python's own default handler is replaced, and only in the main thread, so a
program that imports softplc with its own SIGINT handling keeps it.

This module imports nothing but ``os``, ``signal`` and ``threading``, so
that it is in place within a few milliseconds of softplc's first line.
"""

from __future__ import annotations

import os
import signal
import threading

EXIT_INTERRUPTED = 130


def _quit(signum, frame) -> None:
    # Nothing has been written or started while modules load, so nothing
    # is lost by ending at once; and an exception raised here can be lost:
    # the handler may run inside compile() (a module's source compiled on
    # import), which does not always pass it on.
    os._exit(EXIT_INTERRUPTED)


def quit_while_loading() -> None:
    """From now until main() takes the signals over: Ctrl-C exits 130, quietly."""
    handler = signal.getsignal(signal.SIGINT)
    # the entry module's first lines may have set a stand-in (ends_softplc) while this module loaded
    if threading.current_thread() is threading.main_thread() and \
            (handler is signal.default_int_handler or getattr(handler, "ends_softplc", False)):
        signal.signal(signal.SIGINT, _quit)


def loaded() -> None:
    """Ctrl-C is a KeyboardInterrupt again (the caller catches it)."""
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGINT) is _quit:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def quit_until_handled() -> None:
    """The command owns the process (the console script, python -m): until
    it takes the signals over itself (``raise_on_interrupt``, or a run's own
    handlers once it scans), Ctrl-C and SIGTERM end it at once with 130.
    Loading an app writes nothing a signal could cut short (the code cache
    is written aside and renamed), and a KeyboardInterrupt raised anywhere
    in that code could land in a finalizer, which swallows it: the command
    would then go on as if no one had asked it to stop."""
    if threading.current_thread() is threading.main_thread():
        if signal.getsignal(signal.SIGINT) in (signal.default_int_handler, _quit):
            signal.signal(signal.SIGINT, _quit)
        if signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, _quit):
            signal.signal(signal.SIGTERM, _quit)


def stop_as_interrupt(signum, frame) -> None:
    """SIGTERM does what Ctrl-C does, once: a second one (a service manager
    sending it twice) is ignored, so it cannot cut the quitting short."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
    raise KeyboardInterrupt


def raise_on_interrupt() -> None:
    """From here on Ctrl-C and SIGTERM raise KeyboardInterrupt, for a
    command that ends cleanly on it (the watch view quits as q does)."""
    if threading.current_thread() is threading.main_thread():
        if signal.getsignal(signal.SIGINT) is _quit:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        if signal.getsignal(signal.SIGTERM) is _quit:
            signal.signal(signal.SIGTERM, stop_as_interrupt)
