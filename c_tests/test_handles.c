/* Handle misuse and failure outputs: destroyed, doubly destroyed and reset handles are
 * detected (GLINT_ERROR_INVALID_HANDLE) instead of reading freed or reused memory,
 * per-lane batches never read inactive lanes' handles, and every failing call leaves
 * its outputs in the documented state (zeroed, handles NULL, glint_sample_result.eta
 * = 1). */
#include "common.h"

#include <stdlib.h>

#define LANES 4
/* Two batch blocks (4096 lanes each), so that a runtime with threads=2 uses its pool. */
#define BIG 8192

static const float WHITE[3] = {1.0f, 1.0f, 1.0f};
static const char *LAMBERT = "{\"lobes\": [{\"type\": \"lambert\", \"color\": 0.5}]}";
static const char *MIRROR = "{\"lobes\": [{\"type\": \"mirror\"}]}";

/* A value no successful or failing call writes. */
#define GARBAGE (-7.0f)

static glint_vec3 wi_test(void)
{
    return v3(-0.2f, 0.1f, 0.9f);
}

static glint_closure *from_json(glint_runtime *rt, glint_arena *arena, const char *json)
{
    glint_closure *c = NULL;
    assert_ok(glint_closure_from_json(rt, arena, json, NULL, &c));
    return c;
}

/* glint_eval fails with GLINT_ERROR_INVALID_HANDLE and zeroes the result. */
static void assert_eval_invalid(fixture *fx, const glint_closure *c)
{
    glint_eval_result r = eval_result_init();
    r.value[0] = r.pdf = r.pdf_reverse = GARBAGE;
    check_error(fx, glint_eval(c, test_wo(), wi_test(), &r), GLINT_ERROR_INVALID_HANDLE);
    assert_true(r.struct_size == sizeof r);
    assert_true(r.value[0] == 0.0f && r.pdf == 0.0f && r.pdf_reverse == 0.0f);
}

static void assert_zeroed_sample(const glint_sample_result *s)
{
    assert_true(s->struct_size == sizeof *s);
    assert_true(s->wi.x == 0.0f && s->wi.y == 0.0f && s->wi.z == 0.0f);
    assert_true(s->value[0] == 0.0f && s->pdf == 0.0f && s->weight[0] == 0.0f);
    assert_true(s->flags == 0 && s->lobe == 0 && s->roughness == 0.0f);
    assert_true(s->eta == 1.0f);
}

/* Per-lane eval arrays of a batch, prefilled with GARBAGE. */
typedef struct lanes {
    float wo[3][BIG], wi[3][BIG], value[3][BIG], pdf[BIG];
    const glint_closure *closures[BIG];
    uint8_t active[BIG];
} lanes;

static lanes *lanes_new(size_t count)
{
    lanes *l = calloc(1, sizeof *l);
    assert_non_null(l);
    for (size_t i = 0; i < count; i++) {
        glint_vec3 wo = test_wo(), wi = wi_test();
        l->wo[0][i] = wo.x, l->wo[1][i] = wo.y, l->wo[2][i] = wo.z;
        l->wi[0][i] = wi.x, l->wi[1][i] = wi.y, l->wi[2][i] = wi.z;
        l->value[0][i] = l->value[1][i] = l->value[2][i] = l->pdf[i] = GARBAGE;
        l->active[i] = 1;
    }
    return l;
}

static glint_eval_batch_args eval_args(lanes *l, size_t count)
{
    glint_eval_batch_args a;
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.count = count;
    a.wo_x = l->wo[0], a.wo_y = l->wo[1], a.wo_z = l->wo[2];
    a.wi_x = l->wi[0], a.wi_y = l->wi[1], a.wi_z = l->wi[2];
    a.value_r = l->value[0], a.value_g = l->value[1], a.value_b = l->value[2];
    a.pdf = l->pdf;
    return a;
}

/* ---- D4: destroyed runtimes and arenas ---------------------------------------------- */

static void status_string_names_invalid_handle(void **state)
{
    (void)state;
    assert_true(GLINT_ERROR_INVALID_HANDLE == 20);
    assert_string_not_equal(glint_status_string(GLINT_ERROR_INVALID_HANDLE),
                            "unknown status code");
}

