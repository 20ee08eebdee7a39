#!/usr/bin/env python3
"""Benchmark Glint's batch eval and sample side by side with Mitsuba 3 in one process.

    python3 scripts/bench_vs_mitsuba.py [--quick] [--cases a,b] [--out FILE.md]

A project script, not part of CI. It builds target/release/libglint.so (`cargo build
--release`, a no-op when fresh), installs Debian's libllvm19 if missing (Dr.Jit's LLVM
backend) and, when `mitsuba` cannot be imported, creates target/bench-venv with mitsuba
and numpy from PyPI and re-runs itself there.

Both libraries get the same SoA inputs: cosine-distributed wo and wi in the local frame
(normal +z; for the dielectric every other wi is mirrored below the surface so that
transmission is exercised), and the same uniform numbers for sampling. Glint is called
through its C ABI (one closure shared by all lanes), timed by a loop in C
(c_bench/batch_loop.c, built here with gcc) so that small batches do not measure
ctypes; Mitsuba runs the
`llvm_ad_rgb` variant with BSDF.eval_pdf and BSDF.sample (Glint's wo is Mitsuba's si.wi,
Glint's wi is Mitsuba's wo). Both eval outputs include the cosine of the light direction.
Reported: medians over repeated runs in M lanes/s; Mitsuba both as the wall time of a
call (tracing, cached-kernel launch, dr.eval and dr.sync_thread) and as the execution
time of its kernels alone (Dr.Jit's kernel history); ratios are Glint / Mitsuba. A
correctness section compares the eval values and pdfs, and the mean sample weight.
"""

import argparse
import ctypes
import datetime
import importlib.util
import json
import math
import os
import pathlib
import platform
import statistics
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
VENV = ROOT / "target" / "bench-venv"
LIBGLINT = ROOT / "target" / "release" / "libglint.so"
LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
LOOP_SRC = ROOT / "c_bench" / "batch_loop.c"
LOOP_LIB = ROOT / "target" / "bench-loop.so"

ALPHA = 0.2  # Mitsuba's GGX alpha; Glint's roughness is sqrt(alpha)
IOR = 1.5
DIFFUSE = 0.5
PRINCIPLED_BASE = [0.8, 0.2, 0.1]
CASES = ["roughconductor-F1", "roughconductor-Au", "roughdielectric", "diffuse", "principled"]
SIZES = [64, 256, 4096, 65536, 1 << 20]
QUICK_SIZES = [64, 4096, 1 << 20]
THREADS = [1, 2]
CHECK_LANES = 256  # directions of the eval comparison
ALBEDO_LANES = 1 << 16  # lanes of the mean-weight comparison


def run(cmd, **kw):
    print("+", " ".join(cmd), file=sys.stderr)
    subprocess.run(cmd, check=True, **kw)


def ensure_libllvm():
    if os.path.exists(LIBLLVM):
        return
    sudo = [] if os.geteuid() == 0 else ["sudo"]
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    run(sudo + ["apt-get", "update", "-qq"], env=env)
    run(sudo + ["apt-get", "install", "-y", "-qq", "libllvm19"], env=env)


def ensure_mitsuba():
    """Import mitsuba, or install it into target/bench-venv and re-run the calling
    script there."""
    if all(importlib.util.find_spec(m) for m in ("mitsuba", "numpy")):
        return
    python = VENV / "bin" / "python"
    if pathlib.Path(sys.prefix).resolve() == VENV.resolve():
        sys.exit("mitsuba is not importable even in target/bench-venv")
    if not python.exists():
        run([sys.executable, "-m", "venv", str(VENV)])
    run([str(python), "-m", "pip", "install", "-q", "mitsuba", "numpy"])
    os.execv(str(python), [str(python), os.path.abspath(sys.argv[0])] + sys.argv[1:])


def build_glint():
    run(["cargo", "build", "--release", "-q"], cwd=ROOT)


# --- Glint through the C ABI -------------------------------------------------------

F32P = ctypes.POINTER(ctypes.c_float)
U32P = ctypes.POINTER(ctypes.c_uint32)
VOIDP = ctypes.c_void_p


def soa_fields(names, ctype=F32P):
    return [(n, ctype) for n in names]


