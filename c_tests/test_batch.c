/* glint_eval_batch / glint_pdf_batch / glint_sample_batch: lane-by-lane equal to the
 * scalar calls, one closure or one per lane, active masks, bad lanes, bad arguments. */
#include "common.h"

#include <stdlib.h>

#define N 64
#define SENTINEL (-7.0f)
#define USENTINEL 0xdeadbeefu
/* The documented batch-vs-scalar tolerances (glint::verify::BATCH_TOLERANCE and
 * BATCH_SAMPLE_TOLERANCE): relative, absolute below 1e-2; the SIMD kernels fuse
 * multiply-adds and use vectorized elementary functions. */
#define TOL 2.5e-4f
#define SAMPLE_TOL 2e-3f

/* Inputs shared by the tests, rebuilt by batch_setup. */
typedef struct batch_fixture {
    fixture base;
    const glint_closure *mix;                /* every lobe type */
    const glint_closure *per_lane[N];        /* lane i: one of `pool` */
    float wo_x[N], wo_y[N], wo_z[N];
    float wi_x[N], wi_y[N], wi_z[N];
    float u_lobe[N], u0[N], u1[N];
    uint8_t active[N];
} batch_fixture;

static int batch_setup(void **state)
{
    batch_fixture *bf = calloc(1, sizeof *bf);
    void *base = NULL;
    const glint_closure *pool[GLINT_MAX_LOBES + 1];
    uint32_t n, id, pool_size;
    lcg g;
    int i;
    if (bf == NULL || fixture_setup(&base) != 0)
        return -1;
    bf->base = *(fixture *)base;
    free(base);

    n = lobe_type_count(bf->base.rt);
    bf->mix = all_types_closure(&bf->base, NULL);
    pool[0] = bf->mix;
    for (id = 0; id < n && id < GLINT_MAX_LOBES; id++)
        pool[id + 1] = single_lobe_closure(&bf->base, id, NULL, 0, NULL);
    pool_size = id + 1;

    lcg_seed(&g, 2024);
    for (i = 0; i < N; i++) {
        /* Mostly above the surface; every 8th lane from below. */
        glint_vec3 wo = lcg_direction(&g, i % 8 != 7);
        glint_vec3 wi = lcg_direction(&g, 0);
        float scale = (i % 5 == 0) ? 2.5f : 1.0f; /* not normalized */
        if (i % 8 == 7)
            wo.z = -wo.z;
        bf->wo_x[i] = wo.x * scale;
        bf->wo_y[i] = wo.y * scale;
        bf->wo_z[i] = wo.z * scale;
        bf->wi_x[i] = wi.x;
        bf->wi_y[i] = wi.y;
        bf->wi_z[i] = wi.z;
        bf->u_lobe[i] = lcg_next(&g);
        bf->u0[i] = lcg_next(&g);
        bf->u1[i] = lcg_next(&g);
        bf->active[i] = (uint8_t)(i % 3 != 1 ? 1 + i % 2 : 0); /* any nonzero byte is active */
        bf->per_lane[i] = pool[(uint32_t)i % pool_size];
    }
    /* Some sampled wi as eval directions, so that rough lobes give nonzero values. */
    for (i = 0; i < N; i += 4) {
        glint_sample_result s = sample_result_init();
        if (glint_sample(bf->mix, v3(bf->wo_x[i], bf->wo_y[i], bf->wo_z[i]), bf->u_lobe[i],
                         bf->u0[i], bf->u1[i], &s) == GLINT_OK) {
            bf->wi_x[i] = s.wi.x;
            bf->wi_y[i] = s.wi.y;
            bf->wi_z[i] = s.wi.z;
        }
    }
    *state = bf;
    return 0;
}

static int batch_teardown(void **state)
{
    batch_fixture *bf = *state;
    void *base = malloc(sizeof(fixture));
    if (base == NULL)
        return -1;
    *(fixture *)base = bf->base;
    free(bf);
    return fixture_teardown(&base);
}

static glint_vec3 lane_wo(const batch_fixture *bf, int i)
{
    return v3(bf->wo_x[i], bf->wo_y[i], bf->wo_z[i]);
}

