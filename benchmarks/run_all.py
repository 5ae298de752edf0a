"""Run every benchmark (data table, ladder engine, COMGENIUS format engine and ports, the Modbus RTU master, MODBMAST, the
Modbus RTU slave in ladder, the watch view, the scenario runner), each in its own process, and summarize.

    python benchmarks/run_all.py

Each benchmark prints its own figures and writes benchmarks/results/NAME.json;
this script then prints a summary from those files and writes
benchmarks/results/run_all.json. Misses against a target are reported, not
turned into a failing exit status; a benchmark that crashes is.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

import _common as C

BENCHMARKS = (
    "bench_datatable_memory", "bench_snapshot", "bench_word_access", "bench_ladder", "bench_load_cache",
    "bench_comgenius_format",
    "bench_comgenius_ports", "bench_modbus_master", "bench_modbmast", "bench_modbus_slave", "bench_modbus_server",
    "bench_enips_server", "bench_opcuas", "bench_watch", "bench_trend_view", "bench_trends", "bench_scenarios", "bench_mutation",
    "bench_logix", "bench_st",
)


def med(xs: list) -> float:
    """The middle of a round's figures (the upper one of an even count), as the summary lines show them."""
    return sorted(xs)[len(xs) // 2]


def main() -> int:
    t_start = time.perf_counter()
    failed: list[str] = []
    wall: dict[str, float] = {}
    for name in BENCHMARKS:
        print(f"=== {name} " + "=" * (60 - len(name)), flush=True)
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, str(C.HERE / f"{name}.py")], check=False)
        wall[name] = time.perf_counter() - t0
        if proc.returncode != 0:
            failed.append(name)
        print(flush=True)

    def load(name: str) -> dict | None:
        path = C.RESULTS / f"{name}.json"
        if name in failed or not path.exists():
            return None
        return json.loads(path.read_text(encoding="utf-8"))

    lines: list[str] = []
    mem = load("bench_datatable_memory")
    if mem:
        t, p = mem["table"], mem["plain_lists"]
        lines.append(
            f"memory    {mem['verdict']}: retained {mem['retained_bytes_for_verdict'] / 1e6:.2f} MB "
            f"(tracemalloc {t['tracemalloc_current'] / 1e6:.2f} MB, RSS {t['rss_delta_median'] / 1e6:.2f} MB) "
            f"vs target {mem['target_bytes'] / 1e6:.0f} MB; plain lists "
            f"{p['tracemalloc_current'] / 1e6:.2f} MB ({mem['ratio_plain_over_table_tracemalloc']:.1f}x)"
        )
    snap = load("bench_snapshot")
    if snap:
        m = snap["ms_median"]
        lines.append(
            f"snapshot  {snap['verdict']}: save {m['save']:.1f} ms + load {m['load']:.1f} ms = "
            f"{m['total']:.1f} ms vs target {snap['target_ms']:.0f} ms; {snap['snapshot_bytes']} bytes; "
            f"{snap['ratio_total_snapshot_over_pickle']:.2f}x pickle, "
            f"{snap['ratio_total_snapshot_over_raw_io']:.2f}x raw I/O"
        )
    acc = load("bench_word_access")
    if acc:
        a = acc["access_ns"]
        api = acc["typed_api_ns"]
        lines.append(
            "access    ns net, array (list): "
            + ", ".join(
                f"{op} {a[op]['array_ns']:.1f} ({a[op]['list_ns']:.1f})"
                for op in ("read", "write", "bit_read", "bit_set")
            )
        )
        read_ns = api["table.read('N7:5')"]["ns"]
        write_ns = api["table.write('N7:5', v)"]["ns"]
        lines.append(f"          typed API: read {read_ns:.0f} ns, write {write_ns:.0f} ns per call")

    lad = load("bench_ladder")
    if lad:
        for kind in ("boolean", "mixed"):
            r = lad[kind]
            v = r["verdicts"]
            lines.append(
                f"ladder    {kind}: compiled {r['compiled_scan_ns']['per_instruction']:.0f} ns/instruction "
                f"[{v['ns_per_instruction']} <= {r['targets']['ns_per_instruction']:.0f}], "
                f"{r['ratio_reference_over_compiled']:.1f}x the reference [{v['ratio']}], load "
                f"{r['load']['parse_validate_compile_s']:.2f} s [{v['load']} <= {r['targets']['load_s']:.0f} s]"
            )

    cache = load("bench_load_cache")
    if cache:
        lines.append(f"load      {cache['rungs']:,} boolean rungs, CPU: cold {cache['cold_cpu_s']['median']:.2f} s, "
                     f"warm (code cache) {cache['warm_cpu_s']['median']:.2f} s [<= 0.3 s]")

    fmt = load("bench_comgenius_format")
    if fmt:
        p, sc, d = fmt["strprint_example1"], fmt["strscan_strings_7_8"], fmt["decode_example4"]
        crc = fmt["crc16"]["4 KiB"]
        lines.append(
            f"comgenius STRPRINT ex. 1 {p['fast_us']:.2f} us [{p['verdict']} <= {p['target_us']:.0f}], "
            f"{p['ratio_naive_over_fast']:.1f}x naive, {p['ratio_fast_over_floor']:.1f}x Python %; "
            f"STRSCAN 7/8 {sc['fast_us']:.1f} us, {sc['ratio_naive_over_fast']:.1f}x naive"
        )
        lines.append(
            f"          decode ex. 4 {d['fast_us']:.1f} us [{d['verdict']} <= {d['target_us']:.0f}], "
            f"{d['ratio_naive_over_fast']:.1f}x naive; CRC-16 {crc['bytes_per_s']['crc16'] / 1e6:.1f} MB/s, "
            f"{crc['ratio_naive_over_table']:.1f}x bitwise"
        )

    ports = load("bench_comgenius_ports")
    if ports:
        for kind, r in ports["round_trips"].items():
            rt, lr = r["round_trips_per_s"], r["ratio_ladder_over_raw"]
            lines.append(
                f"{'ports' if kind == 'text' else '':9} {kind} {r['frame_bytes']} B round trips/s: ladder loop:// "
                f"{rt['ladder loop://']:,} ({lr['loop://']:.1f}x raw), pty {rt['ladder pty']:,} "
                f"({lr['pty']:.1f}x raw), sim:// {rt['ladder sim://']:,} ({lr['sim://']:.0f}x raw)"
            )
        b = ports["throughput"]
        lines.append(
            f"          sim:// unlimited {b['bytes_per_s']['sim:// unlimited'] / 1e6:.0f} MB/s, loop:// "
            f"{b['bytes_per_s']['loop://'] / 1e6:.2f} MB/s (4 KiB writes)"
        )

    modbus = load("bench_modbus_master")
    if modbus:
        pty, sim = modbus["pty"], modbus["sim"]
        tps = pty["transactions_per_s"]
        lines.append(
            f"modbus    pty transactions/s: ladder {tps['ladder']:,}, pymodbus sync {tps['sync']:,}, async "
            f"{tps['async']:,}; ladder/sync {pty['ratios']['ladder/sync']:.2f}x [{pty['verdict_ladder_over_sync']} "
            f">= {pty['target_ladder_over_sync']:.1f}], ladder/async {pty['ratios']['ladder/async']:.2f}x"
        )
        lines.append(
            f"          sim:// {sim['ms_per_transaction']:.2f} ms per transaction = {sim['ratio_over_wire_min']:.3f}x "
            f"the wire minimum {sim['wire_min_ms']:.2f} ms [{sim['verdict']} <= {sim['target_ratio']:.2f}]; "
            f"{sim['scans_per_wall_s']:,} scans/s, {sim['transactions_per_wall_s']:,} transactions per wall second"
        )

    mbm = load("bench_modbmast")
    if mbm:
        p, w, s = mbm["pty"], mbm["wire"], mbm["scale"]
        lines.append(f"modbmast  pty {p['transactions_per_s']['modbmast']:,}/s vs sync {p['transactions_per_s']['sync']:,}/s "
                     f"= {p['ratios']['modbmast/sync']:.2f}x [{p['verdict']}]; sim wire worst {w['worst_ratio']:.4f}x "
                     f"the limit [{w['verdict']}]")
        lines.append(f"          32x32x4: waiting {s['idle']['hook_us_per_port_scan']:.2f} us/port/scan "
                     f"[{s['idle']['verdict']}], {s['mixed']['scan_10ms']['us_per_transaction']:.1f} us/transaction "
                     f"at 10 ms [{s['verdict_transaction']}] ({s['mixed']['scan_1ms']['us_per_transaction']:.1f} at "
                     f"1 ms), {s['memory']['bytes_per_request']:,} B/request [{s['memory']['verdict']}]")

    mbs = load("bench_modbus_slave")
    if mbs:
        p, sc = mbs["pty"], mbs["scan"]
        tps, su = p["transactions_per_s"], sc["scan_us"]
        gaps = ", ".join(f"{r['baud']} {r['gap_ms']:.2f} ms ({r['ratio_gap_over_t35']:.2f}x)"
                         for r in mbs["wire"]["rows"] if r["registers"] == 1)
        lines.append(f"mbslave   pty/s: ladder {tps['ladder']:,}, at 1 ms scans {tps['ladder 1ms']:,}, pymodbus server "
                     f"{tps['pymodbus']:,} (sync client): {p['ratios']['ladder/pymodbus']:.2f}x [{p['verdict']} >= "
                     f"{p['target_ladder_over_pymodbus']}], {p['ratios']['ladder 1ms/pymodbus']:.2f}x; sim gap after "
                     f"the request (vs 3.5 chars): {gaps}")
        lines.append(f"          scan us: empty app {su['empty']:.1f}, slave idle {su['idle']:.1f}, serving read 1 "
                     f"{su['read 1']:,.0f}, read 125 {su['read 125']:,.0f}, write 123 {su['write 123']:,.0f}")

    mts = load("bench_modbus_server")
    if mts:
        row = next(r for r in mts["rows"] if r["kind"] == "read" and r["clients"] == 16 and r["processes"] == 1)
        lines.append(f"modbtcps  reads of 100 by 16 clients: {med(row['modbtcps_rates']):,.0f}/s vs pymodbus's server "
                     f"{med(row['pymodbus_rates']):,.0f}/s = {row['ratio']:.2f}x; under 50 busy clients "
                     f"{mts['busy']['scans'].get('late_scans', 0)} late scans, the ladder's longest "
                     f"{mts['state']['max_ladder_ms']:.2f} ms")

    enips = load("bench_enips_server")
    if enips:
        table = enips["table"]
        lines.append(f"enips     reads of 100 (K=4): CIP tag {med(table['cip K=4']['rates']):,.0f}/s = "
                     f"{med(table['cip K=4']['ratio_to_modbtcps']):.2f}x MODBTCPS, PCCC "
                     f"{med(table['pccc K=4']['rates']):,.0f}/s = {med(table['pccc K=4']['ratio_to_modbtcps']):.2f}x; "
                     f"under 50 busy clients {enips['busy'].get('late_scans', 0)} late scans")

    opc = load("bench_opcuas")
    if opc:
        t, mem = opc["table"], opc["memory"]
        late = sum(sum(row["late_scans"]) for row in t.values())
        lines.append(f"opcuas    reads of 100 (K=4): {med(t['reads K=4']['opcuas']):,.0f}/s = "
                     f"{med(t['reads K=4']['ratio']):.2f}x asyncua's Server; data changes "
                     f"{med(t['notifications']['opcuas']):,.0f}/s = {med(t['notifications']['ratio']):.2f}x; "
                     f"{mem['opcuas']['bytes_per_item']:,.0f} B a monitored item "
                     f"(asyncua {mem['asyncua']['bytes_per_item']:,.0f}); {late} late scans under clients")

    logix = load("bench_logix")
    if logix:
        lines.append(f"logix     {logix['export']} ({logix['rungs']} rungs): scan / its rungs as PLC-5 text "
                     f"{med(logix['ratio']):.2f} [{'PASS' if logix['verdict'] else 'MISS'} <= {logix['target']}]")

    stb = load("bench_st")
    if stb:
        lines.append(f"st        {stb['units']} units of ST: scan / the same logic as ladder {med(stb['ratio_ladder']):.2f}, "
                     f"/ straight-line Python {med(stb['ratio_python']):.1f} "
                     f"[{'PASS' if stb['verdict'] else 'MISS'} <= {stb['target']}]")

    trends = load("bench_trends")
    if trends:
        every = [x for r in trends["ratios"].values() for x in r]
        lines.append(f"trends    recording 20 addresses / none: {med(every):.3f} (+{max(trends['added_us'].values()):.2f} "
                     f"us a scan) [{'PASS' if trends['verdict']['both'] else 'MISS'} >= {trends['target']}]")

    watch = load("bench_watch")
    if watch:
        sps = watch["scans_per_s"]
        lines.append(
            f"watch     scans/s: run {sps['run']:,}, view at full speed {sps['view']:,} = "
            f"{watch['ratio_view_over_run']:.2f}x [{watch['verdict']} >= {watch['target_ratio_view_over_run']:.2f}], "
            f"per-scan work alone {watch['ratio_session_over_run']:.2f}x; {watch['redraws_per_s']:.1f} redraws/s "
            f"of {watch['ms_per_redraw']:.1f} ms ({100 * watch['drawing_share_of_wall']:.0f}% of the time)"
        )

    scen = load("bench_scenarios")
    if scen:
        parts = [f"{app} long {r['long']['ratio']:.2f}x, expects {r['expects']['ratio']:.2f}x, "
                 f"dense {r['dense']['ratio']:.2f}x ({r['dense']['us_per_step']:.1f} us a step)"
                 for app, r in scen["apps"].items()]
        lines.append(f"scenarios runner / engine: {'; '.join(parts)} [{scen['verdict']} >= {scen['target_ratio']:.2f}]")

    print("=== summary " + "=" * 53)
    for line in lines:
        print(line)
    for name in failed:
        print(f"FAILED: {name} exited non-zero")
    total = time.perf_counter() - t_start
    print(f"total wall time {total:.1f} s (" + ", ".join(f"{k} {v:.1f} s" for k, v in wall.items()) + ")")
    C.write_results("run_all", {"summary": lines, "failed": failed, "wall_s": wall, "total_wall_s": total})
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