static void runtime_destroyed_twice(void **state)
{
    fixture *fx = *state;
    glint_runtime *rt = NULL;
    uint32_t count = 99;
    assert_ok(glint_runtime_create(NULL, &rt));
    glint_runtime_destroy(rt);
    check_error(fx, glint_lobe_type_count(rt, &count), GLINT_ERROR_INVALID_HANDLE);
    assert_error_mentions("runtime was destroyed");
    assert_int_equal(count, 0);
    glint_runtime_destroy(rt);
    assert_error_mentions("glint_runtime_destroy ignored");
    assert_still_works(fx);
}

static void arena_destroyed_twice(void **state)
{
    fixture *fx = *state;
    glint_arena *arena = NULL;
    glint_closure *c = (glint_closure *)fx;
    assert_ok(glint_arena_create(4, &arena));
    glint_arena_destroy(arena);
    check_error(fx, glint_arena_reset(arena), GLINT_ERROR_INVALID_HANDLE);
    assert_error_mentions("arena was destroyed");
    check_error(fx, glint_closure_from_json(fx->rt, arena, LAMBERT, NULL, &c),
                GLINT_ERROR_INVALID_HANDLE);
    assert_null(c);
    glint_arena_destroy(arena);
    assert_error_mentions("glint_arena_destroy ignored");
    assert_still_works(fx);
}

static void eval_after_arena_destroy(void **state)
{
    fixture *fx = *state;
    glint_arena *arena = NULL;
    glint_closure *c;
    assert_ok(glint_arena_create(4, &arena));
    c = from_json(fx->rt, arena, LAMBERT);
    glint_arena_destroy(arena);
    assert_eval_invalid(fx, c);
    assert_error_mentions("destroyed arena");
}

/* Scalar eval, add_lobe and batches (one closure, per-lane closures, threads=2) on
 * closures whose runtime was destroyed. */
static void closures_of_a_destroyed_runtime(void **state)
{
    fixture *fx = *state;
    glint_runtime *rt = NULL;
    glint_arena *arena = NULL;
    glint_closure *finished, *open;
    glint_eval_batch_args a;
    lanes *l = lanes_new(BIG);
    uint32_t index = 99;
    assert_ok(glint_runtime_create("threads=2", &rt));
    assert_ok(glint_arena_create(4, &arena));
    finished = from_json(rt, arena, LAMBERT);
    assert_ok(glint_closure_begin(rt, arena, NULL, 0, &open));
    glint_runtime_destroy(rt);

    assert_eval_invalid(fx, finished);
    assert_error_mentions("runtime was destroyed");
    check_error(fx,
                glint_closure_add_lobe(open, 0, WHITE, &(glint_frame){{0, 0, 1}, {0, 0, 0}},
                                       NULL, 0, &index),
                GLINT_ERROR_INVALID_HANDLE);
    assert_int_equal(index, 0);

    a = eval_args(l, BIG);
    a.closure = finished;
    check_error(fx, glint_eval_batch(&a), GLINT_ERROR_INVALID_HANDLE);
    for (size_t i = 0; i < BIG; i++)
        l->closures[i] = finished;
    a.closures = l->closures;
    check_error(fx, glint_eval_batch(&a), GLINT_ERROR_INVALID_HANDLE);
    assert_error_mentions("lane 0");
    for (size_t i = 0; i < BIG; i += 1023)
        assert_true(l->value[0][i] == 0.0f && l->pdf[i] == 0.0f);
    glint_arena_destroy(arena);
    free(l);
}

/* ---- D4: the quarantine bounds count only runtime and arena destroys ---------------- */

static const char *DISNEY = "{\"material\": \"disney\"}";

/* What a destroyed runtime and a destroyed arena leave behind. */
typedef struct leftovers {
    glint_runtime *rt;      /* destroyed */
    glint_material *m;      /* a live material of rt */
    glint_arena *kept;      /* a live arena */
    glint_closure *of_rt;   /* a closure of rt in kept */
    glint_arena *dead;      /* destroyed */
    glint_closure *of_dead; /* a closure (of fx->rt) in dead */
} leftovers;

