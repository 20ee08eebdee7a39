/* Stress: 32 host threads at once, each running a rotation of every concurrent use
 * the API allows: building closures in its own arena (from JSON and from parameter
 * blocks) on a shared runtime, evaluating closures shared by all threads, running
 * batches on shared runtimes with threads=1 and threads=2, creating a runtime of its
 * own that loads the Charlie plugin, building closures of compiled materials shared by
 * all threads (per-point contexts and overrides, in its own arena), and running
 * material batches over shared materials on both batch runtimes. Every task writes its
 * results to a buffer
 * that must be bit-identical to the single-threaded run of the same task (and the
 * threads=1 and threads=2 batches to each other). cmocka's assertions are not
 * thread-safe: the threads count mismatches and failures, the main thread asserts. */
#define _POSIX_C_SOURCE 200809L

#include "common.h"

#include <pthread.h>
#include <stdlib.h>

#define THREADS 32
#define ROUNDS 3
#define QUERIES 64
/* Above the batch block size, so a threads=2 runtime splits the batch across its pool. */
#define LANES 9000
#define SCALAR_FLOATS (QUERIES * 20)
#define BATCH_FLOATS (LANES * 14) /* eval 4, sample 7, albedo 3 */

static const char *const DESCRIPTIONS[] = {
    "{\"lobes\": [{\"type\": \"lambert\", \"color\": [0.8, 0.3, 0.2]}]}",
    "{\"lobes\": [{\"type\": \"conductor\", \"distribution\": \"ggx\", \"roughness\": 0.35,"
    " \"anisotropic\": 0.5, \"tangent\": [1, 0.2, 0]}]}",
    "{\"lobes\": [{\"type\": \"lambert\", \"weight\": 0.6},"
    " {\"type\": \"dielectric\", \"roughness\": 0.1, \"eta\": 1.5}]}",
    "{\"transport\": \"importance\", \"lobes\": [{\"type\": \"conductor\","
    " \"distribution\": \"beckmann\", \"roughness\": 0.2},"
    " {\"type\": \"mirror\", \"weight\": 0.3}]}",
};
#define CLOSURES (int)(sizeof DESCRIPTIONS / sizeof DESCRIPTIONS[0])

/* Compiled materials, one per task variant: every Disney lobe (anisotropic), a metal,
 * a car paint, a sheen fabric. */
static const char *const MATERIALS[CLOSURES] = {
    "{\"material\": \"disney\", \"base_color\": [0.8, 0.2, 0.1], \"metallic\": 0.3,"
    " \"subsurface\": 0.5, \"sheen\": 1, \"clearcoat\": 1, \"clearcoat_gloss\": 0.8,"
    " \"anisotropic\": 0.4}",
    "{\"material\": \"disney\", \"base_color\": [0.9, 0.6, 0.3], \"metallic\": 1,"
    " \"roughness\": 0.3, \"anisotropic\": 0.7}",
    "{\"material\": \"disney\", \"base_color\": [0.7, 0.05, 0.05], \"metallic\": 0.6,"
    " \"roughness\": 0.4, \"clearcoat\": 1, \"clearcoat_gloss\": 1}",
    "{\"material\": \"disney\", \"base_color\": [0.3, 0.3, 0.6], \"roughness\": 0.9,"
    " \"sheen\": 1, \"sheen_tint\": 0.5, \"subsurface\": 0.3}",
};

typedef enum task_kind {
    TASK_BUILD_JSON,   /* own arena, shared runtime, closure `variant` from JSON */
    TASK_BUILD_BLOCKS, /* own arena, shared runtime, defaults via parameter blocks */
    TASK_SHARED,       /* shared closure `variant` */
    TASK_BATCH_1,      /* batches on the threads=1 runtime */
    TASK_BATCH_2,      /* the same batches on the threads=2 runtime */
    TASK_PLUGIN,       /* own runtime, load charlie, evaluate a charlie closure */
    TASK_MATERIAL,     /* own arena, shared material `variant`: a closure per query */
    TASK_MATERIAL_BATCH_1, /* material `variant`'s batches on the threads=1 runtime */
    TASK_MATERIAL_BATCH_2, /* the same on the threads=2 runtime */
    TASK_MATERIAL_OWN, /* own arena and own material `variant`, compiled on the shared
                          runtime while others compile, use and destroy theirs */
    TASK_KINDS
} task_kind;

