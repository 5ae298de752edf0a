"""benchmarks/bench_scenarios.py runs: its scenarios pass on the apps they
drive and each loop does the scans it counts, so the yardstick cannot rot
when the runner or the apps change. Its figures are printed, not checked."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_quick_run_passes_its_scenarios_and_prints_each_loop(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_scenarios.py"), "--quick"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    for app in ("motor", "tank"):
        assert any(line.startswith(f"programs/{app}: engine alone") for line in lines), r.stdout
    assert sum(line.strip().startswith(("long ", "expects ", "dense ")) for line in lines) == 6, r.stdout
    assert lines[-1].startswith("worst runner / engine of long and expects"), r.stdout
