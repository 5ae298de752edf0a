"""The trend a failure report draws (docs/testing.md, "The failure
report"): the failing address over the scans before the failure, as the
watch view's trend chart draws it.

Nothing is recorded while the scenarios pass: a failure runs its scenario
again on a fresh PLC (simulated time, the same steps: the same scans), this
time taking the address's value after every scan, and draws the last
``TREND_SCANS`` of them up to the failure (none when fewer than MIN_SCANS
scans came before it). A run that does not fail the
same way again (a scenario whose devices are not deterministic) draws
nothing rather than a different story.
"""

from __future__ import annotations

from collections import deque
from pathlib import Path

from ..datatable.address import ValueKind
from ..ladder.ast import Program
from ..trends.chart import Trace, TrendChart, XAxis
from .runner import Failure, check_names, run_steps
from .scenario import DeviceCounter, Scenario, ScenarioFile
from .scenario_devices import open_plc

TREND_SCANS = 200
MIN_SCANS = 10  # fewer scans before the failure draw no trend (a choice: the report's value says as much)
ANALOG_HEIGHT = 6  # lines of chart for a word or float (legend, four rows, axis)
BIT_HEIGHT = 3  # a bit: legend, its band, axis
_DRAWN = (ValueKind.BIT, ValueKind.WORD, ValueKind.LONG, ValueKind.FLOAT)


def failure_trend(app: str | Path, file: ScenarioFile, scenario: Scenario, failure: Failure,
                  program: Program | None = None, code_cache: tuple | None = None) -> TrendChart | None:
    name = failure.address
    if isinstance(name, DeviceCounter):
        return None
    samples: deque = deque(maxlen=TREND_SCANS)
    with open_plc(app, file, program=program, code_cache=code_cache) as plc:
        check_names(file, plc)
        kind = plc.address(name).kind
        if kind not in _DRAWN:
            return None
        scan = plc.engine.scan

        def scan_and_take() -> None:
            scan()
            samples.append((plc.scan_number, plc.time_ms, plc[name]))

        plc.engine.scan = scan_and_take
        samples.append((plc.scan_number, plc.time_ms, plc[name]))
        again = run_steps(plc, file, scenario)
    if again is None or (again.line, again.scan) != (failure.line, failure.scan) or len(samples) < MIN_SCANS:
        return None
    values = [v for _, _, v in samples]
    trace = Trace(str(name), values, kind is ValueKind.BIT, f"{failure.actual!r}", "red")
    x = XAxis(samples[0][0], samples[-1][0], samples[0][1], samples[-1][1])
    return TrendChart([trace], x, BIT_HEIGHT if kind is ValueKind.BIT else ANALOG_HEIGHT, marker=len(values) - 1)