static glint_vec3 lane_wi(const batch_fixture *bf, int i)
{
    return v3(bf->wi_x[i], bf->wi_y[i], bf->wi_z[i]);
}

static void fill(float *a, float v)
{
    fill_floats(a, N, v);
}

static void fillu(uint32_t *a, uint32_t v)
{
    int i;
    for (i = 0; i < N; i++)
        a[i] = v;
}

/* ---- eval ------------------------------------------------------------------------------ */

typedef struct eval_out {
    float r[N], g[N], b[N], pdf[N], pdf_reverse[N];
} eval_out;

static glint_eval_batch_args eval_args(const batch_fixture *bf, eval_out *o)
{
    glint_eval_batch_args a;
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.count = N;
    a.closure = bf->mix;
    a.wo_x = bf->wo_x, a.wo_y = bf->wo_y, a.wo_z = bf->wo_z;
    a.wi_x = bf->wi_x, a.wi_y = bf->wi_y, a.wi_z = bf->wi_z;
    a.value_r = o->r, a.value_g = o->g, a.value_b = o->b;
    a.pdf = o->pdf;
    a.pdf_reverse = o->pdf_reverse;
    fill(o->r, SENTINEL), fill(o->g, SENTINEL), fill(o->b, SENTINEL);
    fill(o->pdf, SENTINEL), fill(o->pdf_reverse, SENTINEL);
    return a;
}

static int lane_active(const uint8_t *active, int i)
{
    return active == NULL || active[i] != 0;
}

static const glint_closure *lane_closure(const glint_closure *one,
                                         const glint_closure *const *per_lane, int i)
{
    return per_lane != NULL ? per_lane[i] : one;
}

/* Outputs of every lane: inactive untouched, active equal to glint_eval. */
static void check_eval_lanes(const batch_fixture *bf, const glint_eval_batch_args *a,
                             const eval_out *o)
{
    int i, computed = 0, nonzero = 0;
    for (i = 0; i < N; i++) {
        glint_eval_result r = eval_result_init();
        if (!lane_active(a->active, i)) {
            assert_true(o->r[i] == SENTINEL && o->g[i] == SENTINEL && o->b[i] == SENTINEL);
            assert_true(o->pdf[i] == SENTINEL && o->pdf_reverse[i] == SENTINEL);
            continue;
        }
        computed++;
        assert_ok(glint_eval(lane_closure(a->closure, a->closures, i), lane_wo(bf, i),
                             lane_wi(bf, i), &r));
        assert_batch_close(o->r[i], r.value[0], TOL);
        assert_batch_close(o->g[i], r.value[1], TOL);
        assert_batch_close(o->b[i], r.value[2], TOL);
        assert_batch_close(o->pdf[i], r.pdf, TOL);
        if (a->pdf_reverse != NULL)
            assert_batch_close(o->pdf_reverse[i], r.pdf_reverse, TOL);
        else
            assert_true(o->pdf_reverse[i] == SENTINEL);
        nonzero += r.value[0] > 0.0f;
    }
    assert_true(computed > 0);
    assert_true(nonzero > 0);
}

static void eval_batch_matches_scalar(void **state)
{
    batch_fixture *bf = *state;
    eval_out o;
    int variant;
    for (variant = 0; variant < 6; variant++) {
        glint_eval_batch_args a = eval_args(bf, &o);
        if (variant & 1)
            a.active = bf->active;
        if (variant & 2)
            a.closures = bf->per_lane;
        if (variant == 4)
            a.pdf_reverse = NULL; /* optional */
        if (variant == 5) {
            a.closure = NULL; /* unused with per-lane closures */
            a.closures = bf->per_lane;
        }
        assert_ok(glint_eval_batch(&a));
        check_eval_lanes(bf, &a, &o);
    }
}

/* ---- pdf --------------------------------------------------------------------------------- */

