"""Value kinds of scenario steps, checked before any scan
(softplc_lite/testing/values.py): each problem located, all at once,
together with unknown names."""

from pathlib import Path

import pytest

from softplc_lite.testing.runner import run_file
from softplc_lite.testing.scenario import ScenarioErrors

ROOT = Path(__file__).resolve().parent.parent
MOTOR = ROOT / "programs" / "motor"
STRINGS = ROOT / "programs" / "strings"  # Reading ST9:0, Weight F8:0, TicketNo N7:0, R6:0


def _errors(tmp_path, app, steps: list[str]) -> list:
    f = tmp_path / "v.plctest"
    f.write_text('scenario "s":\n' + "".join(f"    {s}\n" for s in steps), encoding="utf-8")
    with pytest.raises(ScenarioErrors) as e:
        run_file(app, f)
    return e.value.errors


@pytest.mark.parametrize("app, at, step, want", [
    (STRINGS, '"12"', 'set TicketNo = "12"',
     "expected a value TicketNo (N7:0) can hold: N7:0 holds a 16-bit signed integer"),
    (STRINGS, '"1.5"', 'expect Weight == "1.5"',
     "expected a number to compare Weight (F8:0) with: it holds a float, not a string"),
    (STRINGS, '"x"', 'wait until TicketNo != "x" within 1 s', "expected a number to compare TicketNo (N7:0) with"),
    (STRINGS, '5', "set Reading = 5", "expected a value Reading (ST9:0) can hold: ST9:0 holds a string (text), got 5"),
    (STRINGS, '0', "expect Reading == 0", "ST9:0 holds a string (text), got 0"),
    (MOTOR, 'T4:0.ACC', "force T4:0.ACC = 1", "expected a bit address after force (I:0/0, B3/5, N7:0/3, T4:0/DN): "
                                  "T4:0.ACC is a whole word"),
    (MOTOR, 'N7:0', "force N7:0 = 1", "N7:0 is a whole word"),
    (MOTOR, 'T4:0', "unforce T4:0", "expected a bit address after unforce (I:0/0, B3/5, N7:0/3, T4:0/DN): "
                            "T4:0 is a whole timer element"),
    (MOTOR, 'C5:0.ACC', "expect rising C5:0.ACC", "expected a bit address after expect rising"),
    (MOTOR, 'N7:0', "expect falling N7:0", "expected a bit address after expect falling"),
    (MOTOR, '2', "force Start = 2", "expected 0 or 1 to force Start (I:0/0) to, not 2"),
    (MOTOR, 'Motor', "expect Motor within 1 of 0", "expected a number address for within: Motor (O:0/0) holds a bit "
                                          "(0 or 1); use expect Motor == 1"),
    (MOTOR, 'B3/0', "expect B3/0 between 0 and 1", "expected a number address for between: B3/0 holds a bit"),
    (STRINGS, 'Reading', "expect Reading between 1 and 2", 'holds a string; use expect Reading == "text"'),
    (MOTOR, '-1', "expect T4:0.ACC within -1 of 3", "expected a tolerance of 0 or more, not -1"),
    (MOTOR, '5', "expect T4:0.ACC between 5 and 1", "expected the lower bound first"),
    (MOTOR, '70000', "set N7:0 = 70000", "70000 does not fit N7:0, which holds a 16-bit signed integer (-32768..32767)"),
    (MOTOR, '1.5', "expect N7:0 == 1.5", "N7:0 holds a 16-bit signed integer (-32768..32767), got 1.5"),
    (MOTOR, '2', "set Motor = 2", "expected a value Motor (O:0/0) can hold: 2 does not fit O:0/0, which holds a bit"),
    (MOTOR, '-1', "wait until B3/0 == -1 within 1 s", "-1 does not fit B3/0"),
    (STRINGS, '1e40', "expect Weight == 1e40", "does not fit F8:0, which holds a float32"),
    (STRINGS, '"x', f'set Reading = "{"x" * 83}"', "a 83-character string does not fit ST9:0"),
    (MOTOR, 'T4:0', "expect T4:0 == 1", "expected a member or a bit of T4:0, a whole timer element (e.g. T4:0.ACC, T4:0/DN)"),
    (MOTOR, 'N7:99', "set N7:99 = 1", "expected an address of the data table: N7:99: element 99 is past the end of N7"),
    (MOTOR, 'B3/99', "expect rising B3/99", "expected an address of the data table: B3/99"),
])
def test_each_kind_problem_is_located_with_what_was_expected(tmp_path, app, at, step, want):
    """``at``: the text of the step the column points at (the name or the value at fault)."""
    [e] = _errors(tmp_path, app, ["scan 1", step])
    assert (e.line, e.column) == (3, 5 + step.index(at))
    assert want in e.message, e.message


def test_all_problems_at_once_with_unknown_names_in_file_order(tmp_path):
    f = tmp_path / "m.plctest"
    f.write_text('setup:\n  set N7:0 = "x"\nscenario "a":\n    expect Nope == 1\n    force N7:0 = 1\n'
                 'scenario "b":\n      expect Motor between 0 and 1\n    set Q9:0 = 1\n    set Motor = 5\n',
                 encoding="utf-8")
    with pytest.raises(ScenarioErrors) as e:
        run_file(MOTOR, f)
    assert [(x.line, x.column) for x in e.value.errors] == [(2, 14), (4, 12), (5, 11), (7, 14), (8, 9), (9, 17)]
    assert str(e.value).splitlines()[0].startswith(f"{f}:2:14: expected a value N7:0 can hold")


def test_the_checks_come_before_any_scan(tmp_path):
    # the bad step is the last one, after a long run: nothing ran when it is reported
    [e] = _errors(tmp_path, MOTOR, ["run 100000 s", "set N7:0 = 70000"])
    assert e.line == 3


def test_values_of_the_right_kind_pass(tmp_path):
    f = tmp_path / "ok.plctest"
    f.write_text('scenario "kinds":\n'
                 '    set Reading = "WT: 12.5 kg #7"\n    set Weight = 2\n    set TicketNo = -32768\n'
                 '    set NewReading = 1\n    force B3/1 = 0\n    scan 2\n    unforce B3/1\n'
                 '    expect Weight within 0.01 of 12.5\n    expect TicketNo between 7 and 7\n'
                 '    expect R6:0.POS == 2\n    expect R6:0/DN == 1\n    expect rising R6:0/DN\n'
                 '    wait until Ticket != "" within 1 s\n    expect Reading == "WT: 12.5 kg #7"\n',
                 encoding="utf-8")
    [r] = run_file(STRINGS, f)
    assert r.passed, r.failure and r.failure.report()
