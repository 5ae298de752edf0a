"""Value kinds of a scenario file's steps, checked against the app's data
table before any scan, so that a step that cannot mean anything is a
located error rather than a failure (or a crash) in the middle of a run.

* ``set``, ``expect ==``/``!=`` and ``wait until``: the value must be one
  the address can hold, as the data table checks a write (a number in
  range for a word, a long or a float, 0 or 1 for a bit, text for an ST
  element; an A or D word also takes its text form in a ``set``, as the
  table does); an expected value the address cannot hold could never be
  met. The address must exist in the table (N7:99 past the end of N7 is
  an error here, not at the step that reaches it). A whole timer, counter
  or control element holds members: a step names one (``T4:0.ACC``,
  ``T4:0/DN``).
* ``force``, ``unforce`` and ``expect rising``/``falling``: a direct bit
  (``I:0/0``, ``B3/5``, ``N7:0/3``, ``T4:0/DN``); a force's value is 0 or 1.
* ``within`` and ``between`` (a softplc_lite choice): on numbers only. A
  string has no distance or order, and a bit is 0 or 1, which ``==`` says
  exactly. A tolerance is 0 or more, and the lower bound comes first.
"""

from __future__ import annotations

from ..datatable import DataTable, DataTableError
from ..datatable.address import Address, ValueKind
from ..datatable.snapshot import decode, encode
from ..errors import LocatedError
from ..ladder.symbols import SymbolError
from .scenario import DeviceCounter, ScenarioFile, Step

_STRUCTURES = (ValueKind.TIMER, ValueKind.COUNTER, ValueKind.CONTROL)
_BIT_STEPS = {"force": "force", "unforce": "unforce", "expect_rising": "expect rising",
              "expect_falling": "expect falling"}
_HOLDS = {ValueKind.BIT: "a bit (0 or 1)", ValueKind.WORD: "a 16-bit signed integer",
          ValueKind.FLOAT: "a float", ValueKind.LONG: "a 32-bit signed integer", ValueKind.STRING: "a string"}


def _holds(a: Address) -> str:
    if a.kind is ValueKind.LONG:  # an L, SI or LI element: its file's width
        return f"a {a.ftype.item_bits}-bit signed integer"
    return _HOLDS[a.kind]


def value_errors(file: ScenarioFile, plc) -> list[LocatedError]:
    """The value-kind problems of every step of ``file``, in file order,
    tried on a copy of ``plc``'s data table (the PLC's own is left as it
    is). A step whose name is unknown is left to the name check."""
    table = decode(encode(plc.table))
    errors = []
    for step in file.all_steps():
        if step.kind in ("scan", "run") or isinstance(step.args[0], DeviceCounter):
            continue  # a device's score is checked with the devices (devices.py)
        try:
            address = plc.address(step.args[0])
        except (DataTableError, SymbolError):  # an unknown name, which check_names reports
            continue
        problem = _problem(step, address, table)
        if problem:
            message, k = problem
            errors.append(LocatedError(message, file.path, step.line, step.column_of(k)))
    return errors


def _problem(step: Step, a: Address, table: DataTable) -> tuple[str, int] | None:
    """What is wrong with ``step`` (its name standing for ``a``), and the
    argument it is about (0 the name, then the values); None when nothing is."""
    k, name = step.kind, step.args[0]
    shown = name if name == str(a) else f"{name} ({a})"
    if k in _BIT_STEPS:
        if a.bit is None or not a.is_direct:
            return (f"expected a bit address after {_BIT_STEPS[k]} (I:0/0, B3/5, N7:0/3, T4:0/DN): "
                    f"{shown} is {_what(a)}"), 0
        if k == "force" and (isinstance(step.args[1], str) or step.args[1] not in (0, 1)):
            return f"expected 0 or 1 to force {shown} to, not {_value(step.args[1])}", 1
        return None if k in ("force", "unforce") else _exists(a, table)
    if a.kind in _STRUCTURES:
        example = f"{a}.POS, {a}/DN" if a.kind is ValueKind.CONTROL else f"{a}.ACC, {a}/DN"
        return f"expected a member or a bit of {shown}, a whole {a.kind.value} element (e.g. {example})", 0
    if k in ("expect_within", "expect_between"):
        if a.kind in (ValueKind.STRING, ValueKind.BIT):
            word = f'expect {name} == "text"' if a.kind is ValueKind.STRING else f"expect {name} == 1"
            return (f"expected a number address for {'within' if k == 'expect_within' else 'between'}: "
                    f"{shown} holds {_holds(a)}; use {word}"), 0
        if k == "expect_within" and step.args[1] < 0:
            return f"expected a tolerance of 0 or more, not {_value(step.args[1])}", 1
        if k == "expect_between" and step.args[1] > step.args[2]:
            return (f"expected the lower bound first: between {_value(step.args[1])} and "
                    f"{_value(step.args[2])} holds nothing"), 1
        return _exists(a, table)
    at = 1 if k == "set" else 2  # set NAME = V; expect/wait NAME OP V
    value = step.args[at]
    if k != "set" and isinstance(value, str) and a.kind is not ValueKind.STRING:
        return f"expected a number to compare {shown} with: it holds {_holds(a)}, not a string", at
    if not a.is_direct:
        return None  # where it points is known only at run time
    missing = _exists(a, table)
    if missing:
        return missing
    try:
        table.write(a, value)
    except DataTableError as e:  # the table says why (range, kind)
        return f"expected a value {shown} can hold: {e}", at
    return None


def _exists(a: Address, table: DataTable) -> tuple[str, int] | None:
    if not a.is_direct:
        return None
    try:
        table.resolve(a)
    except DataTableError as e:  # past the end of its file, or no such file
        return f"expected an address of the data table: {e}", 0
    return None


def _what(a: Address) -> str:
    if a.kind in _STRUCTURES:
        return f"a whole {a.kind.value} element"
    if not a.is_direct:
        return "an indirect or indexed address"
    return {ValueKind.WORD: "a whole word", ValueKind.FLOAT: "a float", ValueKind.LONG: "a whole long",
            ValueKind.STRING: "a string"}.get(a.kind, "not a bit")


def _value(v) -> str:
    return f'"{v}"' if isinstance(v, str) else repr(v)