static void pdf_batch_matches_scalar(void **state)
{
    batch_fixture *bf = *state;
    float pdf[N];
    int variant, i;
    for (variant = 0; variant < 4; variant++) {
        glint_pdf_batch_args a;
        memset(&a, 0, sizeof a);
        a.struct_size = sizeof a;
        a.count = N;
        a.closure = bf->mix;
        a.closures = (variant & 2) ? bf->per_lane : NULL;
        a.active = (variant & 1) ? bf->active : NULL;
        a.wo_x = bf->wo_x, a.wo_y = bf->wo_y, a.wo_z = bf->wo_z;
        a.wi_x = bf->wi_x, a.wi_y = bf->wi_y, a.wi_z = bf->wi_z;
        a.pdf = pdf;
        fill(pdf, SENTINEL);
        assert_ok(glint_pdf_batch(&a));
        for (i = 0; i < N; i++) {
            float p = -1.0f;
            if (!lane_active(a.active, i)) {
                assert_true(pdf[i] == SENTINEL);
                continue;
            }
            assert_ok(glint_pdf(lane_closure(a.closure, a.closures, i), lane_wo(bf, i),
                                lane_wi(bf, i), &p));
            assert_batch_close(pdf[i], p, TOL);
        }
    }
}

/* ---- sample --------------------------------------------------------------------------------- */

typedef struct sample_out {
    float wi_x[N], wi_y[N], wi_z[N], pdf[N], w_r[N], w_g[N], w_b[N];
    float v_r[N], v_g[N], v_b[N], eta[N], roughness[N];
    uint32_t flags[N], lobe[N];
} sample_out;

static glint_sample_batch_args sample_args(const batch_fixture *bf, sample_out *o)
{
    glint_sample_batch_args a;
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.count = N;
    a.closure = bf->mix;
    a.wo_x = bf->wo_x, a.wo_y = bf->wo_y, a.wo_z = bf->wo_z;
    a.u_lobe = bf->u_lobe, a.u0 = bf->u0, a.u1 = bf->u1;
    a.wi_x = o->wi_x, a.wi_y = o->wi_y, a.wi_z = o->wi_z;
    a.pdf = o->pdf;
    a.weight_r = o->w_r, a.weight_g = o->w_g, a.weight_b = o->w_b;
    a.value_r = o->v_r, a.value_g = o->v_g, a.value_b = o->v_b;
    a.flags = o->flags, a.lobe = o->lobe, a.eta = o->eta, a.roughness = o->roughness;
    fill(o->wi_x, SENTINEL), fill(o->wi_y, SENTINEL), fill(o->wi_z, SENTINEL);
    fill(o->pdf, SENTINEL), fill(o->w_r, SENTINEL), fill(o->w_g, SENTINEL), fill(o->w_b, SENTINEL);
    fill(o->v_r, SENTINEL), fill(o->v_g, SENTINEL), fill(o->v_b, SENTINEL);
    fill(o->eta, SENTINEL), fill(o->roughness, SENTINEL);
    fillu(o->flags, USENTINEL), fillu(o->lobe, USENTINEL);
    return a;
}

static void check_sample_lane_untouched(const sample_out *o, int i)
{
    assert_true(o->wi_x[i] == SENTINEL && o->wi_y[i] == SENTINEL && o->wi_z[i] == SENTINEL);
    assert_true(o->pdf[i] == SENTINEL);
    assert_true(o->w_r[i] == SENTINEL && o->w_g[i] == SENTINEL && o->w_b[i] == SENTINEL);
    assert_true(o->v_r[i] == SENTINEL && o->v_g[i] == SENTINEL && o->v_b[i] == SENTINEL);
    assert_true(o->eta[i] == SENTINEL && o->roughness[i] == SENTINEL);
    assert_int_equal(o->flags[i], USENTINEL);
    assert_int_equal(o->lobe[i], USENTINEL);
}

