#!/usr/bin/env python3
"""A census of Studio 5000 exports (L5X and L5K): what a set of real exports uses, so that the
Logix loader is measured against what the world writes rather than what we guess.

    python tools/logix_census.py FILE_OR_DIR... [--json] [--per-file]

For each file and in total: routines by language (RLL, ST, FBD, SFC), rungs, instruction
mnemonics (an identifier followed by ``(`` outside any other instruction's parentheses, so a
CPT's ``ABS(`` is not counted), the features rung text uses (branches, ``?`` operands, indexes,
bit-of-word, module tags, string literals, AOI calls), tag data types by scope, array dimensions,
UDTs, AOIs, tasks by type, modules, alias tags, External Access values and the ``Data Format=``
kinds (L5X). A file that cannot be read is reported by name with the reason, and the census goes
on. Standard library only: it runs beside a checkout without the project installed.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

EXTENSIONS = {".l5x", ".l5k"}
COUNTERS = ("routines", "instructions", "features", "tag_types", "tag_scopes", "array_dims",
            "tasks", "external_access", "data_formats", "export_kinds", "formats")
NUMBERS = ("files", "rungs", "st_lines", "udts", "aois", "modules", "alias_tags", "tags",
           "encoded_routines")

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_MODULE_TAG = re.compile(r"\b[A-Za-z_]\w*:\d+:[IOC]\b")
_SYSTEM_TAG = re.compile(r"(?<![\w:])S:[A-Z]{1,2}\b")
_BIT_OF_WORD = re.compile(r"[\w\]]\.\d+\b(?!\.\d)")
_MEMBER = re.compile(r"[\w\]]\.[A-Za-z_]")
_CONST_INDEX = re.compile(r"\w\[\s*\d+(\s*,\s*\d+)*\s*\]")
_EXPR_INDEX = re.compile(r"\w\[[^\]]*[A-Za-z_][^\]]*\]")
_NUMBER = re.compile(r"^[-+]?(\d+\.?\d*([eE][-+]?\d+)?|\d+#[0-9A-Fa-f_]+)$")


def new_census() -> dict:
    census = {name: Counter() for name in COUNTERS}
    census.update({name: 0 for name in NUMBERS})
    return census


def merge(total: dict, one: dict) -> None:
    for name in COUNTERS:
        total[name].update(one[name])
    for name in NUMBERS:
        total[name] += one[name]


# -- rung text ---------------------------------------------------------------------------------

def split_instructions(text: str) -> list[tuple[str, list[str]]]:
    """The instructions of a rung's neutral text, each with its operands, in order.

    Branches (``[a,b]``) and string literals (``'...'``, ``$'`` escapes) are stepped over;
    an instruction's operands are split on commas outside nested parentheses and brackets."""
    found, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if c == "'":
            i = _skip_string(text, i)
            continue
        m = _IDENT.match(text, i)
        if m and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] in "_.:")):
            j = m.end()
            if j < n and text[j] == "(":
                end = _matching(text, j)
                found.append((m.group(), _operands(text[j + 1:end])))
                i = end + 1
                continue
            i = j
            continue
        i += 1
    return found


def _skip_string(text: str, i: int) -> int:
    j = i + 1
    while j < len(text):
        if text[j] == "$":
            j += 2
            continue
        if text[j] == "'":
            return j + 1
        j += 1
    return j


def _matching(text: str, open_at: int) -> int:
    depth, j = 0, open_at
    while j < len(text):
        c = text[j]
        if c == "'":
            j = _skip_string(text, j)
            continue
        if c in "([":
            depth += 1
        elif c in ")]":
            depth -= 1
            if depth == 0:
                return j
        j += 1
    return len(text)


def _operands(inner: str) -> list[str]:
    parts, depth, start, j = [], 0, 0, 0
    while j < len(inner):
        c = inner[j]
        if c == "'":
            j = _skip_string(inner, j)
            continue
        if c in "([":
            depth += 1
        elif c in ")]":
            depth -= 1
        elif c == "," and depth == 0:
            parts.append(inner[start:j].strip())
            start = j + 1
        j += 1
    parts.append(inner[start:].strip())
    return parts if parts != [""] else []


