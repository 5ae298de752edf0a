"""The ``softplc`` command's entry module: the console script pip installs
imports ``main`` from here, and ``python -m softplc_lite`` runs it.

Its first lines take Ctrl-C over (interrupt.py) before anything heavy
loads. Unlike cli.py, which a program may import and which gives Ctrl-C
back to the importer once loaded, it leaves Ctrl-C ending the process
quietly (exit 130) until main() takes the signals over: the console script
runs a line of its own (a regular expression on argv[0]) between the import
and main(), and a Ctrl-C there would otherwise print a traceback."""

import _signal  # the C module, loaded with the interpreter (signal.py is not: it builds enums)


def _quit_at_once(signum, frame) -> None:  # Ctrl-C before interrupt.py is loaded (it takes over)
    import os

    os._exit(130)


_quit_at_once.ends_softplc = True
if _signal.getsignal(_signal.SIGINT) is _signal.default_int_handler:
    _signal.signal(_signal.SIGINT, _quit_at_once)

from .interrupt import quit_while_loading  # noqa: E402

quit_while_loading()  # Ctrl-C while the command's modules load and until main(): exit 130, no traceback

from .cli import main  # noqa: E402,F401