static leftovers leftovers_make(fixture *fx)
{
    leftovers d;
    assert_ok(glint_runtime_create("threads=1", &d.rt));
    assert_ok(glint_material_create(d.rt, DISNEY, &d.m));
    assert_ok(glint_arena_create(4, &d.kept));
    d.of_rt = from_json(d.rt, d.kept, LAMBERT);
    assert_ok(glint_arena_create(4, &d.dead));
    d.of_dead = from_json(fx->rt, d.dead, LAMBERT);
    glint_runtime_destroy(d.rt);
    glint_arena_destroy(d.dead);
    return d;
}

/* Calls on the destroyed runtime, its material (scalar and batch) and its closure, and
 * on the destroyed arena, fail with the documented messages (not "is not a ... handle
 * (another kind of handle, or freed memory)", and nothing freed is read). */
static void assert_still_destroyed(fixture *fx, const leftovers *d)
{
    uint32_t count = 99;
    glint_closure *out = (glint_closure *)fx;
    glint_shading_context ctx;
    float wo[3] = {0.1f, 0.2f, 0.9f}, n[3] = {0.0f, 0.0f, 1.0f};
    float albedo[3] = {GARBAGE, GARBAGE, GARBAGE};
    glint_material_albedo_batch_args a;
    check_error(fx, glint_lobe_type_count(d->rt, &count), GLINT_ERROR_INVALID_HANDLE);
    assert_error_mentions("runtime was destroyed");
    assert_int_equal(count, 0);
    memset(&ctx, 0, sizeof ctx);
    ctx.struct_size = sizeof ctx;
    ctx.wo = test_wo();
    ctx.normal = v3(0.0f, 0.0f, 1.0f);
    check_error(fx, glint_material_closure(d->m, d->kept, &ctx, NULL, 0, &out),
                GLINT_ERROR_INVALID_HANDLE);
    assert_error_mentions("the material's runtime was destroyed");
    assert_null(out);
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.lanes.material = d->m, a.lanes.count = 1;
    a.lanes.wo_x = &wo[0], a.lanes.wo_y = &wo[1], a.lanes.wo_z = &wo[2];
    a.lanes.normal_x = &n[0], a.lanes.normal_y = &n[1], a.lanes.normal_z = &n[2];
    a.albedo_r = &albedo[0], a.albedo_g = &albedo[1], a.albedo_b = &albedo[2];
    check_error(fx, glint_material_albedo_batch(&a), GLINT_ERROR_INVALID_HANDLE);
    assert_error_mentions("the material's runtime was destroyed");
    assert_eval_invalid(fx, d->of_rt);
    assert_error_mentions("the closure's runtime was destroyed");
    check_error(fx, glint_arena_reset(d->dead), GLINT_ERROR_INVALID_HANDLE);
    assert_error_mentions("arena was destroyed");
}

static void leftovers_free(leftovers *d)
{
    glint_material_destroy(d->m);
    glint_arena_destroy(d->kept);
}

/* Destroying more than GLINT_QUARANTINE_SHELLS materials after a runtime and an arena
 * were destroyed frees neither: they, the runtime's material and closure, and the
 * arena's closure are still detected (material destroys once shared their queue). */
static void material_destroys_keep_runtimes_and_arenas_quarantined(void **state)
{
    fixture *fx = *state;
    leftovers d = leftovers_make(fx);
    for (int k = 0; k < GLINT_QUARANTINE_SHELLS + 100; k++) {
        glint_material *t = NULL;
        assert_ok(glint_material_create(fx->rt, DISNEY, &t));
        glint_material_destroy(t);
    }
    assert_still_destroyed(fx, &d);
    assert_eval_invalid(fx, d.of_dead);
    assert_error_mentions("destroyed arena");
    leftovers_free(&d);
}

/* Arenas whose slots together exceed GLINT_QUARANTINE_BYTES (each below it) free the
 * oldest destroyed arenas' slots, never a shell: the runtime destroyed before them (and
 * its material and closure) and the arena's shell are still detected. */
