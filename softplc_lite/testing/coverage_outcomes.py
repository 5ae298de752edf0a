"""Every counted outcome of a Coverage, one list a rung, in the order the
file-format reporters number them (testing/coverage_formats.py) and the
annotated listing marks them (testing/coverage_annotate.py)."""

from __future__ import annotations

from dataclasses import dataclass

from .coverage import Coverage, ElementInfo, RungInfo


@dataclass(frozen=True)
class Outcome:
    block: int  # 0 the rung itself, else 1 + the element's index in the rung
    branch: int  # which outcome of that block
    what: str  # e.g. "rung true", "XIC leg 2 powered", "XIC seen false"
    missing: str  # what the annotated listing says when it never happened, e.g. "never true"
    count: int  # scans it happened in
    element: ElementInfo | None  # None: the rung itself
    leg: int | None = None  # a leg outcome: which leg

    @property
    def covered(self) -> bool:
        return self.count > 0


def rung_outcomes(cov: Coverage, rung: RungInfo) -> list[Outcome]:
    f, r = rung.key
    t, fl = cov.rungs.get(rung.key, (0, 0))
    found = [Outcome(0, 0, "rung true", "rung never true", t, None)]
    if rung.false_possible:  # an outcome that cannot happen is not counted (coverage.py, _may_end_off)
        found.append(Outcome(0, 1, "rung false", "rung never false", fl, None))
    for el in rung.elements:
        block = el.index + 1
        if el.kind == "branch":
            for k in range(el.legs):
                n = cov.legs.get((f, r, el.index, k), (0, 0))[0]
                found.append(Outcome(block, k, f"leg {k + 1} powered", "leg never powered", n, el, k))
            continue
        counts = cov.instructions.get((f, r, el.index), (0, 0, 0, 0))
        if el.kind == "condition":
            found.append(Outcome(block, 0, f"{el.text} seen true", "never true", counts[2], el))
            found.append(Outcome(block, 1, f"{el.text} seen false", "never false", counts[3], el))
        else:
            found.append(Outcome(block, 0, f"{el.text} on", "never on", counts[0], el))
            if el.off_possible:
                found.append(Outcome(block, 1, f"{el.text} off", "never off", counts[1], el))
    return found
