"""The ``softplc`` command.

Exit codes: 0 ok, 1 a program/config/data error (reported, no traceback),
2 usage error (argparse), 3 a PLC fault (scan engine, later issues).
"""

from __future__ import annotations

import argparse
import sys
from typing import Sequence

from . import __version__
from .datatable import DataTable, DataTableError, parse_address
from .datatable import jsonio, snapshot
from .datatable.display import format_value

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_FAULT = 0, 1, 2, 3


def _cmd_address(args: argparse.Namespace) -> int:
    status = EXIT_OK
    for text in args.text:
        try:
            a = parse_address(text)
        except DataTableError as e:
            print(f"error: {e}", file=sys.stderr)
            if hasattr(e, "context"):
                print("  " + e.context().replace("\n", "\n  "), file=sys.stderr)
            status = EXIT_ERROR
            continue
        direct = "direct" if a.is_direct else "indirect/indexed"
        print(f"{text}\t{a}\t{a.kind.value}\t{direct}")
    return status


def _cmd_datatable(args: argparse.Namespace) -> int:
    table = DataTable()
    for path in args.load:
        if path.endswith(".json"):
            jsonio.load_file(table, path)
        else:
            restored = snapshot.load(path)
            jsonio.load_into(table, jsonio.export_table(restored), path)
    for text in args.print:
        a = parse_address(text)
        print(f"{a} = {format_value(table.read(a))}")
    if args.dump:
        sys.stdout.write(jsonio.dumps(table))
    if args.save:
        snapshot.save(table, args.save)
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="softplc",
        description="A soft PLC: text ladder logic on an emulated PLC-5/SoftPLC data table.",
    )
    p.add_argument("--version", action="version", version=f"softplc_lite {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    a = sub.add_parser("address", help="parse data table addresses and print their canonical form")
    a.add_argument("text", nargs="+", metavar="ADDR", help="address text such as N7:0/3 or I:012/17")
    a.set_defaults(func=_cmd_address)

    d = sub.add_parser("datatable", help="load data table JSON or snapshots, print values, dump, save")
    d.add_argument("load", nargs="*", metavar="FILE", help="datatable .json or a snapshot file, in order")
    d.add_argument("--print", action="append", default=[], metavar="ADDR", help="print a value")
    d.add_argument("--dump", action="store_true", help="write the table as JSON to stdout")
    d.add_argument("--save", metavar="SNAPSHOT", help="save the table as a retentive snapshot")
    d.set_defaults(func=_cmd_datatable)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_OK
    try:
        return args.func(args)
    except DataTableError as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
