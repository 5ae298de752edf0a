"""Building MODBMAST apps for tests: an app directory with MODULES.LST,
MODBMAST.XML and a ladder file, run by a Runner on simulated time, and ways
to look at what went over its ports with exact times."""

from __future__ import annotations

import itertools
from collections import deque
from pathlib import Path

from helpers.apps import make_app
from softplc_lite.app import load_app
from softplc_lite.ladder.engine import Mode
from softplc_lite.ports.wire import char_time_ns
from softplc_lite.runner import RunOptions, Runner

_names = itertools.count()


def link() -> str:
    """A fresh sim:// link name."""
    return f"mbm{next(_names)}"


def write_app(directory: Path, xml: str, ladder: str = "XIC B3/0 OTE B3/1\n", modules: str = "MODBMAST\n",
              extra: dict[str, str] | None = None) -> Path:
    return make_app(directory, ladder, MODULES_LST=modules, MODBMAST_XML=xml, **(extra or {}))


def serial_xml(ports: str, root: str = "") -> str:
    return f"<ModbusSerial{(' ' + root) if root else ''}>\n{ports}\n</ModbusSerial>\n"


class Apps:
    """Makes runners and closes them after the test."""

    def __init__(self, tmp_path: Path) -> None:
        self.tmp_path = tmp_path
        self.runners: list[Runner] = []

    def __call__(self, xml: str, ladder: str = "XIC B3/0 OTE B3/1\n", scan_ms: int = 10, run: bool = True,
                 executor: str = "compiled", options: RunOptions | None = None, **files) -> Runner:
        d = write_app(self.tmp_path / f"app{len(self.runners)}", xml, ladder, extra=files or None)
        opts = options or RunOptions(fresh=True, scan_ms=scan_ms, executor=executor)
        r = Runner(load_app(d), opts)
        self.runners.append(r)
        for m in r.engine.modules:  # keep all the traffic, not only the watch view's last frames
            for port in m.serial_ports():
                port.history = deque(maxlen=100_000)
        if run:
            r.engine.set_mode(Mode.RUN)
        return r

    def close(self) -> None:
        for r in self.runners:
            r.engine.close()


def modbmast(r: Runner):
    return next(m for m in r.engine.modules if m.name == "MODBMAST")


def driver(r: Runner, num: int = 1):
    return next(d for d in modbmast(r).drivers if d.config.num == num)


def status(r: Runner, num: int, slave: int):
    return modbmast(r).status[num][slave]


def traffic(r: Runner, num: int = 1, direction: str = "TX") -> list[tuple[int, bytes]]:
    """(time in ns, frame) of what the port sent (or received), in order."""
    port = driver(r, num).port
    return [(round(t * 1e6), bytes(data)) for t, d, data in port.history if d == direction]


def scans(r: Runner, n: int) -> None:
    for _ in range(n):
        r.engine.scan()


def char(baud: int, bits: int = 8, parity: str = "N", stop: int = 1) -> int:
    return char_time_ns(baud, bits, parity, stop)


def slave_silence(char_ns: int) -> int:
    """3.5 character times, as the simulated slave measures them."""
    return (7 * char_ns + 1) // 2
