"""``softplc test``'s coverage options: measure while the scenarios run
(testing/coverage.py), then print the summary, write the reports asked
for (testing/coverage_report.py) and judge ``--fail-under``;
docs/testing.md "Coverage"."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rich.console import Console

from ..testing.coverage import Coverage
from ..testing.coverage_annotate import annotate
from ..testing.coverage_formats import cobertura, lcov
from ..testing.coverage_report import figures, print_summary
from .common import EXIT_ERROR, EXIT_USAGE

EXIT_UNDER = EXIT_USAGE  # --fail-under not met: 2, as coverage.py's --fail-under exits


def _percent(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a percentage 0..100, got {text!r}") from None
    if not 0 <= value <= 100:
        raise argparse.ArgumentTypeError(f"expected a percentage 0..100, got {text}")
    return value


def add_arguments(c: argparse.ArgumentParser) -> None:
    g = c.add_argument_group("coverage", "measure what the scenarios exercised (docs/testing.md, Coverage); "
                                         "each report option implies --coverage")
    g.add_argument("--coverage", action="store_true",
                   help="measure rung, leg, condition and output coverage and print a summary per program file")
    g.add_argument("--coverage-annotate", metavar="DIR",
                   help="write each .lad file annotated with what never happened, as DIR/NAME.lad.cover")
    g.add_argument("--coverage-xml", metavar="FILE", help="write a Cobertura XML report to FILE")
    g.add_argument("--coverage-lcov", metavar="FILE", help="write an LCOV tracefile to FILE")
    g.add_argument("--fail-under", type=_percent, metavar="PERCENT",
                   help="exit 2 when the total coverage is below PERCENT (the scenarios all passing)")


def wanted(args: argparse.Namespace) -> Coverage | None:
    """A Coverage to record into when any coverage option is given."""
    if args.coverage or args.fail_under is not None or args.coverage_annotate or args.coverage_xml \
            or args.coverage_lcov:
        return Coverage()
    return None


def report(args: argparse.Namespace, cov: Coverage, out: Console, code: int) -> int:
    """Print and write the reports; the exit code given ``code``, the
    scenarios' own (a failed scenario's 1 wins over --fail-under's 2)."""
    out.print()
    print_summary(cov, out)
    writes = [(args.coverage_annotate, lambda d: annotate(cov, d)),
              (args.coverage_xml, lambda f: Path(f).write_text(cobertura(cov), encoding="utf-8")),
              (args.coverage_lcov, lambda f: Path(f).write_text(lcov(cov), encoding="utf-8"))]
    for target, write in writes:
        if target:
            try:
                write(target)
            except OSError as e:
                print(f"{e.filename or target}: cannot write the coverage report: {e.strerror or e}",
                      file=sys.stderr)
                return EXIT_ERROR
    _, total = figures(cov)
    if args.fail_under is not None and total.below(args.fail_under):
        print(f"coverage {total.percent:.2f}% is below --fail-under {args.fail_under:g}%", file=sys.stderr)
        return code if code == EXIT_ERROR else EXIT_UNDER
    return code
