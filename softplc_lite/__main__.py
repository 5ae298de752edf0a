"""``python -m softplc_lite``: the softplc command (cli.main)."""

from .interrupt import quit_while_loading

quit_while_loading()  # Ctrl-C while the command's modules load: exit 130, no traceback (interrupt.py)

import sys  # noqa: E402 (after the Ctrl-C handling)

from .cli import main  # noqa: E402

sys.exit(main())
