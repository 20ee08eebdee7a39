/* Scalar C-call latency: the median time of one glint_eval, glint_eval_forward and
 * glint_sample call per registered lobe type (a closure holding that lobe alone,
 * default parameters), measured through the public C ABI as a ray tracer calls it,
 * of building a two-lobe closure (lambert + conductor) from parameter blocks, and of
 * compiled Disney materials' closures. Prints a Markdown table.
 *
 *   build/c_bench/latency [calls-per-repeat]
 */
#define _POSIX_C_SOURCE 199309L
#include <glint.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define REPEATS 21
#define DIRS 1024

static double now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static float next(unsigned long long *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return (float)(*s >> 40) / 16777216.0f;
}

static void check(glint_status st, const char *what)
{
    if (st != GLINT_OK && st != GLINT_NO_SAMPLE) {
        fprintf(stderr, "%s: %s (%s)\n", what, glint_status_string(st), glint_last_error());
        exit(1);
    }
}

/* Median time of glint_closure_begin, two glint_closure_add_lobe (lambert and a
 * conductor, full parameter blocks) and glint_closure_finish, the arena reset every
 * 64 closures (the reset's time included). */
static void build_two_lobes(glint_runtime *rt, glint_arena *arena, long calls)
{
    const float weight[3] = {0.5f, 0.5f, 0.5f};
    const glint_frame frame = {{0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}};
    const glint_vec3 wo = {0.3f, 0.2f, 0.93f};
    uint32_t ids[2];
    float blocks[2][64];
    uint32_t sizes[2];
    double ns[REPEATS];
    int rep, b;
    check(glint_lobe_type_find(rt, "lambert", &ids[0]), "find lambert");
    check(glint_lobe_type_find(rt, "conductor", &ids[1]), "find conductor");
    for (b = 0; b < 2; b++) {
        glint_lobe_info info;
        info.struct_size = sizeof info;
        check(glint_lobe_type_info(rt, ids[b], &info), "info");
        check(glint_lobe_param_defaults(rt, ids[b], blocks[b], 64), "defaults");
        sizes[b] = info.param_block_size;
    }
    for (rep = 0; rep < REPEATS; rep++) {
        double t0 = now_ns();
        long k;
        for (k = 0; k < calls; k++) {
            glint_closure *c = NULL;
            if (k % 64 == 0)
                check(glint_arena_reset(arena), "reset");
            check(glint_closure_begin(rt, arena, &wo, 0, &c), "begin");
            for (b = 0; b < 2; b++)
                check(glint_closure_add_lobe(c, ids[b], weight, &frame, blocks[b], sizes[b], NULL),
                      "add");
            check(glint_closure_finish(c), "finish");
        }
        ns[rep] = (now_ns() - t0) / (double)calls;
    }
    qsort(ns, REPEATS, sizeof(double), cmp_double);
    printf("\n| two-lobe closure from blocks (begin, 2 add_lobe, finish) | %.1f ns |\n"
           "| --- | --- |\n", ns[REPEATS / 2]);
}

typedef glint_status (*eval_call)(const glint_closure *, glint_vec3, glint_vec3,
                                  glint_eval_result *);

/* Mean time of one `eval` of `c` from `wo` over `calls` calls, `wi` sweeping an arc;
 * the pdfs go to `sink` so that the calls stay. */
static double time_eval(eval_call eval, const glint_closure *c, glint_vec3 wo, long calls,
                        float *sink)
{
    glint_eval_result e;
    double t0 = now_ns();
    long k;
    e.struct_size = sizeof e;
    for (k = 0; k < calls; k++) {
        glint_vec3 wi = {-0.2f + 0.001f * (float)(k & 255), 0.1f, 0.9f};
        check(eval(c, wo, wi, &e), "eval");
        *sink += e.pdf;
    }
    return (now_ns() - t0) / (double)calls;
}

/* Median time of glint_material_closure for a full Disney material (every lobe on),
 * with a base-color and a roughness override per call (as a textured host passes),
 * the arena reset every 64 closures; then glint_eval and glint_eval_forward on such a
 * closure. */