typedef struct world {
    glint_runtime *shared, *batch_rt[2];
    glint_arena *arena;
    const glint_closure *closures[CLOSURES], *batch_closures[2][CLOSURES];
    glint_material *materials[CLOSURES], *batch_materials[2][CLOSURES];
    glint_vec3 wo[QUERIES], wi[QUERIES], normal[QUERIES];
    float u[QUERIES][3];
    float *lanes; /* LANES x 6: wo, then wi (eval) or u_lobe, u0, u1 (sample) */
    float *material_lanes; /* LANES x 7: normal, then base_color and roughness overrides */
    glint_override_lanes lane_overrides[2];
    uint32_t base_color, roughness; /* the Disney parameters the overrides set */
    uint8_t active[LANES];
    const glint_closure *lane_closures[2][LANES];
} world;

static world W;

/* Failures inside tasks: counted, never asserted off the main thread. */
typedef struct tally {
    int failures;
    char first[200];
} tally;

static void record_failure(tally *t, const char *what, glint_status st)
{
    if (t->failures++ == 0)
        snprintf(t->first, sizeof t->first, "%s: %s (%s)", what, glint_status_string(st),
                 glint_last_error());
}

/* eval, sample, pdf and albedo of `c` at query `q`: 20 floats into `o`. */
static void query(const glint_closure *c, int q, float *o, tally *t)
{
    glint_eval_result e = eval_result_init();
    glint_sample_result s = sample_result_init();
    glint_status st;
    if ((st = glint_eval(c, W.wo[q], W.wi[q], &e)) != GLINT_OK)
        record_failure(t, "glint_eval", st);
    st = glint_sample(c, W.wo[q], W.u[q][0], W.u[q][1], W.u[q][2], &s);
    if (st != GLINT_OK && st != GLINT_NO_SAMPLE)
        record_failure(t, "glint_sample", st);
    if ((st = glint_pdf(c, W.wo[q], W.wi[q], &o[0])) != GLINT_OK)
        record_failure(t, "glint_pdf", st);
    if ((st = glint_albedo(c, W.wo[q], &o[1])) != GLINT_OK)
        record_failure(t, "glint_albedo", st);
    memcpy(&o[4], e.value, sizeof e.value);
    o[7] = e.pdf;
    o[8] = e.pdf_reverse;
    o[9] = s.wi.x;
    o[10] = s.wi.y;
    o[11] = s.wi.z;
    memcpy(&o[12], s.value, sizeof s.value);
    o[15] = s.pdf;
    memcpy(&o[16], s.weight, sizeof s.weight);
    o[19] = (float)(s.flags * 32u + s.lobe);
}

/* `query` of `c` at every query: 20 floats each. */
static void scalar_queries(const glint_closure *c, float *out, tally *t)
{
    int q;
    for (q = 0; q < QUERIES; q++)
        query(c, q, out + q * 20, t);
}

/* Material `m`'s closure at each query (its wo and normal, a base color and a
 * roughness set per query), built in `arena`, then `query` of it: 20 floats each. */
static void material_queries(const glint_material *m, glint_arena *arena, float *out, tally *t)
{
    int q;
    for (q = 0; q < QUERIES; q++) {
        glint_shading_context ctx;
        glint_override o[2];
        glint_closure *c = NULL;
        glint_status st;
        memset(&ctx, 0, sizeof ctx);
        memset(o, 0, sizeof o);
        ctx.struct_size = sizeof ctx;
        ctx.wo = W.wo[q];
        ctx.normal = W.normal[q];
        o[0].param = W.base_color;
        o[0].param_type = GLINT_PARAM_RGB;
        o[0].value[0] = W.u[q][0];
        o[0].value[1] = W.u[q][1];
        o[0].value[2] = 0.5f;
        o[1].param = W.roughness;
        o[1].param_type = GLINT_PARAM_FLOAT;
        o[1].value[0] = W.u[q][2];
        glint_arena_reset(arena);
        if ((st = glint_material_closure(m, arena, &ctx, o, 2, &c)) != GLINT_OK)
            record_failure(t, "glint_material_closure", st);
        else
            query(c, q, out + q * 20, t);
    }
}

static glint_closure *build_json(const glint_runtime *rt, glint_arena *arena, const char *json,
                                 tally *t)
{
    glint_closure *c = NULL;
    glint_status st = glint_closure_from_json(rt, arena, json, NULL, &c);
    if (st != GLINT_OK)
        record_failure(t, "glint_closure_from_json", st);
    return c;
}

