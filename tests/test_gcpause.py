"""The collector pause around load stages (softplc_lite/gcpause.py)."""

from __future__ import annotations

import gc
import weakref

import pytest

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


@pytest.fixture
def nothing_frozen():
    """A process with no frozen objects (conftest.py freezes the collected
    tests); frozen again afterwards, as conftest.py leaves it."""
    gc.unfreeze()
    yield
    gc.collect()
    gc.freeze()


def test_a_large_load_is_moved_to_the_oldest_generation_unscanned_and_nothing_stays_frozen(nothing_frozen):
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


def test_a_large_load_leaves_the_frozen_objects_of_the_process_frozen():
    """An embedding program that froze objects (before forking workers)
    finds exactly those still frozen after a large load."""
    embedders = [["an object the embedding program froze"]]
    gc.collect()
    gc.freeze()

    def still_frozen() -> bool:  # the collector lists every tracked object except the frozen ones
        return not any(o is embedders for o in gc.get_objects())

    try:
        assert still_frozen() and gc.get_freeze_count() > 0
        with paused_gc():
            kept = [[k] for k in range(gcpause.LARGE_LOAD_OBJECTS + 10_000)]
        assert gc.isenabled()
        # not the count: a frozen object freed meanwhile (another thread's) leaves the frozen set
        assert still_frozen()
        assert len(kept) > gcpause.LARGE_LOAD_OBJECTS
    finally:
        gc.unfreeze()


def test_the_pause_holds_while_any_thread_loads_and_the_last_restores_it():
    import threading

    steps = [threading.Event() for _ in range(3)]
    seen: list[bool] = []

    def second_load() -> None:
        with paused_gc():
            steps[0].set()  # inside, while the first load is too
            steps[1].wait(10)
            seen.append(gc.isenabled())  # the first load has ended: still paused for this one
        steps[2].set()

    assert gc.isenabled()
    worker = threading.Thread(target=second_load, daemon=True)
    with paused_gc():
        worker.start()
        assert steps[0].wait(10)
    steps[1].set()
    assert steps[2].wait(10)
    worker.join(10)
    assert seen == [False]
    assert gc.isenabled()


def test_a_collector_turned_off_by_the_program_stays_off_after_concurrent_loads():
    import threading

    gc.disable()
    try:
        threads = [threading.Thread(target=_load_briefly) for _ in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(10)
        assert not gc.isenabled()
    finally:
        gc.enable()


def _load_briefly() -> None:
    for _ in range(200):
        with paused_gc():
            with paused_gc():
                pass