def count_rung(census: dict, text: str, aois: set[str]) -> None:
    census["rungs"] += 1
    instructions = split_instructions(text)
    features = set()
    for mnemonic, operands in instructions:
        census["instructions"][mnemonic] += 1
        if mnemonic in aois:
            features.add("aoi_call")
        for operand in operands:
            if operand == "?":
                features.add("question_operand")
            elif operand.startswith("'"):
                features.add("string_literal")
            elif _NUMBER.match(operand):
                features.add("numeric_literal")
            elif re.search(r"[-+*/]|\b(MOD|AND|OR|XOR|NOT)\b", operand) and not _IDENT.fullmatch(operand):
                features.add("expression_operand")
    if not instructions:
        features.add("empty_rung")
    if re.search(r"(^|[),\]])\s*\[|^\[", text):
        features.add("branch")
    if re.search(r"\[[^\[\]]*\[", text) and text.count("[") - len(re.findall(r"\w\[", text)) > 1:
        features.add("nested_branch")
    for name, pattern in (("module_tag", _MODULE_TAG), ("system_tag", _SYSTEM_TAG),
                          ("bit_of_word", _BIT_OF_WORD), ("member_access", _MEMBER),
                          ("constant_index", _CONST_INDEX), ("expression_index", _EXPR_INDEX)):
        if pattern.search(text):
            features.add(name)
    census["features"].update(features)


# -- L5X ---------------------------------------------------------------------------------------

_CONTENT = {"RLL": "RLLContent", "ST": "STContent", "FBD": "FBDContent", "SFC": "SFCContent"}

def census_l5x(path: Path) -> dict:
    census = new_census()
    root = ET.parse(path).getroot()
    if root.tag != "RSLogix5000Content":
        raise ValueError(f"root element is <{root.tag}>, expected <RSLogix5000Content>")
    census["formats"]["L5X"] += 1
    census["export_kinds"][root.get("TargetType", "?")] += 1
    aois = {a.get("Name") for a in root.iter("AddOnInstructionDefinition")}
    census["aois"] = len(aois)
    census["udts"] = sum(1 for _ in root.iter("DataType"))
    census["modules"] = sum(1 for _ in root.iter("Module"))
    for task in root.iter("Task"):
        if task.get("Type"):  # a task named only as a reference carries no type
            census["tasks"][task.get("Type")] += 1
    for data in root.iter("Data"):
        census["data_formats"][data.get("Format", "raw (no Format)")] += 1
    for tags_parent in root.iter():
        if tags_parent.tag not in ("Controller", "Program"):
            continue
        scope = tags_parent.tag.lower()
        tags = tags_parent.find("Tags")
        for tag in tags if tags is not None else ():
            if tag.tag != "Tag":
                continue
            _count_tag(census, scope, tag.get("TagType", "Base"), tag.get("DataType"),
                       tag.get("Dimensions"), tag.get("ExternalAccess"))
    aoi_routines = {id(r) for a in root.iter("AddOnInstructionDefinition") for r in a.iter("Routine")}
    for routine in root.iter("Routine"):
        kind = routine.get("Type") or next((k for k, c in _CONTENT.items() if routine.find(c) is not None), None)
        if kind is None:  # a routine named only as a reference or context, without content
            continue
        census["routines"][("AOI " if id(routine) in aoi_routines else "") + kind] += 1
        for line in routine.iter("Line"):
            census["st_lines"] += 1
        for rung in routine.iter("Rung"):
            text = rung.find("Text")
            count_rung(census, "".join(text.itertext()).strip() if text is not None else "", aois)
    census["encoded_routines"] = sum(1 for _ in root.iter("EncodedData"))
    return census


def _count_tag(census, scope, tag_type, data_type, dims, access) -> None:
    census["tags"] += 1
    census["tag_scopes"][scope] += 1
    if tag_type.lower() == "alias":
        census["alias_tags"] += 1
        census["tag_types"]["(alias)"] += 1
    else:
        census["tag_types"][data_type or "?"] += 1
    if dims and dims.strip() not in ("", "0"):
        census["array_dims"][f"{len(re.split(r'[ ,]+', dims.strip()))}-D"] += 1
    if access:
        census["external_access"][access] += 1


# -- L5K ---------------------------------------------------------------------------------------

_BLOCK = re.compile(r"^\s*(END_)?(CONTROLLER|DATATYPE|MODULE|ADD_ON_INSTRUCTION_DEFINITION|TAG|"
                    r"PROGRAM|ROUTINE|ST_ROUTINE|FBD_ROUTINE|SFC_ROUTINE|TASK|PARAMETERS|"
                    r"LOCAL_TAGS|CONNECTION|CHILD_PROGRAMS|ENCODED_DATA|TREND|WATCH_LIST|"
                    r"QUICK_WATCH|MESSAGE_DEFINITION|ALARM_DEFINITIONS|SUBSYSTEM)\b(.*)$")