/* A closure of every built-in type at its defaults, from parameter blocks. */
static glint_closure *build_blocks(glint_arena *arena, tally *t)
{
    static const char *const types[] = {"lambert", "conductor", "dielectric"};
    glint_closure *c = NULL;
    glint_frame frame = {{0.1f, -0.2f, 1.0f}, {0.0f, 0.0f, 0.0f}};
    glint_vec3 wo = {0.3f, 0.2f, 0.9f};
    glint_status st = glint_closure_begin(W.shared, arena, &wo, 0, &c);
    size_t i;
    if (st != GLINT_OK) {
        record_failure(t, "glint_closure_begin", st);
        return NULL;
    }
    for (i = 0; i < sizeof types / sizeof types[0]; i++) {
        const float weight[3] = {0.3f, 0.25f + 0.1f * (float)i, 0.2f};
        float block[512];
        uint32_t id = 0;
        glint_lobe_info info = lobe_info_init();
        if ((st = glint_lobe_type_find(W.shared, types[i], &id)) != GLINT_OK ||
            (st = glint_lobe_type_info(W.shared, id, &info)) != GLINT_OK ||
            (st = glint_lobe_param_defaults(W.shared, id, block, 512)) != GLINT_OK ||
            (st = glint_closure_add_lobe(c, id, weight, &frame, block, info.param_block_size,
                                         NULL)) != GLINT_OK) {
            record_failure(t, types[i], st);
            return NULL;
        }
    }
    if ((st = glint_closure_finish(c)) != GLINT_OK)
        record_failure(t, "glint_closure_finish", st);
    return c;
}

/* Eval, sample and albedo batches over LANES lanes on runtime `r`: per-lane closures
 * (cycling through that runtime's closures) with every seventh lane inactive. */
static void batches(int r, float *out, tally *t)
{
    const float *l = W.lanes;
    float *o = out;
    glint_status st;
    {
        glint_eval_batch_args a = {0};
        a.struct_size = sizeof a;
        a.count = LANES;
        a.closures = W.lane_closures[r];
        a.active = W.active;
        a.wo_x = l, a.wo_y = l + LANES, a.wo_z = l + 2 * LANES;
        a.wi_x = l + 3 * LANES, a.wi_y = l + 4 * LANES, a.wi_z = l + 5 * LANES;
        a.value_r = o, a.value_g = o + LANES, a.value_b = o + 2 * LANES, a.pdf = o + 3 * LANES;
        if ((st = glint_eval_batch(&a)) != GLINT_OK)
            record_failure(t, "glint_eval_batch", st);
        o += 4 * LANES;
    }
    {
        glint_sample_batch_args a = {0};
        a.struct_size = sizeof a;
        a.count = LANES;
        a.closure = W.batch_closures[r][2];
        a.wo_x = l, a.wo_y = l + LANES, a.wo_z = l + 2 * LANES;
        a.u_lobe = l + 3 * LANES, a.u0 = l + 4 * LANES, a.u1 = l + 5 * LANES;
        a.wi_x = o, a.wi_y = o + LANES, a.wi_z = o + 2 * LANES, a.pdf = o + 3 * LANES;
        a.weight_r = o + 4 * LANES, a.weight_g = o + 5 * LANES, a.weight_b = o + 6 * LANES;
        if ((st = glint_sample_batch(&a)) != GLINT_OK)
            record_failure(t, "glint_sample_batch", st);
        o += 7 * LANES;
    }
    {
        glint_albedo_batch_args a = {0};
        a.struct_size = sizeof a;
        a.count = LANES;
        a.closures = W.lane_closures[r];
        a.active = W.active;
        a.wo_x = l, a.wo_y = l + LANES, a.wo_z = l + 2 * LANES;
        a.albedo_r = o, a.albedo_g = o + LANES;
        a.albedo_b = o + 2 * LANES;
        if ((st = glint_albedo_batch(&a)) != GLINT_OK)
            record_failure(t, "glint_albedo_batch", st);
    }
}

/* The lanes of a material batch over `m`: the closure batches' wo and active lanes,
 * a normal, a base color and a roughness per lane. */
static glint_material_lanes material_lanes(const glint_material *m)
{
    glint_material_lanes l;
    const float *n = W.material_lanes;
    memset(&l, 0, sizeof l);
    l.material = m;
    l.count = LANES;
    l.active = W.active;
    l.wo_x = W.lanes, l.wo_y = W.lanes + LANES, l.wo_z = W.lanes + 2 * LANES;
    l.normal_x = n, l.normal_y = n + LANES, l.normal_z = n + 2 * LANES;
    l.overrides = W.lane_overrides;
    l.override_count = 2;
    return l;
}