class EvalArgs(ctypes.Structure):
    _fields_ = ([("struct_size", ctypes.c_uint32), ("count", ctypes.c_size_t),
                 ("closure", VOIDP), ("closures", VOIDP), ("active", VOIDP)]
                + soa_fields(["wo_x", "wo_y", "wo_z", "wi_x", "wi_y", "wi_z",
                              "value_r", "value_g", "value_b", "pdf", "pdf_reverse"]))


class SampleArgs(ctypes.Structure):
    _fields_ = ([("struct_size", ctypes.c_uint32), ("count", ctypes.c_size_t),
                 ("closure", VOIDP), ("closures", VOIDP), ("active", VOIDP)]
                + soa_fields(["wo_x", "wo_y", "wo_z", "u_lobe", "u0", "u1",
                              "wi_x", "wi_y", "wi_z", "pdf", "weight_r", "weight_g",
                              "weight_b", "value_r", "value_g", "value_b"])
                + soa_fields(["flags", "lobe"], U32P)
                + soa_fields(["eta", "roughness"]))


class Glint:
    def __init__(self, path):
        lib = ctypes.CDLL(str(path))
        lib.glint_status_string.restype = ctypes.c_char_p
        lib.glint_last_error.restype = ctypes.c_char_p
        lib.glint_runtime_create.argtypes = [ctypes.c_char_p, ctypes.POINTER(VOIDP)]
        lib.glint_runtime_isa.argtypes = [VOIDP, ctypes.POINTER(ctypes.c_char_p)]
        lib.glint_arena_create.argtypes = [ctypes.c_size_t, ctypes.POINTER(VOIDP)]
        lib.glint_closure_from_json.argtypes = [VOIDP, VOIDP, ctypes.c_char_p, VOIDP,
                                                ctypes.POINTER(VOIDP)]
        lib.glint_eval_batch.argtypes = [ctypes.POINTER(EvalArgs)]
        lib.glint_sample_batch.argtypes = [ctypes.POINTER(SampleArgs)]
        self.lib = lib
        # Glint is timed by a loop in C: ctypes costs more per call than a small batch.
        if (not LOOP_LIB.exists()
                or LOOP_LIB.stat().st_mtime < LOOP_SRC.stat().st_mtime):
            run(["gcc", "-O2", "-shared", "-fPIC", "-Wall", "-Wextra", "-Wpedantic", "-Werror",
                 str(LOOP_SRC), "-o", str(LOOP_LIB)])
        loop = ctypes.CDLL(str(LOOP_LIB))
        loop.glint_bench_loop.restype = ctypes.c_double
        loop.glint_bench_loop.argtypes = [VOIDP, VOIDP, ctypes.c_int32]
        loop.glint_bench_stream.restype = ctypes.c_double
        loop.glint_bench_stream.argtypes = [ctypes.POINTER(F32P), ctypes.POINTER(F32P),
                                            ctypes.c_size_t, ctypes.c_int32]
        self.loop = loop.glint_bench_loop
        self.stream = loop.glint_bench_stream

    def check(self, status, what):
        if status:
            raise RuntimeError(f"{what}: {self.lib.glint_status_string(status).decode()}: "
                               f"{self.lib.glint_last_error().decode()}")

    def runtime(self, config):
        rt = VOIDP()
        self.check(self.lib.glint_runtime_create(config.encode(), ctypes.byref(rt)), config)
        isa = ctypes.c_char_p()
        self.check(self.lib.glint_runtime_isa(rt, ctypes.byref(isa)), "glint_runtime_isa")
        arena = VOIDP()
        self.check(self.lib.glint_arena_create(64, ctypes.byref(arena)), "glint_arena_create")
        return rt, arena, isa.value.decode()

    def closure(self, rt, arena, desc):
        c = VOIDP()
        text = json.dumps({"lobes": [desc]})
        self.check(self.lib.glint_closure_from_json(rt, arena, text.encode(), None,
                                                    ctypes.byref(c)), text)
        return c


def ptr(a):
    return a.ctypes.data_as(F32P)