_ROUTINE_KIND = {"ROUTINE": "RLL", "ST_ROUTINE": "ST", "FBD_ROUTINE": "FBD", "SFC_ROUTINE": "SFC"}


def statements(lines: list[str]):
    """Join continued lines into statements ended by ';' outside quotes and brackets."""
    buf, depth, quote = [], 0, ""
    for line in lines:
        buf.append(line)
        j = 0
        while j < len(line):
            c = line[j]
            if quote:
                if c == "$":
                    j += 1
                elif c == quote:
                    quote = ""
            elif c in "\"'":
                quote = c
            elif c in "([":
                depth += 1
            elif c in ")]":
                depth -= 1
            elif c == ";" and depth <= 0:
                yield " ".join(s.strip() for s in buf)
                buf, depth = [], 0
                line = line[j + 1:]
                j = -1
                if line.strip():
                    buf = [line]
            j += 1
        quote = ""


def census_l5k(path: Path) -> dict:
    census = new_census()
    text = path.read_bytes().decode("utf-8-sig")
    text = re.sub(r"^\s*\(\*.*?\*\)", "", text, count=1, flags=re.S)
    if not re.search(r"^\s*(IE_VER|CONTROLLER)\b", text, re.M):
        raise ValueError("no IE_VER or CONTROLLER line: not an L5K export")
    census["formats"]["L5K"] += 1
    census["export_kinds"]["Controller" if re.search(r"^\s*CONTROLLER\b", text, re.M) else "other"] += 1
    lines = text.splitlines()
    aois = set(re.findall(r"^\s*ADD_ON_INSTRUCTION_DEFINITION\s+(\w+)", text, re.M))
    census["aois"] = len(aois)
    stack: list[str] = []
    body: list[str] = []
    for lineno, line in enumerate(lines, 1):
        m = _BLOCK.match(line)
        # inside a tag list a line starting with a block word is a tag's name, unless it ends the list
        if m and (m.group(1) or not stack or stack[-1] not in ("TAG", "LOCAL_TAGS", "PARAMETERS")):
            end, word, rest = m.group(1), m.group(2), m.group(3)
            if end:
                if word in ("TAG", "ROUTINE") or word in _ROUTINE_KIND:
                    _l5k_body(census, stack, body, aois)
                if stack and stack[-1] == word:
                    stack.pop()
                body = []
                continue
            if word == "DATATYPE":
                census["udts"] += 1
            elif word == "MODULE":
                census["modules"] += 1
            elif word in _ROUTINE_KIND:
                inside_aoi = "ADD_ON_INSTRUCTION_DEFINITION" in stack
                census["routines"][("AOI " if inside_aoi else "") + _ROUTINE_KIND[word]] += 1
            elif word == "TASK":
                window = " ".join(lines[lineno - 1:lineno + 8])
                kind = re.search(r"Type\s*:=\s*(\w+)", window)
                census["tasks"][kind.group(1) if kind else "?"] += 1
            if not re.search(r"\bEND_\w+\s*$", rest) and not (word == "CONNECTION" and rest.rstrip().endswith("END_CONNECTION")):
                stack.append(word)
            body = []
            continue
        body.append(line)
    return census


def _l5k_body(census: dict, stack: list[str], body: list[str], aois: set[str]) -> None:
    if not stack:
        return
    block = stack[-1]
    if block == "TAG":
        scope = "program" if "PROGRAM" in stack else "controller"
        for st in statements(body):
            _l5k_tag(census, scope, st)
    elif block == "ROUTINE":
        for st in statements(body):
            if st.startswith("N:"):
                count_rung(census, st[2:].rstrip(";").strip(), aois)
    elif block == "ST_ROUTINE":
        census["st_lines"] += sum(1 for line in body if line.strip().startswith("'"))
    elif block == "ENCODED_DATA":
        census["encoded_routines"] += 1


def _l5k_tag(census: dict, scope: str, st: str) -> None:
    alias = re.match(r"^(\w+)\s+OF\s+", st)
    access = re.search(r"ExternalAccess\s*:=\s*([A-Za-z/ ]+?)\s*[,)]", st)
    access = access.group(1) if access else None
    if alias:
        _count_tag(census, scope, "Alias", None, None, access)
        return
    m = re.match(r"^(\w+)\s*:\s*([\w:]+)\s*(\[([\d,\s]+)\])?", st)
    if m:
        _count_tag(census, scope, "Base", m.group(2), (m.group(4) or "").replace(",", " "), access)


