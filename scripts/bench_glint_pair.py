#!/usr/bin/env python3
"""Time two Glint libraries against each other in one process, on one set of arrays.

    target/bench-venv/bin/python scripts/bench_glint_pair.py OLD.so NEW.so \
        [--sizes 4096,1048576] [--rounds 15] [--case principled] \
        [--old-config stores=held] [--new-config stores=direct]

A project script, not part of CI (the venv, with numpy, is the one
scripts/bench_vs_mitsuba.py creates). Separate runs of that script scatter by 5-10%
on this machine (where the kernel and the heap place the arrays and a held call's
ring), more than a kernel change often gains; here both libraries take the script's
own inputs and output arrays (its NumPy layout, the same addresses for both), and
rounds alternate between them: each round is `median_c` of one library, then of the
other. One library may be given twice, its runtimes configured apart (`--old-config`,
`--new-config`: runtime config items added to `isa=auto threads=1`). Reported per size
and op: each library's median M lanes/s and the median, quartiles and count of the
paired ratios NEW / OLD.
"""

import argparse
import ctypes
import statistics
import sys

import bench_vs_mitsuba as bench


def paired(batches, n, rounds):
    """Per library, its rate in each round; the two alternate within a round."""
    inner = max(1, min(64, 16384 // n))
    rates = ([], [])
    for _ in range(rounds):
        for batch, out in zip(batches, rates):
            out.append(bench.rate(n, bench.median_c(batch, inner, 5)))
    return rates


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--sizes", default="4096,1048576")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--case", default="principled")
    parser.add_argument("--old-config", default="")
    parser.add_argument("--new-config", default="")
    args = parser.parse_args()
    import numpy as np

    description = bench.case_table([1, 1, 1], [1, 1, 1])[args.case][1]
    libs = []
    for path, config in ((args.old, args.old_config), (args.new, args.new_config)):
        glint = bench.Glint(path)
        runtime, arena, _ = glint.runtime(f"isa=auto threads=1 {config}")
        libs.append((glint, glint.closure(runtime, arena, description)))
    for n in (int(s) for s in args.sizes.split(",")):
        d = bench.inputs(n, False, np)
        for op in ("eval", "sample"):
            old = bench.GlintBatch(*libs[0], d, op, np)
            new = bench.GlintBatch(*libs[1], d, op, np)
            # The new library's call on the old one's arrays: one layout for both.
            new.args = type(old.args).from_buffer_copy(old.args)
            new.args.closure = libs[1][1]
            new.ref = ctypes.byref(new.args)
            rates = paired((old, new), n, args.rounds)
            median, low, high, ratios = bench.paired_ratios(*rates)
            print(
                f"{args.case} {op} N={n}: old {statistics.median(rates[0]):.1f}, "
                f"new {statistics.median(rates[1]):.1f} M lanes/s; new/old median "
                f"{median:.4f} (quartiles {low:.4f}, {high:.4f}; new faster in "
                f"{sum(r > 1 for r in ratios)}/{len(ratios)})"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