/* Eval, sample and albedo material batches over `m` (as `batches`' outputs). */
static void material_batches(const glint_material *m, float *out, tally *t)
{
    const float *l = W.lanes;
    float *o = out;
    glint_status st;
    {
        glint_material_eval_batch_args a;
        memset(&a, 0, sizeof a);
        a.struct_size = sizeof a;
        a.lanes = material_lanes(m);
        a.wi_x = l + 3 * LANES, a.wi_y = l + 4 * LANES, a.wi_z = l + 5 * LANES;
        a.value_r = o, a.value_g = o + LANES, a.value_b = o + 2 * LANES, a.pdf = o + 3 * LANES;
        if ((st = glint_material_eval_batch(&a)) != GLINT_OK)
            record_failure(t, "glint_material_eval_batch", st);
        o += 4 * LANES;
    }
    {
        glint_material_sample_batch_args a;
        memset(&a, 0, sizeof a);
        a.struct_size = sizeof a;
        a.lanes = material_lanes(m);
        a.u_lobe = l + 3 * LANES, a.u0 = l + 4 * LANES, a.u1 = l + 5 * LANES;
        a.wi_x = o, a.wi_y = o + LANES, a.wi_z = o + 2 * LANES, a.pdf = o + 3 * LANES;
        a.weight_r = o + 4 * LANES, a.weight_g = o + 5 * LANES, a.weight_b = o + 6 * LANES;
        if ((st = glint_material_sample_batch(&a)) != GLINT_OK)
            record_failure(t, "glint_material_sample_batch", st);
        o += 7 * LANES;
    }
    {
        glint_material_albedo_batch_args a;
        memset(&a, 0, sizeof a);
        a.struct_size = sizeof a;
        a.lanes = material_lanes(m);
        a.albedo_r = o, a.albedo_g = o + LANES, a.albedo_b = o + 2 * LANES;
        if ((st = glint_material_albedo_batch(&a)) != GLINT_OK)
            record_failure(t, "glint_material_albedo_batch", st);
    }
}

static void plugin_task(float *out, tally *t)
{
    glint_runtime *rt = NULL;
    glint_arena *arena = NULL;
    glint_status st;
    if ((st = glint_runtime_create("threads=1", &rt)) != GLINT_OK) {
        record_failure(t, "glint_runtime_create", st);
        return;
    }
    if ((st = glint_runtime_load_plugin(rt, GLINT_CHARLIE_PATH)) != GLINT_OK)
        record_failure(t, "glint_runtime_load_plugin", st);
    else if ((st = glint_arena_create(2, &arena)) != GLINT_OK)
        record_failure(t, "glint_arena_create", st);
    else {
        glint_closure *c = build_json(
            rt, arena,
            "{\"lobes\": [{\"type\": \"charlie\", \"roughness\": 0.4, \"color\": [1, 0.5, 0.2]},"
            " {\"type\": \"lambert\", \"weight\": 0.5}]}",
            t);
        if (c)
            scalar_queries(c, out, t);
    }
    glint_arena_destroy(arena);
    glint_runtime_destroy(rt);
}

/* Run task (kind, variant) into `out` (SCALAR_FLOATS or BATCH_FLOATS floats). */
static void run_task(task_kind kind, int variant, float *out, tally *t)
{
    glint_arena *arena = NULL;
    glint_closure *c = NULL;
    glint_status st;
    switch (kind) {
    case TASK_BUILD_JSON:
    case TASK_BUILD_BLOCKS:
        if ((st = glint_arena_create(4, &arena)) != GLINT_OK) {
            record_failure(t, "glint_arena_create", st);
            return;
        }
        c = kind == TASK_BUILD_JSON ? build_json(W.shared, arena, DESCRIPTIONS[variant], t)
                                    : build_blocks(arena, t);
        if (c)
            scalar_queries(c, out, t);
        glint_arena_destroy(arena);
        break;
    case TASK_SHARED:
        scalar_queries(W.closures[variant], out, t);
        break;
    case TASK_BATCH_1:
    case TASK_BATCH_2:
        batches(kind == TASK_BATCH_2, out, t);
        break;
    case TASK_PLUGIN:
        plugin_task(out, t);
        break;
    case TASK_MATERIAL:
        if ((st = glint_arena_create(1, &arena)) != GLINT_OK) {
            record_failure(t, "glint_arena_create", st);
            return;
        }
        material_queries(W.materials[variant], arena, out, t);
        glint_arena_destroy(arena);
        break;
    case TASK_MATERIAL_BATCH_1:
    case TASK_MATERIAL_BATCH_2:
        material_batches(W.batch_materials[kind == TASK_MATERIAL_BATCH_2][variant], out, t);
        break;
    case TASK_MATERIAL_OWN: {
        glint_material *m = NULL;
        if ((st = glint_material_create(W.shared, MATERIALS[variant], &m)) != GLINT_OK) {
            record_failure(t, "glint_material_create", st);
            return;
        }
        if ((st = glint_arena_create(1, &arena)) != GLINT_OK)
            record_failure(t, "glint_arena_create", st);
        else
            material_queries(m, arena, out, t);
        glint_arena_destroy(arena);
        glint_material_destroy(m);
        break;
    }
    default:
        break;
    }
}

