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
from ..testing.mutation import DEFAULT_BUDGET_S
from ..testing.mutation_report import OK, UNDER, mutate_and_report
from ..testing.runner import SCENARIO_GLOB, run_file, scenario_files, scenario_glob
from ..testing.scenario import ScenarioErrors
from . import test_coverage
from .common import EXIT_ERROR, EXIT_OK, EXIT_USAGE

NAME = "test"
EXIT_UNDER_MUTATION = EXIT_USAGE  # --fail-under-mutation not met: 2, as --fail-under for coverage


def add_parser(sub) -> argparse.ArgumentParser:
    c = sub.add_parser(NAME, help="run an app's scenario files",
                       description=f"Run the scenario files of an app ({SCENARIO_GLOB}): exit 0 when every "
                                   "scenario passes, 1 when one fails or a file has problems. See docs/testing.md.")
    c.add_argument("app", metavar="APP", help="app directory, or a Studio 5000 export (.L5X, .L5K) whose "
                                               "scenario files are beside it in NAME.tests/")
    test_coverage.add_arguments(c)
    m = c.add_argument_group("mutation testing (docs/testing.md, \"Mutation testing\")")
    m.add_argument("--mutate", action="store_true",
                   help="then run the scenarios against small faults of the program and report those not caught")
    m.add_argument("--jobs", type=_positive_int, default=None, metavar="N",
                   help="worker processes for the mutants (default: the CPU count)")
    m.add_argument("--mutate-timeout", type=_positive_float, default=None, metavar="SECONDS",
                   help="total time for the mutants; those left are reported as not run "
                        f"(default {DEFAULT_BUDGET_S:g})")
    m.add_argument("--fail-under-mutation", type=float, default=None, metavar="PERCENT",
                   help="exit 2 when the mutation score is under PERCENT")
    c.set_defaults(func=run)
    return c


def run(args: argparse.Namespace) -> int:
    out = Console(highlight=False, soft_wrap=True)
    alone = [flag for flag, value in (("--jobs", args.jobs), ("--mutate-timeout", args.mutate_timeout),
                                      ("--fail-under-mutation", args.fail_under_mutation)) if value is not None]
    if alone and not args.mutate:
        print(f"softplc test: {', '.join(alone)} {'applies' if len(alone) == 1 else 'apply'} to mutation "
              "testing: add --mutate", file=sys.stderr)
        return EXIT_USAGE
    files = scenario_files(args.app)
    if not files:
        print(f"{shown_path(args.app)}: no scenario files ({scenario_glob(args.app)})", file=sys.stderr)
        return EXIT_ERROR
    passed = failed = 0
    cov = test_coverage.wanted(args)
    for path in files:
        try:
            results = run_file(args.app, path, coverage=cov, trend=True)
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
    code = EXIT_ERROR if failed else EXIT_OK
    if cov is not None:
        code = test_coverage.report(args, cov, out, code)
    if code != EXIT_OK:
        return code
    if args.mutate:
        budget = DEFAULT_BUDGET_S if args.mutate_timeout is None else args.mutate_timeout
        verdict = mutate_and_report(args.app, out, sys.stderr, args.jobs, budget, args.fail_under_mutation)
        return {OK: EXIT_OK, UNDER: EXIT_UNDER_MUTATION}.get(verdict, EXIT_ERROR)
    return EXIT_OK


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number of 1 or more, got {text!r}")
    return value


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a number of seconds above 0, got {text!r}")
    return value