class GlintBatch:
    """One glint_eval_batch or glint_sample_batch over `d`, callable; keeps its arrays."""

    def __init__(self, glint, closure, d, op, np):
        n = len(d["wo"][0])
        self.glint, self.op, self.d = glint, op, d
        if op == "eval":
            self.out = {k: np.empty(n, np.float32) for k in ("r", "g", "b", "pdf")}
            self.args = EvalArgs(ctypes.sizeof(EvalArgs), n, closure, None, None,
                                 *map(ptr, d["wo"]), *map(ptr, d["wi"]),
                                 *(ptr(self.out[k]) for k in ("r", "g", "b", "pdf")), None)
            self.fn = glint.lib.glint_eval_batch
        else:
            keys = ("x", "y", "z", "pdf", "r", "g", "b")
            self.out = {k: np.empty(n, np.float32) for k in keys}
            self.args = SampleArgs(ctypes.sizeof(SampleArgs), n, closure, None, None,
                                   *map(ptr, d["wo"]), *map(ptr, d["u"]),
                                   *(ptr(self.out[k]) for k in keys))
            self.fn = glint.lib.glint_sample_batch
        self.ref = ctypes.byref(self.args)

    def __call__(self):
        self.glint.check(self.fn(self.ref), self.op)
        return self.out

    def seconds(self, calls):
        """Seconds for `calls` calls, timed in C."""
        fn = ctypes.cast(self.fn, VOIDP)
        t = self.glint.loop(fn, ctypes.addressof(self.args), calls)
        if t < 0:
            self.glint.check(int(-t), self.op)
        return t


def streaming_bound(glint, n, repeats, np):
    """M lanes/s of one thread streaming the bytes an n-lane eval moves (6 arrays read,
    4 written), timed in C: the eval's memory-bandwidth bound."""
    d = inputs(n, False, np)
    ins = (F32P * 6)(*map(ptr, d["wo"] + d["wi"]))
    outs_np = [np.empty(n, np.float32) for _ in range(4)]
    outs = (F32P * 4)(*map(ptr, outs_np))
    glint.stream(ins, outs, n, 1)
    return rate(n, statistics.median(glint.stream(ins, outs, n, 1) for _ in range(repeats)))


def median_c(batch, inner, repeats):
    """Median seconds of one call of `batch`, each sample `inner` calls timed in C."""
    batch.seconds(2)
    return statistics.median(batch.seconds(inner) / inner for _ in range(repeats))


# --- inputs and cases --------------------------------------------------------------

def cosine_dirs(rng, n, np):
    u1, u2 = rng.random(n, np.float32), rng.random(n, np.float32)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    z = np.sqrt(np.maximum(0, 1 - u1))
    return [np.ascontiguousarray(v, np.float32) for v in (r * np.cos(phi), r * np.sin(phi), z)]


def inputs(n, transmit, np):
    rng = np.random.default_rng(n)
    wo, wi = cosine_dirs(rng, n, np), cosine_dirs(rng, n, np)
    if transmit:
        wi[2][1::2] *= -1
    u = [rng.random(n, np.float32) for _ in range(3)]
    return {"wo": wo, "wi": wi, "u": u}


def case_table(au_eta, au_k):
    """{case: (Mitsuba dict, Glint lobe or material JSON or None, wi below the surface too)}."""
    rough = math.sqrt(ALPHA)
    return {
        "roughconductor-F1": (
            {"type": "roughconductor", "distribution": "ggx", "alpha": ALPHA,
             "material": "none"},
            {"type": "conductor", "distribution": "ggx", "roughness": rough,
             "fresnel": "schlick", "f0": 1, "f90": 1}, False),
        "roughconductor-Au": (
            {"type": "roughconductor", "distribution": "ggx", "alpha": ALPHA,
             "material": "Au"},
            {"type": "conductor", "distribution": "ggx", "roughness": rough,
             "fresnel": "conductor", "eta": au_eta, "k": au_k}, False),
        "roughdielectric": (
            {"type": "roughdielectric", "distribution": "ggx", "alpha": ALPHA,
             "int_ior": IOR, "ext_ior": 1.0},
            {"type": "dielectric", "distribution": "ggx", "roughness": rough, "eta": IOR},
            True),
        "diffuse": (
            {"type": "diffuse", "reflectance": {"type": "rgb", "value": DIFFUSE}},
            {"type": "lambert", "color": DIFFUSE}, False),
        # Every lobe on in both (Glint: Burley 2012's diffuse + subsurface blend, sheen,
        # anisotropic GTR2, GTR1 clearcoat; Mitsuba: its principled, Burley 2015's
        # model without transmission), so values differ by model, not by error.
        "principled": (
            {"type": "principled", "base_color": {"type": "rgb", "value": PRINCIPLED_BASE},
             "metallic": 0.3, "roughness": 0.5, "anisotropic": 0.4, "sheen": 1.0,
             "clearcoat": 1.0, "clearcoat_gloss": 0.8, "specular": 0.5},
            {"material": "disney", "base_color": PRINCIPLED_BASE, "metallic": 0.3,
             "roughness": 0.5, "anisotropic": 0.4, "sheen": 1.0, "subsurface": 0.5,
             "clearcoat": 1.0, "clearcoat_gloss": 0.8, "specular": 0.5}, False),
    }