static void arena_slot_bytes_keep_runtime_and_arena_shells_quarantined(void **state)
{
    fixture *fx = *state;
    leftovers d = leftovers_make(fx);
    for (int k = 0; k < 8; k++) { /* 65536 slots: some MiB each */
        glint_arena *t = NULL;
        assert_ok(glint_arena_create(65536, &t));
        glint_arena_destroy(t);
    }
    assert_still_destroyed(fx, &d);
    leftovers_free(&d);
}

/* ---- D5: handles from before glint_arena_reset -------------------------------------- */

static void stale_handle_after_reset(void **state)
{
    fixture *fx = *state;
    glint_arena *arena = NULL;
    glint_closure *lambert, *mirror;
    glint_sample_result s = sample_result_init();
    glint_eval_result r = eval_result_init();
    uint32_t count = 99;
    assert_ok(glint_arena_create(1, &arena));
    lambert = from_json(fx->rt, arena, LAMBERT);
    assert_ok(glint_eval(lambert, test_wo(), wi_test(), &r));
    assert_true(r.value[0] > 0.0f);

    assert_ok(glint_arena_reset(arena));
    assert_eval_invalid(fx, lambert);
    assert_error_mentions("arena was reset");

    /* The only slot now holds a mirror: the lambert handle must not become it. */
    mirror = from_json(fx->rt, arena, MIRROR);
    assert_eval_invalid(fx, lambert);
    assert_error_mentions("newer closure");
    check_error(fx, glint_closure_lobe_count(lambert, &count), GLINT_ERROR_INVALID_HANDLE);
    assert_int_equal(count, 0);
    s.pdf = GARBAGE;
    check_error(fx, glint_sample(lambert, test_wo(), 0.5f, 0.5f, 0.5f, &s),
                GLINT_ERROR_INVALID_HANDLE);
    assert_zeroed_sample(&s);
    assert_ok(glint_sample(mirror, test_wo(), 0.5f, 0.5f, 0.5f, &s));
    assert_true(s.flags & GLINT_FLAG_SPECULAR);
    glint_arena_destroy(arena);
}

/* A stale handle in one lane of a per-lane batch: that lane is zeroed and reported,
 * the others are computed. */
static void stale_handle_in_a_batch_lane(void **state)
{
    fixture *fx = *state;
    glint_arena *arena = NULL;
    glint_closure *old, *fresh;
    glint_eval_result r = eval_result_init();
    lanes *l = lanes_new(LANES);
    glint_eval_batch_args a = eval_args(l, LANES);
    assert_ok(glint_arena_create(4, &arena));
    old = from_json(fx->rt, arena, LAMBERT);
    assert_ok(glint_arena_reset(arena));
    fresh = from_json(fx->rt, arena, LAMBERT);
    l->closures[0] = fresh, l->closures[1] = fresh, l->closures[2] = old;
    l->closures[3] = fresh;
    a.closures = l->closures;
    check_error(fx, glint_eval_batch(&a), GLINT_ERROR_INVALID_HANDLE);
    assert_error_mentions("lane 2");
    assert_ok(glint_eval(fresh, test_wo(), wi_test(), &r));
    assert_true(l->value[0][2] == 0.0f && l->pdf[2] == 0.0f);
    for (int i = 0; i < LANES; i += 3)
        assert_close(l->value[0][i], r.value[0], 1e-6f);
    glint_arena_destroy(arena);
    free(l);
}

/* ---- D1: inactive lanes' handles are never read ------------------------------------- */

