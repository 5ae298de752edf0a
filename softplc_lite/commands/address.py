"""``softplc address``: each address's canonical form, value kind and
whether it is direct (docs/datatable.md)."""

from __future__ import annotations

import argparse
import sys

from ..datatable import DataTableError, parse_address
from .common import EXIT_ERROR, EXIT_OK

NAME = "address"


def add_parser(sub) -> argparse.ArgumentParser:
    a = sub.add_parser(NAME, help="parse data table addresses and print their canonical form",
                       description="Print each address's canonical form, value kind and whether it is direct "
                                   "(docs/datatable.md).")
    a.add_argument("text", nargs="+", metavar="ADDR", help="address text such as N7:0/3 or I:012/17")
    a.set_defaults(func=run)
    return a


def run(args: argparse.Namespace) -> int:
    status = EXIT_OK
    print("address\tcanonical\tkind\taccess")  # the columns, tab-separated as the rows
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
