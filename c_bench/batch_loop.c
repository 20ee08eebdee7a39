/* A timing loop for scripts/bench_vs_mitsuba.py: calls a Glint batch entry point
 * `reps` times from C, so that small batches are timed without the per-call cost
 * of Python's ctypes (about 0.5 us, more than a 64-lane batch takes).
 * Built by the script: gcc -O2 -shared -fPIC c_bench/batch_loop.c. */
#include <stddef.h>
#include <stdint.h>
#include <time.h>

typedef int32_t (*glint_batch_fn)(const void *args);

/* Seconds for `reps` calls of `fn(args)`, or minus the status of the first failed
 * call. */
double glint_bench_loop(glint_batch_fn fn, const void *args, int32_t reps) {
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (int32_t i = 0; i < reps; i++) {
        int32_t status = fn(args);
        if (status != 0) {
            return -(double)status;
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    return (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
}

/* Seconds for `reps` streaming passes over the bytes a batch eval moves: reads the
 * six direction arrays `in` (wo, wi) and writes the four outputs `out` (value, pdf),
 * `n` lanes each. The memory-bandwidth bound of an eval at that size. */
double glint_bench_stream(const float *const *in, float *const *out, size_t n, int32_t reps) {
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (int32_t r = 0; r < reps; r++) {
        for (size_t i = 0; i < n; i++) {
            out[0][i] = in[0][i] + in[3][i];
            out[1][i] = in[1][i] + in[4][i];
            out[2][i] = in[2][i] + in[5][i];
            out[3][i] = in[2][i] * in[5][i];
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    return (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
}