/* Lane i equals the scalar sample result `s` (a zeroed result for GLINT_NO_SAMPLE). */
static void check_sample_lane(const glint_sample_batch_args *a, const sample_out *o, int i,
                              const glint_sample_result *s)
{
    assert_batch_close(o->wi_x[i], s->wi.x, SAMPLE_TOL);
    assert_batch_close(o->wi_y[i], s->wi.y, SAMPLE_TOL);
    assert_batch_close(o->wi_z[i], s->wi.z, SAMPLE_TOL);
    assert_batch_close(o->pdf[i], s->pdf, SAMPLE_TOL);
    assert_batch_close(o->w_r[i], s->weight[0], SAMPLE_TOL);
    assert_batch_close(o->w_g[i], s->weight[1], SAMPLE_TOL);
    assert_batch_close(o->w_b[i], s->weight[2], SAMPLE_TOL);
    if (a->value_r != NULL) {
        assert_batch_close(o->v_r[i], s->value[0], SAMPLE_TOL);
        assert_batch_close(o->v_g[i], s->value[1], SAMPLE_TOL);
        assert_batch_close(o->v_b[i], s->value[2], SAMPLE_TOL);
    } else {
        assert_true(o->v_r[i] == SENTINEL && o->v_g[i] == SENTINEL && o->v_b[i] == SENTINEL);
    }
    if (a->flags != NULL)
        assert_int_equal(o->flags[i], s->flags);
    else
        assert_int_equal(o->flags[i], USENTINEL);
    if (a->lobe != NULL)
        assert_int_equal(o->lobe[i], s->lobe);
    else
        assert_int_equal(o->lobe[i], USENTINEL);
    if (a->eta != NULL)
        assert_batch_close(o->eta[i], s->eta, SAMPLE_TOL);
    else
        assert_true(o->eta[i] == SENTINEL);
    if (a->roughness != NULL)
        assert_batch_close(o->roughness[i], s->roughness, SAMPLE_TOL);
    else
        assert_true(o->roughness[i] == SENTINEL);
}

static void check_sample_lanes(const batch_fixture *bf, const glint_sample_batch_args *a,
                               const sample_out *o)
{
    int i, valid = 0, failed = 0;
    for (i = 0; i < N; i++) {
        glint_sample_result s = sample_result_init();
        glint_status st;
        if (!lane_active(a->active, i)) {
            check_sample_lane_untouched(o, i);
            continue;
        }
        st = glint_sample(lane_closure(a->closure, a->closures, i), lane_wo(bf, i), bf->u_lobe[i],
                          bf->u0[i], bf->u1[i], &s);
        assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
        if (st == GLINT_NO_SAMPLE) {
            /* Documented: pdf 0, zero wi and weight, flags 0. */
            failed++;
            assert_true(o->pdf[i] == 0.0f);
            assert_true(o->wi_x[i] == 0.0f && o->wi_y[i] == 0.0f && o->wi_z[i] == 0.0f);
            assert_true(o->w_r[i] == 0.0f && o->w_g[i] == 0.0f && o->w_b[i] == 0.0f);
            if (a->flags != NULL)
                assert_int_equal(o->flags[i], 0);
        } else {
            valid++;
        }
        check_sample_lane(a, o, i, &s);
    }
    assert_true(valid > 0);
    (void)failed;
}

static void sample_batch_matches_scalar(void **state)
{
    batch_fixture *bf = *state;
    sample_out *o = malloc(sizeof *o);
    int variant;
    assert_non_null(o);
    for (variant = 0; variant < 6; variant++) {
        glint_sample_batch_args a = sample_args(bf, o);
        if (variant & 1)
            a.active = bf->active;
        if (variant & 2)
            a.closures = bf->per_lane;
        if (variant >= 4) {
            /* The optional outputs are not written when NULL. */
            a.value_r = a.value_g = a.value_b = NULL;
            a.flags = NULL;
            a.lobe = NULL;
            a.eta = NULL;
            a.roughness = NULL;
        }
        assert_ok(glint_sample_batch(&a));
        check_sample_lanes(bf, &a, o);
    }
    free(o);
}

/* ---- bad lanes: an error status, the other lanes still computed ------------------------- */

