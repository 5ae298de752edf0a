"""The compiler's generated code: only validated tokens reach it, and its
line table maps faults back to instructions."""

from __future__ import annotations

import ast

from helpers.generated_code import ALLOWED, names_in

from softplc_lite.ladder import Engine, load_text


HOSTILE = r'''
SYMBOL __import__ N7:0
SYMBOL os B3/0
SYMBOL exec_ N7:1
DATA ST12 1 = "\"); import os; os.system(\"echo pwned"
XIC os MOV __import__ exec_
CPT N7:2 "__import__ + exec_ * 2"
CMP "exec_ > 0" OTE B3/1
'''


def test_program_text_never_reaches_generated_code():
    engine = Engine(load_text(HOSTILE, "hostile.lad"))
    source = engine.files[2][0].source
    names = names_in(source)
    assert all(ALLOWED.match(n) for n in names), sorted(n for n in names if not ALLOWED.match(n))
    assert "__import__" not in source and "os" not in names and "pwned" not in source
    # Strings in generated code are only subscript keys of the bindings table.
    strings = {n.value for n in ast.walk(ast.parse(source)) if isinstance(n, ast.Constant) and isinstance(n.value, str)}
    assert strings <= {n for n in names}


def test_every_example_program_compiles_to_allowed_names(tmp_path):
    from softplc_lite.app import load_app

    from helpers.shipped_apps import copy_programs

    copy_programs(tmp_path)  # a server's port found free
    for app_dir in sorted((tmp_path / "programs").iterdir()):
        if not any(app_dir.glob("*.lad")):
            continue
        app = load_app(app_dir)
        engine = Engine(app.program, modules=app.modules)
        try:
            for compiled, _ in engine.files.values():
                assert all(ALLOWED.match(n) for n in names_in(compiled.source)), app_dir
        finally:
            engine.close()  # the modules' ports


def test_line_table_names_the_failing_instruction():
    from softplc_lite.ladder import Mode

    text = "MOV 9 N7:0\nBST XIC B3/0 NXB XIO B3/0 BND ADD 1 2 N7:2 MOV N7:[N7:0] N7:1 OTE B3/1\n"
    engine = Engine(load_text(text, "t.lad"))
    compiled = engine.files[2][0]
    # The contact branch is one generated line, mapped to its first contact.
    assert {ins.mnemonic for ins in compiled.line_table.values()} == {"MOV", "XIC", "ADD", "OTE"}
    assert "c = (w3_0 & 1 or not w3_0 & 1)" in compiled.source  # B3:0 held in a local, XIC as a truthy word & mask
    engine.set_mode(Mode.RUN)
    engine.scan()
    fault = engine.fault
    assert fault is not None and (fault.file, fault.rung) == (2, 1)
    assert fault.instruction == "MOV N7:[N7:0] N7:1 at t.lad:2:44"
    assert engine.table.read("N7:2") == 3  # the instruction before it ran; the data is kept
