"""The plug-in door: a third-party TLM, defined here, installed as a real
distribution (a dist-info folder with an entry point) on sys.path, found,
enabled by MODULES.LST and run by both executors, exactly as COMGENIUS is."""

from __future__ import annotations

import os
import shutil
import sys
import textwrap
from pathlib import Path

import pytest

from softplc_lite.app import AppError, load_app
from softplc_lite.cli import main
from softplc_lite.datatable import DataTable
from softplc_lite.ladder import Mode
from softplc_lite.ladder.engine import Engine
from softplc_lite.ladder.fmt import format_program
from softplc_lite.tlm import ModuleError, installed, load_modules

from helpers.cli import softplc, softplc_here
from helpers.apps import make_app

DEMO_MODULE = '''
"""A third-party TLM for the tests: PULSE and TWICE, a config file, hooks."""
from softplc_lite.ladder.errors import LadderError
from softplc_lite.ladder.instructions import InstructionSpec, K, OperandSpec
from softplc_lite.tlm import TLM, ControlledInstruction
from softplc_lite.tlm.api import find_file

PULSE = InstructionSpec("PULSE", "finish after N true scans", (OperandSpec("control", K.CONTROL),
                        OperandSpec("scans", K.PRESET)), True, 0, "DEMO")
TWICE = InstructionSpec("TWICE", "dest = 2 * gain * source", (OperandSpec("source", K.INT_SOURCE),
                        OperandSpec("dest", K.WORD)), True, 0, "DEMO")


class Pulse(ControlledInstruction):
    def __init__(self, ctx):
        super().__init__(ctx.operands[0])
        self.scans = ctx.operands[1].constant
        self.left = 0

    def start(self, ctl):
        self.left = self.scans
        return self.step(ctl)

    def step(self, ctl):
        self.left -= 1
        ctl.pos = self.scans - self.left
        if self.left <= 0:
            ctl.len = self.scans
            ctl.finish(error=self.scans > 3)
            return True
        return False


class Demo(TLM):
    name = "DEMO"
    config_file = "DEMO.LST"

    def __init__(self):
        self.gain = 1
        self.events = []

    def configure(self, app_dir):
        path = find_file(app_dir, self.config_file) if app_dir else None
        if path is not None:
            self.gain = int(path.read_text().strip())
        return ["demo says hello"]

    def instructions(self):
        return [PULSE, TWICE]

    def check(self, instr):
        if instr.mnemonic == "PULSE" and instr.operands[1].value > 3:
            return [LadderError(instr.operands[1].pos, "PULSE longer than 3 scans ends with ER")]
        return []

    def create(self, instr, ctx):
        if instr.mnemonic == "PULSE":
            return Pulse(ctx)
        src, dest = ctx.operands

        def twice(c):
            if c:
                d, i, _ = dest.location()
                d[i] = 2 * self.gain * src.value()
            return c
        return twice

    def on_input(self, engine):
        self.events.append(("input", engine.scans))

    def on_output(self, engine, enabled):
        self.events.append(("output", enabled))

    def on_mode(self, engine, old, new):
        self.events.append(("mode", old.name, new.name))

    def close(self):
        self.events.append(("close",))
'''


@pytest.fixture
def demo_path(tmp_path, monkeypatch) -> Path:
    """Install the DEMO module as a distribution found on sys.path."""
    site = tmp_path / "site"
    (site / "demo_tlm").mkdir(parents=True)
    (site / "demo_tlm" / "__init__.py").write_text(DEMO_MODULE)
    info = site / "demo_tlm-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: demo-tlm\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[softplc_lite.tlms]\nDEMO = demo_tlm:Demo\n")
    monkeypatch.syspath_prepend(str(site))
    yield site
    sys.modules.pop("demo_tlm", None)


def demo_app(tmp_path: Path, program: str, modules: str | None = "demo ; the test module\n", **files: str) -> Path:
    """TMP_PATH/app running PROGRAM with MODULES as its MODULES.LST (none
    for None); FILES named as they are."""
    listed = {} if modules is None else {"MODULES.LST": modules}
    return make_app(tmp_path / "app", textwrap.dedent(program), **listed, **files)


PROGRAM = """\
    XIC B3/0 PULSE R6:0 2
    TWICE(N7:0,N7:1);
    XIC B3/1 BST TWICE N7:0 N7:2 NXB PULSE R6:1 5 BND
"""


def test_installed_modules_come_from_entry_points(demo_path):
    names = installed()
    assert list(names) == sorted(names)
    assert {"COMGENIUS", "DEMO"} <= set(names)
    assert names["DEMO"].value == "demo_tlm:Demo"


