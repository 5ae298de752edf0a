"""The fuzz oracle: run softplc on a case and say what is wrong.

``check_case(case, root)`` writes the case's files under ``root``, runs its
commands through the real entry point ``softplc_lite.cli.main(argv)``
in-process (``run_main``: output captured, a watchdog for hangs) or as the
real ``softplc`` command (``run_command``), and returns the findings:

========================  ==============================================================
class                     what the oracle saw
========================  ==============================================================
``exception``             an exception escaped ``main()`` (in-process), or a
                          ``Traceback`` in the command's output
``internal-error``        exit status 4 or "internal error" in the output: the
                          last-resort handler caught an exception
``exit-code``             an exit status outside the documented 0, 1, 2, 3, 130
``fault-255``             "major fault 255" (an internal error contained as a fault)
``check-run``             ``check`` accepted the app but ``run --scans 3 --fresh``
                          refused it (exit 1 or 2)
``fmt-reparse``           ``fmt``'s output does not parse back (same style)
``fmt-idempotent``        formatting ``fmt``'s output again gives other text
``hang``                  a command ran past its time limit
``unlocated``             exit 1 with an error line naming the fuzzed file (a
                          line-oriented one: .lad, .toml, .LST, .XML, trace) as a
                          path without ``:line``
``unencodable-output``    standard output a real UTF-8 stdout cannot write (a lone
                          surrogate): the real command would die on it
``dump-roundtrip``        ``datatable ... --dump`` printed JSON that does not load
                          back to the same dump
``snapshot-roundtrip``    ``datatable ... --save S`` wrote a snapshot that does not
                          load back to the same table
========================  ==============================================================

A case with a ``driver`` (``DRIVERS``: files changed between commands,
signals to a real run, requests to a live Modbus TCP server) is run by it
instead, with the classes of its module (``fuzz_files``, ``fuzz_signals``,
``fuzz_protocol``) besides these.

A finding's ``signature`` (command, class, exception type and last frame,
or a normalised message) is what ``tools/fuzz.py`` de-duplicates on.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

from helpers.fuzz_inputs import Case

EXIT_CODES = {0, 1, 2, 3, 130}
# Errors about a file as a whole, which have no line to give.
WHOLE_FILE = re.compile(r"does not exist|no events for port|no such file|is empty|is a directory", re.IGNORECASE)


@dataclass
class Result:
    argv: list[str]
    code: int | None
    out: str = ""
    err: str = ""
    exception: str | None = None  # "TypeName: message"
    traceback: str | None = None
    seconds: float = 0.0
    hung: bool = False
    how: str = "in-process"


@dataclass
class Finding:
    cls: str
    signature: str
    argv: list[str]
    detail: str
    kind: str = ""
    result: Result | None = field(default=None, repr=False)

    def __str__(self) -> str:
        return f"[{self.cls}] {self.signature}\n  softplc {' '.join(_quote(a) for a in self.argv)}\n  {self.detail}"


def _quote(arg: str) -> str:
    short = arg if len(arg) <= 120 else arg[:100] + f"...<{len(arg)} chars>"
    return short if re.fullmatch(r"[\w./:=#\-\[\]{}@%+,]+", short) else repr(short)


# -- running ----------------------------------------------------------------------------


def _exit_code(e: SystemExit, err: io.StringIO) -> int:
    if e.code is None:
        return 0
    if isinstance(e.code, int):
        return e.code
    print(e.code, file=err)  # what the interpreter does with sys.exit("message")
    return 1


_pending = {"signals": 0, "armed": False}


def _on_sigint(signum, frame) -> None:
    """SIGINT while run_main runs: the watchdog's interrupt ends the command
    (KeyboardInterrupt) or, arriving late, is swallowed; a real Ctrl-C still
    interrupts."""
    if _pending["signals"] > 0:
        _pending["signals"] -= 1
        if not _pending["armed"]:
            return
    raise KeyboardInterrupt


def _interrupt_main() -> None:
    _pending["signals"] += 1
    try:
        signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)
    except (AttributeError, ValueError, OSError):  # pragma: no cover - not POSIX
        import _thread
        _thread.interrupt_main()


def run_main(argv: list[str], timeout: float = 20.0) -> Result:
    """``softplc_lite.cli.main(argv)`` in this process, stdout and stderr
    captured. After ``timeout`` seconds a watchdog thread sends SIGINT to the
    main thread: the command ends as on Ctrl-C and the result says ``hung``."""
    from softplc_lite.cli import main

    in_main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGINT, _on_sigint) if in_main_thread else None
    out, err = io.StringIO(), io.StringIO()
    lock = threading.Lock()
    state = {"done": False, "fired": False}

    def fire() -> None:
        with lock:
            if state["done"]:
                return
            state["fired"] = True
            if in_main_thread:
                _interrupt_main()

    timer = threading.Timer(timeout, fire)
    timer.daemon = True
    result = Result(list(argv), None)
    start = time.monotonic()
    _pending["armed"] = True
    timer.start()
    try:
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                try:
                    result.code = main(list(argv))
                except SystemExit as e:
                    result.code = _exit_code(e, err)
                finally:
                    with lock:
                        state["done"] = True
                        _pending["armed"] = False
        except KeyboardInterrupt:
            if not state["fired"]:
                raise  # a real Ctrl-C
            result.exception = "KeyboardInterrupt: (the watchdog's)"
        except BaseException as e:  # noqa: BLE001 - that is the point
            result.exception = f"{type(e).__name__}: {str(e)[:300]}"
            result.traceback = traceback.format_exc()[-4000:]
    finally:
        timer.cancel()
        with lock:
            state["done"] = True
            _pending["armed"] = False
        if state["fired"]:
            time.sleep(0.05)  # a late watchdog SIGINT lands here, and is swallowed
        if in_main_thread:
            signal.signal(signal.SIGINT, previous)
    result.seconds = time.monotonic() - start
    result.hung = state["fired"]
    result.out, result.err = out.getvalue(), err.getvalue()
    return result


def softplc_command() -> list[str]:
    exe = shutil.which("softplc")
    return [exe] if exe else [sys.executable, "-m", "softplc_lite"]


def run_command(argv: list[str], timeout: float = 30.0) -> Result:
    """The real ``softplc`` command in a subprocess (its own session, killed
    whole on timeout); standard input is /dev/null."""
    start = time.monotonic()
    env = dict(os.environ, COLUMNS="100")
    proc = subprocess.Popen(softplc_command() + list(argv),
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True, env=env)
    hung = False
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        hung = True
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
    r = Result(list(argv), proc.returncode, out.decode("utf-8", "replace"), err.decode("utf-8", "replace"),
               seconds=time.monotonic() - start, hung=hung, how="subprocess")
    if "Traceback (most recent call last)" in r.err:
        last = [line for line in r.err.strip().splitlines() if line and not line.startswith(" ")]
        r.exception = last[-1][:300] if last else "Traceback"
        r.traceback = r.err[-4000:]
    return r


# -- judging ----------------------------------------------------------------------------------


def normalise(text: str, root: str | None = None) -> str:
    """A message with the variable parts blanked, for de-duplication."""
    if root:
        text = text.replace(root, "<d>")
    text = re.sub(r"/tmp/[^\s:'\"]+", "<tmp>", text)
    text = re.sub(r"'[^']*'|\"[^\"]*\"", "Q", text)
    text = re.sub(r"\d+", "N", text)
    return text.strip()[:100]


def _last_frame(tb: str | None) -> str:
    if not tb:
        return "?"
    frames = re.findall(r'File "([^"]+)", line (\d+), in (\S+)', tb)
    for path, _line, func in reversed(frames):
        if "softplc_lite" in path:
            return f"{path.split('softplc_lite/')[-1]}:{func}"
    if frames:
        path, _line, func = frames[-1]
        return f"{Path(path).name}:{func}"
    return "?"


def _first_error(err: str) -> str:
    for line in err.splitlines():
        if line.startswith("error:"):
            return line.strip()
    for line in err.splitlines():
        if line.strip() and not line.startswith("warning"):
            return line.strip()
    return err.strip()[:200]


class CaseRun:
    """The commands of one case, run on its directory ``{d}`` by ``runner``:
    each result kept, and judged by the common oracle (without the location
    property: these kinds judge their own files)."""

    def __init__(self, case: Case, root: str, timeout: float, runner) -> None:
        self.case, self.root, self.timeout, self.runner = case, root, timeout, runner
        self.findings: list[Finding] = []
        self.results: list[Result] = []

    def do(self, argv: list[str]) -> Result:
        r = self.runner([a.replace("{d}", self.root) for a in argv], self.timeout)
        self.results.append(r)
        self.findings.extend(judge(r, self.case, self.root, False))
        return r


def judge(r: Result, case: Case, root: str, check_location: bool = True) -> list[Finding]:
    """Findings about one command's result: (a), (b), (e), fault 255, (f)."""
    cmd = r.argv[0] if r.argv else "?"
    found: list[Finding] = []

    def add(cls: str, sig: str, detail: str) -> None:
        found.append(Finding(cls, f"{cls}:{cmd}:{sig}", r.argv, detail, case.kind, r))

    if r.hung:
        add("hang", case.kind, f"no answer within the time limit ({r.seconds:.1f} s)")
        return found
    if r.exception:
        etype = r.exception.split(":", 1)[0]
        add("exception", f"{etype}@{_last_frame(r.traceback)}", r.exception)
    elif "Traceback (most recent call last)" in r.out + r.err:
        add("exception", "Traceback-in-output", _first_error(r.err))
    internal = re.search(r"softplc: internal error: (\w+)", r.err)
    if r.code == 4 or internal:
        etype = internal.group(1) if internal else "?"
        add("internal-error", f"{r.code}:{etype}", f"exit status {r.code}: {_first_error(r.err)[:300]}")
    elif r.code is not None and r.code not in EXIT_CODES and not r.exception:
        add("exit-code", str(r.code), f"exit status {r.code}: {_first_error(r.err)[:300]}")
    if r.code == 130:
        add("exit-code", "130-without-interrupt", "exit 130 but nobody pressed Ctrl-C")
    fault = re.search(r"major fault 255[^\n]*", r.out + r.err)
    if fault:
        # "major fault 255: program file 2, rung 0, MOV ... at x.lad:1:1: <what>": keep <what>, blanked
        what = re.sub(r"^major fault 255:( program file \d+, rung \d+,)?", "", fault.group(0))
        what = re.sub(r".*\.lad:\d+:\d+: ", "", what)
        add("fault-255", normalise(what, root)[:60], fault.group(0)[:300])
    try:  # stderr writes with backslashreplace; stdout is strict
        r.out.encode("utf-8")
    except UnicodeEncodeError as e:
        add("unencodable-output", "stdout", f"stdout holds {r.out[e.start:e.end]!r}: a UTF-8 stdout cannot write it")
    if check_location and r.code == 1 and case.target and case.located == "line" and not r.exception:
        name = Path(case.target).name
        # A line naming the file as a path (".../name" or "name" first), not in passing ("the app's MODULES.LST").
        as_path = re.compile(r"(?:^|[/\\]|error: )" + re.escape(name) + r"(?!:\d)", re.IGNORECASE)
        located = re.compile(re.escape(name) + r":\d+", re.IGNORECASE)
        # A line located elsewhere (main.lad:39:41: ... port 0 is not in [PORTS] of .../COMGENIUS.LST) is located.
        elsewhere = re.compile(r"^(?:warning: |error: )?\S+:\d+(?::\d+)?: ")
        bad = [ln for ln in r.err.splitlines()
               if as_path.search(ln) and not located.search(ln) and not WHOLE_FILE.search(ln)
               and not elsewhere.match(ln)]
        if bad:
            words = re.search(r"\bline \d+|at end of document", bad[0])
            what = "" if words else ":" + normalise(bad[0].split(name, 1)[1], root)[:12]
            add("unlocated", f"{case.kind}:{'line-in-words' if words else 'no-line'}{what}",
                f"an error about {name} without path:line: {bad[0][:300]}")
    return found


