"""A child process of bench_peers.py, run by the peers' own venv (never the
project's environment): the boolean benchmark program on one peer soft PLC.

    /tmp/softplc-peers-venv/bin/python benchmarks/peer_child.py PEER PROGRAM_JSON

PEER is ``awlsim`` (Siemens S7 STL, awlsim's CPU) or ``pyrung`` (a CLICK-PLC
ladder DSL in Python). PROGRAM_JSON (written by bench_peers.py) holds the
rungs as a neutral tree -- ``["XIC"|"XIO"|"OTE"|"OTL"|"OTU", "I"|"B", bit]``
or ``["BST", [leg, ...]]``, bit = 16 x word + bit of I:0..7 or B3 -- the
initial B3 words and the 64 input rows. Same protocol as ladder_child.py's
``serve``: one JSON line after loading, then ``scan N`` (N scans, each with
the next input row written first, each timed) and ``words`` (B3 as signed
16-bit words, to compare with softplc's table after the same scans).

The mapping, instruction by instruction (same PLC semantics: contacts in
series AND, branch legs OR, OTE writes the rung condition, OTL/OTU only when
it is true, every write seen by the next rung):

- awlsim: XIC/XIO -> A/AN, a branch -> A( leg O leg ... ), OTE/OTL/OTU ->
  = / S / R; B3 bit n is M n//8.n%8 (so the M bytes are B3's words, low
  byte first) and input bit n is I n//8.n%8; one OB1.
- pyrung: one Bool tag per bit; a rung is ``rung(*contacts)`` with XIO as
  ``~tag`` and a branch as ``Or(And(...), ...)``, the coils in its body as
  out/latch/reset; the inputs through ``plc.patch`` before each ``step``.
"""

from __future__ import annotations

import gc
import json
import sys
import time


def reply(doc: dict) -> None:
    sys.stdout.write(json.dumps(doc) + "\n")
    sys.stdout.flush()


def words_from_bytes(raw: bytes | bytearray, count: int) -> list[int]:
    out = []
    for k in range(count):
        w = raw[2 * k] | raw[2 * k + 1] << 8
        out.append(w - 0x10000 if w & 0x8000 else w)
    return out


def bytes_from_words(words: list[int]) -> bytes:
    return b"".join((w & 0xFFFF).to_bytes(2, "little") for w in words)


# -- awlsim -------------------------------------------------------------------------------


def awl_series(elements: list, out: list[str]) -> None:
    for el in elements:
        if el[0] == "BST":
            out.append("A(")
            for k, leg in enumerate(el[1]):
                if k:
                    out.append("O")
                awl_series(leg, out)
            out.append(")")
        else:
            op, space, bit = el
            operand = f"{'M' if space == 'B' else 'I'} {bit // 8}.{bit % 8}"
            if op in ("XIC", "XIO"):
                out.append(f"{'A' if op == 'XIC' else 'AN'} {operand}")
            else:
                out.append(f"{ {'OTE': '=', 'OTL': 'S', 'OTU': 'R'}[op] } {operand}")


def awl_rung(rung: list, out: list[str]) -> None:
    contacts = [el for el in rung if el[0] in ("XIC", "XIO") or el[0] == "BST" and not has_coil(el)]
    coils = rung[len(contacts):]
    if contacts != rung[:len(contacts)]:
        raise ValueError("a rung with contacts after a coil")
    if contacts:
        awl_series(contacts, out)
    else:
        out.append("SET")
    for el in coils:  # a coil, or parallel coils (a branch whose legs are coils)
        legs = el[1] if el[0] == "BST" else [[el]]
        for leg in legs:
            if any(e[0] not in ("OTE", "OTL", "OTU") for e in leg):
                raise ValueError("a branch mixing contacts and coils")
            awl_series(leg, out)  # = S R leave the RLO as it is: each coil sees the rung condition


def has_coil(el) -> bool:
    if el[0] == "BST":
        return any(has_coil(e) for leg in el[1] for e in leg)
    return el[0] in ("OTE", "OTL", "OTU")


