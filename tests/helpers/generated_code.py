"""What the compiler's generated code may name: the tests that hold the
generated code to it (test_compiler, test_jsr_params) share one list, so a
new kind of generated name is allowed in one place."""

from __future__ import annotations

import ast
import re

# Every name generated code may use: data arrays, temporaries, rung
# functions, bound kernels, module (TLM) instruction instances and
# expression helpers.
ALLOWED = re.compile(
    r"^(f\d+|w\d+_\d+|z|_m|_block|_d\d+|_i\d+|_m\d+|b\d+|o\d+|r\d+|c|_env|_factory|_loc\d+|_tli\d+|_bi\d+|_jsr|_zone|_x_div|_x_mod|_x_pow|_int|"
    r"_fn_[A-Z]+|_[a-z]+(?:_[a-z]+)*|abs|bool)$"
)


def names_in(source: str) -> set[str]:
    """Every name, function name and argument name in ``source``."""
    tree = ast.parse(source)
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    names |= {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}
    names |= {a.arg for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) for a in n.args.args}
    return names
