"""benchmarks/bench_opcuas.py runs in its tiny mode: both servers answer
every read with 100 numbers, both send the data changes of the words the
ladder changes every scan, both take 100 monitored items (1,000 in the measured runs), and the
runtime ends in RUN. Its figures are printed and written, not checked
against times."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

pytest.importorskip("asyncua")
pytestmark = pytest.mark.timeout(300)


def test_the_tiny_run_serves_both_servers_and_writes_its_figures(tmp_path):
    out = tmp_path / "bench_opcuas.json"
    r = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_opcuas.py"), "--tiny", "--json", str(out)],
                       cwd=tmp_path, capture_output=True, text=True, timeout=280)
    assert r.returncode == 0, r.stdout + r.stderr  # 1: a client error, a refusal, the runtime faulted
    fig = json.loads(out.read_text(encoding="utf-8"))
    assert fig["variables"] > 2000 and 0 < fig["subscribed"] <= 100
    for kind in ("reads K=1", "reads K=4", "notifications"):
        row = fig["table"][kind]
        assert min(row["opcuas"]) > 0 and min(row["asyncua"]) > 0 and row["ratio"], kind
        assert row["scans"][0] > 0, "the runtime scanned in the window"
    for name in ("opcuas", "asyncua"):
        memory = fig["memory"][name]
        assert memory["items"] == 100 and memory["refused"] == 0, memory  # the tiny run's count
    assert fig["state"]["mode"] == "RUN" and fig["state"]["fault"] is None
    assert "data changes of" in r.stdout and "memory a monitored item" in r.stdout
