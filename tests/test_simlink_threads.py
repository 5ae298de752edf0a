"""sim:// links opened, used and closed from many threads at once: the
process's link registry (ports/simlink.py) and device kinds
(ports/simdevices.py) are shared by every thread."""

from __future__ import annotations

import sys
import threading

import pytest
import serial

import softplc_lite.ports.urlhandler  # noqa: F401  (sim:// for serial_for_url)
from softplc_lite.ports import simdevices, simlink
from softplc_lite.ports.simdevices import EchoDevice

THREADS = 6
ROUNDS = 40


@pytest.fixture(autouse=True)
def threads_switch_often():
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-5)  # every registry operation interleaved with the others
    yield
    sys.setswitchinterval(interval)


def _run(target, count: int) -> list[BaseException]:
    errors: list[BaseException] = []

    def body(k: int) -> None:
        try:
            target(k)
        except BaseException as e:  # reported by the test, not lost in the thread
            errors.append(e)

    threads = [threading.Thread(target=body, args=(k,), daemon=True) for k in range(count)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert not any(t.is_alive() for t in threads)
    return errors


def _port(url: str, now: list[int]):
    port = serial.serial_for_url(url, baudrate=38400)
    port.set_clock(lambda: now[0])
    return port


def test_device_links_of_one_name_opened_from_many_threads_each_answer_their_own_port():
    start = threading.Barrier(THREADS)

    def echo_rounds(k: int) -> None:
        start.wait(10)
        for r in range(ROUNDS):
            now = [0]
            port = _port("sim://tc_shared?device=echo", now)
            try:
                payload = f"{k}:{r}".encode()
                port.write(payload)
                now[0] = 50_000_000
                assert port.read(100) == payload
            finally:
                port.close()

    assert _run(echo_rounds, THREADS) == []
    assert "tc_shared" not in simlink.link_names()


def test_threads_racing_for_the_ends_of_one_link_get_exactly_two():
    start = threading.Barrier(THREADS)
    opened: list[list] = [[] for _ in range(ROUNDS)]
    refused: list[int] = [0] * ROUNDS
    counted = threading.Lock()

    def race(k: int) -> None:
        for r in range(ROUNDS):
            start.wait(10)
            try:
                port = _port(f"sim://tc_race_{r}", [0])
            except serial.SerialException as e:
                assert "already has two ends" in str(e)
                with counted:
                    refused[r] += 1
            else:
                with counted:
                    opened[r].append(port)
            start.wait(10)
            if k == 0:  # the two ends talk, then close
                a, b = opened[r]
                a.write(b"ping")
                b._clock = lambda: 10_000_000
                assert b.read(10) == b"ping"
                a.close()
                b.close()
            start.wait(10)

    assert _run(race, THREADS) == []
    assert [len(ends) for ends in opened] == [2] * ROUNDS
    assert refused == [THREADS - 2] * ROUNDS
    assert not any(name.startswith("tc_race_") for name in simlink.link_names())


def test_a_registry_of_its_own_keeps_its_links_apart_from_the_process():
    own = simlink.LinkRegistry()
    a = own.open_port_end("tc_own")
    b = own.open_port_end("tc_own")
    try:
        assert own.link_names() == ["tc_own"]
        assert "tc_own" not in simlink.link_names()
        a.configure(38400, 8, "N", 1, False)
        a.write(b"x", 0)
        assert b.read(1, 10_000_000) == b"x"
        with pytest.raises(serial.SerialException, match="already has two ends"):
            own.open_port_end("tc_own")
        c = simlink.open_port_end("tc_own")  # the process's link of that name is another
        c.close()
    finally:
        a.close()
        b.close()
    assert own.link_names() == []


def test_device_kinds_registered_from_many_threads_keep_one_factory_each():
    kinds = [f"tc_kind_{k}" for k in range(4)]
    factories = {kind: [lambda options: EchoDevice(), lambda options: EchoDevice()] for kind in kinds}
    start = threading.Barrier(THREADS)
    won: list[tuple[str, int]] = []
    lost = []

    def register(k: int) -> None:
        start.wait(10)
        for kind in kinds:
            which = k % 2
            try:
                simdevices.register_device(kind, factories[kind][which])
                won.append((kind, which))
            except ValueError:
                lost.append(kind)

    try:
        assert _run(register, THREADS) == []
        for kind in kinds:
            winner = simdevices.DEVICES[kind]
            assert {which for name, which in won if name == kind} == {factories[kind].index(winner)}
            assert lost.count(kind) == THREADS - sum(1 for name, _ in won if name == kind)
    finally:
        for kind in kinds:
            simdevices.DEVICES.pop(kind, None)