def mitsuba_au(mi):
    """Mitsuba's RGB eta and k of material Au (its spectral data reduced to RGB)."""
    params = mi.traverse(mi.load_dict({"type": "roughconductor", "material": "Au"}))
    return tuple([round(float(params[key][c][0]), 6) for c in range(3)]
                 for key in ("eta.value", "k.value"))


# --- Mitsuba -----------------------------------------------------------------------

class Mitsuba:
    def __init__(self, mi, dr):
        self.mi, self.dr = mi, dr
        self.ctx = mi.BSDFContext()

    def interaction(self, d):
        mi, dr = self.mi, self.dr
        n = len(d["wo"][0])
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(*map(mi.Float, d["wo"]))
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        wo = mi.Vector3f(*map(mi.Float, d["wi"]))
        u_lobe = mi.Float(d["u"][0])
        u2 = mi.Point2f(mi.Float(d["u"][1]), mi.Float(d["u"][2]))
        dr.eval(si, wo, u_lobe, u2)
        return si, wo, u_lobe, u2

    def eval_call(self, bsdf, si, wo):
        def call():
            value, pdf = bsdf.eval_pdf(self.ctx, si, wo)
            self.dr.eval(value, pdf)
            self.dr.sync_thread()
            return value, pdf
        return call

    def sample_call(self, bsdf, si, u_lobe, u2):
        def call():
            bs, weight = bsdf.sample(self.ctx, si, u_lobe, u2)
            self.dr.eval(bs.wo, bs.pdf, weight)
            self.dr.sync_thread()
            return bs, weight
        return call

    def kernel_ms(self, call, inner):
        """Execution time of the kernels of `inner` calls, per call, and cache misses."""
        dr = self.dr
        dr.kernel_history_clear()
        for _ in range(inner):
            call()
        jit = [k for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT]
        misses = sum(1 for k in jit if not k["cache_hit"])
        return sum(k["execution_time"] for k in jit) / inner, misses

    def kernel_outputs(self, call):
        """Arrays the kernels of one call write (a grey RGB value is one array)."""
        dr = self.dr
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        dr.kernel_history_clear()
        call()
        jit = [k for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT]
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        return sum(k["output_count"] for k in jit)


# --- measurement -------------------------------------------------------------------

def median_wall(call, inner, repeats):
    """Median seconds of one call, each sample timing `inner` calls after a warm-up."""
    call()
    call()
    samples = []
    for _ in range(repeats):
        t = time.perf_counter()
        for _ in range(inner):
            call()
        samples.append((time.perf_counter() - t) / inner)
    return statistics.median(samples)


def median_kernel(mits, call, inner, repeats):
    call()
    mits.dr.set_flag(mits.dr.JitFlag.KernelHistory, True)
    runs = [mits.kernel_ms(call, inner) for _ in range(repeats)]
    mits.dr.set_flag(mits.dr.JitFlag.KernelHistory, False)
    return statistics.median(ms for ms, _ in runs) * 1e-3, sum(m for _, m in runs)


def rate(n, seconds):
    return n / seconds / 1e6 if seconds else None


