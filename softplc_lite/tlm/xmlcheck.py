"""Checking a module's XML configuration against a table of its elements'
attributes, collecting every problem (MODBMAST.XML, MODBTCPS.XML).

One ``XmlChecker`` walks one file's tree (``xmlreader.XmlNode``): it converts
and range-checks attributes (``Attr``), matches an element's children against
a content model (a sequence of (name, min, max)), and records each problem as
a ``ModuleError`` with file, line and column, so a file is reported whole, not
one problem per run. The messages are MODBMAST's (docs/modbmast.md, "Every
problem at once"); a module's own rules add theirs through ``error``.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass
from typing import Iterable, Mapping

from .errors import ModuleError, ModuleErrors
from .xmlreader import XmlNode, XmlSyntaxError, read_xml

MAX_PROBLEMS = 200  # listed; a file with more gets a count of the rest
MANY = 10**9  # no upper bound, in a content model


@dataclass(frozen=True)
class Attr:
    """One allowed attribute: a choice list or an integer range, required or
    with a default (None: optional and inherited, or absent)."""

    name: str
    low: int | None = None
    high: int | None = None
    choices: tuple[str, ...] = ()
    required: bool = False
    default: object = None
    extension: bool = False  # softplc_lite's, not the manual's
    text: bool = False  # any text (a device, an address)
    what: str = ""  # what a text attribute holds, for messages ("a data table address")


_INTEGER = re.compile(r"^\s*([+-]?)(0[xX][0-9A-Fa-f]{1,8}|[0-9]{1,10})\s*$")


def parse_integer(text: str) -> int | None:
    """A decimal or ``0x`` hex integer (MODBMAST manual 4.3: "16" or "0x0010"), or None."""
    m = _INTEGER.match(text)
    if m is None:
        return None
    value = int(m.group(2), 16 if m.group(2)[:2].lower() == "0x" else 10)
    return -value if m.group(1) == "-" else value


def expected(spec: Attr) -> str:
    """What an attribute takes, as messages say it: "an integer 1..247"."""
    if spec.text:
        return spec.what or "text"
    if spec.choices:
        return " or ".join(repr(c) for c in spec.choices)
    return f"an integer {spec.low}..{spec.high}"


def content(model: list[tuple[str, int, int]]) -> str:
    """A content model as messages say it: "<ModemControl>?, <Slave>*"."""
    if not model:
        return "no elements"
    marks = {(1, 1): "", (0, 1): "?", (1, MANY): "+", (0, MANY): "*"}
    return ", ".join(f"<{name}>{marks.get((low, high), '')}" for name, low, high in model)


class XmlChecker:
    """Walks one file's tree, collecting every problem.

    ``attributes``: each element name's allowed attributes; ``root``: the
    document element's name; ``hint_names``: element names offered as "did
    you mean" for an unknown element, beside those of the content model in
    force (MODBMAST offers its request elements everywhere)."""

    def __init__(self, path: str, attributes: Mapping[str, tuple[Attr, ...]], root: str,
                 hint_names: Iterable[str] = ()) -> None:
        self.path = path
        self.attribute_table = attributes
        self.root = root
        self.hint_names = list(hint_names)
        self.problems: list[ModuleError] = []
        self.more = 0  # problems past MAX_PROBLEMS, counted

    def error(self, node: XmlNode, message: str, attr: str | None = None) -> None:
        if len(self.problems) >= MAX_PROBLEMS:
            self.more += 1
            return
        line, column = node.where(attr)
        self.problems.append(ModuleError(message, self.path, line, column))

    def read_root(self, data: bytes, source: str) -> XmlNode:
        """The file's top element, which must be the checker's root; else
        ModuleErrors (a syntax error, or the wrong root: ``source`` says
        where the root is documented)."""
        try:
            root = read_xml(data)
        except XmlSyntaxError as e:
            raise ModuleErrors([ModuleError(e.message, self.path, e.line, e.column)]) from None
        if root.name != self.root:
            self.error(root, f"the top element is <{root.name}>; expected <{self.root}> ({source})")
            raise ModuleErrors(self.found())
        return root

    def found(self) -> list[ModuleError]:
        """The problems, with a last line counting those not listed."""
        if not self.more:
            return self.problems
        last = self.problems[-1]
        return self.problems + [ModuleError(f"... and {self.more} more problem{'s' if self.more != 1 else ''} "
                                            f"(the first {MAX_PROBLEMS} are listed)", self.path, last.line,
                                            last.column + 1)]

    # - - - attributes - - -
    def attributes(self, node: XmlNode) -> dict[str, object]:
        """The node's attribute values, converted; defaults filled in; a
        problem for each unknown, missing or bad one (its value is then left out)."""
        allowed = {a.name: a for a in self.attribute_table[node.name]}
        out: dict[str, object] = {}
        for key, raw in node.attrs.items():
            spec = allowed.get(key)
            if spec is None:
                names = ", ".join(allowed) or "none"
                close = difflib.get_close_matches(key, list(allowed), n=1)
                hint = f"; did you mean {close[0]}?" if close else ""
                self.error(node, f"<{node.name}> has no attribute {key!r} (its attributes: {names}){hint}", key)
                continue
            value = self._value(node, spec, raw)
            if value is not None:
                out[key] = value
        for spec in allowed.values():
            if spec.name not in node.attrs:
                if spec.required:
                    self.error(node, f"<{node.name}> needs the attribute {spec.name} ({expected(spec)})")
                elif spec.default is not None:
                    out[spec.name] = spec.default
        return out

    def _value(self, node: XmlNode, spec: Attr, raw: str) -> object:
        if spec.text:
            if not raw.strip():
                self.error(node, f"{spec.name} is empty; expected {expected(spec)}", spec.name)
                return None
            return raw.strip()
        if spec.choices:
            for choice in spec.choices:
                if raw.strip().lower() == choice.lower():
                    return choice
            self.error(node, f"{spec.name}={raw!r}: expected {expected(spec)}", spec.name)
            return None
        value = parse_integer(raw)
        if value is None or not spec.low <= value <= spec.high:
            self.error(node, f"{spec.name}={raw!r}: expected {expected(spec)}", spec.name)
            return None
        return value

    # - - - content - - -
    def children(self, node: XmlNode, model: list[tuple[str, int, int]]) -> list[list[XmlNode]]:
        """Match the children against a sequence of (name, min, max): the
        children found for each item, and a problem for what does not fit."""
        groups: list[list[XmlNode]] = [[] for _ in model]
        i = 0  # the model item the last child fitted
        for kid in node.children:
            # The first item from here on this child fits (a later one when this one is full).
            j = next((j for j in range(i, len(model)) if model[j][0] == kid.name
                      and (j > i or len(groups[j]) < model[j][2])), None)
            if j is None:  # fits nowhere from here: reported, and the next child matched on
                self.extra(node, kid, model)
                continue
            for k in range(i, j):  # items skipped over
                if len(groups[k]) < model[k][1]:
                    self.error(kid, f"<{node.name}> needs <{model[k][0]}> here ({content(model)})")
            i = j
            groups[j].append(kid)
        for k in range(i, len(model)):
            if len(groups[k]) < model[k][1]:
                self.error(node, f"<{node.name}> needs <{model[k][0]}> here ({content(model)})")
        return groups

    def any_order(self, node: XmlNode, names: Iterable[str]) -> list[XmlNode]:
        """The children named in ``names`` (any number of each, in any order);
        a problem for each other child."""
        names = list(names)
        kids = []
        for kid in node.children:
            if kid.name in names:
                kids.append(kid)
                continue
            known = kid.name in self.attribute_table or kid.name == self.root
            close = difflib.get_close_matches(kid.name, names + self.hint_names, n=1)
            what = f"<{kid.name}> is not allowed here" if known else f"unknown element <{kid.name}>"
            hint = f"; did you mean <{close[0]}>?" if close and not known else ""
            listed = ", ".join(f"<{name}>" for name in names)
            self.error(kid, f"{what} (<{node.name}> contains {listed}: any number of each, in any order){hint}")
        return kids

    def extra(self, node: XmlNode, extra: XmlNode, model: list[tuple[str, int, int]]) -> None:
        """A child that the content model has no place for."""
        known = extra.name in self.attribute_table or extra.name == self.root
        close = difflib.get_close_matches(extra.name, [n for n, _, _ in model] + self.hint_names, n=1)
        what = f"<{extra.name}> is not allowed here" if known else f"unknown element <{extra.name}>"
        hint = f"; did you mean <{close[0]}>?" if close and not known else ""
        self.error(extra, f"{what} (<{node.name}> contains {content(model)}){hint}")

    def text_integer(self, node: XmlNode, low: int, high: int, what: str) -> int | None:
        """The integer an element holds as its text (<andMask>0xFF00</andMask>)."""
        self.attributes(node)
        self.children(node, [])
        value = parse_integer(node.text)
        if value is None or not low <= value <= high:
            self.error(node, f"<{node.name}>{node.text.strip()[:40]}</{node.name}>: expected {what}")
            return None
        return value