static void bad_lanes_are_reported_and_others_computed(void **state)
{
    batch_fixture *bf = *state;
    eval_out o;
    sample_out *so = malloc(sizeof *so);
    float pdf[N];
    const float saved_wo_x5 = bf->wo_x[5], saved_wi[3] = {bf->wi_x[9], bf->wi_y[9], bf->wi_z[9]};
    const float saved_u0 = bf->u0[3];
    int i;
    assert_non_null(so);

    bf->wo_x[5] = NAN;                                    /* NaN wo in lane 5 */
    bf->wi_x[9] = bf->wi_y[9] = bf->wi_z[9] = 0.0f;       /* zero-length wi in lane 9 */
    bf->u0[3] = NAN;                                      /* NaN random number in lane 3 */

    {
        glint_eval_batch_args a = eval_args(bf, &o);
        a.closures = bf->per_lane;
        check_error(&bf->base, glint_eval_batch(&a), GLINT_ERROR_INVALID_ARGUMENT);
        assert_error_mentions("lane 5"); /* the first bad lane */
        assert_error_mentions("wo");
        for (i = 0; i < N; i++) {
            glint_eval_result r = eval_result_init();
            if (i == 5 || i == 9) {
                assert_true(o.r[i] == 0.0f && o.g[i] == 0.0f && o.b[i] == 0.0f);
                assert_true(o.pdf[i] == 0.0f && o.pdf_reverse[i] == 0.0f);
                continue;
            }
            assert_ok(glint_eval(bf->per_lane[i], lane_wo(bf, i), lane_wi(bf, i), &r));
            assert_batch_close(o.r[i], r.value[0], TOL);
            assert_batch_close(o.pdf[i], r.pdf, TOL);
            assert_batch_close(o.pdf_reverse[i], r.pdf_reverse, TOL);
        }
    }
    {
        glint_pdf_batch_args a;
        memset(&a, 0, sizeof a);
        a.struct_size = sizeof a;
        a.count = N;
        a.closure = bf->mix;
        a.wo_x = bf->wo_x, a.wo_y = bf->wo_y, a.wo_z = bf->wo_z;
        a.wi_x = bf->wi_x, a.wi_y = bf->wi_y, a.wi_z = bf->wi_z;
        a.pdf = pdf;
        fill(pdf, SENTINEL);
        check_error(&bf->base, glint_pdf_batch(&a), GLINT_ERROR_INVALID_ARGUMENT);
        assert_error_mentions("lane 5");
        for (i = 0; i < N; i++) {
            float p = -1.0f;
            if (i == 5 || i == 9) {
                assert_true(pdf[i] == 0.0f);
                continue;
            }
            assert_ok(glint_pdf(bf->mix, lane_wo(bf, i), lane_wi(bf, i), &p));
            assert_batch_close(pdf[i], p, TOL);
        }
    }
    {
        glint_sample_batch_args a = sample_args(bf, so);
        check_error(&bf->base, glint_sample_batch(&a), GLINT_ERROR_INVALID_ARGUMENT);
        assert_error_mentions("lane 3");
        for (i = 0; i < N; i++) {
            glint_sample_result s = sample_result_init();
            if (i == 3 || i == 5) {
                assert_true(so->pdf[i] == 0.0f);
                assert_true(so->w_r[i] == 0.0f && so->wi_z[i] == 0.0f);
                assert_int_equal(so->flags[i], 0);
                continue;
            }
            glint_sample(bf->mix, lane_wo(bf, i), bf->u_lobe[i], bf->u0[i], bf->u1[i], &s);
            check_sample_lane(&a, so, i, &s);
        }
    }
    /* Inactive bad lanes are not read: no error. */
    {
        glint_eval_batch_args a = eval_args(bf, &o);
        uint8_t active[N];
        memcpy(active, bf->active, sizeof active);
        active[5] = active[9] = 0;
        a.active = active;
        assert_ok(glint_eval_batch(&a));
        assert_true(o.r[5] == SENTINEL && o.r[9] == SENTINEL);
    }

    bf->wo_x[5] = saved_wo_x5;
    bf->wi_x[9] = saved_wi[0], bf->wi_y[9] = saved_wi[1], bf->wi_z[9] = saved_wi[2];
    bf->u0[3] = saved_u0;
    free(so);
}

