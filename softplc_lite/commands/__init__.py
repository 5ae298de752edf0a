"""The ``softplc`` subcommands, one module each: its ``add_parser(sub)``
(the subparser, with ``func`` set to its ``run``) and its ``run(args)``,
which returns the exit code. What they share is in ``common``; cli.py
builds the parser from ``COMMANDS`` and runs the one chosen. A new
subcommand is a module here, added to ``COMMANDS``."""

from . import address, check, datatable, fmt, opcua_cert, opcua_user, run, test, watch

COMMANDS = (run, watch, check, test, fmt, address, datatable, opcua_cert, opcua_user)  # in the order --help lists them
