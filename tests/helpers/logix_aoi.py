"""Hand-written Add-On Instruction definitions for tests, in the L5X shape
Studio 5000 exports them (tests/fixtures/logix/whole_controller.L5X has one),
put into an export that tests/helpers/logix_l5x.py writes."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .logix_l5x import l5x_text


@dataclass
class Param:
    name: str
    data_type: str  # "DINT", "REAL", "BOOL[32]" ...
    usage: str  # Input, Output, InOut
    required: bool = True
    default: str | None = None  # a decorated DataValue's Value


@dataclass
class Aoi:
    name: str
    params: list[Param]
    routines: dict[str, list[str]]  # Logic, EnableInFalse ... -> rung texts
    local_tags: list[tuple[str, str, str | None]] = field(default_factory=list)  # (name, type, decorated data XML)
    encoded: bool = False
    scan_modes: list[str] | None = None  # the routines the header says to run (None: the Prescan, EnableInFalse given)


def _dims(data_type: str) -> tuple[str, str]:
    if "[" in data_type:
        base, _, rest = data_type.partition("[")
        return base, f' Dimensions="{rest.rstrip("]")}"'
    return data_type, ""


def aoi_xml(a: Aoi) -> str:
    out = []
    params = [Param("EnableIn", "BOOL", "Input", False), Param("EnableOut", "BOOL", "Output", False)] + a.params
    modes = a.scan_modes if a.scan_modes is not None else [r for r in a.routines if r in ("Prescan", "EnableInFalse")]
    head = (f'Name="{a.name}" Revision="1.0" ExecutePrescan="{str("Prescan" in modes).lower()}" '
            f'ExecutePostscan="false" ExecuteEnableInFalse="{str("EnableInFalse" in modes).lower()}"')
    out.append(f'<EncodedData EncodedType="AddOnInstructionDefinition" {head}>' if a.encoded
               else f"<AddOnInstructionDefinition {head}>")
    out.append("<Parameters>")
    for p in params:
        base, dims = _dims(p.data_type)
        visible = "true" if p.required else "false"
        attrs = (f'Name="{p.name}" TagType="Base" DataType="{base}"{dims} Usage="{p.usage}" Radix="Decimal" '
                 f'Required="{str(p.required).lower()}" Visible="{visible}"')
        if p.default is None:
            out.append(f"<Parameter {attrs}/>")
        else:
            out += [f"<Parameter {attrs}>", '<DefaultData Format="Decorated">',
                    f'<DataValue DataType="{base}" Radix="Decimal" Value="{p.default}"/>', "</DefaultData>",
                    "</Parameter>"]
    out.append("</Parameters>")
    if a.encoded:
        out += ["QUJDREVGR0g=", "</EncodedData>"]
        return "\n".join(out)
    out.append("<LocalTags>")
    for name, data_type, data in a.local_tags:
        base, dims = _dims(data_type)
        attrs = f'Name="{name}" DataType="{base}"{dims} Radix="Decimal" ExternalAccess="Read/Write"'
        out.append(f"<LocalTag {attrs}/>" if data is None else
                   f'<LocalTag {attrs}>\n<DefaultData Format="Decorated">\n{data}\n</DefaultData>\n</LocalTag>')
    out += ["</LocalTags>", "<Routines>"]
    for routine, rungs in a.routines.items():
        out += [f'<Routine Name="{routine}" Type="RLL">', "<RLLContent>"]
        for k, text in enumerate(rungs):
            out += [f'<Rung Number="{k}" Type="N">', "<Text>", f"<![CDATA[{text}]]>", "</Text>", "</Rung>"]
        out += ["</RLLContent>", "</Routine>"]
    out += ["</Routines>", "</AddOnInstructionDefinition>"]
    return "\n".join(out)


def write_aoi_l5x(path: Path, aois: list[Aoi], tags, programs, tasks) -> Path:
    text = l5x_text(tags, programs, tasks)
    defs = "<AddOnInstructionDefinitions>\n" + "\n".join(aoi_xml(a) for a in aois) + "\n</AddOnInstructionDefinitions>"
    path.write_text(text.replace("<AddOnInstructionDefinitions/>", defs, 1), encoding="utf-8")
    return path
