"""Coverage in the files CI tools read: Cobertura XML and LCOV tracefiles,
a rung as a line (its source line in its .lad file; hits: the scans it
ran in) and each counted outcome of the rung (ended true, ended false, a
leg powered, a condition seen true or false, an output on or off) as a
branch of that line (testing/coverage_outcomes.py numbers them).

Cobertura: the coverage-04 DTD's elements and attributes, one <class> a
program file (several may share a .lad file), its lines the file's rungs;
<source> the directory the .lad files are in, each class's filename
relative to it. LCOV: one record (SF ... end_of_record) a .lad file, a
program file as a function (FN at its first rung's line, FNDA the scans of
its first rung), DA a rung, BRDA an outcome ("-" when its rung never ran),
and the FNF/FNH, LF/LH, BRF/BRH totals (the geninfo(1) format).

A program file made from Structured Text has for lines the lines of the
export where a statement starts or an arm is tested (hits: the scans of
the first rung there), and for branches its arms, each at its own line
(testing/coverage_st.py); the text report counts its statements, these
count lines, as coverage.py's XML does for Python."""

from __future__ import annotations

import os
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from .. import __version__
from .coverage import Coverage, FileInfo
from . import coverage_st
from .coverage_outcomes import rung_outcomes

COBERTURA_DTD = "http://cobertura.sourceforge.net/xml/coverage-04.dtd"


def _sources(covs: tuple[Coverage, ...]) -> dict[str, list[tuple[Coverage, FileInfo]]]:
    """Absolute .lad path -> its program files (with the measurement each
    is in: several apps' may go in one report), in file number order. A
    file the program made itself (a Logix export's continuous task, at
    ``<generated>``) has no source a CI tool could show: left out, as the
    annotated listing leaves it out."""
    by_source: dict[str, list[tuple[Coverage, FileInfo]]] = {}
    for cov in covs:
        for number in sorted(cov.files):
            info = cov.files[number]
            if not os.path.isfile(info.source):
                continue
            by_source.setdefault(os.path.abspath(info.source), []).append((cov, info))
    return by_source


Branch = tuple[int, int, int, bool]  # (block, branch, scans it happened in, its rung ran)


@dataclass
class Line:
    number: int
    hits: int
    branches: list[Branch]


def file_lines(cov: Coverage, info: FileInfo) -> list[Line]:
    """A program file's lines, in order, each with its branches: a ladder
    file's rungs with their outcomes, a Structured Text file's lines with
    their arms."""
    if info.listing is not None:
        return [Line(number, hits, [(a.index, 0, a.count, a.ran) for a in arms])
                for number, hits, arms in coverage_st.lines(cov, info)]
    found = []
    for rung in info.rungs:
        ran = cov.executed(rung.key)
        found.append(Line(rung.line, cov.scans(rung.key),
                          [(o.block, o.branch, o.count, ran) for o in rung_outcomes(cov, rung)]))
    return found


@dataclass
class _Counts:
    lines: int = 0
    hit: int = 0
    branches: int = 0
    taken: int = 0

    def add(self, lines: list[Line]) -> "_Counts":
        for line in lines:
            self.lines += 1
            self.hit += line.hits > 0
            self.branches += len(line.branches)
            self.taken += sum(1 for b in line.branches if b[2] > 0)
        return self


def _rate(covered: int, total: int) -> str:
    return f"{covered / total:.4g}" if total else "1"


def _line_rates(c: _Counts) -> dict[str, str]:
    return {"line-rate": _rate(c.hit, c.lines), "branch-rate": _rate(c.taken, c.branches), "complexity": "0"}


def cobertura(*covs: Coverage) -> str:
    """One report of one or more measurements (of different apps)."""
    by_source = _sources(covs)
    root_dir = os.path.commonpath([os.path.dirname(s) for s in by_source]) if by_source else os.getcwd()
    total = _Counts()
    classes = []
    for source, infos in by_source.items():
        for cov, info in infos:
            lines = file_lines(cov, info)
            total.add(lines)
            classes.append((source, info, lines, _Counts().add(lines)))
    rates = _line_rates(total)
    root = ET.Element("coverage", {
        "line-rate": rates["line-rate"], "branch-rate": rates["branch-rate"],
        "lines-covered": str(total.hit), "lines-valid": str(total.lines),
        "branches-covered": str(total.taken), "branches-valid": str(total.branches),
        "complexity": "0", "version": f"softplc_lite {__version__}", "timestamp": str(int(time.time() * 1000))})
    ET.SubElement(ET.SubElement(root, "sources"), "source").text = root_dir
    package = ET.SubElement(ET.SubElement(root, "packages"), "package",
                            {"name": os.path.basename(root_dir) or root_dir, **_line_rates(total)})
    classes_el = ET.SubElement(package, "classes")
    for source, info, lines, counts in classes:
        name = f"{Path(source).name} file {info.number}" + (f" {info.name}" if info.name else "")
        cls = ET.SubElement(classes_el, "class", {"name": name, "filename": os.path.relpath(source, root_dir),
                                                  **_line_rates(counts)})
        ET.SubElement(cls, "methods")
        lines_el = ET.SubElement(cls, "lines")
        for line in lines:
            attrs = {"number": str(line.number), "hits": str(line.hits), "branch": "true" if line.branches else "false"}
            if line.branches:
                seen = sum(1 for b in line.branches if b[2] > 0)
                attrs["condition-coverage"] = f"{seen * 100 // len(line.branches)}% ({seen}/{len(line.branches)})"
            ET.SubElement(lines_el, "line", attrs)
    ET.indent(root)
    return ('<?xml version="1.0" ?>\n'
            f'<!DOCTYPE coverage SYSTEM "{COBERTURA_DTD}">\n' + ET.tostring(root, encoding="unicode") + "\n")


def lcov(*covs: Coverage) -> str:
    """One tracefile of one or more measurements (of different apps)."""
    out = ["TN:"]
    for source, infos in _sources(covs).items():
        out.append(f"SF:{source}")
        functions = [(cov, info, info.rungs[0]) for cov, info in infos if info.rungs]
        for cov, info, first in functions:
            out.append(f"FN:{first.line},{_function(info)}")
        for cov, info, first in functions:
            out.append(f"FNDA:{cov.scans(first.key)},{_function(info)}")
        out.append(f"FNF:{len(functions)}")
        out.append(f"FNH:{sum(cov.executed(first.key) for cov, _, first in functions)}")
        per_file = [file_lines(cov, info) for cov, info in infos]
        counts = _Counts()
        for lines in per_file:
            counts.add(lines)
            for line in lines:
                for block, branch, count, ran in line.branches:
                    out.append(f"BRDA:{line.number},{block},{branch},{count if ran else '-'}")
        for lines in per_file:
            out += [f"DA:{line.number},{line.hits}" for line in lines]
        out += [f"BRF:{counts.branches}", f"BRH:{counts.taken}", f"LF:{counts.lines}", f"LH:{counts.hit}",
                "end_of_record"]
    return "\n".join(out) + "\n"


def _function(info: FileInfo) -> str:
    return f"file_{info.number}" + (f"_{info.name}" if info.name else "")
