#!/usr/bin/env python3
"""Turn the criterion results of `cargo bench --bench batch` into the README's
Markdown table: median throughput in million lanes per second (per core unless the
column says otherwise) and the 1M eval as a fraction of the memory-bandwidth bound
measured in the same run.

    cargo bench --bench batch && python3 scripts/bench_report.py
"""

import json
import pathlib
import sys

CRITERION = pathlib.Path(__file__).resolve().parent.parent / "target" / "criterion"
SIZES = ["64", "4096", "1048576"]


def results():
    """{(group, function, size): median lanes per second}."""
    out = {}
    for bench in CRITERION.glob("**/new/benchmark.json"):
        meta = json.loads(bench.read_text())
        estimates = json.loads((bench.parent / "estimates.json").read_text())
        lanes = meta["throughput"]["Elements"]
        median_ns = estimates["median"]["point_estimate"]
        key = (meta["group_id"], meta["function_id"], meta["value_str"])
        out[key] = lanes / (median_ns * 1e-9)
    return out


def main():
    r = results()
    if not r:
        sys.exit(f"no criterion results under {CRITERION}: run `cargo bench --bench batch`")
    bound = r.get(("bandwidth", "stream_eval_bytes", SIZES[2]))
    groups = sorted({g for (g, _, _) in r if g != "bandwidth"})
    m = lambda v: f"{v / 1e6:.0f}" if v is not None else "-"
    print("| lobe | ISA | eval 64 | eval 4096 | eval 1M | sample 64 | sample 4096 | sample 1M "
          "| eval 1M, all cores | eval 1M / bandwidth bound |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for g in groups:
        lobe, isa = g.split("/")
        cells = [m(r.get((g, f, n))) for f in ("eval", "sample") for n in SIZES]
        all_cores = r.get((g, "eval_all_cores", SIZES[2]))
        one_core = r.get((g, "eval", SIZES[2]))
        share = f"{100 * one_core / bound:.0f}%" if one_core and bound else "-"
        print(f"| {lobe} | {isa} | " + " | ".join(cells) + f" | {m(all_cores)} | {share} |")
    if bound:
        print(f"\nBandwidth bound (one core streaming the 40 bytes per lane a 1M eval reads "
              f"and writes): {bound / 1e6:.0f} M lanes/s.")


if __name__ == "__main__":
    main()
