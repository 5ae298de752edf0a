"""Pause the cyclic garbage collector while a program loads.

Parsing, validating and compiling a large program allocates millions of
small objects that all live on (tokens, AST nodes, code objects). Each
allocation burst triggers collections that walk every object alive, so on a
10,000-rung program the collector took about 40% of the load time and freed
nothing. Load stages run with it paused; a stage nested in another leaves
it paused, and the outermost one turns it back on.

The collector is one per process, so the pause is too: it holds while any
thread is inside a load stage (a count under a lock), and the last stage to
end restores the state the first one found (a collector the embedding
program had turned off stays off).

Turning it back on is not free either: the next allocation would start a
collection of the youngest generation, which then holds every object the
load made (about 0.1 s of a 10,000-rung load, to free nothing again). So
when a pause ends after a large load, its objects are first moved to the
oldest generation unscanned (``gc.freeze()`` then ``gc.unfreeze()``: two
list splices in CPython, nothing stays frozen). A cycle among them is
still collected, by the next full collection instead of the next young
one (softplc choice; small loads, such as most tests make, are left to
the collector).

``gc.unfreeze()`` releases every frozen object, not only the ones just
frozen; so when the process already holds frozen objects (an embedding
program called ``gc.freeze()``, e.g. before forking workers), the move is
skipped and its frozen set is left exactly as it was: the load's objects
are then left to the collector (slower, never a change to the embedder's
memory).
"""

from __future__ import annotations

import functools
import gc
import threading
from contextlib import contextmanager
from typing import Callable, Iterator, TypeVar

F = TypeVar("F", bound=Callable)

# Objects allocated (net) during a pause above which they are moved to the
# oldest generation when it ends: about what a 300-rung program makes.
LARGE_LOAD_OBJECTS = 50_000

_lock = threading.Lock()
_active = 0  # load stages running now, in every thread
_was_enabled = False  # the collector's state when the first of them began


@contextmanager
def paused_gc() -> Iterator[None]:
    global _active, _was_enabled
    with _lock:
        if _active == 0:
            _was_enabled = gc.isenabled()
            gc.disable()
        _active += 1
    try:
        yield
    finally:
        with _lock:
            _active -= 1
            if _active == 0 and _was_enabled:
                if gc.get_count()[0] > LARGE_LOAD_OBJECTS and gc.get_freeze_count() == 0:
                    gc.freeze()
                    gc.unfreeze()
                gc.enable()


def gc_paused(func: F) -> F:
    """Decorator: run ``func`` with the collector paused."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with paused_gc():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
