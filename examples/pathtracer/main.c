/* pathtracer: a unidirectional path tracer on Embree 3 whose every surface is a Glint
 * closure. See README.md in this directory for the options and the tests. */
#define _POSIX_C_SOURCE 200809L

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host.h"
#include "image_io.h"
#include "pt.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: pathtracer [options]\n"
            "  --width W, --height H   image size (default 640 x 360)\n"
            "  --spp N                 samples per pixel (default 128)\n"
            "  --max-depth D           most bounces (default 12)\n"
            "  --rr-depth D            Russian roulette from this bounce on (default 3)\n"
            "  --threads T             render threads (default 2)\n"
            "  --out PREFIX            write PREFIX.exr (linear) and PREFIX.png (sRGB)\n"
            "                          (default: render)\n"
            "  --seed S                random seed (default 1)\n"
            "  --strategy S            mis (default) | bsdf | light\n"
            "  --scene FILE.json       render a scene file instead of the showcase\n"
            "  --plugin PATH           load a Glint plugin (default: " CHARLIE_FILE
            " next to\n"
            "                          the executable, if there)\n"
            "  --furnace               white furnace: one sphere in a uniform environment\n"
            "                          of radiance 1\n"
            "  --material M            the furnace sphere's material: a name (see\n"
            "                          --list-materials) or JSON: a closure or a material\n"
            "                          document (default: white)\n"
            "  --pixel-center          one camera ray through each pixel's center (no jitter)\n"
            "  --aovs                  add variance.R/G/B (variance of each pixel's mean,\n"
            "                          from its samples) and coverage to the EXR\n"
            "  --quiet                 no progress bar\n"
            "  --no-timing             do not time the Glint calls (no Glint share reported)\n"
            "  --list-materials        print the named materials and exit\n");
}

int main(int argc, char **argv)
{
    pt_settings set;
    const char *out = "render", *scene_file = NULL, *plugin = NULL, *material = "white";
    int furnace = 0, aovs = 0, i, status = EXIT_FAILURE;
    glint_runtime *rt = NULL;
    ex_scene scene;
    pt_accum acc;
    pt_stats stats;
    size_t npix;
    static const char *const strategy_names[] = {"mis", "bsdf", "light"};

    scene_program = "pathtracer";
    memset(&set, 0, sizeof set);
    memset(&acc, 0, sizeof acc);
    set.width = 640;
    set.height = 360;
    set.spp = 128;
    set.max_depth = 12;
    set.rr_depth = 3;
    set.threads = 2;
    set.seed = 1;
    set.strategy = STRATEGY_MIS;
    set.timing = 1;

    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        long n = 0;
#define NEED_VALUE                                                                           \
    do {                                                                                     \
        if (!v) {                                                                            \
            fprintf(stderr, "pathtracer: %s needs a value\n", a);                            \
            return EXIT_FAILURE;                                                             \
        }                                                                                    \
        i++;                                                                                 \
    } while (0)
#define INT_OPT(name, lo, hi, field)                                                         \
    if (strcmp(a, name) == 0) {                                                              \
        NEED_VALUE;                                                                          \
        if (host_parse_int(a, v, lo, hi, &n) != 0)                                                \
            return EXIT_FAILURE;                                                             \
        field = (int)n;                                                                      \
        continue;                                                                            \
    }
        INT_OPT("--width", 1, 16384, set.width)
        INT_OPT("--height", 1, 16384, set.height)
        INT_OPT("--spp", 1, 1 << 20, set.spp)
        INT_OPT("--max-depth", 0, 10000, set.max_depth)
        INT_OPT("--rr-depth", 0, 10000, set.rr_depth)
        INT_OPT("--threads", 1, 256, set.threads)
        if (strcmp(a, "--seed") == 0) {
            NEED_VALUE;
            if (host_parse_int(a, v, 0, LONG_MAX, &n) != 0)
                return EXIT_FAILURE;
            set.seed = (uint64_t)n;
        } else if (strcmp(a, "--out") == 0) {
            NEED_VALUE;
            out = v;
        } else if (strcmp(a, "--scene") == 0) {
            NEED_VALUE;
            scene_file = v;
        } else if (strcmp(a, "--plugin") == 0) {
            NEED_VALUE;
            plugin = v;
        } else if (strcmp(a, "--material") == 0) {
            NEED_VALUE;
            material = v;
        } else if (strcmp(a, "--strategy") == 0) {
            NEED_VALUE;
            if (strcmp(v, "mis") == 0)
                set.strategy = STRATEGY_MIS;
            else if (strcmp(v, "bsdf") == 0)
                set.strategy = STRATEGY_BSDF;
            else if (strcmp(v, "light") == 0)
                set.strategy = STRATEGY_LIGHT;
            else {
                fprintf(stderr,
                        "pathtracer: --strategy expects mis, bsdf or light, got \"%s\"\n", v);
                return EXIT_FAILURE;
            }
        } else if (strcmp(a, "--furnace") == 0) {
            furnace = 1;
        } else if (strcmp(a, "--pixel-center") == 0) {
            set.pixel_center = 1;
        } else if (strcmp(a, "--aovs") == 0) {
            aovs = 1;
        } else if (strcmp(a, "--no-timing") == 0) {
            set.timing = 0;
        } else if (strcmp(a, "--quiet") == 0) {
            set.quiet = 1;
        } else if (strcmp(a, "--list-materials") == 0) {
            material_list();
            return EXIT_SUCCESS;
        } else if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return EXIT_SUCCESS;
        } else {
            fprintf(stderr, "pathtracer: unknown option \"%s\"\n", a);
            usage(stderr);
            return EXIT_FAILURE;
        }
