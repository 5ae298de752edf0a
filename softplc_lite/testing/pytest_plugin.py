"""pytest plugin: collects ``*.plctest`` files under an app's ``tests/``
directory, one item a scenario, and gives a ``plc`` fixture factory."""

from __future__ import annotations

from pathlib import Path

import pytest

from .plc import PLC
from .runner import run_scenario
from .scenario import ScenarioErrors, load_scenarios


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
        result = run_scenario(self.path.parent.parent, self.file, self.scenario)
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