/* Per-lane closures that are NULL or unfinished fail only their lane. */
static void bad_per_lane_closures(void **state)
{
    batch_fixture *bf = *state;
    const glint_closure *lanes[N];
    glint_closure *open = NULL;
    glint_frame f = frame_z();
    const float white[3] = {1, 1, 1};
    eval_out o;
    int i;
    assert_ok(glint_closure_begin(bf->base.rt, bf->base.arena, NULL, 0, &open));
    assert_ok(glint_closure_add_lobe(open, 0, white, &f, NULL, 0, NULL));
    memcpy(lanes, bf->per_lane, sizeof lanes);
    lanes[10] = NULL;
    lanes[20] = open;
    {
        glint_eval_batch_args a = eval_args(bf, &o);
        a.closures = lanes;
        check_error(&bf->base, glint_eval_batch(&a), GLINT_ERROR_NULL_POINTER);
        assert_error_mentions("lane 10");
        for (i = 0; i < N; i++) {
            glint_eval_result r = eval_result_init();
            if (i == 10 || i == 20) {
                assert_true(o.r[i] == 0.0f && o.pdf[i] == 0.0f);
                continue;
            }
            assert_ok(glint_eval(lanes[i], lane_wo(bf, i), lane_wi(bf, i), &r));
            assert_batch_close(o.r[i], r.value[0], TOL);
        }
        lanes[10] = bf->per_lane[10];
        a = eval_args(bf, &o);
        a.closures = lanes;
        check_error(&bf->base, glint_eval_batch(&a), GLINT_ERROR_INVALID_STATE);
        assert_error_mentions("lane 20");
        assert_true(o.r[10] != SENTINEL);
    }
}

/* ---- argument errors ----------------------------------------------------------------------- */

static void eval_batch_argument_errors(void **state)
{
    batch_fixture *bf = *state;
    fixture *fx = &bf->base;
    eval_out o;
    glint_eval_batch_args a;
    int k;
    check_error(fx, glint_eval_batch(NULL), GLINT_ERROR_NULL_POINTER);
    a = eval_args(bf, &o);
    a.struct_size = 0;
    check_error(fx, glint_eval_batch(&a), GLINT_ERROR_STRUCT_SIZE);
    a.struct_size = sizeof a - 1;
    check_error(fx, glint_eval_batch(&a), GLINT_ERROR_STRUCT_SIZE);
    assert_error_mentions("struct_size");
    a = eval_args(bf, &o);
    a.closure = NULL;
    check_error(fx, glint_eval_batch(&a), GLINT_ERROR_NULL_POINTER);
    assert_error_mentions("closure");
    for (k = 0; k < 10; k++) {
        a = eval_args(bf, &o);
        switch (k) {
        case 0: a.wo_x = NULL; break;
        case 1: a.wo_y = NULL; break;
        case 2: a.wo_z = NULL; break;
        case 3: a.wi_x = NULL; break;
        case 4: a.wi_y = NULL; break;
        case 5: a.wi_z = NULL; break;
        case 6: a.value_r = NULL; break;
        case 7: a.value_g = NULL; break;
        case 8: a.value_b = NULL; break;
        default: a.pdf = NULL; break;
        }
        check_error(fx, glint_eval_batch(&a), GLINT_ERROR_NULL_POINTER);
        /* Argument errors are found before any lane runs. */
        assert_true(o.pdf[0] == SENTINEL || a.pdf == NULL);
        assert_true(o.r[0] == SENTINEL || a.value_r == NULL);
    }
    /* count 0: nothing to do. */
    a = eval_args(bf, &o);
    a.count = 0;
    assert_ok(glint_eval_batch(&a));
    assert_true(o.r[0] == SENTINEL);
    /* A larger struct (newer caller) is accepted. */
    {
        struct {
            glint_eval_batch_args a;
            unsigned char future[16];
        } big;
        memset(&big, 0, sizeof big);
        big.a = eval_args(bf, &o);
        big.a.struct_size = sizeof big;
        assert_ok(glint_eval_batch(&big.a));
        assert_true(o.r[0] != SENTINEL);
    }
}

