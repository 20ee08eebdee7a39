/* Batch calls under hostile inputs (issue 12): counts far beyond any array (D2), two
 * runtimes' different plugin lobes of one name and type id in one per-lane batch (D3),
 * and denormal sample pdfs from the Charlie plugin (D8). CMake passes the plugin paths
 * (GLINT_CHARLIE_PATH, GLINT_TEST_MATTE_A_PATH, GLINT_TEST_MATTE_B_PATH). */
#include "common.h"

#include <stdlib.h>

#define N 64
#define PI_F 3.14159265f
/* The batch-vs-scalar tolerances of test_batch.c. */
#define TOL 2.5e-4f
#define SAMPLE_TOL 2e-3f

/* Every lane's inputs and outputs of the four batch calls. */
typedef struct lanes {
    const glint_closure *closures[N];
    float wo_x[N], wo_y[N], wo_z[N], wi_x[N], wi_y[N], wi_z[N];
    float u_lobe[N], u0[N], u1[N];
    float value_r[N], value_g[N], value_b[N], pdf[N], pdf_only[N];
    float albedo_r[N], albedo_g[N], albedo_b[N];
    float s_wi_x[N], s_wi_y[N], s_wi_z[N], s_pdf[N], weight_r[N], weight_g[N], weight_b[N];
    uint32_t flags[N];
} lanes;

static glint_eval_batch_args eval_args(lanes *l, size_t count)
{
    glint_eval_batch_args a = {sizeof a, count, NULL, l->closures, NULL,
                               l->wo_x, l->wo_y, l->wo_z, l->wi_x, l->wi_y, l->wi_z,
                               l->value_r, l->value_g, l->value_b, l->pdf, NULL};
    return a;
}

static glint_pdf_batch_args pdf_args(lanes *l, size_t count)
{
    glint_pdf_batch_args a = {sizeof a, count, NULL, l->closures, NULL, l->wo_x, l->wo_y,
                              l->wo_z, l->wi_x, l->wi_y, l->wi_z, l->pdf_only};
    return a;
}

static glint_albedo_batch_args albedo_args(lanes *l, size_t count)
{
    glint_albedo_batch_args a = {sizeof a, count, NULL, l->closures, NULL,
                                 l->wo_x, l->wo_y, l->wo_z,
                                 l->albedo_r, l->albedo_g, l->albedo_b};
    return a;
}

static glint_sample_batch_args sample_args(lanes *l, size_t count)
{
    glint_sample_batch_args a = {sizeof a, count, NULL, l->closures, NULL,
                                 l->wo_x, l->wo_y, l->wo_z, l->u_lobe, l->u0, l->u1,
                                 l->s_wi_x, l->s_wi_y, l->s_wi_z, l->s_pdf,
                                 l->weight_r, l->weight_g, l->weight_b,
                                 NULL, NULL, NULL, l->flags, NULL, NULL, NULL, NULL};
    return a;
}

/* Random directions above the surface and random numbers. */
static void fill_lanes(lanes *l, uint64_t seed)
{
    lcg g;
    int i;
    lcg_seed(&g, seed);
    for (i = 0; i < N; i++) {
        glint_vec3 wo = lcg_direction(&g, 1), wi = lcg_direction(&g, 1);
        l->wo_x[i] = wo.x, l->wo_y[i] = wo.y, l->wo_z[i] = wo.z;
        l->wi_x[i] = wi.x, l->wi_y[i] = wi.y, l->wi_z[i] = wi.z;
        l->u_lobe[i] = lcg_next(&g), l->u0[i] = lcg_next(&g), l->u1[i] = lcg_next(&g);
    }
}

/* Every batch output of lane i equals the scalar calls on that lane's closure. */
static void check_lane_against_scalar(const lanes *l, int i)
{
    glint_vec3 wo = v3(l->wo_x[i], l->wo_y[i], l->wo_z[i]);
    glint_eval_result e = eval_result_init();
    glint_sample_result s = sample_result_init();
    glint_status status;
    float albedo[3];
    assert_ok(glint_eval(l->closures[i], wo, v3(l->wi_x[i], l->wi_y[i], l->wi_z[i]), &e));
    assert_close(l->value_r[i], e.value[0], TOL);
    assert_close(l->value_g[i], e.value[1], TOL);
    assert_close(l->value_b[i], e.value[2], TOL);
    assert_close(l->pdf[i], e.pdf, TOL);
    assert_close(l->pdf_only[i], e.pdf, TOL);
    assert_ok(glint_albedo(l->closures[i], wo, albedo));
    assert_close(l->albedo_r[i], albedo[0], TOL);
    assert_close(l->albedo_g[i], albedo[1], TOL);
    assert_close(l->albedo_b[i], albedo[2], TOL);
    status = glint_sample(l->closures[i], wo, l->u_lobe[i], l->u0[i], l->u1[i], &s);
    if (status == GLINT_NO_SAMPLE) {
        if (l->flags[i] != 0)
            print_error("lane %d: no scalar sample, batch pdf %g weight %g value\n", i,
                        (double)l->s_pdf[i], (double)l->weight_r[i]);
        assert_int_equal(l->flags[i], 0);
        assert_true(l->s_pdf[i] == 0.0f);
        assert_true(l->weight_r[i] == 0.0f && l->weight_g[i] == 0.0f && l->weight_b[i] == 0.0f);
        return;
    }
    assert_ok(status);
    assert_int_equal(l->flags[i], s.flags);
    assert_close(l->s_wi_x[i], s.wi.x, SAMPLE_TOL);
    assert_close(l->s_wi_y[i], s.wi.y, SAMPLE_TOL);
    assert_close(l->s_wi_z[i], s.wi.z, SAMPLE_TOL);
    assert_close(l->s_pdf[i], s.pdf, SAMPLE_TOL);
    assert_close(l->weight_r[i], s.weight[0], SAMPLE_TOL);
    assert_close(l->weight_g[i], s.weight[1], SAMPLE_TOL);
    assert_close(l->weight_b[i], s.weight[2], SAMPLE_TOL);
}

