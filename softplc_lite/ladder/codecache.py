"""The code cache: a program loaded before loads without being
parsed, validated or compiled again.

An app's cache is one file, ``APP/.softplc/codecache.bin``, beside the
retentive snapshot. It holds, under a key, the validated program (as plain
data, ladder/treecodec.py), the warnings its checks gave, and each program
file's compiled blocks: their code objects (``marshal``) and a recipe for
every name the code uses
(a data file's array, a kernel, a bound or module instruction, a resolver),
from which the names are bound again to this run's table and machine.

The key is a SHA-256 of everything the cached result depends on: the text
of every program file and of the settings and module config files, the
module set (names and versions), softplc_lite's version, and Python's
version and marshal format (code objects are only valid in the Python that
made them). Any change of any of them is a different key: the cache is
rebuilt, never used stale. A cache file that cannot be read, does not
match, or is damaged is ignored (and replaced by the next successful
load); it never stops a run. docs/performance.md, "Code cache".

The file (little-endian)::

    "SPLCCODE"  u16 FORMAT  u16 reserved  u64 payload length
    32 bytes    SHA-256 of the key
    32 bytes    SHA-256 of the 52 bytes above and the payload
    payload     marshal of (tree, extra, warnings, compiled files)

The payload's code objects are run, so nothing in it is unmarshalled
before the digest over the whole file has matched: a flipped bit, a
truncated or padded file is seen as damaged and the program compiled from
its text (a marshal of code that decodes after a flip could run other
logic, or crash the interpreter). The digest finds damage; it does not
authenticate (docs/engine.md, "The code cache").
"""

from __future__ import annotations

import errno
import hashlib
import marshal
import struct
import sys
from pathlib import Path

from ..datatable.snapshot import write as write_atomically
from ..errors import FileAccessError, os_error_words
from ..gcpause import gc_paused
from ..textfile import CODE_CACHE, read_bytes
from . import treecodec
from .ast import Program, address_refs, instructions_of
from .blocks import CompiledFile, run_block

CACHE_FILE = "codecache.bin"
FORMAT = 3  # of the cache file; part of the key
MAGIC = b"SPLCCODE"
_HEAD = struct.Struct("<8sHHQ32s")  # magic, format, reserved, payload length, key
_DIGEST = 32  # SHA-256, after _HEAD


def softplc_version() -> str:
    # The package's own version (the same as pyproject.toml's, tests/test_cli_usage.py),
    # not the installed distribution's metadata: reading that costs 10 ms a start.
    from .. import __version__

    return __version__


def cache_key(parts) -> str:
    """The key of ``parts`` (name, text or bytes) with the versions that
    make compiled code valid."""
    h = hashlib.sha256()
    for item in (f"format {FORMAT}", f"softplc_lite {softplc_version()}", sys.version,
                 f"marshal {marshal.version}", sys.implementation.cache_tag or ""):
        h.update(item.encode() + b"\0")
    for name, data in parts:
        data = data.encode("utf-8", "surrogatepass") if isinstance(data, str) else data
        h.update(f"{name}\0{len(data)}\0".encode() + data)
    return h.hexdigest()


# -- what a compiled file becomes in the cache ------------------------------------------------


def _locators(rungs) -> dict[int, tuple]:
    """id(node) -> (rung, instruction number in walk order[, address number])."""
    out: dict[int, tuple] = {}
    for k, rung in enumerate(rungs):
        for i, ins in enumerate(instructions_of(rung.elements)):
            out[id(ins)] = (k, i)
            j = 0
            for op in ins.operands:
                for ref in address_refs(op):
                    out.setdefault(id(ref), (k, i, j))
                    j += 1
    return out


class _Nodes:
    """Locator -> node of one program file (each rung walked once, when asked)."""

    def __init__(self, rungs) -> None:
        self.rungs = rungs
        self.walked: dict[int, list] = {}

    def instruction(self, k: int, i: int):
        ins = self.walked.get(k)
        if ins is None:
            ins = self.walked[k] = instructions_of(self.rungs[k].elements)
        return ins[i]

    def __call__(self, loc):
        ins = self.instruction(loc[0], loc[1])
        if len(loc) == 2:
            return ins
        refs = [ref for op in ins.operands for ref in address_refs(op)]
        return refs[loc[2]]