def check_case(case: Case, root: Path, timeout: float = 20.0, runner=run_main,
               fmt_styles: tuple[str, ...] = ("mnemonic", "neutral")) -> tuple[list[Finding], list[Result]]:
    """Write ``case`` under ``root``, run it, apply every property."""
    root = Path(root)
    case.write(root)
    if case.driver:
        return DRIVERS[case.driver](case, root, timeout, runner)
    d = str(root)
    findings: list[Finding] = []
    results: list[Result] = []

    def do(argv: list[str], located: bool = True) -> Result:
        r = runner([a.replace("{d}", d) for a in argv], timeout)
        results.append(r)
        findings.extend(judge(r, case, d, located))
        return r

    if case.app:
        app = "{d}/" + case.app
        checked = do(["check", app])
        if checked.code == 0:  # (c) check ok => run loads
            ran = do(["run", app, "--scans", "3", "--fresh", "--state", "{d}/state-c"])
            # A device that is not there is the machine's business, not the app's (a sim:// or loop://
            # URL is the app's: check could have read it).
            absent = re.search(r"cannot open (?!sim://|loop://)", ran.err)
            if ran.code not in (0, 3) and not ran.hung and not ran.exception and not absent:
                findings.append(Finding("check-run", f"check-run:run:{normalise(_first_error(ran.err), d)}",
                                        ran.argv, f"check said ok, run exits {ran.code}: {_first_error(ran.err)[:300]}",
                                        case.kind, ran))
    for argv in case.commands:
        r = do(argv)
        if argv[0] == "datatable" and "--dump" in argv and r.code == 0 and not r.hung:
            dump_roundtrip(r, root, do, findings, case)
        if argv[0] == "datatable" and "--save" in argv and r.code == 0 and not r.hung:
            saved = argv[argv.index("--save") + 1]
            loads = [a for a in argv[1:] if not a.startswith("--") and a != saved and argv[argv.index(a) - 1] != "--print"]
            before = do(["datatable", *loads, "--dump"], located=False)
            after = do(["datatable", saved, "--dump"], located=False)
            if before.code == 0 and (after.code != 0 or after.out != before.out) and not after.hung:
                findings.append(Finding("snapshot-roundtrip", f"snapshot-roundtrip:datatable:{after.code}", after.argv,
                                        f"the saved snapshot does not load back to the same table (exit {after.code}: "
                                        f"{_first_error(after.err)[:200]})", case.kind, after))
    for rel in case.fmt:
        for style in fmt_styles:
            fmt_roundtrip(root / rel, style, do, findings, case)
    return findings, results


