"""Messages of the command line and the watch view's prompts name what the
user typed and say what was expected in words: ``--set StopOk=abc: I:0/1
holds a bit (0 or 1), got abc``, never a Python type name (str, float, dict)
nor raw errno text ("[Errno 2] No such file or directory")."""

from __future__ import annotations

import re
import shutil

import pytest

from helpers.cli import ROOT, softplc_here
from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions
from softplc_lite.watch.session import WatchOptions, WatchSession
from softplc_lite.watch.terminal import Controller

# Python's words that must not reach a user
LEAKS = re.compile(r"\((str|int|float|dict|list|bool|NoneType)\)|\bdict\b|ValueError|TypeError|\[Errno|Traceback")


@pytest.fixture
def apps(tmp_path):
    for name in ("motor", "loopback", "modbus_scada"):
        shutil.copytree(ROOT / "programs" / name, tmp_path / name, ignore=shutil.ignore_patterns(".softplc"))
    return tmp_path


def test_set_a_bit_to_text_names_the_option_the_bit_and_what_was_typed(apps):
    p = softplc_here("run", "motor", "--fresh", "--scans", "1", "--set", "StopOk=abc", cwd=apps)
    assert p.returncode == 1 and p.stdout == ""
    assert p.stderr == "error: --set StopOk=abc: I:0/1 holds a bit (0 or 1), got abc\n"


@pytest.mark.parametrize("item, said", [
    ("N7:0=abc", "--set N7:0=abc: N7:0 holds a 16-bit signed integer (-32768..32767), got abc"),
    ("N7:0=1.5", "--set N7:0=1.5: N7:0 holds a 16-bit signed integer (-32768..32767), got 1.5"),
    ('N7:0=""', '--set N7:0="": N7:0 holds a 16-bit signed integer (-32768..32767), got ""'),
    ("N7:0=[1,2]", "--set N7:0=[1,2]: N7:0 holds a 16-bit signed integer (-32768..32767), got [1, 2]"),
    ("F8:0=x", "--set F8:0=x: F8:0 holds a float (a number), got x"),
    ("T4:0=2", '--set T4:0=2: T4:0 is a timer element: give its members as an object, e.g. {"PRE": 10} '
               "(members EN TT DN PRE ACC), or one member (T4:0.PRE)"),
    ('T4:0={"PRE":"x"}', '--set T4:0={"PRE":"x"}: T4:0.PRE holds a 16-bit signed integer (-32768..32767), got x'),
    ("StopOkk=1", "--set StopOkk=1: StopOkk is neither an address nor a program symbol (did you mean StopOk?)"),
    ("N7:0", "--set N7:0: expected ADDR=VALUE, e.g. N7:0=5"),
])
def test_every_set_refusal_is_said_in_words(apps, item, said):
    p = softplc_here("run", "motor", "--fresh", "--scans", "1", "--set", item, cwd=apps)
    assert p.returncode == 1
    assert p.stderr == f"error: {said}\n"
    assert not LEAKS.search(p.stderr)


def test_a_missing_device_for_port_names_the_option_and_says_no_such_device(apps):
    missing = apps / "no-such-tty"
    p = softplc_here("run", "loopback", "--fresh", "--scans", "1", "--port", f"0={missing}", cwd=apps)
    assert p.returncode == 1
    assert p.stderr == (f"error: --port 0={missing}: cannot open {missing}: no such device "
                        "(set PORT_ERRORS=RETRY in [DRIVER] to run on without it)\n")
    p = softplc_here("run", "modbus_scada", "--fresh", "--scans", "1", "--port", f"1={missing}", cwd=apps)
    assert p.returncode == 1
    assert p.stderr.startswith(f"error: --port MODBMAST:1={missing}: cannot open {missing}: no such device ")


@pytest.mark.parametrize("device, words", [(".", "it is a directory, not a device"),
                                           ("motor/main.lad", "not a serial device")])
def test_a_device_that_is_no_serial_port_is_said_in_words(apps, device, words):
    p = softplc_here("run", "loopback", "--fresh", "--scans", "1", "--port", f"0={device}", cwd=apps)
    assert p.returncode == 1 and f"cannot open {device}: {words} " in p.stderr
    assert not LEAKS.search(p.stderr)


@pytest.fixture
def view(tmp_path):
    app_dir = tmp_path / "motor"
    shutil.copytree(ROOT / "programs" / "motor", app_dir, ignore=shutil.ignore_patterns(".softplc"))
    session = WatchSession(load_app(app_dir, state_dir=tmp_path / "state"),
                           WatchOptions(run=RunOptions(fresh=True), online=False))
    yield session, Controller(session)
    session.quit()


@pytest.mark.parametrize("typed, said", [
    ("Start=2", "force Start=2: expected ADDR=1 or ADDR=0, e.g. I:0/0=1"),
    ("N7:0=1", "force N7:0=1: only a direct bit address can be forced (e.g. O:0/0, B3/5, N7:0/3)"),
    ("Strat=1", "force Strat=1: Strat is neither an address nor a program symbol (did you mean Start?)"),
])
def test_the_force_prompt_names_what_was_typed_not_the_option(view, typed, said):
    session, control = view
    control._submit("F", typed)
    assert session.message == said
    assert session.forces.listed() == []


def test_the_set_and_unforce_prompts_say_a_symbol_problem_once(view):
    session, control = view
    control._submit("=", "Strat = 1")
    assert session.message == "set Strat: Strat is neither an address nor a program symbol (did you mean Start?)"
    control._submit("=", "N7:0 = abc")
    assert session.message == "set N7:0: N7:0 holds a 16-bit signed integer (-32768..32767), got abc"
    control._submit("U", "N7:0")
    assert session.message == "unforce N7:0: only a direct bit address is forced (e.g. O:0/0, B3/5, N7:0/3)"
    control._submit("F", "Start=1")
    assert session.message == "forced Start=1"
    control._submit("U", "Start")
    assert session.message == "force removed: Start"