def _functions() -> dict:
    """The module functions compiled code binds by name (recipe "function")."""
    from .semantics import lim
    from .templates import _block_check

    return {"_lim": lim, "_block_check": _block_check}


def export_file(compiled: CompiledFile, rungs, machine, table) -> tuple | None:
    """The cache's form of a compiled file, or None when some name in its
    code cannot be bound again from a recipe (then nothing is cached)."""
    from .expr import namespace

    fc = compiled.compiler
    loc = _locators(rungs)
    named = {name: (kind, key_id) for (key_id, kind), name in fc.named.items() if kind != "call"}
    functions = _functions()
    expr_names = set(namespace(machine))
    arrays = {id(f.data): f.number for f in table.files()}
    recipe = {}
    for name, value in fc.env.items():
        if name in named:
            kind, key_id = named[name]
            if key_id not in loc:
                return None
            recipe[name] = (kind, loc[key_id])
        elif name in ("_jsr", "_zone", "_m"):
            recipe[name] = (name,)
        elif name in expr_names:
            recipe[name] = ("expr",)
        elif name == "_calls":
            if any(id(ins) not in loc for ins in value):
                return None
            recipe[name] = ("calls", tuple(loc[id(ins)] for ins in value))
        elif id(value) in arrays:
            recipe[name] = ("array", arrays[id(value)])
        elif getattr(value, "__self__", None) is machine:
            recipe[name] = ("machine", value.__name__)
        elif functions.get(name) is value:
            recipe[name] = ("function",)
        else:
            return None
    blocks = []
    bounds = compiled.starts + [compiled.rung_count]
    for k, module in enumerate(compiled.modules):
        blocks.append((bounds[k], bounds[k + 1], module.co_filename, module))
    return (compiled.rung_count, compiled.has_mcr, tuple(blocks), recipe)


def import_file(data: tuple, program: Program, number: int, table, machine, jsr, zone,
                module_instance=None) -> CompiledFile:
    """A compiled file from its cached form, its names bound to this run's
    table, machine and instructions."""
    from .bound import BoundAccess
    from .expr import namespace
    from .instr import BOUND
    from .resolvers import resolver
    from . import compiler as C

    rung_count, has_mcr, blocks, recipe = data
    rungs = program.files[number].rungs
    node = _Nodes(rungs)
    expr = namespace(machine)
    functions = _functions()
    env: dict[str, object] = {}
    named: dict[tuple, str] = {}
    access = BoundAccess(table, machine)
    for name, (kind, *args) in recipe.items():
        if kind == "_jsr":
            env[name] = jsr
        elif kind == "_zone":
            env[name] = zone
        elif kind == "_m":
            env[name] = machine
        elif kind == "expr":
            env[name] = expr[name]
        elif kind == "array":
            env[name] = table.file(args[0]).data
        elif kind == "machine":
            env[name] = getattr(machine, args[0])
        elif kind == "function":
            env[name] = functions[name]
        elif kind == "calls":
            calls = [node(loc) for loc in args[0]]
            env[name] = calls
            for k, ins in enumerate(calls):
                named[(id(ins), "call")] = f"_calls[{k}]"
        else:
            target = node(args[0])
            named[(id(target), kind)] = name
            if kind == "bi":
                env[name] = BOUND[target.mnemonic].bind(target, access)
            elif kind == "tli":
                env[name] = module_instance(target, access)
            elif kind == "loc":
                env[name] = resolver(table, target.address)
            else:
                raise ValueError(f"unknown recipe {kind}")

    def make_compiler():
        fc = C._FileCompiler(table, machine, number, rungs, zone, jsr, module_instance)
        fc.env, fc.named = env, named  # the same objects the cached code uses
        return fc

    cf = CompiledFile(number, rung_count, has_mcr, make_compiler)
    for first, end, name, module in blocks:
        cf.add_compiled(run_block(module, env), first, end, name, module)
    return cf


# -- the file ----------------------------------------------------------------------------------


