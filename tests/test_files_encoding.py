"""Input files from Windows editors: a UTF-8 BOM, and UTF-16 LE
or BE with a BOM, are read in every file kind: .lad, softplc.toml,
MODULES.LST, COMGENIUS.LST, MODBMAST.XML, datatable.json, --load JSON,
watch files, port traces. Line and column numbers count the characters
after the BOM."""

from __future__ import annotations

import codecs
import shutil
from pathlib import Path

import pytest

from softplc_lite.app import AppError, load_app
from softplc_lite.datatable import DataTable, jsonio
from softplc_lite.errors import LocatedError
from softplc_lite.textfile import decode_text

from helpers.cli import softplc_here

ROOT = Path(__file__).resolve().parent.parent
ENCODINGS = {
    "utf-8-bom": lambda text: codecs.BOM_UTF8 + text.encode("utf-8"),
    "utf-16-le-bom": lambda text: codecs.BOM_UTF16_LE + text.encode("utf-16-le"),
    "utf-16-be-bom": lambda text: codecs.BOM_UTF16_BE + text.encode("utf-16-be"),
}
# Every text file kind an app directory holds, from the shipped apps.
APPS = {
    "loopback": ["main.lad", "MODULES.LST", "COMGENIUS.LST"],  # .lad, MODULES.LST, COMGENIUS.LST
    "modbus_master": ["main.lad", "MODULES.LST", "COMGENIUS.LST", "softplc.toml"],
    "modbus_scada": ["main.lad", "MODULES.LST", "MODBMAST.XML", "softplc.toml"],
    "tank": ["main.lad", "datatable.json"],
}


def reencode(path: Path, encoding: str) -> None:
    text = path.read_text(encoding="utf-8")
    if path.suffix.upper() == ".XML" and encoding.startswith("utf-16"):
        text = text.replace('encoding="UTF-8"', 'encoding="UTF-16"').replace("encoding='UTF-8'", "encoding='UTF-16'")
    path.write_bytes(ENCODINGS[encoding](text))


@pytest.mark.parametrize("encoding", ENCODINGS)
@pytest.mark.parametrize("app_name", APPS)
def test_every_app_file_kind_loads_with_a_bom(tmp_path, app_name, encoding):
    original = load_app(ROOT / "programs" / app_name, state_dir=tmp_path / "state0", use_cache=False)
    app_dir = tmp_path / app_name
    shutil.copytree(ROOT / "programs" / app_name, app_dir)
    if app_name == "tank":  # no shipped app has a datatable.json: give this one initial values
        (app_dir / "datatable.json").write_text('{"N7": [5, -6, 7]}\n', encoding="utf-8")
        original = load_app(app_dir, state_dir=tmp_path / "state0", use_cache=False)
    for name in APPS[app_name]:
        assert (app_dir / name).exists(), name
        reencode(app_dir / name, encoding)
        assert (app_dir / name).read_bytes()[:2] in (b"\xef\xbb", b"\xff\xfe", b"\xfe\xff")
    app = load_app(app_dir, state_dir=tmp_path / "state", use_cache=False)
    assert app.program == original.program
    assert [m.name for m in app.modules] == [m.name for m in original.modules]
    assert app.settings == original.settings
    if app.datatable_json is not None:
        ours, theirs = DataTable(), DataTable()
        jsonio.load_file(ours, str(app.datatable_json))
        jsonio.load_file(theirs, str(original.datatable_json))
        assert ours == theirs


def test_modules_lst_with_a_bom_no_longer_names_the_bom_as_a_module(tmp_path):
    """The issue's report: `module ï»¿ is not installed`."""
    app_dir = tmp_path / "app"
    shutil.copytree(ROOT / "programs" / "loopback", app_dir)
    reencode(app_dir / "MODULES.LST", "utf-8-bom")
    result = softplc_here("check", str(app_dir))
    assert result.returncode == 0, result.stderr
    assert "ï»¿" not in result.stderr and "module COMGENIUS" in result.stdout


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_columns_count_characters_after_the_bom(tmp_path, encoding):
    lad = "OTE N7:\nXIC B3:0/0\n"  # on the first line, where the BOM is
    plain, bom = tmp_path / "plain.lad", tmp_path / "bom.lad"
    plain.write_text(lad, encoding="utf-8")
    bom.write_bytes(ENCODINGS[encoding](lad))
    reports = []
    for path in (plain, bom):
        with pytest.raises(AppError) as e:
            load_app(path, use_cache=False)
        (problem,) = e.value.errors
        reports.append((problem.pos.line, problem.pos.column, problem.message))
    assert reports[0] == reports[1]
    assert reports[0][:2] == (1, 8)  # just past N7:, where the element number is missing


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_load_json_watch_file_and_trace_read_with_a_bom(tmp_path, encoding):
    doc = '{"N7": [1, 2, 3]}\n'
    path = tmp_path / "values.json"
    path.write_bytes(ENCODINGS[encoding](doc))
    table = DataTable()
    jsonio.load_file(table, str(path))  # --load and datatable.json
    from softplc_lite.datatable import parse_address
    assert table.read(parse_address("N7:2")) == 3
    # a watch file, with its located error still at the right column
    from softplc_lite.watch.watchlist import read_watch_file
    (tmp_path / "w.txt").write_bytes(ENCODINGS[encoding]("N7:0\nT4:0.ACC  # the timer\n"))
    assert read_watch_file(tmp_path / "w.txt") == ["N7:0", "T4:0.ACC"]
    (tmp_path / "bad.txt").write_bytes(ENCODINGS[encoding]("  N7:x\n"))
    with pytest.raises(LocatedError) as e:
        read_watch_file(tmp_path / "bad.txt")
    plain = tmp_path / "plain.txt"
    plain.write_text("  N7:x\n", encoding="utf-8")
    with pytest.raises(LocatedError) as p:
        read_watch_file(plain)
    assert (e.value.line, e.value.column) == (p.value.line, p.value.column) == (1, 6)
    # the shipped port trace (--replay)
    from softplc_lite.ports.trace import read_trace
    shipped = ROOT / "programs" / "modbus_master" / "pymodbus-session.trace"
    (tmp_path / "t.trace").write_bytes(ENCODINGS[encoding](shipped.read_text(encoding="utf-8")))
    assert read_trace(tmp_path / "t.trace") == read_trace(shipped)


def test_bad_bytes_are_located_whatever_the_bom():
    with pytest.raises(LocatedError) as e:
        decode_text(codecs.BOM_UTF8 + b"ok\nab\xffc\n", "f.lad")
    assert (e.value.line, e.value.column) == (2, 3) and "UTF-8" in e.value.message
    with pytest.raises(LocatedError) as e:
        decode_text(b"ok\nab\xffc\n", "f.lad")
    assert (e.value.line, e.value.column) == (2, 3)
    with pytest.raises(LocatedError) as e:
        decode_text(codecs.BOM_UTF16_LE + "ab\ncd".encode("utf-16-le") + b"x", "f.lad")
    assert e.value.line == 2 and "half a character" in e.value.message
    with pytest.raises(LocatedError) as e:
        decode_text(codecs.BOM_UTF16_BE + "a\nb".encode("utf-16-be") + b"\xd8\x00\x00a", "f.lad")
    assert (e.value.line, e.value.column) == (2, 2) and "surrogate" in e.value.message
    assert decode_text(b"caf\xe9", "X.LST", fallback="latin-1") == "café"  # DOS-era LST files
