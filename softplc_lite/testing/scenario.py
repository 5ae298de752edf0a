"""Scenario files (``APP/tests/*.plctest``) -> typed steps with line and column.

Each line is parsed on its own with ``scenario.lark``; the block a step
belongs to (``setup:`` or ``scenario "name":``) is found by indentation.
Every mistake of a file is collected and raised together as
``ScenarioErrors``, each a ``LocatedError`` (file:line:col).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

from lark import Lark, Transformer, Token
from lark.exceptions import UnexpectedInput, VisitError

from ..errors import LocatedError

_GRAMMAR = (Path(__file__).with_name("scenario.lark")).read_text(encoding="utf-8")
_PARSER = Lark(_GRAMMAR, parser="lalr", maybe_placeholders=False)


@dataclass(frozen=True)
class Step:
    kind: str  # set force unforce scan run wait_until expect_cmp expect_within ...
    args: tuple
    line: int
    column: int
    at: tuple[int, ...] = field(default=(), compare=False)  # the column of each of args

    def column_of(self, k: int) -> int:
        """Where argument ``k`` starts (the step's column when not known)."""
        return self.at[k] if k < len(self.at) else self.column


class _At(NamedTuple):
    """A value of a step and the column it starts at (in the parsed line)."""

    value: object
    column: int


@dataclass
class Scenario:
    name: str
    line: int
    steps: list[Step] = field(default_factory=list)


@dataclass(frozen=True)
class DeviceLine:
    """``device PORT = KIND KEY=VALUE...``: a simulated device on a port of
    the app, for every scenario of the file (testing/devices.py)."""

    port: str
    kind: str
    options: tuple[tuple[str, str], ...]
    line: int
    column: int


class DeviceCounter(str):
    """A step's ``device PORT NAME``: a number of a simulated device's score
    (``device 0 bad``), read where an address is read; the text is the name."""

    port: str
    attribute: str

    def __new__(cls, port: str, attribute: str) -> "DeviceCounter":
        self = super().__new__(cls, f"device {port} {attribute}")
        self.port, self.attribute = port, attribute
        return self

    def __reduce__(self):  # pickles as what it is made from (a Failure that names one goes to other processes)
        return DeviceCounter, (self.port, self.attribute)


@dataclass
class ScenarioFile:
    path: str
    setup: list[Step]
    scenarios: list[Scenario]
    devices: list[DeviceLine] = field(default_factory=list)

    def all_steps(self) -> list[Step]:
        """The setup's steps, then every scenario's, in file order."""
        return self.setup + [s for sc in self.scenarios for s in sc.steps]


_KEYWORDS = {"set", "force", "unforce", "scan", "run", "wait", "expect", "scenario", "setup", "device"}


class ScenarioErrors(Exception):
    """Every problem of a scenario file, reported together."""

    def __init__(self, errors: list[LocatedError]) -> None:
        self.errors = errors
        super().__init__("\n".join(e.report() for e in errors))


class _ToSteps(Transformer):
    def __init__(self, line: int, column: int) -> None:
        super().__init__()
        self.line, self.column = line, column

    def target(self, c):
        t = c[0]
        return t if isinstance(t, _At) else _At(str(t), t.column)

    def number(self, c):
        text = str(c[0])
        return _At(float(text) if any(ch in text for ch in ".eE") else int(text), c[0].column)

    def value(self, c):
        v = c[0]
        if isinstance(v, Token) and v.type == "STRING":
            return _At(json.loads(str(v)), v.column)
        return v

    def _step(kind):  # noqa: N805 - a factory of rule actions
        def act(self, c):
            args, at = [], []
            for a in c:
                if isinstance(a, _At):
                    a, column = a
                else:
                    column = a.column
                    a = int(a) if a.type == "INT" else str(a)  # INT, or OP and UNIT
                args.append(a)
                at.append(self.column - 1 + column)  # the line was parsed without its indent
            return Step(kind, tuple(args), self.line, self.column, tuple(at))
        return act

    set = _step("set")
    force = _step("force")
    unforce = _step("unforce")
    scan = _step("scan")
    run = _step("run")
    wait_until = _step("wait_until")
    expect_cmp = _step("expect_cmp")
    expect_within = _step("expect_within")
    expect_between = _step("expect_between")
    expect_rising = _step("expect_rising")
    expect_falling = _step("expect_falling")

    def counter(self, c):
        return _At(DeviceCounter(str(c[0]), str(c[1])), c[0].column)  # located at its port

    def option(self, c):
        v = c[1]
        return (str(c[0]), json.loads(str(v)) if v.type == "STRING" else str(v))

    def device(self, c):
        return ("device", DeviceLine(str(c[0]), str(c[1]), tuple(c[2:]), self.line, self.column))

    def setup(self, c):
        return ("setup", None)

    def scenario(self, c):
        return ("scenario", json.loads(str(c[0])))


def _strip_comment(text: str) -> str:
    out, quoted, i = [], False, 0
    while i < len(text):
        ch = text[i]
        if ch == '"':
            quoted = not quoted
        elif not quoted and (ch == "#" or text.startswith("//", i)):
            break
        out.append(ch)
        i += 1
    return "".join(out).rstrip()


def parse_scenarios(text: str, path: str = "<scenario>") -> ScenarioFile:
    errors: list[LocatedError] = []
    setup: list[Step] = []
    scenarios: list[Scenario] = []
    devices: list[DeviceLine] = []
    block: list[Step] | None = None
    for number, raw in enumerate(text.splitlines(), 1):
        body = _strip_comment(raw)
        if not body.strip():
            continue
        indent = len(body) - len(body.lstrip())
        column = indent + 1
        try:
            item = _ToSteps(number, column).transform(_PARSER.parse(body.strip()))
        except UnexpectedInput as e:
            first = body.split()[0]
            known = first in _KEYWORDS or first.rstrip(":") == "setup"
            col = indent + getattr(e, "column", 1) if known else column
            errors.append(LocatedError(
                "expected a step (set, force, unforce, scan, run, wait until, expect), "
                "a block header (setup:, scenario \"name\":) or a device line (device PORT = KIND KEY=VALUE...)",
                path, number, col))
            continue
        except VisitError as e:
            errors.append(LocatedError(str(e.orig_exc), path, number, column))
            continue
        if isinstance(item, tuple):
            if indent:
                errors.append(LocatedError("expected a block header at the start of the line",
                                           path, number, column))
                continue
            if item[0] == "device":
                line: DeviceLine = item[1]
                if setup or scenarios or block is not None:
                    errors.append(LocatedError("expected device lines before setup: and the scenarios",
                                               path, number, column))
                elif any(d.port == line.port for d in devices):
                    errors.append(LocatedError(f"expected one device a port: port {line.port} has one already",
                                               path, number, column))
                else:
                    seen = [k for k, _ in line.options]
                    twice = sorted({k for k in seen if seen.count(k) > 1})
                    if twice:
                        errors.append(LocatedError(f"expected each option once: {', '.join(twice)} given twice",
                                                   path, number, column))
                    devices.append(line)
                continue
            if item[0] == "setup":
                if setup or scenarios:
                    errors.append(LocatedError("expected setup: before the scenarios, once",
                                               path, number, column))
                block = setup
            else:
                scenarios.append(Scenario(item[1], number))
                block = scenarios[-1].steps
            continue
        if block is None or not indent:
            errors.append(LocatedError("expected an indented step inside setup: or scenario \"name\":",
                                       path, number, column))
            continue
        block.append(item)
    if not scenarios and not errors:
        errors.append(LocatedError("expected at least one scenario \"name\": block", path, 1, 1))
    if errors:
        raise ScenarioErrors(errors)
    return ScenarioFile(path, setup, scenarios, devices)


def load_scenarios(path: str | Path) -> ScenarioFile:
    p = Path(path)
    return parse_scenarios(p.read_text(encoding="utf-8"), str(p))
