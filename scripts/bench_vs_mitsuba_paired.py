#!/usr/bin/env python3
"""Glint against Mitsuba 3 in alternating rounds, one thread: the paired ratio.

    python3 scripts/bench_vs_mitsuba_paired.py [--sizes 4096,1048576] [--rounds 15] \
        [--case principled]

A project script, not part of CI (it sets up Mitsuba and builds Glint as
scripts/bench_vs_mitsuba.py does). On a shared machine whose speed drifts by tens of
percent over minutes, a ratio of two medians taken one after the other moves with the
drift; here each round times Glint's call (`median_c`, as that script) and then
Mitsuba's kernels (`median_kernel`: Dr.Jit's kernel execution time), and the ratio is
taken per round. Reported per size and op: each side's median M lanes/s and the median,
quartiles and count of the per-round ratios Glint / Mitsuba kernel.
"""

import argparse
import os
import statistics
import sys

import bench_vs_mitsuba as bench


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", default="4096,1048576")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--case", default="principled")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per side a round")
    args = parser.parse_args()
    bench.ensure_libllvm()
    os.environ["DRJIT_LIBLLVM_PATH"] = bench.LIBLLVM
    bench.ensure_mitsuba()
    bench.build_glint()
    import drjit as dr
    import mitsuba as mi
    import numpy as np
    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(1)

    glint = bench.Glint(bench.LIBGLINT)
    runtime, arena, isa = glint.runtime("isa=auto threads=1")
    au_eta, au_k = bench.mitsuba_au(mi)
    mi_desc, glint_desc, transmit = bench.case_table(au_eta, au_k)[args.case]
    mits = bench.Mitsuba(mi, dr)
    bsdf = mits.mi.load_dict(mi_desc)
    closure = glint.closure(runtime, arena, glint_desc)
    print(f"{bench.cpu_model()}, Glint ISA {isa}, commit {bench.git_commit()}, "
          f"mitsuba {mi.__version__}; {args.rounds} rounds", flush=True)
    for n in (int(s) for s in args.sizes.split(",")):
        d = bench.inputs(n, transmit, np)
        inner = max(1, min(64, 16384 // n))
        si, wo, u_lobe, u2 = mits.interaction(d)
        for op in ("eval", "sample"):
            mcall = (mits.eval_call(bsdf, si, wo) if op == "eval"
                     else mits.sample_call(bsdf, si, u_lobe, u2))
            gcall = bench.GlintBatch(glint, closure, d, op, np)
            rates = ([], [])
            misses = 0
            for _ in range(args.rounds):
                rates[0].append(bench.rate(n, bench.median_c(gcall, inner, args.repeats)))
                seconds, miss = bench.median_kernel(mits, mcall, inner, args.repeats)
                rates[1].append(bench.rate(n, seconds))
                misses += miss
            median, low, high, ratios = bench.paired_ratios(rates[1], rates[0])
            print(
                f"{args.case} {op} N={n}: Glint {statistics.median(rates[0]):.1f}, Mitsuba "
                f"kernel {statistics.median(rates[1]):.1f} M lanes/s; Glint/Mitsuba median "
                f"{median:.2f} (quartiles {low:.2f}, {high:.2f}; at least 2 in "
                f"{sum(r >= 2 for r in ratios)}/{len(ratios)})"
                + (f"; {misses} Mitsuba kernels missed the cache" if misses else ""),
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
