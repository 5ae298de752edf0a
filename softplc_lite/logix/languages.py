"""A routine of either language the engine runs, as ladder rungs: RLL
rung by rung (rungs.py), Structured Text statement by statement
(st_routine.py). The export's routines and Add-On Instructions' routines
both come through here."""

from __future__ import annotations

from ..ladder.ast import Instruction, Listing, Rung
from .rungs import translate_rung
from .st_routine import translate_st

LANGUAGES = ("RLL", "ST")


def routine_rungs(routine, ctx, rung_counts=None, statement_counts=None) -> tuple[list[Rung], Listing | None]:
    """The ladder rungs of an RLL or ST routine (its Listing for ST), its
    problems and warnings in ``ctx``; counted into the dicts given."""
    if routine.kind == "ST":
        rungs, listing, counts = translate_st(routine, ctx)
        if statement_counts is not None:
            for key, n in counts.items():
                statement_counts[key] += n
        return rungs, listing
    rungs = []
    for rung in routine.rungs:
        translated = translate_rung(rung, ctx)
        if rung_counts is not None:
            rung_counts["total"] += 1
        if translated is None:  # its problems are errors: the program does not run
            translated = Rung([Instruction("NOP", [], rung.pos)], rung.comment, rung.pos)
            key = "errors"
        else:
            key = "not run" if ctx.skip else "run"
        if rung_counts is not None:
            rung_counts[key] += 1
        rungs.append(translated)
    return rungs, None