static size_t task_floats(task_kind kind)
{
    return kind == TASK_BATCH_1 || kind == TASK_BATCH_2 || kind == TASK_MATERIAL_BATCH_1 ||
                   kind == TASK_MATERIAL_BATCH_2
               ? BATCH_FLOATS
               : SCALAR_FLOATS;
}

/* Single-threaded results of every (kind, variant). */
static float *reference[TASK_KINDS][CLOSURES];

typedef struct worker {
    int index;
    tally t;
    int mismatches, tasks;
    float *out;
} worker;

static void *work(void *arg)
{
    worker *w = arg;
    int round, k;
    for (round = 0; round < ROUNDS; round++) {
        for (k = 0; k < TASK_KINDS; k++) {
            /* Threads start at different kinds, so every kind runs alongside the others. */
            task_kind kind = (task_kind)((k + w->index + round) % TASK_KINDS);
            int variant = (w->index + round) % CLOSURES;
            size_t n = task_floats(kind);
            memset(w->out, 0xff, n * sizeof(float));
            run_task(kind, variant, w->out, &w->t);
            w->tasks++;
            if (memcmp(w->out, reference[kind][variant], n * sizeof(float)) != 0)
                w->mismatches++;
        }
    }
    return NULL;
}

static void setup_world(void)
{
    lcg g;
    int i, r;
    assert_int_equal(glint_runtime_create("threads=1", &W.shared), GLINT_OK);
    assert_int_equal(glint_runtime_create("threads=1", &W.batch_rt[0]), GLINT_OK);
    assert_int_equal(glint_runtime_create("threads=2", &W.batch_rt[1]), GLINT_OK);
    assert_int_equal(glint_arena_create(3 * CLOSURES, &W.arena), GLINT_OK);
    for (i = 0; i < CLOSURES; i++) {
        tally t = {0};
        W.closures[i] = build_json(W.shared, W.arena, DESCRIPTIONS[i], &t);
        for (r = 0; r < 2; r++)
            W.batch_closures[r][i] = build_json(W.batch_rt[r], W.arena, DESCRIPTIONS[i], &t);
        assert_int_equal(t.failures, 0);
        assert_int_equal(glint_material_create(W.shared, MATERIALS[i], &W.materials[i]),
                         GLINT_OK);
        for (r = 0; r < 2; r++)
            assert_int_equal(
                glint_material_create(W.batch_rt[r], MATERIALS[i], &W.batch_materials[r][i]),
                GLINT_OK);
    }
    {
        uint32_t disney = 0;
        assert_int_equal(glint_material_type_find(W.shared, "disney", &disney), GLINT_OK);
        assert_int_equal(glint_material_param_find(W.shared, disney, "base_color", &W.base_color),
                         GLINT_OK);
        assert_int_equal(glint_material_param_find(W.shared, disney, "roughness", &W.roughness),
                         GLINT_OK);
    }
    lcg_seed(&g, 12);
    for (i = 0; i < QUERIES; i++) {
        W.wo[i] = lcg_direction(&g, i % 8 != 0);
        W.wi[i] = lcg_direction(&g, i % 3 != 0);
        W.u[i][0] = lcg_next(&g);
        W.u[i][1] = lcg_next(&g);
        W.u[i][2] = lcg_next(&g);
        W.normal[i] = v3(0.4f * lcg_next(&g) - 0.2f, 0.4f * lcg_next(&g) - 0.2f, 1.0f);
    }
    W.lanes = malloc(6 * LANES * sizeof(float));
    assert_non_null(W.lanes);
    W.material_lanes = malloc(7 * LANES * sizeof(float));
    assert_non_null(W.material_lanes);
    for (i = 0; i < LANES; i++) {
        glint_vec3 wo = lcg_direction(&g, i % 8 != 0);
        W.lanes[i] = wo.x;
        W.lanes[LANES + i] = wo.y;
        W.lanes[2 * LANES + i] = wo.z;
        for (r = 3; r < 6; r++) /* wi components for eval, random numbers for sample */
            W.lanes[r * LANES + i] = lcg_next(&g);
        W.active[i] = i % 7 != 3;
        W.material_lanes[i] = 0.4f * lcg_next(&g) - 0.2f;
        W.material_lanes[LANES + i] = 0.4f * lcg_next(&g) - 0.2f;
        W.material_lanes[2 * LANES + i] = 1.0f;
        for (r = 3; r < 7; r++) /* base color, roughness */
            W.material_lanes[r * LANES + i] = lcg_next(&g);
        for (r = 0; r < 2; r++)
            W.lane_closures[r][i] = W.batch_closures[r][(i / 5) % CLOSURES];
    }
    W.lane_overrides[0].param = W.base_color;
    W.lane_overrides[0].param_type = GLINT_PARAM_RGB;
    for (r = 0; r < 3; r++)
        W.lane_overrides[0].value[r] = W.material_lanes + (3 + r) * LANES;
    W.lane_overrides[1].param = W.roughness;
    W.lane_overrides[1].param_type = GLINT_PARAM_FLOAT;
    W.lane_overrides[1].value[0] = W.material_lanes + 6 * LANES;
}

