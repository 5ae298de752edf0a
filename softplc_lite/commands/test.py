"""``softplc test``: run an app's scenario files (APP/tests/*.plctest),
one line a scenario (a failure with the rungs that write its address), then
the totals; docs/testing.md."""

from __future__ import annotations

import argparse
import sys

from rich.console import Console
from rich.markup import escape

from ..app import AppError
from ..errors import shown_path
from ..testing.runner import SCENARIO_GLOB, run_file, scenario_files
from ..testing.scenario import ScenarioErrors
from .common import EXIT_ERROR, EXIT_OK

NAME = "test"


def add_parser(sub) -> argparse.ArgumentParser:
    c = sub.add_parser(NAME, help="run an app's scenario files",
                       description=f"Run the scenario files of an app ({SCENARIO_GLOB}): exit 0 when every "
                                   "scenario passes, 1 when one fails or a file has problems. See docs/testing.md.")
    c.add_argument("app", metavar="APP", help="app directory")
    c.set_defaults(func=run)
    return c


def run(args: argparse.Namespace) -> int:
    out = Console(highlight=False, soft_wrap=True)
    files = scenario_files(args.app)
    if not files:
        print(f"{shown_path(args.app)}: no scenario files ({SCENARIO_GLOB})", file=sys.stderr)
        return EXIT_ERROR
    passed = failed = 0
    for path in files:
        try:
            results = run_file(args.app, path)
        except (ScenarioErrors, AppError) as e:
            print(str(e), file=sys.stderr)
            return EXIT_ERROR
        for r in results:
            if r.passed:
                passed += 1
                out.print(f"[green]PASS[/] {escape(shown_path(path))}: {escape(r.name)}")
            else:
                failed += 1
                out.print(f"[red]FAIL[/] {escape(shown_path(path))}: {escape(r.name)}")
                out.print(r.failure)
    summary = f"{passed} passed, {failed} failed"
    out.print(f"[red]{summary}[/]" if failed else f"[green]{summary}[/]")
    return EXIT_ERROR if failed else EXIT_OK