def _drivers() -> dict:
    from helpers import fuzz_files
    from helpers import fuzz_protocol
    from helpers import fuzz_signals

    return {"files": fuzz_files.run_files_case, "signals": fuzz_signals.run_signals_case,
            "modbus_tcp": fuzz_protocol.run_modbus_case}


class _Drivers(dict):
    def __missing__(self, key):
        self.update(_drivers())
        return dict.__getitem__(self, key)


DRIVERS = _Drivers()


def dump_roundtrip(first: Result, root: Path, do, findings: list[Finding], case: Case) -> None:
    """(g): the JSON ``datatable --dump`` prints loads back to the same table
    (docs/datatable.md: export then import gives back the same table)."""
    path = root / "roundtrip.json"
    try:
        path.write_text(first.out, encoding="utf-8")
    except UnicodeEncodeError:
        return  # reported by judge as unencodable-output
    second = do(["datatable", str(path), "--dump"], located=False)
    if second.hung or second.exception:
        return
    if second.code != 0:
        findings.append(Finding("dump-roundtrip", f"dump-roundtrip:datatable:{normalise(_first_error(second.err), str(root))}",
                                second.argv, f"the dump does not load back: {_first_error(second.err)[:300]}",
                                case.kind, second))
    elif second.out != first.out:
        a, b = first.out.splitlines(), second.out.splitlines()
        k = next((i for i, (x, y) in enumerate(zip(a, b)) if x != y), min(len(a), len(b)))
        findings.append(Finding("dump-roundtrip", "dump-roundtrip:datatable:changed", second.argv,
                                f"dump, load, dump differs: {a[k][:150] if k < len(a) else '<end>'!r} became "
                                f"{b[k][:150] if k < len(b) else '<end>'!r}", case.kind, second))


