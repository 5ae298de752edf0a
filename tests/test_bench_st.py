"""benchmarks/bench_st.py runs: its ST routine, the same logic as ladder and
the straight-line Python end every scan with the same values, so the
yardstick measures the same work when the translator or the engine change.
Its figures are printed, not checked."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_quick_run_finds_the_three_renderings_agree_and_prints_each(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_st.py"), "--quick", "--units", "3"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr  # 2: the renderings differ or one faulted
    out = r.stdout
    assert "3 units of the logic" in out and "the three renderings agree after" in out
    for line in ("ST ", "ladder ", "Python ", "target: "):
        assert any(x.strip().startswith(line) for x in out.splitlines()), line

