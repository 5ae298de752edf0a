"""``softplc check``: parse and validate an app, list every problem (exit 1),
then its verify warnings (exit 0 with warnings only); docs/language.md."""

from __future__ import annotations

import argparse
import sys

from ..app import AppError, load_app
from .common import EXIT_ERROR, EXIT_OK, print_warnings

NAME = "check"


def add_parser(sub) -> argparse.ArgumentParser:
    c = sub.add_parser(NAME, help="parse and validate an app; list every problem",
                       description="Parse and validate an app; list every problem (exit 1), then RSLogix-style "
                                   "verify warnings (exit 0 with warnings only). See docs/language.md.")
    c.add_argument("app", metavar="APP", help="app directory, .lad file, or Studio 5000 export (.L5X, .L5K)")
    c.set_defaults(func=run)
    return c


def run(args: argparse.Namespace) -> int:
    try:
        app = load_app(args.app, use_cache=False)  # check reads every text, whatever was cached
    except AppError as e:
        print(str(e), file=sys.stderr)
        count = len(e.errors) or 1
        print(f"{count} problem{'s' if count != 1 else ''} found", file=sys.stderr)
        return EXIT_ERROR
    print_warnings(app.warnings)
    # A Structured Text routine's file is made of rungs too; its statements are what a user wrote.
    rungs = sum(len(f.rungs) for f in app.program.files.values() if f.listing is None)
    statements = sum(len(f.listing.statements) for f in app.program.files.values() if f.listing is not None)
    extra = f", {statements} ST statement{'s' if statements != 1 else ''}" if statements else ""
    extra += "".join(f", module {m.name}" for m in app.modules)
    if app.warnings:
        extra += f", {len(app.warnings)} warning{'s' if len(app.warnings) != 1 else ''}"
    print(f"{app.name}: ok ({len(app.program.files)} program file{'s' if len(app.program.files) != 1 else ''}, "
          f"{rungs} rung{'s' if rungs != 1 else ''}{extra})")
    return EXIT_OK