static void teardown_world(void)
{
    int r, i;
    for (i = 0; i < CLOSURES; i++) {
        glint_material_destroy(W.materials[i]);
        for (r = 0; r < 2; r++)
            glint_material_destroy(W.batch_materials[r][i]);
    }
    glint_arena_destroy(W.arena);
    glint_runtime_destroy(W.shared);
    for (r = 0; r < 2; r++)
        glint_runtime_destroy(W.batch_rt[r]);
    free(W.lanes);
    free(W.material_lanes);
}

static void test_stress_matches_single_threaded(void **state)
{
    static worker workers[THREADS];
    pthread_t threads[THREADS];
    int k, v, i, mismatches = 0, failures = 0, tasks = 0;
    (void)state;
    setup_world();
    for (k = 0; k < TASK_KINDS; k++) {
        for (v = 0; v < CLOSURES; v++) {
            tally t = {0};
            reference[k][v] = malloc(task_floats((task_kind)k) * sizeof(float));
            assert_non_null(reference[k][v]);
            memset(reference[k][v], 0xff, task_floats((task_kind)k) * sizeof(float));
            run_task((task_kind)k, v, reference[k][v], &t);
            if (t.failures)
                fail_msg("single-threaded task %d/%d: %s", k, v, t.first);
        }
    }
    /* Batch results do not depend on the runtime's thread count. */
    assert_memory_equal(reference[TASK_BATCH_1][0], reference[TASK_BATCH_2][0],
                        BATCH_FLOATS * sizeof(float));
    /* Nor on the runtime's thread count; a material compiled again from the same
     * document builds the same closures. */
    for (v = 0; v < CLOSURES; v++) {
        assert_memory_equal(reference[TASK_MATERIAL_BATCH_1][v],
                            reference[TASK_MATERIAL_BATCH_2][v], BATCH_FLOATS * sizeof(float));
        assert_memory_equal(reference[TASK_MATERIAL_OWN][v], reference[TASK_MATERIAL][v],
                            SCALAR_FLOATS * sizeof(float));
    }

    for (i = 0; i < THREADS; i++) {
        workers[i].index = i;
        workers[i].out = malloc(BATCH_FLOATS * sizeof(float));
        assert_non_null(workers[i].out);
        assert_int_equal(pthread_create(&threads[i], NULL, work, &workers[i]), 0);
    }
    for (i = 0; i < THREADS; i++) {
        assert_int_equal(pthread_join(threads[i], NULL), 0);
        mismatches += workers[i].mismatches;
        failures += workers[i].t.failures;
        tasks += workers[i].tasks;
        if (workers[i].t.failures)
            print_message("thread %d: %s\n", i, workers[i].t.first);
        free(workers[i].out);
    }
    assert_int_equal(tasks, THREADS * ROUNDS * TASK_KINDS);
    assert_int_equal(failures, 0);
    assert_int_equal(mismatches, 0);
    for (k = 0; k < TASK_KINDS; k++)
        for (v = 0; v < CLOSURES; v++)
            free(reference[k][v]);
    teardown_world();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stress_matches_single_threaded),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