class CodeCache:
    """One app's cache file. ``load`` and ``save`` never raise for a
    problem with the file: a cache is an optimisation."""

    def __init__(self, directory: str | Path) -> None:
        self.path = Path(directory) / CACHE_FILE
        self.problem: str | None = None  # why the last load or save did not use the file

    @gc_paused
    def load(self, key: str) -> tuple[Program, list, dict] | None:
        """(program, warnings, compiled files' data) cached under ``key``, or
        None: no cache, another key or format (silently), or a file that is
        damaged or cannot be read (``problem`` says which)."""
        self.problem = None
        try:
            blob = read_bytes(self.path, CODE_CACHE)  # a regular file of a sane size, or refused
        except FileAccessError as e:
            if e.errno not in (errno.ENOENT, errno.ENOTDIR):  # no cache (yet): nothing to say
                self._ignored(e.words)
            return None
        if len(blob) < _HEAD.size + _DIGEST:
            return self._ignored(f"{len(blob)} bytes, too short for a code cache (damaged)")
        magic, fmt, _, length, stored_key = _HEAD.unpack_from(blob)
        if magic != MAGIC:  # damaged, or from a softplc_lite before this format: said, it is never expected
            return self._ignored("not a code cache this softplc_lite reads")
        if fmt != FORMAT or stored_key != _key_bytes(key):
            return None  # another softplc_lite's format or another program: replaced after this load, nothing wrong
        payload = memoryview(blob)[_HEAD.size + _DIGEST:]
        if len(payload) != length or _digest(blob, payload) != blob[_HEAD.size:_HEAD.size + _DIGEST]:
            return self._ignored("damaged code cache (its digest does not match its contents)")
        try:
            tree, extra, warnings, files = marshal.loads(payload)
            return treecodec.decode(tree, extra), list(warnings), files
        except Exception:  # a digest that matches: only a bug of ours can lead here
            return self._ignored("a code cache this softplc_lite cannot decode")

    def _ignored(self, why: str) -> None:
        self.problem = f"{self.path}: {why}; ignored, the program is compiled from its text and the cache rewritten"
        return None

    @gc_paused
    def save(self, key: str, program: Program, warnings: list, files: dict) -> bool:
        try:
            tree, extra = treecodec.encode(program)
            payload = marshal.dumps((tree, extra, tuple(warnings), files))
            if len(payload) + _HEAD.size + _DIGEST > CODE_CACHE.size:
                self.problem = f"{self.path}: code cache not written (over the {CODE_CACHE.size >> 20} MiB limit)"
                return False
            head = _HEAD.pack(MAGIC, FORMAT, 0, len(payload), _key_bytes(key))
            blob = b"".join((head, _digest(head, payload), payload))
            write_atomically(blob, self.path, durable=False)  # a cache: a lost write costs a compile
            return True
        except Exception as e:  # unwritable state directory, a tree the codec does not take: no cache
            self.problem = f"{self.path}: code cache not written ({os_error_words(e)})"
            return False


def _key_bytes(key: str) -> bytes:
    """The 32 bytes of the header that stand for ``key`` (cache_key's hex, or any text)."""
    return hashlib.sha256(key.encode("utf-8", "surrogatepass")).digest()


def _digest(head, payload) -> bytes:
    """SHA-256 of the header (its first _HEAD.size bytes) and the payload."""
    h = hashlib.sha256(memoryview(head)[:_HEAD.size])
    h.update(payload)
    return h.digest()


def export_engine(engine) -> dict | None:
    """A compiled engine's code in the cache's form (every program file, and
    the data table's layout the program makes), or None. Call it on a new
    engine, before a table is restored into it."""
    files = {}
    for number, (compiled, _) in engine.files.items():
        if not isinstance(compiled, CompiledFile):
            return None
        data = export_file(compiled, engine.program.files[number].rungs, engine.machine, engine.table)
        if data is None:
            return None
        files[number] = data
    layout = tuple((f.ftype.letter, f.number, f.size) for f in engine.table.files())
    return {"files": files, "layout": layout}


def apply_layout(table, layout) -> None:
    """Create and grow the table's files as the program's references did
    (Engine: reference_program) when the code was cached."""
    for letter, number, size in layout:
        table.create_file(letter, number, size)


__all__ = ["CodeCache", "apply_layout", "cache_key", "export_engine", "import_file"]