static void material_closure(glint_runtime *rt, glint_arena *arena, long calls)
{
    const char *json = "{\"material\": \"disney\", \"base_color\": [0.8, 0.2, 0.1], "
                       "\"metallic\": 0.3, \"subsurface\": 0.5, \"sheen\": 1, "
                       "\"clearcoat\": 1, \"clearcoat_gloss\": 0.8, \"anisotropic\": 0.4}";
    glint_material *m = NULL;
    glint_shading_context ctx;
    glint_override o[2];
    double ns[REPEATS], eval_ns[REPEATS], forward_ns[REPEATS];
    uint32_t lobes = 0;
    int rep;
    float sink = 0.0f;
    memset(&ctx, 0, sizeof ctx);
    memset(o, 0, sizeof o);
    ctx.struct_size = sizeof ctx;
    ctx.wo.x = 0.3f, ctx.wo.y = 0.2f, ctx.wo.z = 0.93f;
    ctx.normal.z = 1.0f;
    o[0].param = 0, o[0].param_type = GLINT_PARAM_RGB;
    o[1].param = 5, o[1].param_type = GLINT_PARAM_FLOAT;
    check(glint_material_create(rt, json, &m), "material");
    for (rep = 0; rep < REPEATS; rep++) {
        double t0 = now_ns();
        long k;
        for (k = 0; k < calls; k++) {
            glint_closure *c = NULL;
            if (k % 64 == 0)
                check(glint_arena_reset(arena), "reset");
            o[0].value[0] = 0.5f + 0.4f * (float)(k & 7) / 8.0f;
            o[0].value[1] = o[0].value[2] = 0.3f;
            o[1].value[0] = 0.2f + 0.05f * (float)(k & 15);
            check(glint_material_closure(m, arena, &ctx, o, 2, &c), "material closure");
        }
        ns[rep] = (now_ns() - t0) / (double)calls;
    }
    for (rep = 0; rep < REPEATS; rep++) {
        glint_closure *c = NULL;
        check(glint_arena_reset(arena), "reset");
        check(glint_material_closure(m, arena, &ctx, o, 2, &c), "material closure");
        check(glint_closure_lobe_count(c, &lobes), "lobes");
        eval_ns[rep] = time_eval(glint_eval, c, ctx.wo, calls, &sink);
        forward_ns[rep] = time_eval(glint_eval_forward, c, ctx.wo, calls, &sink);
    }
    qsort(ns, REPEATS, sizeof(double), cmp_double);
    qsort(eval_ns, REPEATS, sizeof(double), cmp_double);
    qsort(forward_ns, REPEATS, sizeof(double), cmp_double);
    printf("| full disney material: glint_material_closure (2 overrides) | %.1f ns |\n"
           "| glint_eval on its closure (%u lobes) | %.1f ns |\n"
           "| glint_eval_forward on its closure | %.1f ns |\n",
           ns[REPEATS / 2], lobes, eval_ns[REPEATS / 2], forward_ns[REPEATS / 2]);
    if (!(sink >= 0.0f))
        fprintf(stderr, "unexpected pdf sum\n");
    glint_material_destroy(m);
}

/* Median time of glint_arena_reset and glint_material_closure as a path tracer calls
 * them at each hit (the path tracer's "closure build" interval): its car paint
 * (disney_paint: diffuse, specular and clearcoat lobes), no overrides, the host's
 * tangent and geometric normal given, normals tilted and views varying over DIRS
 * shading points. */
static void material_closure_at_hits(glint_runtime *rt, glint_arena *arena, long calls,
                                     const glint_vec3 *wo)
{
    const char *json = "{\"material\": \"disney\", \"base_color\": [0.70, 0.04, 0.04], "
                       "\"metallic\": 0.5, \"roughness\": 0.4, \"clearcoat\": 1, "
                       "\"clearcoat_gloss\": 0.9}";
    static glint_vec3 normal[DIRS], tangent[DIRS];
    glint_material *m = NULL;
    glint_shading_context ctx;
    double ns[REPEATS];
    int rep, i;
    memset(&ctx, 0, sizeof ctx);
    ctx.struct_size = sizeof ctx;
    for (i = 0; i < DIRS; i++) {
        /* Unit normals 11 degrees off z and a unit tangent perpendicular to each. */
        const float phi = 6.2831853f * (float)i / (float)DIRS;
        const float s = sinf(phi), c = cosf(phi);
        normal[i].x = 0.19612f * s, normal[i].y = 0.19612f * c, normal[i].z = 0.98058f;
        tangent[i].x = c, tangent[i].y = -s, tangent[i].z = 0.0f;
    }
    check(glint_material_create(rt, json, &m), "material");
    for (rep = 0; rep < REPEATS; rep++) {
        double t0 = now_ns();
        long k;
        for (k = 0; k < calls; k++) {
            glint_closure *c = NULL;
            const long at = k % DIRS;
            ctx.wo = wo[at];
            ctx.normal = ctx.geometric_normal = normal[at];
            ctx.tangent = tangent[at];
            ctx.position.x = ctx.reference_position.x = (float)at;
            check(glint_arena_reset(arena), "reset");
            check(glint_material_closure(m, arena, &ctx, NULL, 0, &c), "material closure");
        }
        ns[rep] = (now_ns() - t0) / (double)calls;
    }
    qsort(ns, REPEATS, sizeof(double), cmp_double);
    printf("| car paint at path-tracer hits: glint_arena_reset + glint_material_closure | "
           "%.1f ns |\n",
           ns[REPEATS / 2]);
    glint_material_destroy(m);
}

