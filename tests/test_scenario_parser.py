"""The scenario file grammar: every step kind parsed with its place, and every
mistake of a file reported together, file:line:col."""

import pytest

from softplc_lite.testing.scenario import ScenarioErrors, load_scenarios, parse_scenarios

TEXT = '''# a comment
setup:
    set StopOk = 1   // another
scenario "seal in":
    set Start = 1
    force I:0/2 = 0
    unforce I:0/2
    scan 3
    run 2.5 s
    wait until Motor == 1 within 500 ms
    expect Motor == 1
    expect Motor != 0
    expect N7:0 within 0.5 of 3
    expect N7:0 between 1 and 5
    expect rising Motor
    expect falling B3/0
    set ST9:0 = "a # not a comment"
scenario "second":
    scan 1
'''


def test_every_step_kind_is_parsed_with_its_line_and_column():
    f = parse_scenarios(TEXT, "m.plctest")
    assert [(s.kind, s.args, s.line, s.column) for s in f.setup] == [("set", ("StopOk", 1), 3, 5)]
    assert [s.name for s in f.scenarios] == ["seal in", "second"]
    steps = [(s.kind, s.args, s.line) for s in f.scenarios[0].steps]
    assert steps == [
        ("set", ("Start", 1), 5),
        ("force", ("I:0/2", 0), 6),
        ("unforce", ("I:0/2",), 7),
        ("scan", (3,), 8),
        ("run", (2.5, "s"), 9),
        ("wait_until", ("Motor", "==", 1, 500, "ms"), 10),
        ("expect_cmp", ("Motor", "==", 1), 11),
        ("expect_cmp", ("Motor", "!=", 0), 12),
        ("expect_within", ("N7:0", 0.5, 3), 13),
        ("expect_between", ("N7:0", 1, 5), 14),
        ("expect_rising", ("Motor",), 15),
        ("expect_falling", ("B3/0",), 16),
        ("set", ("ST9:0", "a # not a comment"), 17),
    ]


def test_every_mistake_of_a_file_is_located_all_at_once():
    text = 'scenario "x":\n    sett A = 1\n    scan two\nscan 2\n  setup:\nsetup:\n'
    with pytest.raises(ScenarioErrors) as e:
        parse_scenarios(text, "b.plctest")
    where = [(x.path, x.line, x.column) for x in e.value.errors]
    assert where == [("b.plctest", 2, 5), ("b.plctest", 3, 10), ("b.plctest", 4, 1),
                     ("b.plctest", 5, 3), ("b.plctest", 6, 1)]
    assert str(e.value).splitlines()[0].startswith("b.plctest:2:5: expected a step")


def test_a_file_without_a_scenario_is_an_error(tmp_path):
    p = tmp_path / "empty.plctest"
    p.write_text("setup:\n    scan 1\n", encoding="utf-8")
    with pytest.raises(ScenarioErrors, match="empty.plctest:1:1: expected at least one scenario"):
        load_scenarios(p)
