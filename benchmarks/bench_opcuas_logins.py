"""OPCUAS under a flood of wrong passwords: how long a good client's
subscription goes without a notification while LOGINS clients try a wrong
password at once. A password is checked with scrypt (about 50 ms of CPU,
users.py); checked on the server's event loop, it stops everything that
loop serves for as long.

    python benchmarks/bench_opcuas_logins.py          # about 15 s; needs asyncua
    python benchmarks/bench_opcuas_logins.py --rounds 1

Processes: the runtime (modbus_server_runtime.py) with an app whose ladder
adds 1 to Count every 10 ms real-time scan, OPCUAS secured as by default
(SignAndEncrypt, one user); this process, one good client on an encrypted
anonymous session subscribed to Count (publishing every 10 ms, every scan
sampled), noting when each notification arrives; in a process of its own
(its RSA work must not delay this one's), LOGINS clients at once, each
asking for a session as the user with a wrong password (each refused
BadUserAccessDenied). Each round: QUIET_S with no login, then the flood;
the figures are the longest gap between notifications in each and the
notifications the flood window got of the scans in it.

Prints the figures; writes nothing (docs/opcuas.md quotes them).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _common as C  # noqa: F401 - sys.path: the project and tests/ (helpers)
from bench_modbus_server import RUNTIME, Child, stop_all
from bench_opcuas import register_entry_point

from helpers.modbus_peer import free_tcp_port

LOGINS = 20
QUIET_S = 1.5
SCAN_MS = 10
NS = "urn:softplc-lite:opcuas"
USER, PASSWORD = "operator", "a long passphrase"

FLOOD = r"""
import asyncio, json, logging, sys
sys.path[:0] = sys.argv[4:]
from asyncua import ua
from helpers.opcuas_security import secure_client
for name in ("asyncua",):
    logging.getLogger(name).setLevel(logging.CRITICAL)
port, logins, base = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]

async def one(i):
    client = await secure_client(f"opc.tcp://127.0.0.1:{port}/", f"{base}/client_cert.der", f"{base}/client_key.pem",
                                 user="operator", password=f"wrong guess {i}")
    try:
        await client.connect()
    except ua.UaStatusCodeError as e:
        return type(e).__name__
    except Exception as e:
        return repr(e)
    await client.disconnect()
    return "accepted"

async def main():
    loop = asyncio.get_running_loop()
    start = loop.time()
    print(json.dumps({"results": await asyncio.gather(*(one(i) for i in range(logins))),
                      "seconds": loop.time() - start}), flush=True)
asyncio.run(main())
"""


def write_app(work: Path) -> Path:
    from softplc_lite.tlm.opcuas.security import CertPaths, create_certificate
    from softplc_lite.tlm.opcuas.users import FILE_NAME, Users

    from helpers.opcuas_security import client_cert
    app = work / "app"
    app.mkdir()
    (app / "MODULES.LST").write_text("OPCUAS\n")
    (app / "OPCUAS.XML").write_text(f'<?xml version="1.0"?>\n<OpcUaServer port="{free_tcp_port()}" '
                                    f'maxSessions="{LOGINS + 5}" status="N40:0"/>\n')
    (app / "main.lad").write_text("SYMBOL Count N7:5\nADD N7:5 1 N7:5\n")
    (app / "softplc.toml").write_text(f"[scan]\nscan_ms = {SCAN_MS}\n")
    paths = CertPaths.for_app(app)
    create_certificate(paths.cert, paths.key, "urn:example:softplc-bench-server", "bench server", "localhost", 2)
    users = Users()
    users.set(USER, PASSWORD, can_write=True)
    users.save(app / FILE_NAME)
    client_cert(work)
    return app


def gaps_ms(times: list[float], start: float, end: float) -> float:
    inside = [t for t in times if start <= t <= end]
    edges = [start] + inside + [end]
    return 1000.0 * max(b - a for a, b in zip(edges, edges[1:]))


async def rounds(port: int, work: Path, n: int) -> list[dict]:
    from helpers.opcuas_security import secure_client

    times: list[float] = []
    loop = asyncio.get_running_loop()

    class Handler:
        def datachange_notification(self, node, value, data):
            times.append(loop.time())

    client = await secure_client(f"opc.tcp://127.0.0.1:{port}/", work / "client_cert.der", work / "client_key.pem")
    out = []
    async with client:
        ns = await client.get_namespace_index(NS)
        sub = await client.create_subscription(SCAN_MS, Handler())
        await sub.subscribe_data_change(client.get_node(f"ns={ns};s=Count"), queuesize=1000, sampling_interval=0)
        await asyncio.sleep(1.0)
        for _ in range(n):
            q0 = loop.time()
            await asyncio.sleep(QUIET_S)
            f0 = loop.time()
            proc = await asyncio.create_subprocess_exec(
                sys.executable, "-c", FLOOD, str(port), str(LOGINS), str(work), *sys.path,
                stdout=subprocess.PIPE)
            line = (await proc.stdout.readline()).decode()
            await proc.wait()
            f1 = loop.time()
            flood = json.loads(line)
            out.append({"quiet_max_gap_ms": gaps_ms(times, q0, f0), "flood_max_gap_ms": gaps_ms(times, f0, f1),
                        "flood_s": f1 - f0, "flood_notifications": sum(1 for t in times if f0 <= t <= f1),
                        "refused": flood["results"].count("BadUserAccessDenied"),
                        "other": [r for r in flood["results"] if r != "BadUserAccessDenied"]})
            print(json.dumps(out[-1]), flush=True)
        await sub.delete()
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    logging.getLogger("asyncua").setLevel(logging.CRITICAL)
    with tempfile.TemporaryDirectory(prefix="bench-opcuas-logins-") as tmp:
        work = Path(tmp)
        register_entry_point(work)
        app = write_app(work)
        runtime = Child([RUNTIME, str(app), str(work / "scans.json"), "0", "OPCUAS"], "the runtime (OPCUAS)")
        try:
            t0 = time.monotonic()
            out = asyncio.run(rounds(runtime.fields[0], work, args.rounds))
        finally:
            stop_all([runtime])
    med = sorted(r["flood_max_gap_ms"] for r in out)[len(out) // 2]
    print(f"{LOGINS} wrong-password logins at once: the good client's longest gap between notifications "
          f"{med:.0f} ms (median of {len(out)}; quiet: "
          f"{sorted(r['quiet_max_gap_ms'] for r in out)[len(out) // 2]:.0f} ms), in {time.monotonic() - t0:.0f} s")
    return 0 if all(r["refused"] == LOGINS for r in out) else 1


if __name__ == "__main__":
    sys.exit(main())