def test_a_module_installed_or_removed_while_the_process_lives_is_seen_at_the_next_look(tmp_path, monkeypatch):
    # installed() keeps its answer while the import path and its directories are unchanged
    site = tmp_path / "site"
    site.mkdir()
    monkeypatch.syspath_prepend(str(site))
    assert "LATE" not in installed()
    _install(site, "LATE", "from softplc_lite.tlm import TLM\nclass Late(TLM):\n    pass\n", "late:Late")
    assert installed()["LATE"].value == "late:Late"
    shutil.rmtree(site / "late-1.0.dist-info")
    assert "LATE" not in installed() and "COMGENIUS" in installed()


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_a_third_party_module_runs_through_the_same_door(demo_path, tmp_path, executor):
    app = load_app(demo_app(tmp_path, PROGRAM, **{"DEMO.LST": "3\n"}))
    assert [m.name for m in app.modules] == ["DEMO"]
    assert app.warnings[0] == "demo says hello"
    assert "main.lad:3:45: PULSE longer than 3 scans ends with ER" in app.warnings[1]
    demo = app.modules[0]
    table = DataTable()
    engine = Engine(app.program, table, app.settings, executor=executor, modules=app.modules)
    table.write("N7:0", 7)
    engine.set_mode(Mode.RUN)
    engine.scan()
    assert table.read("N7:1") == 42  # 2 * gain 3 * 7, from the config file
    assert table.read("N7:2") == 0
    table.write("B3/0", 1)
    seen = []
    for _ in range(4):
        engine.scan()
        r = table.read("R6:0")
        seen.append((r["EN"], r["DN"], r["ER"], r["POS"]))
    # starts on the transition, done on its second true scan, then holds until the rung goes false
    assert seen == [(1, 0, 0, 1), (1, 1, 0, 2), (1, 1, 0, 2), (1, 1, 0, 2)]
    table.write("B3/0", 0)
    engine.scan()
    assert table.read("R6:0")["EN"] == 0 and table.read("R6:0")["DN"] == 0
    engine.close()
    assert demo.events[0] == ("mode", "PROGRAM", "RUN")
    assert ("input", 0) in demo.events and ("output", True) in demo.events
    assert demo.events[-1] == ("close",)


def test_a_false_rung_before_completion_gives_no_completion(demo_path, tmp_path):
    app = load_app(demo_app(tmp_path, "XIC B3/0 PULSE R6:0 3\n"))
    table = DataTable()
    engine = Engine(app.program, table, modules=app.modules)
    engine.set_mode(Mode.RUN)
    table.write("B3/0", 1)
    engine.scan()
    table.write("B3/0", 0)
    engine.scan()
    table.write("B3/0", 1)
    engine.run(2)
    r = table.read("R6:0")
    assert (r["EN"], r["DN"], r["POS"]) == (1, 0, 2)  # restarted: 2 of 3 scans, not done
    engine.scan()
    assert table.read("R6:0")["DN"] == 1


def test_module_errors_set_er_with_dn(demo_path, tmp_path):
    app = load_app(demo_app(tmp_path, "PULSE R6:0 4\n"))
    table = DataTable()
    Engine(app.program, table, modules=app.modules, executor="reference")
    engine = Engine(app.program, table, modules=app.modules)
    engine.set_mode(Mode.RUN)
    engine.run(4)
    r = table.read("R6:0")
    assert (r["DN"], r["ER"], r["LEN"]) == (1, 1, 4)


def test_test_mode_tells_output_hooks_outputs_are_disabled(demo_path, tmp_path):
    app = load_app(demo_app(tmp_path, "TWICE 1 N7:1\n"))
    engine = Engine(app.program, modules=app.modules)
    engine.set_mode(Mode.TEST)
    engine.scan()
    assert ("output", False) in app.modules[0].events


def test_fmt_prints_module_instructions_in_both_styles(demo_path, tmp_path):
    app = load_app(demo_app(tmp_path, PROGRAM))
    mnemonic = format_program(app.source_program, "mnemonic")
    assert "XIC B3/1 BST TWICE N7:0 N7:2 NXB PULSE R6:1 5 BND" in mnemonic
    assert "XIC(B3/1)[TWICE(N7:0,N7:2),PULSE(R6:1,5)];" in format_program(app.source_program, "neutral")


