"""Peer soft PLCs on the same boolean logic (optional, for context): awlsim
(Siemens S7 STL) and pyrung (CLICK-PLC ladder in Python), both on PyPI,
against softplc's compiled engine, in one run.

    python benchmarks/bench_peers.py [--rungs 2000] [--blocks 9] [--venv /tmp/softplc-peers-venv]

The peers are installed (pinned versions, below) into their own venv,
created here on first use, never into the project's environment. Without
the network, or when an install fails, the script says so and exits 0.

The boolean benchmark program (ladder_programs.boolean_program, 2,000 rungs
by default: a peer scan is slow) is validated by softplc, turned into a
neutral rung tree and written as each peer's own language by peer_child.py
(which says how each instruction maps). Each peer runs in its own process
from the peers' venv; softplc runs in this one. Blocks of scans alternate
(softplc, peer), every scan with the next input row, and the figure is the
median of the per-block ratios peer / softplc. After the same scans each
peer's B3 must equal softplc's: a difference means the translation is wrong
and the figure is not comparable (printed).

Writes benchmarks/results/bench_peers.json; always exits 0.
"""

from __future__ import annotations

import argparse
import gc
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _common as C
import ladder_programs as L
import ladder_trees as T

from softplc_lite.ladder import parse_program, validate

PEERS = {"awlsim": "awlsim==0.77.1", "pyrung": "pyrung==0.15.2"}
VENV = Path("/tmp/softplc-peers-venv")
RUNGS = 2_000
BLOCKS, SCANS_PER_BLOCK = 9, 3


def ensure_venv(venv: Path) -> str | None:
    """The venv's python with the peers installed, or None (said why)."""
    python = venv / "bin" / "python"
    if not python.exists():
        made = subprocess.run([sys.executable, "-m", "venv", str(venv)], capture_output=True, text=True, check=False)
        if made.returncode != 0:
            print(f"skipped: cannot create the venv {venv}: {made.stderr.strip()[-300:]}")
            return None
    have = subprocess.run([str(python), "-c", "import awlsim, pyrung"], capture_output=True, text=True, check=False)
    if have.returncode != 0:
        print(f"installing {', '.join(PEERS.values())} into {venv} ...", flush=True)
        try:
            pip = subprocess.run([str(python), "-m", "pip", "install", "-q", *PEERS.values()],
                                 capture_output=True, text=True, timeout=900, check=False)
        except subprocess.TimeoutExpired:
            print("skipped: installing the peers took more than 15 minutes (no network?)")
            return None
        if pip.returncode != 0:
            tail = pip.stderr.strip().splitlines()[-3:]
            print("skipped: the peers could not be installed (no network?):\n  " + "\n  ".join(tail))
            return None
    return str(python)


def neutral(elements) -> list:
    """A validated series as peer_child.py's neutral tree."""
    out = []
    for el in elements:
        legs = getattr(el, "legs", None)
        if legs is not None:
            out.append(["BST", [neutral(leg) for leg in legs]])
            continue
        address = el.operands[0].address
        space = {"I": "I", "B": "B"}[address.type_letter]
        number = address.element * 16 + address.bit if address.element is not None else address.bit
        out.append([el.mnemonic, space, number])
    return out


def softplc_blocks(engine, scans: int) -> float:
    samples = []
    gc.collect()
    gc.disable()
    try:
        for _ in range(scans):
            t0 = time.perf_counter_ns()
            engine.scan()
            samples.append(time.perf_counter_ns() - t0)
    finally:
        gc.enable()
    return statistics.median(samples)


def run_peer(python: str, peer: str, doc_path: Path, program, blocks: int, scans: int) -> dict:
    engine = L.make_engine(program)
    child = T.Child(C.REPO, "", doc_path, argv=[python, str(T.HERE / "peer_child.py"), peer, str(doc_path)])
    try:
        loaded = child.read()
        child.ask(f"scan {L_WARMUP}")
        softplc_blocks(engine, L_WARMUP)
        ours, theirs = [], []
        for _ in range(blocks):
            ours.append(softplc_blocks(engine, scans))
            theirs.append(statistics.median(child.ask(f"scan {scans}")["ns"]))
        words = child.ask("words")["b3"]
    finally:
        child.close()
    same = words == list(engine.table.file(3).data)
    ratios = [p / s for p, s in zip(theirs, ours)]
    n = loaded["instructions"]
    return {"peer_ns_per_instruction": round(statistics.median(theirs) / n, 1),
            "softplc_ns_per_instruction": round(statistics.median(ours) / n, 1),
            "peer_over_softplc": round(statistics.median(ratios), 1),
            "range": [round(min(ratios), 1), round(max(ratios), 1)],
            "b3_equal_after_same_scans": same, "peer_load_s": round(loaded["load"]["total_s"], 1)}


L_WARMUP = 2


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rungs", type=int, default=RUNGS)
    ap.add_argument("--blocks", type=int, default=BLOCKS)
    ap.add_argument("--scans", type=int, default=SCANS_PER_BLOCK, help="scans per block")
    ap.add_argument("--venv", type=Path, default=VENV)
    ap.add_argument("--json")
    args = ap.parse_args()
    python = ensure_venv(args.venv)
    if python is None:
        return 0
    program = validate(parse_program(L.boolean_program(args.rungs, L.SEED), "<boolean>"))
    rungs, instructions = L.count_instructions(program)
    doc = {"rungs": [neutral(r.elements) for r in program.files[2].rungs], "instructions": instructions,
           "b3_words": list(L.initial_table(L.SEED).file(3).data), "input_rows": L.input_rows(L.SEED)}
    figures: dict = {"rungs": rungs, "instructions": instructions, "blocks": args.blocks,
                     "scans_per_block": args.scans, "versions": PEERS, "peers": {}}
    with tempfile.TemporaryDirectory(prefix="bench_peers_") as tmp:
        doc_path = Path(tmp) / "program.json"
        doc_path.write_text(json.dumps(doc), encoding="utf-8")
        print(f"the boolean program, {rungs:,} rungs, {instructions:,} instructions; blocks of {args.scans} scans, "
              f"{args.blocks} per peer, alternating with softplc's compiled engine (this tree)", flush=True)
        for peer in PEERS:
            try:
                r = run_peer(python, peer, doc_path, program, args.blocks, args.scans)
            except (T.ChildFailed, ValueError) as exc:
                print(f"  {peer:7}: could not run the same logic: {exc}")
                figures["peers"][peer] = {"error": str(exc)}
                continue
            figures["peers"][peer] = r
            print(f"  {peer:7}: {r['peer_ns_per_instruction']:8.0f} ns/instruction, softplc "
                  f"{r['softplc_ns_per_instruction']:.0f}: {peer} / softplc = {r['peer_over_softplc']:.1f}x "
                  f"({r['range'][0]}-{r['range'][1]}); B3 equal after the same scans: "
                  f"{r['b3_equal_after_same_scans']}"
                  + ("" if r["b3_equal_after_same_scans"] else "  <-- the translation differs: not comparable"),
                  flush=True)
    C.save_figures("bench_peers", figures, False, args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
