"""``python -m softplc_lite``: the softplc command (cli.main)."""

import _signal  # the C module, loaded with the interpreter (signal.py is not: it builds enums)


def _quit_at_once(signum, frame) -> None:  # Ctrl-C before interrupt.py is loaded (it takes over)
    import os

    os._exit(130)


_quit_at_once.ends_softplc = True
if _signal.getsignal(_signal.SIGINT) is _signal.default_int_handler:
    _signal.signal(_signal.SIGINT, _quit_at_once)

from .interrupt import quit_while_loading

quit_while_loading()  # Ctrl-C while the command's modules load: exit 130, no traceback (interrupt.py)

import sys  # noqa: E402 (after the Ctrl-C handling)

from .cli import main  # noqa: E402

sys.exit(main())