def test_check_validates_module_operands_with_location(demo_path, tmp_path, capsys):
    demo_app(tmp_path, "PULSE N7:0 2\nTWICE N7:0\n")
    assert main(["check", str(tmp_path / "app")]) == 1
    err = capsys.readouterr().err
    assert "main.lad:1:7: PULSE operand 1 (control) must be control element (R), not N7:0 (a word)" in err
    assert "main.lad:2:1: TWICE takes 2 operands (TWICE source dest), got 1" in err


def test_check_and_run_print_module_warnings(demo_path, tmp_path, capsys):
    demo_app(tmp_path, "PULSE R6:0 9\n")
    assert main(["check", str(tmp_path / "app")]) == 0
    captured = capsys.readouterr()
    assert "app: ok (1 program file, 1 rung, module DEMO, 2 warnings)" in captured.out
    assert "main.lad:1:12: PULSE longer than 3 scans ends with ER" in captured.err


def test_modules_lst_is_case_insensitive_with_comments(demo_path, tmp_path):
    app = load_app(demo_app(tmp_path, "TWICE 1 N7:1\n", modules="; modules\n\n  Demo   ; the demo\n"))
    assert [m.name for m in app.modules] == ["DEMO"]


def test_a_module_not_installed_is_an_error_listing_the_installed_ones(demo_path, tmp_path):
    with pytest.raises(AppError) as e:
        load_app(demo_app(tmp_path, "TWICE 1 N7:1\n", modules="demo\nMODBSLAV\n"))
    assert "MODULES.LST:2: module MODBSLAV is not installed (installed modules: COMGENIUS, DEMO, ENIPS, MODBMAST, MODBTCPS, OPCUAS)" \
        in str(e.value)


def test_a_module_named_twice_is_an_error(demo_path, tmp_path):
    with pytest.raises(AppError, match=r"MODULES.LST:2: module DEMO is named twice \(first on line 1\)"):
        load_app(demo_app(tmp_path, "TWICE 1 N7:1\n", modules="DEMO\ndemo\n"))


def test_instructions_of_a_module_not_enabled_are_unknown_with_a_hint(demo_path, tmp_path):
    with pytest.raises(AppError) as e:
        load_app(demo_app(tmp_path, "TWICE 1 N7:1\n", modules=None))
    assert ("main.lad:1:1: unknown instruction 'TWICE' (TWICE is an instruction of the DEMO module: "
            "add DEMO to the app's MODULES.LST)") in str(e.value)


def test_without_modules_lst_an_app_has_no_modules(tmp_path):
    app = load_app(demo_app(tmp_path, "XIC B3/0 OTE B3/1\n", modules=None))
    assert app.modules == [] and app.warnings == []


def _install(site: Path, name: str, source: str, entry: str, requires: tuple[str, ...] = ()) -> None:
    pkg = site / name.lower()
    pkg.mkdir(parents=True, exist_ok=True)
    (pkg / "__init__.py").write_text(source)
    info = site / f"{name.lower()}-1.0.dist-info"
    info.mkdir()
    requirements = "".join(f"Requires-Dist: {r}\n" for r in requires)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name.lower()}\nVersion: 1.0\n{requirements}")
    (info / "entry_points.txt").write_text(f"[softplc_lite.tlms]\n{name} = {entry}\n")


def test_a_module_claiming_a_builtin_mnemonic_is_refused(tmp_path, monkeypatch):
    site = tmp_path / "site"
    _install(site, "CLASH", textwrap.dedent('''
        from softplc_lite.ladder.instructions import InstructionSpec
        from softplc_lite.tlm import TLM
        class Clash(TLM):
            def instructions(self):
                return [InstructionSpec("MOV", "my move", (), True, 0, "CLASH")]
    '''), "clash:Clash")
    monkeypatch.syspath_prepend(str(site))
    app = demo_app(tmp_path, "XIC B3/0 OTE B3/1\n", modules="CLASH\n")
    with pytest.raises(ModuleError, match="MOV of module CLASH is already an instruction of the built-in"):
        load_modules(app)
    sys.modules.pop("clash", None)


def test_a_module_that_fails_to_import_is_named_with_its_package(tmp_path, monkeypatch):
    site = tmp_path / "site"
    _install(site, "BROKEN", "raise RuntimeError('no license key')\n", "broken:Broken")
    monkeypatch.syspath_prepend(str(site))
    app = demo_app(tmp_path, "XIC B3/0 OTE B3/1\n", modules="; modules\nBROKEN\n")
    with pytest.raises(ModuleError) as e:
        load_modules(app)
    assert str(e.value) == (f"{app / 'MODULES.LST'}:2: module BROKEN (package broken) failed to load: an error in "
                            "its code (no license key) (python -c 'import broken' shows where)")
    sys.modules.pop("broken", None)


