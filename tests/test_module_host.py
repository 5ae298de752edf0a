"""The engine hosts a plug-in module through ladder.host.Module alone: a
module built on it (not on tlm.TLM) owns an instruction, gets its attach
options and its driver hooks, and is closed; the runner's module_engine
routes the run's options to the module that asks for them."""

from __future__ import annotations

import pytest

from softplc_lite.ladder import load_text
from softplc_lite.ladder.engine import Engine
from softplc_lite.ladder.host import Mode, Module, overrides
from softplc_lite.ladder.instructions import InstructionSet
from softplc_lite.ladder.specs import InstructionSpec, K, OperandSpec


class Counter(Module):
    """CNTR N: adds 1 to the word N each true scan; counts its hook calls."""

    name = "COUNTER"

    def __init__(self) -> None:
        self.options = None
        self.inputs = 0
        self.modes: list[tuple[Mode, Mode]] = []
        self.closed = False

    def instructions(self):
        return [InstructionSpec("CNTR", "count", (OperandSpec("word", K.WORD),), True, module=self.name)]

    def attach(self, engine, options):
        self.options = dict(options)
        return ["counter attached"]

    def instance(self, engine, instr):
        address = instr.operands[0].address
        table = engine.table

        def run(c: bool) -> bool:
            if c:
                table.write(address, table.read(address) + 1)
            return c
        return run

    def on_input(self, engine) -> None:
        self.inputs += 1

    def on_mode(self, engine, old, new) -> None:
        self.modes.append((old, new))

    def close(self) -> None:
        self.closed = True


def program(module: Module):
    return load_text("XIC B3/0 CNTR N7:0", instructions=InstructionSet(module.instructions()))


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_a_module_on_the_host_protocol_alone_runs_its_instruction(executor):
    module = Counter()
    engine = Engine(program(module), executor=executor, modules=[module], module_options={"COUNTER": {"k": 1}})
    assert module.options == {"k": 1} and engine.module_warnings == ["counter attached"]
    engine.table.write("B3/0", 1)
    engine.set_mode(Mode.RUN)
    engine.run(3)
    assert engine.table.read("N7:0") == 3 and module.inputs == 3
    assert module.modes == [(Mode.PROGRAM, Mode.RUN)]
    engine.close()
    assert module.closed


def test_only_the_hooks_a_module_overrides_are_called():
    module = Counter()
    assert overrides(module, "on_input") and overrides(module, "on_mode")
    assert not overrides(module, "on_output")
    engine = Engine(program(module), modules=[module])
    assert engine.input_hooks == [module.on_input] and engine.output_hooks == []
    assert module.options == {}  # no run options: attach gets an empty mapping


def test_module_engine_gives_each_module_its_run_options_and_the_recorder(tmp_path):
    from softplc_lite.runner import module_engine
    from softplc_lite.tlm import TLM

    class CounterTLM(Counter, TLM):  # the runner's policy asks what a TLM knows (its port claims)
        pass

    module = CounterTLM()
    trace = tmp_path / "run.trace"
    engine = module_engine(program(module), modules=[module],
                           module_options={"replay": None, "record": str(trace), "ports": {}})
    try:
        assert module.options["ports"] == {} and module.options["recorder"] is engine.recorder
        assert engine.recorder is not None and engine.recorder.path == str(trace)
    finally:
        engine.close()
    assert engine.recorder is None and trace.exists()
