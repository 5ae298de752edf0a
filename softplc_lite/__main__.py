"""``python -m softplc_lite``: the softplc command (console.main)."""

from .console import main  # first: it takes Ctrl-C over before anything else loads

import sys  # noqa: E402

sys.exit(main())
