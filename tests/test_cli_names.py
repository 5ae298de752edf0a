"""How the softplc command names apps and files (docs/cli.md, "Names"):
a file or directory name that is not UTF-8 (Linux allows any bytes but
"/" and NUL) is shown with backslash escapes, never an encoding error; an
app given as "." is named after the directory it stands for. The real
command in subprocesses, its output read as bytes."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

NOT_UTF8 = b"\xff"  # a byte no UTF-8 text holds
# A UTF-8 locale, whose standard output refuses what cannot be encoded.
ENV = dict(os.environ, LC_ALL="C.UTF-8", PYTHONIOENCODING="utf-8")


def softplc(cwd: Path, *args: str | bytes) -> subprocess.CompletedProcess[bytes]:
    return subprocess.run([sys.executable, "-m", "softplc_lite", *args], cwd=cwd, capture_output=True,
                          timeout=60, env=ENV, check=False)


def lines(data: bytes) -> list[str]:
    return data.decode("utf-8").splitlines()  # the output is UTF-8 itself


@pytest.fixture(name="bad_file_app")
def fixture_bad_file_app(tmp_path) -> Path:
    app = tmp_path / "app"
    app.mkdir()
    (Path(os.fsdecode(bytes(app) + b"/" + NOT_UTF8 + b".lad"))).write_text("XIC B3/0 OTE B3/1\n")
    return app


def test_a_program_file_name_that_is_not_utf8_is_shown_with_escapes(tmp_path, bad_file_app):
    p = softplc(tmp_path, "check", "app")
    assert p.returncode == 0 and lines(p.stdout) == ["app: ok (1 program file, 1 rung)"], p
    p = softplc(tmp_path, "run", "app", "--fresh", "--scans", "1", "--set", "B3/0=1", "--print", "B3/1")
    assert p.returncode == 0 and lines(p.stdout) == ["B3/1 = 1"], p
    p = softplc(tmp_path, "watch", "app", "--fresh", "--scans", "1", "--snapshot", "view.txt")
    assert p.returncode == 0, p
    assert "B3/1" in (tmp_path / "view.txt").read_text(encoding="utf-8")
    # a problem in that file: located by the name with its byte escaped
    bad = Path(os.fsdecode(bytes(bad_file_app) + b"/" + NOT_UTF8 + b".lad"))
    bad.write_text("XIC B3/0 OTE B3/x\n")
    for command in (("check", "app"), ("run", "app", "--scans", "1"),
                    ("watch", "app", "--scans", "1", "--snapshot", "view.txt")):
        p = softplc(tmp_path, *command)
        assert p.returncode == 1, (command, p)
        assert lines(p.stderr)[0] == "app/\\xff.lad:1:17: expected a bit number but found 'x'", (command, p)


def test_an_app_directory_named_with_bytes_that_are_not_utf8(tmp_path):
    name = b"pump" + NOT_UTF8
    app = Path(os.fsdecode(bytes(tmp_path) + b"/" + name))
    app.mkdir()
    (app / "main.lad").write_text("MOV 40 N7:1\nMOV N7:[N7:1] N7:0\n")  # a major fault at the first scan
    p = softplc(tmp_path, "check", name)
    assert p.returncode == 0 and lines(p.stdout) == ["pump\\xff: ok (1 program file, 2 rungs)"], p
    p = softplc(tmp_path, "run", name, "--scans", "1")
    assert p.returncode == 3 and lines(p.stderr)[-1].startswith("softplc: pump\\xff: major fault 20"), p
    p = softplc(tmp_path, "check", name + b"/nosuch.lad")
    assert p.returncode == 1 and lines(p.stderr)[0] == "pump\\xff/nosuch.lad: no such app directory or .lad file", p


def test_an_app_given_as_dot_is_named_after_its_directory(tmp_path):
    app = tmp_path / "pump"
    app.mkdir()
    (app / "main.lad").write_text("MOV 40 N7:1\nMOV N7:[N7:1] N7:0\n")
    (app / "softplc.toml").write_text('[display]\nsummary = { "N7:1" = "N7:1" }\n')
    p = softplc(app, "check", ".")
    assert p.returncode == 0 and lines(p.stdout) == ["pump: ok (1 program file, 2 rungs)"], p
    p = softplc(app, "run", ".", "--scans", "1", "--state", str(tmp_path / "state"))
    assert p.returncode == 3, p
    assert lines(p.stdout)[0] == "pump: 1 scans, 0.01 s simulated time", p
    assert lines(p.stderr)[-1].startswith("softplc: pump: major fault 20"), p
    sub = app / "sub"
    sub.mkdir()
    p = softplc(sub, "check", "..")
    assert p.returncode == 0 and lines(p.stdout) == ["pump: ok (1 program file, 2 rungs)"], p
