"""The collector pause around load stages (softplc_lite/gcpause.py)."""

from __future__ import annotations

import gc
import weakref

from softplc_lite import gcpause
from softplc_lite.gcpause import paused_gc


class _Node:
    pass


def test_pause_turns_the_collector_back_on_and_nests():
    assert gc.isenabled()
    with paused_gc():
        assert not gc.isenabled()
        with paused_gc():
            assert not gc.isenabled()
        assert not gc.isenabled()  # the inner stage leaves it paused
    assert gc.isenabled()


def test_a_large_load_is_moved_to_the_oldest_generation_unscanned_and_nothing_stays_frozen():
    with paused_gc():
        kept = [[k] for k in range(gcpause.LARGE_LOAD_OBJECTS + 10_000)]
        a, b = _Node(), _Node()
        a.other, b.other = b, a  # a cycle made during the load
        watch = weakref.ref(a)
        del a, b
    assert gc.isenabled()
    assert gc.get_freeze_count() == 0
    assert gc.get_count()[0] < 1_000  # no young generation of a million objects left to walk
    assert watch() is not None  # not collected by a young collection...
    gc.collect()
    assert watch() is None  # ...but by the next full one
    assert len(kept) > gcpause.LARGE_LOAD_OBJECTS


def test_a_small_load_is_left_to_the_collector():
    gc.collect()
    with paused_gc():
        kept = [[k] for k in range(100)]
    assert gc.get_count()[0] >= 100  # still young: nothing moved
    assert len(kept) == 100