class Awlsim:
    def __init__(self, doc: dict) -> None:
        import importlib

        # in this order, as awlsim-test imports them: awlcompiler before core
        # leaves names awlsim's cpu module needs undefined
        for module in ("awlsim.common", "awlsim.core", "awlsim.awlcompiler"):
            importlib.import_module(module)
        from awlsim.awlcompiler import AwlParser
        from awlsim.common import AwlSource, S7CPUConfig
        from awlsim.core import AwlSim

        lines = ["ORGANIZATION_BLOCK OB 1", "BEGIN"]
        for rung in doc["rungs"]:
            awl_rung(rung, lines)
        lines.append("END_ORGANIZATION_BLOCK")
        self.sim = AwlSim()
        self.sim.reset()
        self.cpu = self.sim.getCPU()
        self.cpu.getConf().setConfiguredMnemonics(S7CPUConfig.MNEMONICS_EN)
        self.cpu.getSpecs().setNrFlags(max(2048, 2 * len(doc["b3_words"])))
        parser = AwlParser()
        parser.parseSource(AwlSource(name="OB1", sourceBytes=("\n".join(lines) + "\n").encode()))
        self.sim.load(parser.getParseTree())
        self.sim.build()
        self.sim.startup()
        self.b3_words = len(doc["b3_words"])
        self.cpu.flags.getRawDataBytes()[:2 * self.b3_words] = bytes_from_words(doc["b3_words"])
        self.rows = [bytes_from_words(row) for row in doc["input_rows"]]
        self.scans = 0

    def scan(self) -> None:
        row = self.rows[self.scans % len(self.rows)]
        self.scans += 1
        self.cpu.inputs.getRawDataBytes()[:len(row)] = row
        self.sim.runCycle()

    def words(self) -> list[int]:
        return words_from_bytes(self.cpu.flags.getRawDataBytes(), self.b3_words)


# -- pyrung ---------------------------------------------------------------------------------------


class Pyrung:
    def __init__(self, doc: dict) -> None:
        from pyrung import PLC, And, Bool, Or, Program, latch, out, reset, rung

        self.b3 = doc["b3_words"]
        initial = [(self.b3[n // 16] >> (n % 16)) & 1 for n in range(16 * len(self.b3))]
        self.b_tags = [Bool(f"B3_{n}", default=bool(initial[n])) for n in range(len(initial))]
        self.i_tags = [Bool(f"I_{n}") for n in range(16 * len(doc["input_rows"][0]))]
        coil = {"OTE": out, "OTL": latch, "OTU": reset}

        def tag(space, bit):
            return (self.b_tags if space == "B" else self.i_tags)[bit]

        def term(el):
            if el[0] == "BST":
                legs = [[term(e) for e in leg] for leg in el[1]]
                return Or(*[leg[0] if len(leg) == 1 else And(*leg) for leg in legs])
            return tag(el[1], el[2]) if el[0] == "XIC" else ~tag(el[1], el[2])

        with Program(strict=False) as logic:  # strict mode forbids building rungs in a Python loop
            for r in doc["rungs"]:
                contacts = [el for el in r if el[0] in ("XIC", "XIO") or el[0] == "BST" and not has_coil(el)]
                coils = r[len(contacts):]
                with rung(*[term(el) for el in contacts]):
                    for el in coils:
                        for leg in (el[1] if el[0] == "BST" else [[el]]):
                            for c in leg:
                                coil[c[0]](tag(c[1], c[2]))
        # the smallest history pyrung keeps: its time travel is not what is compared here
        self.plc = PLC(logic, history=1)
        self.plc.__enter__()
        self.rows = [{self.i_tags[16 * w + b]: bool((row[w] >> b) & 1) for w in range(len(row)) for b in range(16)}
                     for row in doc["input_rows"]]
        self.scans = 0

    def scan(self) -> None:
        self.plc.patch(self.rows[self.scans % len(self.rows)])
        self.scans += 1
        self.plc.step()

    def words(self) -> list[int]:
        out = []
        for w in range(len(self.b3)):
            v = sum(1 << b for b in range(16) if self.b_tags[16 * w + b].value)
            out.append(v - 0x10000 if v & 0x8000 else v)
        return out


def main() -> int:
    peer, path = sys.argv[1], sys.argv[2]
    with open(path, encoding="utf-8") as fh:
        doc = json.load(fh)
    t0 = time.perf_counter()
    plc = {"awlsim": Awlsim, "pyrung": Pyrung}[peer](doc)
    reply({"load": {"total_s": time.perf_counter() - t0}, "instructions": doc["instructions"]})
    for line in sys.stdin:
        command, _, arg = line.strip().partition(" ")
        if command == "scan":
            samples = []
            gc.collect()
            gc.disable()
            try:
                for _ in range(int(arg)):
                    t0 = time.perf_counter_ns()
                    plc.scan()
                    samples.append(time.perf_counter_ns() - t0)
            finally:
                gc.enable()
            reply({"ns": samples, "mode": "RUN"})
        elif command == "words":
            reply({"b3": plc.words()})
        elif command == "quit":
            break
    return 0


if __name__ == "__main__":
    sys.exit(main())