/* ---- D2: a count no array can hold --------------------------------------------------- */

/* The call returns OUT_OF_RANGE naming the count and the limit, and writes nothing. */
static void check_count_refused(glint_status status, size_t count)
{
    char count_text[32], limit_text[32];
    snprintf(count_text, sizeof count_text, "%zu", count);
    snprintf(limit_text, sizeof limit_text, "%llu", (unsigned long long)GLINT_MAX_BATCH_COUNT);
    if (status != GLINT_ERROR_OUT_OF_RANGE)
        print_error("count %zu -> %u: %s\n", count, (unsigned)status, glint_last_error());
    assert_int_equal(status, GLINT_ERROR_OUT_OF_RANGE);
    assert_non_null(strstr(glint_last_error(), count_text));
    assert_non_null(strstr(glint_last_error(), limit_text));
}

static void huge_counts_are_refused(void **state)
{
    const fixture *fx = *state;
    const size_t counts[] = {(size_t)1 << 40, (size_t)1 << 62, SIZE_MAX,
                             (size_t)GLINT_MAX_BATCH_COUNT + 1};
    lanes *l = calloc(1, sizeof *l);
    size_t k;
    int i;
    assert_non_null(l);
    fill_lanes(l, 40);
    for (i = 0; i < N; i++)
        l->closures[i] = fx->ok;
    fill_floats(l->pdf, N, -7.0f);
    fill_floats(l->s_pdf, N, -7.0f);
    for (k = 0; k < sizeof counts / sizeof counts[0]; k++) {
        size_t n = counts[k];
        glint_eval_batch_args e = eval_args(l, n);
        glint_pdf_batch_args p = pdf_args(l, n);
        glint_albedo_batch_args a = albedo_args(l, n);
        glint_sample_batch_args s = sample_args(l, n);
        check_count_refused(glint_eval_batch(&e), n);
        check_count_refused(glint_pdf_batch(&p), n);
        check_count_refused(glint_albedo_batch(&a), n);
        check_count_refused(glint_sample_batch(&s), n);
        /* One closure for every lane takes the same check. */
        e.closures = NULL;
        e.closure = fx->ok;
        check_count_refused(glint_eval_batch(&e), n);
    }
    for (i = 0; i < N; i++) {
        assert_true(l->pdf[i] == -7.0f);
        assert_true(l->s_pdf[i] == -7.0f);
    }
    /* A count within the arrays still works. */
    {
        glint_sample_batch_args s = sample_args(l, N);
        glint_eval_batch_args e = eval_args(l, N);
        glint_pdf_batch_args p = pdf_args(l, N);
        glint_albedo_batch_args a = albedo_args(l, N);
        assert_ok(glint_eval_batch(&e));
        assert_ok(glint_pdf_batch(&p));
        assert_ok(glint_albedo_batch(&a));
        assert_ok(glint_sample_batch(&s));
        for (i = 0; i < N; i++)
            check_lane_against_scalar(l, i);
    }
    free(l);
    assert_still_works(fx);
}

/* ---- D3: two lobe types of one name and type id, from two runtimes -------------------- */

typedef struct matte_runtime {
    glint_runtime *rt;
    glint_arena *arena;
    const glint_closure *closure;
    float reflectance; /* the plugin's default */
} matte_runtime;

static matte_runtime matte_open(const char *path, float reflectance)
{
    matte_runtime m = {NULL, NULL, NULL, reflectance};
    glint_closure *c = NULL;
    assert_ok(glint_runtime_create(NULL, &m.rt));
    assert_ok(glint_arena_create(16, &m.arena));
    assert_ok(glint_runtime_load_plugin(m.rt, path));
    assert_ok(glint_closure_from_json(m.rt, m.arena, "{\"lobes\": [{\"type\": \"matte\"}]}",
                                      NULL, &c));
    m.closure = c;
    return m;
}

