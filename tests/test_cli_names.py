"""How the softplc command names apps and files (docs/cli.md, "Names"):
a file or directory name that is not UTF-8 (Linux allows any bytes but
"/" and NUL) is shown with backslash escapes, never an encoding error; an
app given as "." is named after the directory it stands for. Names that
are not UTF-8 go through the real command in a process, its output read as
bytes from a standard output that refuses what it cannot encode; the rest
runs cli.main in the test's process."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from helpers.cli import softplc, softplc_here

NOT_UTF8 = b"\xff"  # a byte no UTF-8 text holds
# A UTF-8 locale, whose standard output refuses what cannot be encoded: names that are not
# UTF-8 go through a process for it (and as bytes on its command line), its output read as bytes.
ENV = dict(os.environ, LC_ALL="C.UTF-8", PYTHONIOENCODING="utf-8")


def lines(data: bytes) -> list[str]:
    return data.decode("utf-8").splitlines()  # the output is UTF-8 itself


@pytest.fixture(name="bad_file_app")
def fixture_bad_file_app(tmp_path) -> Path:
    app = tmp_path / "app"
    app.mkdir()
    (Path(os.fsdecode(bytes(app) + b"/" + NOT_UTF8 + b".lad"))).write_text("XIC B3/0 OTE B3/1\n")
    return app


def test_a_program_file_name_that_is_not_utf8_is_shown_with_escapes(tmp_path, bad_file_app):
    p = softplc("check", "app", cwd=tmp_path, env=ENV, text=False)
    assert p.returncode == 0 and lines(p.stdout) == ["app: ok (1 program file, 1 rung)"], p
    p = softplc("run", "app", "--fresh", "--scans", "1", "--set", "B3/0=1", "--print", "B3/1", cwd=tmp_path, env=ENV,
                text=False)
    assert p.returncode == 0 and lines(p.stdout) == ["B3/1 = 1"], p
    p = softplc("watch", "app", "--fresh", "--scans", "1", "--snapshot", "view.txt", cwd=tmp_path, env=ENV, text=False)
    assert p.returncode == 0, p
    assert "B3/1" in (tmp_path / "view.txt").read_text(encoding="utf-8")
    # a problem in that file: located by the name with its byte escaped
    bad = Path(os.fsdecode(bytes(bad_file_app) + b"/" + NOT_UTF8 + b".lad"))
    bad.write_text("XIC B3/0 OTE B3/x\n")
    for command in (("check", "app"), ("run", "app", "--scans", "1"),
                    ("watch", "app", "--scans", "1", "--snapshot", "view.txt")):
        p = softplc(*command, cwd=tmp_path, env=ENV, text=False)
        assert p.returncode == 1, (command, p)
        assert lines(p.stderr)[0] == "app/\\xff.lad:1:17: expected a bit number but found 'x'", (command, p)


def test_an_app_directory_named_with_bytes_that_are_not_utf8(tmp_path):
    name = b"pump" + NOT_UTF8
    app = Path(os.fsdecode(bytes(tmp_path) + b"/" + name))
    app.mkdir()
    (app / "main.lad").write_text("MOV 40 N7:1\nMOV N7:[N7:1] N7:0\n")  # a major fault at the first scan
    p = softplc("check", name, cwd=tmp_path, env=ENV, text=False)
    assert p.returncode == 0 and lines(p.stdout) == ["pump\\xff: ok (1 program file, 2 rungs)"], p
    p = softplc("run", name, "--scans", "1", cwd=tmp_path, env=ENV, text=False)
    assert p.returncode == 3 and lines(p.stderr)[-1].startswith("softplc: pump\\xff: major fault 20"), p
    p = softplc("check", name + b"/nosuch.lad", cwd=tmp_path, env=ENV, text=False)
    assert p.returncode == 1 and lines(p.stderr)[0] == "pump\\xff/nosuch.lad: no such app directory or .lad file", p


def test_an_app_given_as_dot_is_named_after_its_directory(tmp_path):
    app = tmp_path / "pump"
    app.mkdir()
    (app / "main.lad").write_text("MOV 40 N7:1\nMOV N7:[N7:1] N7:0\n")
    (app / "softplc.toml").write_text('[display]\nsummary = { "N7:1" = "N7:1" }\n')
    p = softplc_here("check", ".", cwd=app)
    assert p.returncode == 0 and p.stdout.splitlines() == ["pump: ok (1 program file, 2 rungs)"], p
    p = softplc_here("run", ".", "--scans", "1", "--state", str(tmp_path / "state"), cwd=app)
    assert p.returncode == 3, p
    assert p.stdout.splitlines()[0] == "pump: 1 scans, 0.01 s simulated time", p
    assert p.stderr.splitlines()[-1].startswith("softplc: pump: major fault 20"), p
    sub = app / "sub"
    sub.mkdir()
    p = softplc_here("check", "..", cwd=sub)
    assert p.returncode == 0 and p.stdout.splitlines() == ["pump: ok (1 program file, 2 rungs)"], p