static void pdf_batch_argument_errors(void **state)
{
    batch_fixture *bf = *state;
    fixture *fx = &bf->base;
    float pdf[N];
    glint_pdf_batch_args a, base;
    int k;
    memset(&base, 0, sizeof base);
    base.struct_size = sizeof base;
    base.count = N;
    base.closure = bf->mix;
    base.wo_x = bf->wo_x, base.wo_y = bf->wo_y, base.wo_z = bf->wo_z;
    base.wi_x = bf->wi_x, base.wi_y = bf->wi_y, base.wi_z = bf->wi_z;
    base.pdf = pdf;
    fill(pdf, SENTINEL);

    check_error(fx, glint_pdf_batch(NULL), GLINT_ERROR_NULL_POINTER);
    a = base;
    a.struct_size = 0;
    check_error(fx, glint_pdf_batch(&a), GLINT_ERROR_STRUCT_SIZE);
    a.struct_size = sizeof a - 1;
    check_error(fx, glint_pdf_batch(&a), GLINT_ERROR_STRUCT_SIZE);
    a = base;
    a.closure = NULL;
    check_error(fx, glint_pdf_batch(&a), GLINT_ERROR_NULL_POINTER);
    for (k = 0; k < 7; k++) {
        a = base;
        switch (k) {
        case 0: a.wo_x = NULL; break;
        case 1: a.wo_y = NULL; break;
        case 2: a.wo_z = NULL; break;
        case 3: a.wi_x = NULL; break;
        case 4: a.wi_y = NULL; break;
        case 5: a.wi_z = NULL; break;
        default: a.pdf = NULL; break;
        }
        check_error(fx, glint_pdf_batch(&a), GLINT_ERROR_NULL_POINTER);
    }
    assert_true(pdf[0] == SENTINEL);
    assert_ok(glint_pdf_batch(&base));
    assert_true(pdf[0] != SENTINEL);
}

static void sample_batch_argument_errors(void **state)
{
    batch_fixture *bf = *state;
    fixture *fx = &bf->base;
    sample_out *o = malloc(sizeof *o);
    glint_sample_batch_args a;
    int k;
    assert_non_null(o);
    check_error(fx, glint_sample_batch(NULL), GLINT_ERROR_NULL_POINTER);
    a = sample_args(bf, o);
    a.struct_size = 0;
    check_error(fx, glint_sample_batch(&a), GLINT_ERROR_STRUCT_SIZE);
    a.struct_size = sizeof a - 1;
    check_error(fx, glint_sample_batch(&a), GLINT_ERROR_STRUCT_SIZE);
    a = sample_args(bf, o);
    a.closure = NULL;
    check_error(fx, glint_sample_batch(&a), GLINT_ERROR_NULL_POINTER);
    for (k = 0; k < 15; k++) {
        a = sample_args(bf, o);
        switch (k) {
        case 0: a.wo_x = NULL; break;
        case 1: a.wo_y = NULL; break;
        case 2: a.wo_z = NULL; break;
        case 3: a.u_lobe = NULL; break;
        case 4: a.u0 = NULL; break;
        case 5: a.u1 = NULL; break;
        case 6: a.wi_x = NULL; break;
        case 7: a.wi_y = NULL; break;
        case 8: a.wi_z = NULL; break;
        case 9: a.pdf = NULL; break;
        case 10: a.weight_r = NULL; break;
        case 11: a.weight_g = NULL; break;
        case 12: a.weight_b = NULL; break;
        case 13: a.value_g = NULL; break; /* value is all three or none */
        default: a.value_r = a.value_g = NULL; break;
        }
        check_error(fx, glint_sample_batch(&a), GLINT_ERROR_NULL_POINTER);
        assert_true(o->w_b[0] == SENTINEL || a.weight_b == NULL);
    }
    free(o);
}

/* ---- albedo ------------------------------------------------------------------------------ */

static glint_albedo_batch_args albedo_args(const batch_fixture *bf, float *r, float *g, float *b)
{
    glint_albedo_batch_args a;
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.count = N;
    a.closure = bf->mix;
    a.wo_x = bf->wo_x, a.wo_y = bf->wo_y, a.wo_z = bf->wo_z;
    a.albedo_r = r, a.albedo_g = g, a.albedo_b = b;
    fill(r, SENTINEL), fill(g, SENTINEL), fill(b, SENTINEL);
    return a;
}

static void albedo_batch_matches_scalar(void **state)
{
    batch_fixture *bf = *state;
    float r[N], g[N], b[N];
    int variant, i;
    for (variant = 0; variant < 4; variant++) {
        glint_albedo_batch_args a = albedo_args(bf, r, g, b);
        if (variant & 1)
            a.active = bf->active;
        if (variant & 2)
            a.closures = bf->per_lane;
        assert_ok(glint_albedo_batch(&a));
        for (i = 0; i < N; i++) {
            float expected[3];
            if (!lane_active(a.active, i)) {
                assert_true(r[i] == SENTINEL && g[i] == SENTINEL && b[i] == SENTINEL);
                continue;
            }
            assert_ok(glint_albedo(lane_closure(a.closure, a.closures, i), lane_wo(bf, i),
                                   expected));
            assert_batch_close(r[i], expected[0], TOL);
            assert_batch_close(g[i], expected[1], TOL);
            assert_batch_close(b[i], expected[2], TOL);
        }
    }
}

