"""``softplc datatable``: load data table JSON or snapshot files in order,
then print values, dump JSON or save a snapshot (docs/datatable.md)."""

from __future__ import annotations

import argparse
import sys

from ..datatable import DataTable, jsonio, snapshot
from ..errors import file_error
from .common import EXIT_ERROR, EXIT_OK, print_values

NAME = "datatable"


def add_parser(sub) -> argparse.ArgumentParser:
    d = sub.add_parser(NAME, help="load data table JSON or snapshots, print values, dump, save",
                       description="Load data table files in order, then print values, dump JSON or save a "
                                   "snapshot (docs/datatable.md).",
                       epilog="example: softplc datatable docs/examples/datatable.json --print ST9:0")
    d.add_argument("load", nargs="*", metavar="FILE",
                   help="datatable .json or a snapshot file, loaded in order (none: an empty table)")
    d.add_argument("--print", action="append", default=[], metavar="ADDR", help="print a value (repeatable)")
    d.add_argument("--dump", action="store_true", help="write the table as JSON to stdout")
    d.add_argument("--save", metavar="SNAPSHOT", help="save the table as a retentive snapshot")
    d.set_defaults(func=run, parser=d)
    return d


def run(args: argparse.Namespace) -> int:
    if not (args.load or args.print or args.dump or args.save):  # nothing to do: say what it is for
        args.parser.error("expected FILEs to load (datatable .json or snapshot files) and what to do with them "
                          "(--print ADDR, --dump, --save SNAPSHOT), e.g. "
                          "softplc datatable docs/examples/datatable.json --print N7:0")
    table = DataTable()
    for path in args.load:
        if path.endswith(".json"):
            jsonio.load_file(table, path)
        else:
            table.assign(snapshot.load(path))
    print_values(table, args.print)
    if args.dump:
        sys.stdout.write(jsonio.dumps(table))
    if args.save:
        try:
            snapshot.save(table, args.save)
        except OSError as e:
            print(f"error: --save: {file_error(e, args.save, 'write')}", file=sys.stderr)
            return EXIT_ERROR
    return EXIT_OK
