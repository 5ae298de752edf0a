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
and the FNF/FNH, LF/LH, BRF/BRH totals (the geninfo(1) format)."""

from __future__ import annotations

import os
import time
import xml.etree.ElementTree as ET
from pathlib import Path

from .. import __version__
from .coverage import Coverage, FileInfo
from .coverage_outcomes import rung_outcomes
from .coverage_report import Figures, file_figures

COBERTURA_DTD = "http://cobertura.sourceforge.net/xml/coverage-04.dtd"


def _sources(covs: tuple[Coverage, ...]) -> dict[str, list[tuple[Coverage, FileInfo]]]:
    """Absolute .lad path -> its program files (with the measurement each
    is in: several apps' may go in one report), in file number order."""
    by_source: dict[str, list[tuple[Coverage, FileInfo]]] = {}
    for cov in covs:
        for number in sorted(cov.files):
            info = cov.files[number]
            by_source.setdefault(os.path.abspath(info.source), []).append((cov, info))
    return by_source


def _rate(covered: int, total: int) -> str:
    return f"{covered / total:.4g}" if total else "1"


def _line_rates(fig: Figures) -> dict[str, str]:
    return {"line-rate": _rate(fig.rungs_run, fig.rungs), "branch-rate": _rate(fig.branches_seen, fig.branches),
            "complexity": "0"}


def cobertura(*covs: Coverage) -> str:
    """One report of one or more measurements (of different apps)."""
    by_source = _sources(covs)
    root_dir = os.path.commonpath([os.path.dirname(s) for s in by_source]) if by_source else os.getcwd()
    total = Figures()
    classes = []
    for source, infos in by_source.items():
        for cov, info in infos:
            fig = file_figures(cov, info)
            total.add(fig)
            classes.append((source, cov, info, fig))
    rates = _line_rates(total)
    root = ET.Element("coverage", {
        "line-rate": rates["line-rate"], "branch-rate": rates["branch-rate"],
        "lines-covered": str(total.rungs_run), "lines-valid": str(total.rungs),
        "branches-covered": str(total.branches_seen), "branches-valid": str(total.branches),
        "complexity": "0", "version": f"softplc_lite {__version__}", "timestamp": str(int(time.time() * 1000))})
    ET.SubElement(ET.SubElement(root, "sources"), "source").text = root_dir
    package = ET.SubElement(ET.SubElement(root, "packages"), "package",
                            {"name": os.path.basename(root_dir) or root_dir, **_line_rates(total)})
    classes_el = ET.SubElement(package, "classes")
    for source, cov, info, fig in classes:
        name = f"{Path(source).name} file {info.number}" + (f" {info.name}" if info.name else "")
        cls = ET.SubElement(classes_el, "class", {"name": name, "filename": os.path.relpath(source, root_dir),
                                                  **_line_rates(fig)})
        ET.SubElement(cls, "methods")
        lines = ET.SubElement(cls, "lines")
        for rung in info.rungs:
            outcomes = rung_outcomes(cov, rung)
            seen = sum(o.covered for o in outcomes)
            ET.SubElement(lines, "line", {
                "number": str(rung.line), "hits": str(cov.scans(rung.key)), "branch": "true",
                "condition-coverage": f"{seen * 100 // len(outcomes)}% ({seen}/{len(outcomes)})"})
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
        lines = hit = branches = taken = 0
        for cov, info in infos:
            for rung in info.rungs:
                ran = cov.executed(rung.key)
                for o in rung_outcomes(cov, rung):
                    out.append(f"BRDA:{rung.line},{o.block},{o.branch},{o.count if ran else '-'}")
                    branches += 1
                    taken += o.covered
        for cov, info in infos:
            for rung in info.rungs:
                out.append(f"DA:{rung.line},{cov.scans(rung.key)}")
                lines += 1
                hit += cov.executed(rung.key)
        out += [f"BRF:{branches}", f"BRH:{taken}", f"LF:{lines}", f"LH:{hit}", "end_of_record"]
    return "\n".join(out) + "\n"


def _function(info: FileInfo) -> str:
    return f"file_{info.number}" + (f"_{info.name}" if info.name else "")
