"""Which rungs of a Structured Text routine ran in the last scan, for the
watch view's marks (st_view.py; docs/watch.md, "Watching Structured Text").

An ST routine runs as ladder rungs (logix/st_routine.py): an IF's arm that
is not taken is rungs a JMP skips, a loop's body rungs the engine runs again
after a backward JMP. So "this line ran" is "a rung made from it was
called". The watch session splits each ST file's compiled code into a block
a rung (ladder/blocks.py ``split_rungs``; the reference executor has one
already) and wraps each block in a function that writes the number of the
scan it runs in; a rung ran in the last scan when that number is the last
scan's. Both executors call the same blocks in the same order, so they give
the same marks.

Only a watch session does this, and only to the files made from ST: a run
without the view (``softplc run``, the test runner) scans the compiler's
own blocks, untouched. In the view it costs a call a rung (the block call
the split adds, and the wrapper's) of the ST files only.
"""

from __future__ import annotations


class RanRungs:
    """For each program file with a listing (an ST routine's), the scan each
    rung last ran in: ``ran[file][rung]``, -1 before its first run."""

    def __init__(self, engine) -> None:
        self.engine = engine
        self.ran: dict[int, list[int | None]] = {}
        self.install()

    def install(self) -> None:
        """Wrap the blocks of every ST file of the engine's program (again
        after an online edit put a new program, and so new blocks, in place).
        Called before the breakpoints are set on the new blocks, so a
        breakpoint wraps this wrapper and clearing it puts this one back."""
        engine = self.engine
        self.ran = {}
        for number, pfile in engine.program.files.items():
            if pfile.listing is None or number not in engine.files:
                continue
            compiled = engine.files[number][0]
            compiled.split_rungs()
            ran = self.ran[number] = [None] * len(pfile.rungs)
            blocks = compiled.blocks
            for rung in range(len(blocks)):
                blocks[rung] = _recording(blocks[rung], ran, rung, engine)

    def last_scan(self, number: int) -> set[int] | None:
        """The rungs of file ``number`` that ran in the newest scan; None for a
        file that is not recorded (not ST)."""
        ran = self.ran.get(number)
        if ran is None:
            return None
        scan = self.engine.scans - 1  # the newest scan ran while engine.scans held this
        return {rung for rung, when in enumerate(ran) if when == scan}


def _recording(block, ran: list[int | None], rung: int, engine):
    def recorded(c):
        ran[rung] = engine.scans
        return block(c)
    return recorded