static void matte_close(matte_runtime *m)
{
    glint_arena_destroy(m->arena);
    glint_runtime_destroy(m->rt);
}

static void run_all(lanes *l)
{
    glint_eval_batch_args e = eval_args(l, N);
    glint_pdf_batch_args p = pdf_args(l, N);
    glint_albedo_batch_args a = albedo_args(l, N);
    glint_sample_batch_args s = sample_args(l, N);
    assert_ok(glint_eval_batch(&e));
    assert_ok(glint_pdf_batch(&p));
    assert_ok(glint_albedo_batch(&a));
    assert_ok(glint_sample_batch(&s));
}

static void same_name_lobes_of_two_runtimes_in_one_batch(void **state)
{
    matte_runtime m[2];
    lanes *l = calloc(1, sizeof *l);
    int first, i, pattern;
    (void)state;
    assert_non_null(l);
    m[0] = matte_open(GLINT_TEST_MATTE_A_PATH, 0.5f);
    m[1] = matte_open(GLINT_TEST_MATTE_B_PATH, 0.9f);
    {
        uint32_t id[2];
        assert_ok(glint_lobe_type_find(m[0].rt, "matte", &id[0]));
        assert_ok(glint_lobe_type_find(m[1].rt, "matte", &id[1]));
        assert_int_equal(id[0], id[1]); /* the case under test: one type id, two types */
    }
    fill_lanes(l, 3);
    /* Either runtime's closure in lane 0; alternating lanes, then runs of eight. */
    for (first = 0; first < 2; first++) {
        for (pattern = 0; pattern < 2; pattern++) {
            for (i = 0; i < N; i++) {
                int which = (pattern == 0 ? i : i / 8) % 2 == 0 ? first : 1 - first;
                l->closures[i] = m[which].closure;
            }
            run_all(l);
            for (i = 0; i < N; i++) {
                int which = l->closures[i] == m[0].closure ? 0 : 1;
                /* Independently of the scalar calls: reflectance cos_i / pi. */
                float expected = m[which].reflectance * l->wi_z[i] / PI_F;
                check_lane_against_scalar(l, i);
                assert_close(l->value_r[i], expected, TOL);
                assert_close(l->albedo_r[i], m[which].reflectance, TOL);
            }
        }
    }
    matte_close(&m[0]);
    matte_close(&m[1]);
    free(l);
}

/* ---- D8: weight = value / pdf when the pdf is denormal --------------------------------- */

/* The Charlie lobe at roughness 0.17 with u0 = 0 samples the mirror direction, where its
 * distribution (sin theta_h)^(1/a) vanishes: pdf and value are denormal (3e-45) or zero,
 * and the weight is value / pdf ~ 1 (not value * (1 / pdf) = value * Inf). The runtime
 * runs the scalar kernels: at this degenerate input an ulp of difference in the
 * normalized wo decides whether a sample exists, and the scalar kernels match the scalar
 * calls bit for bit. */
static void denormal_pdfs_give_the_scalar_weight(void **state)
{
    glint_runtime *rt = NULL;
    glint_arena *arena = NULL;
    glint_closure *c = NULL;
    lanes *l = calloc(1, sizeof *l);
    int i, denormal = 0;
    (void)state;
    assert_non_null(l);
    assert_ok(glint_runtime_create("isa=scalar", &rt));
    assert_ok(glint_arena_create(4, &arena));
    assert_ok(glint_runtime_load_plugin(rt, GLINT_CHARLIE_PATH));
    assert_ok(glint_closure_from_json(
        rt, arena, "{\"lobes\": [{\"type\": \"charlie\", \"roughness\": 0.17}]}", NULL, &c));
    fill_lanes(l, 8);
    for (i = 0; i < N; i++) {
        l->closures[i] = c;
        l->u0[i] = 0.0f;
    }
    run_all(l);
    for (i = 0; i < N; i++) {
        glint_sample_result s = sample_result_init();
        glint_status status = glint_sample(c, v3(l->wo_x[i], l->wo_y[i], l->wo_z[i]),
                                           l->u_lobe[i], 0.0f, l->u1[i], &s);
        assert_finite_nonneg(l->weight_r[i]);
        assert_finite_nonneg(l->weight_g[i]);
        assert_finite_nonneg(l->weight_b[i]);
        check_lane_against_scalar(l, i);
        if (status == GLINT_OK) {
            assert_true(l->weight_r[i] == s.weight[0] && l->weight_g[i] == s.weight[1] &&
                        l->weight_b[i] == s.weight[2]);
            denormal += s.pdf < 1e-37f;
        }
    }
    /* The inputs reach the case (unless plugin outputs this small become no sample). */
    print_message("lanes with a pdf below 1e-37: %d of %d\n", denormal, N);
    glint_arena_destroy(arena);
    glint_runtime_destroy(rt);
    free(l);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(huge_counts_are_refused, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test(same_name_lobes_of_two_runtimes_in_one_batch),
        cmocka_unit_test(denormal_pdfs_give_the_scalar_weight),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