#undef INT_OPT
#undef NEED_VALUE
    }
    if (host_open(&rt, &scene, plugin, scene_file, furnace, material) != 0)
        goto done;
    if (scene_build(&scene, rt) != 0)
        goto done;

    npix = (size_t)set.width * (size_t)set.height;
    acc.sum = calloc(npix * 3, sizeof(double));
    acc.sum_sq = calloc(npix * 3, sizeof(double));
    acc.hits = calloc(npix, sizeof(uint32_t));
    if (!acc.sum || !acc.sum_sq || !acc.hits) {
        fprintf(stderr, "pathtracer: out of memory\n");
        goto done_acc;
    }

    if (!set.quiet)
        fprintf(stderr,
                "pathtracer: %s, %dx%d, %d spp, max depth %d, %d thread%s, strategy %s\n",
                scene_file ? scene_file : furnace ? "white furnace" : "material showcase",
                set.width, set.height, set.spp, set.max_depth, set.threads,
                set.threads == 1 ? "" : "s", strategy_names[set.strategy]);
    if (render(&scene, rt, &set, &acc, &stats) != 0) {
        fprintf(stderr, "pathtracer: rendering failed\n");
        goto done_acc;
    }

    {
        const int nch = aovs ? 7 : 3;
        static const char *const names[7] = {"R", "G", "B", "variance.R", "variance.G",
                                              "variance.B", "coverage"};
        float *px = malloc(npix * (size_t)nch * sizeof(float));
        char path[PATH_MAX], err[512];
        image_attr attrs[5];
        const double n = (double)set.spp;
        size_t p;
        int c, ok = 1;
        if (!px) {
            fprintf(stderr, "pathtracer: out of memory\n");
            goto done_acc;
        }
        for (p = 0; p < npix; p++) {
            for (c = 0; c < 3; c++) {
                const double sum = acc.sum[3 * p + (size_t)c], sq = acc.sum_sq[3 * p + (size_t)c];
                const double mean = sum / n;
                px[p * (size_t)nch + (size_t)c] = (float)mean;
                if (aovs) {
                    /* Unbiased sample variance of the estimates, divided by n: the variance
                     * of the pixel's mean. */
                    double var = set.spp > 1 ? (sq - sum * mean) / (n - 1.0) / n : 0.0;
                    if (var < 0.0)
                        var = 0.0;
                    px[p * (size_t)nch + 3 + (size_t)c] = (float)var;
                }
            }
            if (aovs)
                px[p * (size_t)nch + 6] = (float)((double)acc.hits[p] / n);
        }
        snprintf(attrs[0].name, sizeof attrs[0].name, "glint:spp");
        snprintf(attrs[0].value, sizeof attrs[0].value, "%d", set.spp);
        snprintf(attrs[1].name, sizeof attrs[1].name, "glint:strategy");
        snprintf(attrs[1].value, sizeof attrs[1].value, "%s", strategy_names[set.strategy]);
        snprintf(attrs[2].name, sizeof attrs[2].name, "glint:seed");
        snprintf(attrs[2].value, sizeof attrs[2].value, "%llu", (unsigned long long)set.seed);
        snprintf(attrs[3].name, sizeof attrs[3].name, "glint:max_depth");
        snprintf(attrs[3].value, sizeof attrs[3].value, "%d", set.max_depth);
        snprintf(attrs[4].name, sizeof attrs[4].name, "glint:nonfinite_samples");
        snprintf(attrs[4].value, sizeof attrs[4].value, "%llu",
                 (unsigned long long)stats.nonfinite);

        snprintf(path, sizeof path, "%s.exr", out);
        if (image_write_exr(path, set.width, set.height, nch, names, px, attrs, 5, err,
                            sizeof err) != 0) {
            fprintf(stderr, "pathtracer: %s\n", err);
            ok = 0;
        }
        snprintf(path, sizeof path, "%s.png", out);
        if (ok && image_write_png(path, set.width, set.height, nch, px, err, sizeof err) != 0) {
            fprintf(stderr, "pathtracer: %s\n", err);
            ok = 0;
        }
        free(px);
        if (!ok)
            goto done_acc;
    }

    printf("render: %.2f s wall, %d thread%s, %.1f M rays, %.2f M rays/s, %.2f M camera "
           "samples\n",
           stats.seconds, set.threads, set.threads == 1 ? "" : "s", (double)stats.rays * 1e-6,
           (double)stats.rays * 1e-6 / stats.seconds, (double)stats.samples * 1e-6);
    if (!set.timing) {
        printf("glint: %.1f M calls, not timed (--no-timing)\n",
               (double)stats.glint_calls * 1e-6);
    } else {
        /* Each timed call adds timer_inside_ns to the Glint time and timer_pair_ns to the
         * thread's time: report the shares without them (and the raw measurement). */
        static const char *const kinds[GLINT_KINDS] = {
            "closure build (reset + lobe blocks)", "closure build (reset + compiled material)",
            "glint_eval", "glint_sample"};
        const double calls = (double)stats.glint_calls;
        const double thread = stats.thread_seconds - calls * stats.timer_pair_ns * 1e-9;
        const double glint = stats.glint_seconds - calls * stats.timer_inside_ns * 1e-9;
        int k;
        printf("glint: %.1f%% of render-thread time inside glint calls (%.1f of %.1f thread-s, "
               "%.1f M calls; the timers' own cost removed: %.0f ns per call, %.0f ns of it "
               "inside the interval; as measured %.1f%%)\n",
               thread > 0 ? 100.0 * glint / thread : 0.0, glint, thread, calls * 1e-6,
               stats.timer_pair_ns, stats.timer_inside_ns,
               stats.thread_seconds > 0 ? 100.0 * stats.glint_seconds / stats.thread_seconds
                                        : 0.0);
        for (k = 0; k < GLINT_KINDS; k++) {
            const double n = (double)stats.glint_kind_calls[k];
            const double t = stats.glint_kind_seconds[k] - n * stats.timer_inside_ns * 1e-9;
            printf("  %-41s %5.1f%% of thread time, %6.1f M calls, %5.0f ns each\n", kinds[k],
                   thread > 0 ? 100.0 * t / thread : 0.0, n * 1e-6, n > 0 ? t * 1e9 / n : 0.0);
        }
    }
    if (stats.nonfinite)
        printf("warning: %llu samples were NaN or infinite\n", (unsigned long long)stats.nonfinite);
    if (stats.glint_errors)
        printf("warning: %llu glint errors, the first: %s\n",
               (unsigned long long)stats.glint_errors, stats.first_error);
    printf("wrote %s.exr and %s.png\n", out, out);
    status = stats.glint_errors ? EXIT_FAILURE : EXIT_SUCCESS;

done_acc:
    free(acc.sum);
    free(acc.sum_sq);
    free(acc.hits);
done:
    scene_free(&scene);
    glint_runtime_destroy(rt);
    return status;
}