def fmt_roundtrip(path: Path, style: str, do, findings: list[Finding], case: Case) -> None:
    """(d): fmt's output parses back and is a fixed point."""
    first = do(["fmt", str(path), "--style", style])
    if first.code != 0:
        return
    again_dir = path.parent.parent / f"fmt-{style}"
    again_dir.mkdir(exist_ok=True)
    for p in path.parent.iterdir():  # the module list and configs: the same instruction set
        if p.is_file() and p.suffix.lower() != ".lad":
            shutil.copyfile(p, again_dir / p.name)
    again = again_dir / "main.lad"
    try:
        again.write_text(first.out, encoding="utf-8")
    except UnicodeEncodeError:
        return  # reported by judge as unencodable-output
    second = do(["fmt", str(again), "--style", style], located=False)
    if second.hung or second.exception:
        return
    if second.code != 0:
        findings.append(Finding("fmt-reparse", f"fmt-reparse:fmt:{style}:{normalise(_first_error(second.err), str(again_dir))}",
                                second.argv, f"fmt --style {style} printed text that does not parse: "
                                             f"{_first_error(second.err)[:300]}", case.kind, second))
    elif second.out != first.out:
        a, b = first.out.splitlines(), second.out.splitlines()
        k = next((i for i, (x, y) in enumerate(zip(a, b)) if x != y), min(len(a), len(b)))
        findings.append(Finding("fmt-idempotent", f"fmt-idempotent:fmt:{style}", second.argv,
                                f"line {k + 1}: {a[k][:150] if k < len(a) else '<end>'!r} became "
                                f"{b[k][:150] if k < len(b) else '<end>'!r}", case.kind, second))