# A library a module needs and that is not installed: (how the module gets it, what it says)
MISSING = {
    "imported": ("import not_a_module_anywhere\n", (), "needs the Python package 'not_a_module_anywhere', which "
                 "is not installed (install it into the Python that runs softplc)"),
    "required": ("from not_a_module_anywhere import thing\n", ("not-a-module-anywhere>=2,<3",),
                 "needs the Python package 'not_a_module_anywhere', which is not installed "
                 "(pip install 'not-a-module-anywhere>=2,<3')"),
    # imported later (in a process of its own, on first use), so declared in ``libraries``
    "declared": ("from softplc_lite.tlm import TLM\nclass Lib(TLM):\n    libraries = ('not_a_module_anywhere',)\n",
                 ("not_a_module_anywhere==1.0",), "needs the Python package 'not_a_module_anywhere', which is not "
                 "installed (pip install not_a_module_anywhere==1.0)"),
    "a part of one": ("import softplc_lite.not_a_module_anywhere\n", (), "needs "
                      "'softplc_lite.not_a_module_anywhere', which the installed softplc-lite "),
}


@pytest.mark.parametrize("case", MISSING)
def test_a_module_whose_library_is_missing_says_which_in_one_located_line(case, tmp_path):
    # Through the real command, as a user meets it: one line naming the
    # package, at the MODULES.LST line that enables the module; the exit
    # code of a config error; no traceback; nothing started.
    source, requires, said = MISSING[case]
    site = tmp_path / "site"
    _install(site, "NEEDY", source, "needy:Lib", requires)
    app = demo_app(tmp_path, "XIC B3/0 OTE B3/1\n", modules="; the test module\nneedy\n")
    # a process: the module comes in at the start of a fresh interpreter, from PYTHONPATH, as a user's does
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]))
    for command in (["run", str(app), "--fresh", "--scans", "3"], ["check", str(app)]):
        proc = softplc(*command, env=env, cwd=tmp_path)
        assert proc.returncode == 1, proc.stderr
        assert "Traceback" not in proc.stderr and proc.stdout == ""
        lines = proc.stderr.splitlines()
        assert len(lines) == (1 if command[0] == "run" else 2), proc.stderr  # check adds its count line
        assert lines[0].startswith(f"{app / 'MODULES.LST'}:2: module NEEDY {said}"), lines[0]


def test_modbtcps_in_an_install_without_pymodbus_says_so_at_load(tmp_path):
    # A broken install: no process can import pymodbus (a sitecustomize hides
    # it from this one and from the server process it would start).
    # MODBTCPS imports pymodbus only in its server process, and declares it
    # in ``libraries`` so that the load finds it missing, before any process
    # starts and before MODBTCPS.XML's address and port are looked at.
    hide = tmp_path / "hide"
    hide.mkdir()
    (hide / "sitecustomize.py").write_text("import sys\nsys.modules['pymodbus'] = None\n")
    app = tmp_path / "hmi_server"
    shutil.copytree(Path(__file__).resolve().parent.parent / "programs" / "hmi_server", app,
                    ignore=shutil.ignore_patterns(".softplc"))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(hide), os.environ.get("PYTHONPATH", "")]))
    proc = softplc("run", str(app), "--fresh", "--scans", "100", "--print", "Level", env=env, cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr
    assert proc.stderr.splitlines() == [
        f"{app / 'MODULES.LST'}:2: module MODBTCPS needs the Python package 'pymodbus', which is not installed "
        "(pip install 'pymodbus<3.17,>=3.16.1')"]
    assert proc.stdout == ""


def test_the_softplc_command_runs_a_third_party_module(demo_path, tmp_path):
    app = demo_app(tmp_path, PROGRAM)
    proc = softplc_here("run", str(app), "--fresh", "--scans", "3", "--set", "N7:0=5", "--set", "B3/0=1",
                        "--print", "N7:1", "--print", "R6:0.POS")  # demo_path: DEMO on this process's import path
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines() == ["N7:1 = 10", "R6:0.POS = 2"]
    assert "warning: demo says hello" in proc.stderr


def test_a_config_file_of_a_module_not_enabled_is_pointed_out(tmp_path):
    app = demo_app(tmp_path, "XIC B3/0 OTE B3/1\n", modules=None, **{"comgenius.lst": "not read\n", "notes.txt": ""})
    assert load_app(app).warnings == [f"{app / 'comgenius.lst'}: COMGENIUS is not enabled (add COMGENIUS to "
                                      "MODULES.LST), so this file is not read"]
    (app / "comgenius.lst").unlink()
    assert load_app(app).warnings == []