# -- files and output --------------------------------------------------------------------------

def find_files(paths: list[str]) -> list[Path]:
    found = []
    for name in paths:
        p = Path(name)
        if p.is_dir():
            found += sorted(f for f in p.rglob("*") if f.is_file() and f.suffix.lower() in EXTENSIONS)
        else:
            found.append(p)
    return found


def census_file(path: Path) -> dict:
    head = path.read_bytes()[:4096].decode("utf-8-sig", "replace").lstrip()
    if path.suffix.lower() == ".l5x" or head.startswith("<"):
        return census_l5x(path)
    return census_l5k(path)


def run(paths: list[str]) -> dict:
    total, per_file, errors = new_census(), {}, {}
    for path in find_files(paths):
        try:
            one = census_file(path)
        except ET.ParseError as e:
            errors[str(path)] = f"not well-formed XML at line {e.position[0]}, column {e.position[1] + 1}"
            continue
        except (OSError, UnicodeDecodeError, ValueError, RecursionError) as e:
            errors[str(path)] = f"{type(e).__name__}: {e}"
            continue
        one["files"] = 1
        per_file[str(path)] = one
        merge(total, one)
    return {"total": total, "files": per_file, "errors": errors}


def _share(counter: Counter, whole: int, top: int = 0) -> str:
    items = counter.most_common(top or None)
    return ", ".join(f"{k} {v}" + (f" ({100 * v / whole:.0f}%)" if whole else "") for k, v in items)


def print_table(result: dict, per_file: bool, top: int) -> None:
    if per_file:
        print(f"{'file':60} {'kind':12} {'rungs':>6} {'RLL':>4} {'ST':>3} {'FBD':>3} {'SFC':>3} "
              f"{'tags':>5} {'UDT':>4} {'AOI':>4} {'mod':>4}")
        for name, c in result["files"].items():
            r = c["routines"]
            kind = next(iter(c["export_kinds"]), "?")
            print(f"{name[-60:]:60} {kind[:12]:12} {c['rungs']:>6} "
                  f"{r['RLL'] + r['AOI RLL']:>4} {r['ST'] + r['AOI ST']:>3} {r['FBD'] + r['AOI FBD']:>3} "
                  f"{r['SFC']:>3} {c['tags']:>5} {c['udts']:>4} {c['aois']:>4} {c['modules']:>4}")
        print()
    t = result["total"]
    rungs, uses = t["rungs"], sum(t["instructions"].values())
    print(f"files {t['files']} ({_share(t['formats'], 0)}), unreadable {len(result['errors'])}")
    print(f"export kinds: {_share(t['export_kinds'], 0)}")
    print(f"routines: {_share(t['routines'], sum(t['routines'].values()))}; encoded {t['encoded_routines']}")
    print(f"rungs {rungs}, instruction uses {uses}, distinct mnemonics {len(t['instructions'])}, ST lines {t['st_lines']}")
    print(f"instructions (top {top}): {_share(t['instructions'], uses, top)}")
    print(f"rung features (share of rungs): {_share(t['features'], rungs)}")
    print(f"tags {t['tags']} ({_share(t['tag_scopes'], 0)}), alias {t['alias_tags']}, arrays: {_share(t['array_dims'], 0)}")
    print(f"tag data types (top {top}): {_share(t['tag_types'], t['tags'], top)}")
    print(f"UDTs {t['udts']}, AOIs {t['aois']}, modules {t['modules']}, tasks: {_share(t['tasks'], 0)}")
    print(f"External Access: {_share(t['external_access'], 0)}")
    print(f"Data Format kinds: {_share(t['data_formats'], 0)}")
    for name, why in result["errors"].items():
        print(f"{name}: {why}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="+", help="L5X/L5K files or directories searched for them")
    ap.add_argument("--json", action="store_true", help="print the census as JSON")
    ap.add_argument("--per-file", action="store_true", help="a line per file before the totals")
    ap.add_argument("--top", type=int, default=40, help="how many instructions and types to list")
    args = ap.parse_args(argv)
    result = run(args.paths)
    if args.json:
        json.dump(result, sys.stdout, indent=1, sort_keys=True)
        print()
    else:
        print_table(result, args.per_file, args.top)
    return 1 if result["errors"] and not result["files"] else 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BrokenPipeError:  # the reader (head, less) stopped early: nothing left to say
        sys.exit(0)