static void albedo_batch_argument_errors(void **state)
{
    batch_fixture *bf = *state;
    fixture *fx = &bf->base;
    float r[N], g[N], b[N];
    glint_albedo_batch_args a;
    int k;
    check_error(fx, glint_albedo_batch(NULL), GLINT_ERROR_NULL_POINTER);
    a = albedo_args(bf, r, g, b);
    a.struct_size = sizeof a - 1;
    check_error(fx, glint_albedo_batch(&a), GLINT_ERROR_STRUCT_SIZE);
    a = albedo_args(bf, r, g, b);
    a.closure = NULL;
    check_error(fx, glint_albedo_batch(&a), GLINT_ERROR_NULL_POINTER);
    for (k = 0; k < 6; k++) {
        a = albedo_args(bf, r, g, b);
        switch (k) {
        case 0: a.wo_x = NULL; break;
        case 1: a.wo_y = NULL; break;
        case 2: a.wo_z = NULL; break;
        case 3: a.albedo_r = NULL; break;
        case 4: a.albedo_g = NULL; break;
        default: a.albedo_b = NULL; break;
        }
        check_error(fx, glint_albedo_batch(&a), GLINT_ERROR_NULL_POINTER);
    }
    assert_true(r[0] == SENTINEL);
    a = albedo_args(bf, r, g, b);
    bf->wo_z[3] = NAN;
    check_error(fx, glint_albedo_batch(&a), GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("lane 3");
    assert_true(r[3] == 0.0f && r[0] != SENTINEL);
}

/* ---- every kernel set ---------------------------------------------------------------- */

/* Batches on a runtime forced to each ISA this CPU has match the scalar calls. */
static void every_isa_matches_scalar(void **state)
{
    static const char *const isas[] = {"scalar", "avx2", "avx512"};
    batch_fixture *bf = *state;
    size_t k;
    int tested = 0;
    for (k = 0; k < sizeof isas / sizeof isas[0]; k++) {
        char config[32];
        fixture fx;
        glint_closure *c;
        eval_out o;
        glint_eval_batch_args a;
        int i;
        snprintf(config, sizeof config, "isa=%s threads=1", isas[k]);
        memset(&fx, 0, sizeof fx);
        if (glint_runtime_create(config, &fx.rt) != GLINT_OK)
            continue; /* not on this CPU (every_isa_is_available_or_refused checks why) */
        assert_ok(glint_arena_create(4, &fx.arena));
        c = all_types_closure(&fx, NULL);
        a = eval_args(bf, &o);
        a.closure = c;
        assert_ok(glint_eval_batch(&a));
        for (i = 0; i < N; i++) {
            glint_eval_result r = eval_result_init();
            assert_ok(glint_eval(c, lane_wo(bf, i), lane_wi(bf, i), &r));
            assert_batch_close(o.r[i], r.value[0], TOL);
            assert_batch_close(o.pdf[i], r.pdf, TOL);
            assert_batch_close(o.pdf_reverse[i], r.pdf_reverse, TOL);
        }
        glint_arena_destroy(fx.arena);
        glint_runtime_destroy(fx.rt);
        tested++;
    }
    assert_true(tested >= 1);
}

int main(void)
{
#define T(f) cmocka_unit_test_setup_teardown(f, batch_setup, batch_teardown)
    const struct CMUnitTest tests[] = {
        T(eval_batch_matches_scalar),
        T(pdf_batch_matches_scalar),
        T(sample_batch_matches_scalar),
        T(bad_lanes_are_reported_and_others_computed),
        T(bad_per_lane_closures),
        T(eval_batch_argument_errors),
        T(pdf_batch_argument_errors),
        T(sample_batch_argument_errors),
        T(albedo_batch_matches_scalar),
        T(albedo_batch_argument_errors),
        T(every_isa_matches_scalar),
    };
#undef T
    return cmocka_run_group_tests(tests, NULL, NULL);
}
