"""The bracket filter of ladder/limits.py (nesting_within) against the exact
scan it spares: it may only clear a text the exact scan would clear, and
it clears every ordinary text, so the exact scan runs only on hostile ones."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from softplc_lite.ladder import limits
from softplc_lite.ladder.limits import nesting_within


def deepest(text: str) -> int:
    """The deepest nesting the exact scan sees: parentheses and brackets
    outside strings and comments, an unmatched close ignored."""
    depth = deepest = 0
    for m in limits._NESTING_SCAN.finditer(text):
        first = m.group()[0]
        if first in "([":
            depth += 1
            deepest = max(deepest, depth)
        elif first in ")]":
            depth = max(0, depth - 1)
    return deepest


pieces = st.sampled_from(["(", ")", "[", "]", '"', "//", "\n", "A", " ", "\\", "N7:1"])
texts = st.lists(pieces, max_size=60).map("".join)


@settings(max_examples=400)
@given(texts, st.integers(0, 8))
def test_the_filter_clears_a_text_only_within_the_limit(text, limit):
    if nesting_within(text, limit):
        assert deepest(text) <= limit


@settings(max_examples=400)
@given(st.lists(st.sampled_from(["(", ")", "[", "]", "A", " "]), max_size=60).map("".join), st.integers(0, 8))
def test_the_filter_clears_every_shallow_text_without_strings(text, limit):
    # for a text whose every "(" is closed, the filter's bound is exact
    if deepest(text) <= limit and "(" * (limit + 1) not in text.translate(limits._ONE_KIND):
        opened = text.translate(limits._ONE_KIND)
        stack = 0
        for ch in opened:
            if ch == "(":
                stack += 1
            elif ch == ")" and stack:
                stack -= 1
        if stack == 0:
            assert nesting_within(text, limit)


def test_a_ten_megabyte_rung_of_ordinary_brackets_is_cleared_without_the_exact_scan():
    text = "XIC(B3/0)" + "OTE(B3/1)" * 1_000_000 + ";\n"
    assert nesting_within(text)
    assert limits.nesting_problem(text) is None


def test_deep_nesting_is_left_to_the_exact_scan_which_locates_it():
    text = "CPT(N7:0," + "(" * 6000 + "N7:1" + ")" * 6000 + ");\n"
    assert not nesting_within(text)
    assert limits.nesting_problem(text) == (9 + limits.MAX_NESTING - 1,
                                            f"parentheses and brackets nested more than {limits.MAX_NESTING:,} deep")
