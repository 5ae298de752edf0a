"""pytest plugin: collects ``*.plctest`` files under an app's ``tests/``
directory, one item a scenario, and gives a ``plc`` fixture factory.
``--plc-coverage`` measures the scenarios' coverage, an app at a time, and
prints each app's summary at the end (``--plc-coverage-xml FILE``,
``--plc-coverage-lcov FILE``: one report of every app); docs/testing.md."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from rich.console import Console

from .coverage import Coverage
from .coverage_formats import cobertura, lcov
from .coverage_report import print_summary
from .plc import PLC
from .runner import run_scenario
from .scenario import ScenarioErrors, load_scenarios


_COVERAGE = pytest.StashKey[dict]()  # app directory -> its Coverage, when --plc-coverage is on
_XDIST = pytest.StashKey[bool]()


def pytest_addoption(parser) -> None:
    g = parser.getgroup("softplc", "ladder scenarios (softplc_lite)")
    g.addoption("--plc-coverage", action="store_true",
                help="measure the scenarios' ladder coverage and print a summary per app")
    g.addoption("--plc-coverage-xml", metavar="FILE", help="write the ladder coverage as Cobertura XML to FILE")
    g.addoption("--plc-coverage-lcov", metavar="FILE", help="write the ladder coverage as an LCOV tracefile to FILE")


def pytest_configure(config) -> None:
    o = config.option
    if getattr(o, "plc_coverage", False) or getattr(o, "plc_coverage_xml", None) \
            or getattr(o, "plc_coverage_lcov", None):
        config.stash[_COVERAGE] = {}
        if getattr(o, "numprocesses", None) and not hasattr(config, "workerinput"):
            config.stash[_XDIST] = True  # each worker would measure its own share, and none reports it


def _coverage(config, app: Path) -> Coverage | None:
    apps = config.stash.get(_COVERAGE, None)
    if apps is None:
        return None
    return apps.setdefault(str(app), Coverage())


def pytest_terminal_summary(terminalreporter, exitstatus, config) -> None:
    if config.stash.get(_XDIST, False):
        terminalreporter.write_line("ladder coverage is not measured across pytest-xdist workers: "
                                    "run the scenarios without -n")
        return
    apps = config.stash.get(_COVERAGE, None)
    if not apps:
        return
    for app, cov in sorted(apps.items()):
        terminalreporter.write_sep("-", f"ladder coverage: {app}")
        text = io.StringIO()
        print_summary(cov, Console(file=text, width=_width(config), highlight=False, color_system=None))
        terminalreporter.write(text.getvalue())
    for path, write in ((config.option.plc_coverage_xml, cobertura), (config.option.plc_coverage_lcov, lcov)):
        if path:
            Path(path).write_text(write(*apps.values()), encoding="utf-8")
            terminalreporter.write_line(f"ladder coverage written to {path}")


def pytest_collect_file(parent, file_path: Path):
    if file_path.suffix == ".plctest" and file_path.parent.name == "tests":
        return ScenarioFileNode.from_parent(parent, path=file_path)
    return None


class ScenarioFileNode(pytest.File):
    def collect(self):
        try:
            scenarios = load_scenarios(self.path)
        except ScenarioErrors as e:
            raise self.CollectError(str(e)) from None
        for sc in scenarios.scenarios:
            yield ScenarioItem.from_parent(self, name=sc.name, file=scenarios, scenario=sc)


class ScenarioItem(pytest.Item):
    def __init__(self, *, file, scenario, **kw) -> None:
        super().__init__(**kw)
        self.file, self.scenario = file, scenario

    def runtest(self) -> None:
        app = self.path.parent.parent
        result = run_scenario(app, self.file, self.scenario, coverage=_coverage(self.config, app), trend=True)
        if result.failure is not None:
            raise ScenarioFailed(result.failure)

    def repr_failure(self, excinfo):
        """The failure and the rungs that write its address, as plain text
        (the terminal report and --junitxml show the same)."""
        if isinstance(excinfo.value, ScenarioFailed):
            return excinfo.value.failure.text(_width(self.config))
        if isinstance(excinfo.value, ScenarioErrors):
            return str(excinfo.value)
        return super().repr_failure(excinfo)

    def reportinfo(self):
        return self.path, self.scenario.line - 1, f"scenario {self.scenario.name}"


class ScenarioFailed(Exception):
    def __init__(self, failure) -> None:
        super().__init__(failure.report())
        self.failure = failure


def _width(config) -> int:
    """The terminal's width as pytest sees it (80 when not on a terminal)."""
    try:
        return max(config.get_terminal_writer().fullwidth, 40)
    except (AssertionError, AttributeError):  # no terminal reporter: pytest's own default width
        return 80


@pytest.fixture
def plc():
    """``plc(APP)``: a fresh ``PLC`` on APP, closed after the test."""
    opened = []

    def load(app, **kw) -> PLC:
        opened.append(PLC.load(app, **kw))
        return opened[-1]
    yield load
    for p in opened:
        p.close()