int main(int argc, char **argv)
{
    long calls = argc > 1 ? atol(argv[1]) : 200000;
    glint_runtime *rt = NULL;
    glint_arena *arena = NULL;
    static glint_vec3 wo[DIRS], wi[DIRS];
    static float u[DIRS][3];
    unsigned long long seed = 0x2545f4914f6cdd1dull;
    uint32_t count = 0, id;
    const char *isa = NULL;
    int i;
    check(glint_runtime_create(NULL, &rt), "runtime");
    check(glint_arena_create(64, &arena), "arena");
    check(glint_lobe_type_count(rt, &count), "count");
    check(glint_runtime_isa(rt, &isa), "isa");
    for (i = 0; i < DIRS; i++) {
        float z = fmaxf(next(&seed), 0.01f), phi = 6.2831853f * next(&seed);
        float r = sqrtf(1.0f - z * z);
        wo[i].x = r * cosf(phi), wo[i].y = r * sinf(phi), wo[i].z = z;
        z = fmaxf(next(&seed), 0.01f), phi = 6.2831853f * next(&seed), r = sqrtf(1.0f - z * z);
        wi[i].x = r * cosf(phi), wi[i].y = r * sinf(phi), wi[i].z = z;
        u[i][0] = next(&seed), u[i][1] = next(&seed), u[i][2] = next(&seed);
    }
    printf("| lobe | glint_eval (ns) | glint_eval_forward (ns) | glint_sample (ns) |\n"
           "| --- | --- | --- | --- |\n");
    for (id = 0; id < count; id++) {
        glint_lobe_info info;
        glint_closure *c = NULL;
        const float weight[3] = {1.0f, 1.0f, 1.0f};
        const glint_frame frame = {{0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}};
        double eval_ns[REPEATS], forward_ns[REPEATS], sample_ns[REPEATS];
        float sink = 0.0f;
        int rep;
        info.struct_size = sizeof info;
        check(glint_lobe_type_info(rt, id, &info), "info");
        check(glint_closure_begin(rt, arena, NULL, 0, &c), "begin");
        check(glint_closure_add_lobe(c, id, weight, &frame, NULL, 0, NULL), "add");
        check(glint_closure_finish(c), "finish");
        for (rep = 0; rep < REPEATS; rep++) {
            double t0 = now_ns();
            long k;
            for (k = 0; k < calls; k++) {
                glint_eval_result r;
                r.struct_size = sizeof r;
                check(glint_eval(c, wo[k % DIRS], wi[k % DIRS], &r), "eval");
                sink += r.pdf;
            }
            eval_ns[rep] = (now_ns() - t0) / (double)calls;
            t0 = now_ns();
            for (k = 0; k < calls; k++) {
                glint_eval_result r;
                r.struct_size = sizeof r;
                check(glint_eval_forward(c, wo[k % DIRS], wi[k % DIRS], &r), "eval_forward");
                sink += r.pdf;
            }
            forward_ns[rep] = (now_ns() - t0) / (double)calls;
            t0 = now_ns();
            for (k = 0; k < calls; k++) {
                glint_sample_result s;
                const float *uk = u[k % DIRS];
                s.struct_size = sizeof s;
                check(glint_sample(c, wo[k % DIRS], uk[0], uk[1], uk[2], &s), "sample");
                sink += s.pdf;
            }
            sample_ns[rep] = (now_ns() - t0) / (double)calls;
        }
        qsort(eval_ns, REPEATS, sizeof(double), cmp_double);
        qsort(forward_ns, REPEATS, sizeof(double), cmp_double);
        qsort(sample_ns, REPEATS, sizeof(double), cmp_double);
        printf("| %s | %.1f | %.1f | %.1f |\n", info.name, eval_ns[REPEATS / 2],
               forward_ns[REPEATS / 2], sample_ns[REPEATS / 2]);
        if (!(sink >= 0.0f))
            fprintf(stderr, "unexpected pdf sum\n");
    }
    build_two_lobes(rt, arena, calls);
    material_closure(rt, arena, calls);
    material_closure_at_hits(rt, arena, calls, wo);
    printf("\n(median of %d repeats of %ld calls; glint_runtime_isa: %s)\n", REPEATS, calls, isa);
    glint_arena_destroy(arena);
    glint_runtime_destroy(rt);
    return 0;
}