static void inactive_lane_handle_is_not_read(void **state)
{
    fixture *fx = *state;
    glint_eval_result r = eval_result_init();
    lanes *l = lanes_new(LANES);
    glint_eval_batch_args a = eval_args(l, LANES);
    glint_pdf_batch_args p;
    glint_albedo_batch_args al;
    glint_sample_batch_args s;
    float u[LANES] = {0.5f, 0.5f, 0.5f, 0.5f}, w[3][LANES], pdf[LANES], alb[3][LANES];
    l->closures[0] = (const glint_closure *)(uintptr_t)0x10;
    l->closures[1] = l->closures[2] = l->closures[3] = fx->ok;
    l->active[0] = 0;
    a.closures = l->closures;
    a.active = l->active;
    assert_ok(glint_eval_batch(&a));
    assert_ok(glint_eval(fx->ok, test_wo(), wi_test(), &r));
    assert_true(l->value[0][0] == GARBAGE && l->pdf[0] == GARBAGE);
    for (int i = 1; i < LANES; i++)
        assert_close(l->value[0][i], r.value[0], 1e-6f);

    memset(&p, 0, sizeof p);
    p.struct_size = sizeof p;
    p.count = LANES, p.closures = l->closures, p.active = l->active;
    p.wo_x = l->wo[0], p.wo_y = l->wo[1], p.wo_z = l->wo[2];
    p.wi_x = l->wi[0], p.wi_y = l->wi[1], p.wi_z = l->wi[2];
    p.pdf = pdf;
    assert_ok(glint_pdf_batch(&p));

    memset(&al, 0, sizeof al);
    al.struct_size = sizeof al;
    al.count = LANES, al.closures = l->closures, al.active = l->active;
    al.wo_x = l->wo[0], al.wo_y = l->wo[1], al.wo_z = l->wo[2];
    al.albedo_r = alb[0], al.albedo_g = alb[1], al.albedo_b = alb[2];
    assert_ok(glint_albedo_batch(&al));

    memset(&s, 0, sizeof s);
    s.struct_size = sizeof s;
    s.count = LANES, s.closures = l->closures, s.active = l->active;
    s.wo_x = l->wo[0], s.wo_y = l->wo[1], s.wo_z = l->wo[2];
    s.u_lobe = u, s.u0 = u, s.u1 = u;
    s.wi_x = l->wi[0], s.wi_y = l->wi[1], s.wi_z = l->wi[2];
    s.pdf = pdf;
    s.weight_r = w[0], s.weight_g = w[1], s.weight_b = w[2];
    assert_ok(glint_sample_batch(&s));
    free(l);
}

/* ---- D13: failing calls leave their outputs in the documented state ----------------- */