def paired_ratios(a, b):
    """Per-round ratios b / a of two paired rate lists: (median, lower quartile, upper
    quartile, the sorted ratios)."""
    ratios = sorted(y / x for x, y in zip(a, b))
    q = len(ratios)
    return ratios[q // 2], ratios[q // 4], ratios[3 * q // 4], ratios


def fmt(v):
    if v is None:
        return "n/a"
    return f"{v:.0f}" if v >= 100 else f"{v:.3g}"


def ratio(a, b):
    return f"{a / b:.2f}" if a and b else "n/a"


def benchmark(args, glint, runtimes, mits, cases, np):
    sizes = QUICK_SIZES if args.quick else SIZES
    rows, misses = [], 0
    for threads in THREADS:
        mits.dr.set_thread_count(threads)
        rt, arena, _ = runtimes[threads]
        for name in args.cases:
            mi_desc, glint_desc, transmit = cases[name]
            bsdf = mits.mi.load_dict(mi_desc)
            closure = glint.closure(rt, arena, glint_desc) if glint_desc else None
            for n in sizes:
                d = inputs(n, transmit, np)
                # Each sample times enough calls to cover ~16K lanes, and a cell
                # at most ~8M lanes beyond the first three samples.
                inner = max(1, min(64, 16384 // n))
                repeats = max(3, min(args.repeats, (1 << 23) // (n * inner)))
                si, wo, u_lobe, u2 = mits.interaction(d)
                row = [name, n, threads]
                for op in ("eval", "sample"):
                    mcall = (mits.eval_call(bsdf, si, wo) if op == "eval"
                             else mits.sample_call(bsdf, si, u_lobe, u2))
                    gcall = GlintBatch(glint, closure, d, op, np) if closure else None
                    g = rate(n, median_c(gcall, inner, repeats)) if gcall else None
                    mw = rate(n, median_wall(mcall, inner, repeats))
                    seconds, miss = median_kernel(mits, mcall, inner, repeats)
                    mk = rate(n, seconds)
                    misses += miss
                    row += [g, mw, mk]
                rows.append(row)
                print(f"  {name} N={n} threads={threads} done", file=sys.stderr)
    return rows, misses


def table(rows):
    head = ("| case | N | threads | Glint eval | Mitsuba eval wall | Mitsuba eval kernel "
            "| eval G/M wall | eval G/M kernel | Glint sample | Mitsuba sample wall "
            "| Mitsuba sample kernel | sample G/M wall | sample G/M kernel |")
    lines = [head, "|" + " --- |" * (head.count("|") - 1)]
    for name, n, threads, ge, mwe, mke, gs, mws, mks in rows:
        lines.append(f"| {name} | {n} | {threads} | {fmt(ge)} | {fmt(mwe)} | {fmt(mke)} "
                     f"| {ratio(ge, mwe)} | {ratio(ge, mke)} | {fmt(gs)} | {fmt(mws)} "
                     f"| {fmt(mks)} | {ratio(gs, mws)} | {ratio(gs, mks)} |")
    return lines


# --- correctness -------------------------------------------------------------------

def rel_diff(a, b, np):
    """|a - b| / |b| where either is above 1e-4: max, median and the argmax."""
    keep = np.maximum(np.abs(a), np.abs(b)) > 1e-4
    r = np.where(keep, np.abs(a - b) / np.maximum(np.abs(b), 1e-6), 0)
    return float(r.max()), float(np.median(r[keep])) if keep.any() else 0.0, int(r.argmax())


def triple(v):
    return "(" + ", ".join(f"{x:.4f}" for x in v) + ")"


def correctness(glint, runtimes, mits, cases, names, np):
    rt, arena, _ = runtimes[THREADS[0]]
    lines = ["| case | eval max rel diff | eval median | worst (cos_o, cos_i) "
             "| pdf max rel diff | pdf median | mean sample weight, Glint | Mitsuba "
             "| Mitsuba kernel outputs, eval/sample |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for name in names:
        mi_desc, glint_desc, transmit = cases[name]
        bsdf = mits.mi.load_dict(mi_desc)
        d = inputs(CHECK_LANES, transmit, np)
        si, wo, u_lobe, u2 = mits.interaction(d)
        outputs = (f"{mits.kernel_outputs(mits.eval_call(bsdf, si, wo))}/"
                   f"{mits.kernel_outputs(mits.sample_call(bsdf, si, u_lobe, u2))}")
        if glint_desc is None:
            lines.append(f"| {name} |" + " n/a |" * 7 + f" {outputs} |")
            continue
        closure = glint.closure(rt, arena, glint_desc)
        g = GlintBatch(glint, closure, d, "eval", np)()
        value, pdf = mits.eval_call(bsdf, si, wo)()
        gv = np.stack([g["r"], g["g"], g["b"]])
        vmax, vmed, worst = rel_diff(gv, np.array(value, np.float32).reshape(3, -1), np)
        lane = worst % CHECK_LANES
        pmax, pmed, _ = rel_diff(g["pdf"], np.array(pdf, np.float32), np)
        a = inputs(ALBEDO_LANES, transmit, np)
        s = GlintBatch(glint, closure, a, "sample", np)()
        si, _, u_lobe, u2 = mits.interaction(a)
        _, weight = mits.sample_call(bsdf, si, u_lobe, u2)()
        mw = np.array(weight, np.float32).reshape(3, -1).mean(axis=1)
        lines.append(f"| {name} | {vmax:.2e} | {vmed:.2e} "
                     f"| ({d['wo'][2][lane]:.3f}, {d['wi'][2][lane]:.3f}) "
                     f"| {pmax:.2e} | {pmed:.2e} | {triple(s[c].mean() for c in 'rgb')} "
                     f"| {triple(mw)} | {outputs} |")
    return lines


# --- main --------------------------------------------------------------------------

def cpu_model():
    for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return platform.processor() or "unknown CPU"


def git_commit():
    out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                           capture_output=True, text=True, check=True).stdout.strip()
    return out + ("-dirty" if dirty else "")


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true",
                   help=f"N in {QUICK_SIZES} and at most 5 repeats")
    p.add_argument("--cases", default=",".join(CASES),
                   help=f"comma-separated subset of {','.join(CASES)}")
    p.add_argument("--repeats", type=int, default=21, help="timed runs per cell (median)")
    p.add_argument("--out", type=pathlib.Path, help="also write the report to this file")
    args = p.parse_args()
    args.cases = [c for c in args.cases.split(",") if c]
    unknown = set(args.cases) - set(CASES)
    if unknown:
        p.error(f"unknown cases {sorted(unknown)}; valid: {', '.join(CASES)}")
    if args.quick:
        args.repeats = min(args.repeats, 5)
    return args


def main():
    args = parse_args()
    ensure_libllvm()
    os.environ["DRJIT_LIBLLVM_PATH"] = LIBLLVM
    ensure_mitsuba()
    build_glint()
    import drjit as dr
    import mitsuba as mi
    import numpy as np
    mi.set_variant("llvm_ad_rgb")

    glint = Glint(LIBGLINT)
    runtimes = {t: glint.runtime(f"isa=auto threads={t}") for t in THREADS}
    isa = runtimes[THREADS[0]][2]
    au_eta, au_k = mitsuba_au(mi)
    cases = case_table(au_eta, au_k)
    mits = Mitsuba(mi, dr)

    rows, misses = benchmark(args, glint, runtimes, mits, cases, np)
    bound = streaming_bound(glint, 1 << 20, 15, np)
    checks = correctness(glint, runtimes, mits, cases, args.cases, np)

    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    report = [
        f"Machine: {cpu_model()}, {os.cpu_count()} cores (load average {load}); "
        f"Glint ISA {isa}; date {datetime.date.today()}; commit {git_commit()}; "
        f"mitsuba {mi.__version__} ({mi.variant()}), drjit {dr.__version__}, "
        f"Python {platform.python_version()}.",
        "",
        "M lanes/s, medians; G/M = Glint / Mitsuba (wall: whole call; kernel: Dr.Jit "
        "kernel execution time only). Glint: isa=auto threads=T; Mitsuba: "
        "dr.set_thread_count(T). Au: Mitsuba's RGB "
        f"eta {au_eta}, k {au_k} in both."
        + (f" WARNING: {misses} measured Mitsuba kernels missed the cache." if misses else ""),
        "",
        *table(rows),
        "",
        f"Streaming bound (one thread, 1M lanes, the bytes a Glint eval moves: 6 arrays "
        f"read, 4 written), measured in this run: {fmt(bound)} M lanes/s.",
        "",
        f"Correctness: eval value (f cos, RGB) and pdf on {CHECK_LANES} directions, relative "
        f"to Mitsuba; mean sample weight over {ALBEDO_LANES} lanes (a directional albedo "
        "estimate). Mitsuba's Smith G2 is separable, G1(wo) G1(wi); Glint's is "
        "height-correlated, so microfacet values differ most at grazing angles. Glint's "
        "batch calls read 6 direction arrays and write 4 (eval: RGB, pdf) or 7 (sample: wi, "
        "pdf, RGB weight); Dr.Jit reads only the inputs a kernel uses and writes a grey RGB "
        "as one array.",
        "",
        *checks,
    ]
    text = "\n".join(report) + "\n"
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