static void failing_calls_zero_their_outputs(void **state)
{
    fixture *fx = *state;
    const glint_vec3 nan_wo = v3(NAN, 0.0f, 1.0f);
    glint_eval_result r = eval_result_init();
    glint_sample_result s = sample_result_init();
    glint_lobe_info li = lobe_info_init();
    glint_param_info pi = param_info_init();
    float f = GARBAGE, rgb[3] = {GARBAGE, GARBAGE, GARBAGE}, defaults[4];
    uint32_t u = 99;
    uint64_t u64 = 99;
    const char *isa = "garbage";
    glint_closure *c = (glint_closure *)fx;

    s.pdf = s.eta = GARBAGE;
    check_error(fx, glint_sample_lobe(fx->ok, 0, nan_wo, 0.5f, 0.5f, 0.5f, &s),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_zeroed_sample(&s);
    s.pdf = s.eta = GARBAGE;
    check_error(fx, glint_sample(NULL, test_wo(), 0.5f, 0.5f, 0.5f, &s),
                GLINT_ERROR_NULL_POINTER);
    assert_zeroed_sample(&s);

    r.pdf = GARBAGE;
    check_error(fx, glint_eval_lobe(fx->ok, 0, nan_wo, wi_test(), &r),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_true(r.pdf == 0.0f && r.struct_size == sizeof r);
    r.pdf = GARBAGE;
    check_error(fx, glint_eval(NULL, test_wo(), wi_test(), &r), GLINT_ERROR_NULL_POINTER);
    assert_true(r.pdf == 0.0f);

    check_error(fx, glint_pdf(fx->ok, nan_wo, wi_test(), &f), GLINT_ERROR_INVALID_ARGUMENT);
    assert_true(f == 0.0f);
    f = GARBAGE;
    check_error(fx, glint_pdf_lobe(fx->ok, 5, test_wo(), wi_test(), &f),
                GLINT_ERROR_OUT_OF_RANGE);
    assert_true(f == 0.0f);
    check_error(fx, glint_albedo(fx->ok, nan_wo, rgb), GLINT_ERROR_INVALID_ARGUMENT);
    assert_true(rgb[0] == 0.0f && rgb[1] == 0.0f && rgb[2] == 0.0f);
    rgb[0] = GARBAGE;
    check_error(fx, glint_albedo_lobe(fx->ok, 5, test_wo(), rgb), GLINT_ERROR_OUT_OF_RANGE);
    assert_true(rgb[0] == 0.0f);

    f = GARBAGE;
    check_error(fx, glint_closure_lobe(fx->ok, 5, &u, &f), GLINT_ERROR_OUT_OF_RANGE);
    assert_true(u == 0 && f == 0.0f);
    u = 99;
    check_error(fx, glint_closure_lobe_count(NULL, &u), GLINT_ERROR_NULL_POINTER);
    assert_int_equal(u, 0);
    c = (glint_closure *)fx;
    check_error(fx, glint_closure_begin(fx->rt, fx->arena, &nan_wo, 0, &c),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_null(c);

    check_error(fx, glint_runtime_isa(NULL, &isa), GLINT_ERROR_NULL_POINTER);
    assert_null(isa);
    u = 99;
    check_error(fx, glint_lobe_type_count(NULL, &u), GLINT_ERROR_NULL_POINTER);
    assert_int_equal(u, 0);
    u = 99;
    check_error(fx, glint_lobe_type_find(fx->rt, "no such lobe", &u), GLINT_ERROR_UNKNOWN_NAME);
    assert_int_equal(u, 0);
    check_error(fx, glint_lobe_sanitized_count(fx->rt, 9999, &u64), GLINT_ERROR_OUT_OF_RANGE);
    assert_int_equal(u64, 0);
    li.flags = 99;
    check_error(fx, glint_lobe_type_info(fx->rt, 9999, &li), GLINT_ERROR_OUT_OF_RANGE);
    assert_true(li.struct_size == sizeof li && li.name == NULL && li.flags == 0);
    pi.size = 99;
    check_error(fx, glint_lobe_param_info(fx->rt, 0, 9999, &pi), GLINT_ERROR_OUT_OF_RANGE);
    assert_true(pi.struct_size == sizeof pi && pi.name == NULL && pi.size == 0);
    u = 99;
    check_error(fx, glint_lobe_param_find(fx->rt, 0, "no such parameter", &u),
                GLINT_ERROR_UNKNOWN_NAME);
    assert_int_equal(u, 0);
    f = GARBAGE;
    check_error(fx, glint_lobe_param_choice(fx->rt, 0, 9999, "ggx", &f),
                GLINT_ERROR_OUT_OF_RANGE);
    assert_true(f == 0.0f);
    fill_floats(defaults, 4, GARBAGE);
    check_error(fx, glint_lobe_param_defaults(fx->rt, 9999, defaults, 4),
                GLINT_ERROR_OUT_OF_RANGE);
    for (int i = 0; i < 4; i++)
        assert_true(defaults[i] == 0.0f);
    /* A wild capacity is not written through: no block is longer than
     * GLINT_MAX_PARAM_VALUES floats, and a failure zeroes no more. */
    {
        float big[GLINT_MAX_PARAM_VALUES + 64];
        const size_t n = sizeof big / sizeof big[0];
        fill_floats(big, n, GARBAGE);
        check_error(fx, glint_lobe_param_defaults(fx->rt, 9999, big, SIZE_MAX),
                    GLINT_ERROR_OUT_OF_RANGE);
        for (size_t i = 0; i < n; i++)
            assert_true(big[i] == (i < GLINT_MAX_PARAM_VALUES ? 0.0f : GARBAGE));
        fill_floats(big, n, GARBAGE);
        assert_ok(glint_lobe_param_defaults(fx->rt, 0, big, SIZE_MAX));
        assert_true(big[n - 1] == GARBAGE);
    }
}

/* ---- D14: glint_closure_lobe on an unfinished closure -------------------------------- */

static void closure_lobe_needs_a_finished_closure(void **state)
{
    fixture *fx = *state;
    glint_closure *c = NULL;
    uint32_t type_id = 99;
    float probability = GARBAGE;
    assert_ok(glint_closure_begin(fx->rt, fx->arena, NULL, 0, &c));
    assert_ok(glint_closure_add_lobe(c, 0, WHITE, &(glint_frame){{0, 0, 1}, {0, 0, 0}}, NULL,
                                     0, NULL));
    check_error(fx, glint_closure_lobe(c, 0, &type_id, &probability),
                GLINT_ERROR_INVALID_STATE);
    assert_error_mentions("glint_closure_finish");
    assert_true(type_id == 0 && probability == 0.0f);
    assert_ok(glint_closure_finish(c));
    assert_ok(glint_closure_lobe(c, 0, &type_id, &probability));
    assert_true(probability == 1.0f);
}

/* A handle of one kind passed as another (a host mixing up its void pointers) is refused
 * as an invalid handle: every handle begins with its tag, so the check reads within the
 * object, and the closure handle carries generation bits (its arena was reset once) that
 * must not make the other kinds' checks fault. Destroys of the wrong kind are ignored,
 * and every handle still works afterwards. */
static void handles_of_another_kind_are_refused(void **state)
{
    fixture *fx = *state;
    glint_runtime *rt = NULL;
    glint_arena *arena = NULL;
    glint_material *m = NULL;
    glint_closure *c = NULL, *out = NULL;
    glint_shading_context ctx;
    const char *isa = NULL;
    uint32_t n = 0;
    void *handles[4];
    int i;
    assert_ok(glint_runtime_create("threads=1", &rt));
    assert_ok(glint_arena_create(4, &arena));
    assert_ok(glint_material_create(rt, "{\"material\": \"disney\"}", &m));
    from_json(rt, arena, LAMBERT);
    assert_ok(glint_arena_reset(arena));
    c = from_json(rt, arena, LAMBERT);
    memset(&ctx, 0, sizeof ctx);
    ctx.struct_size = sizeof ctx;
    ctx.wo = test_wo();
    ctx.normal = v3(0.0f, 0.0f, 1.0f);
    handles[0] = rt, handles[1] = arena, handles[2] = m, handles[3] = c;
    for (i = 0; i < 4; i++) {
        if (i != 0) {
            check_error(fx, glint_runtime_isa((glint_runtime *)handles[i], &isa),
                        GLINT_ERROR_INVALID_HANDLE);
            glint_runtime_destroy((glint_runtime *)handles[i]);
        }
        if (i != 1) {
            check_error(fx, glint_arena_reset((glint_arena *)handles[i]),
                        GLINT_ERROR_INVALID_HANDLE);
            glint_arena_destroy((glint_arena *)handles[i]);
        }
        if (i != 2) {
            check_error(fx, glint_material_closure((glint_material *)handles[i], arena, &ctx,
                                                   NULL, 0, &out),
                        GLINT_ERROR_INVALID_HANDLE);
            glint_material_destroy((glint_material *)handles[i]);
        }
        if (i != 3)
            check_error(fx, glint_closure_lobe_count((glint_closure *)handles[i], &n),
                        GLINT_ERROR_INVALID_HANDLE);
    }
    assert_ok(glint_runtime_isa(rt, &isa));
    assert_ok(glint_closure_lobe_count(c, &n));
    assert_true(n == 1);
    assert_ok(glint_material_closure(m, arena, &ctx, NULL, 0, &out));
    assert_ok(glint_arena_reset(arena));
    glint_material_destroy(m);
    glint_arena_destroy(arena);
    glint_runtime_destroy(rt);
}

int main(void)
{
#define T(f) cmocka_unit_test_setup_teardown(f, fixture_setup, fixture_teardown)
    const struct CMUnitTest tests[] = {
        T(status_string_names_invalid_handle),
        T(runtime_destroyed_twice),
        T(arena_destroyed_twice),
        T(eval_after_arena_destroy),
        T(closures_of_a_destroyed_runtime),
        T(material_destroys_keep_runtimes_and_arenas_quarantined),
        T(arena_slot_bytes_keep_runtime_and_arena_shells_quarantined),
        T(stale_handle_after_reset),
        T(stale_handle_in_a_batch_lane),
        T(inactive_lane_handle_is_not_read),
        T(failing_calls_zero_their_outputs),
        T(closure_lobe_needs_a_finished_closure),
        T(handles_of_another_kind_are_refused),
    };
#undef T
    return cmocka_run_group_tests(tests, NULL, NULL);
}
