/* Plugin ABI version 2 (include/glint_plugin.h): a version-2 lobe's samples report their
 * own class and component through glint_sample and the sample batch's flags and component
 * arrays, alone and beside built-ins; version-1 plugins still load and report their type's
 * class and component 0; every version-2 load error (a version-1 table answered as 2, no
 * class in the flags, no components) with a message and nothing registered; samples that
 * break the class or component rules are repaired to what a version-1 sample reports and
 * counted. CMake passes the plugin paths (GLINT_*_PATH). */
#include "common.h"

#define N 512
/* The layered lobe's parameters in the tests. */
#define ALBEDO 0.9
#define GLOSSY 0.3
#define EXPONENT 6.0

static const char *LAYERED = "{\"lobes\": [{\"type\": \"glint_test_v2_layered\", \"albedo\": 0.9,"
                             " \"glossy\": 0.3, \"exponent\": 6}]}";
static const char *MIXED = "{\"lobes\": [{\"type\": \"lambert\", \"weight\": 0.5},"
                           " {\"type\": \"glint_test_v2_layered\", \"albedo\": 0.9,"
                           " \"glossy\": 0.3, \"exponent\": 6}]}";

static void load(const fixture *fx, const char *path)
{
    assert_ok(glint_runtime_load_plugin(fx->rt, path));
}

/* f64 reference of the layered lobe (plugins/test/v2_layered.c's formula, normal +z):
 * weight value / pdf of a direction with cosines co, ci. */
static double layered_weight(double co, double ci)
{
    const double pi = 3.14159265358979;
    double lobe = (EXPONENT + 1.0) / (2.0 * pi) * pow(ci, EXPONENT);
    double value = ALBEDO * (1.0 - GLOSSY) * ci / pi + ALBEDO * GLOSSY * pow(co, EXPONENT - 1.0) * lobe;
    double pdf = (1.0 - GLOSSY) * ci / pi + GLOSSY * lobe;
    return value / pdf;
}

/* The class and component a layered sample drawn with u[0] = u_lobe must report, and
 * the cosine of its direction from u0 (the lobe's u[1]). */
static void expect_layered(const glint_sample_result *s, float u_lobe, float u0, glint_vec3 wo)
{
    int glossy = u_lobe < GLOSSY;
    double ci = glossy ? pow(u0, 1.0 / (EXPONENT + 1.0)) : sqrt(1.0 - u0);
    assert_int_equal(s->flags,
                     GLINT_FLAG_REFLECTION | (glossy ? GLINT_FLAG_GLOSSY : GLINT_FLAG_DIFFUSE));
    assert_int_equal(s->component, glossy ? 1u : 0u);
    assert_close(s->wi.z, ci, 1e-5f);
    assert_close(s->weight[0], layered_weight(wo.z, ci), 2e-4f);
}

static void layered_samples_report_class_and_component(void **state)
{
    fixture *fx = *state;
    glint_closure *c;
    glint_lobe_info info;
    int seen[2] = {0, 0}, i;
    lcg g;
    load(fx, GLINT_TEST_V2_LAYERED_PATH);
    info = lobe_type(fx->rt, lobe_id(fx->rt, "glint_test_v2_layered"));
    assert_int_equal(info.flags, GLINT_FLAG_REFLECTION | GLINT_FLAG_DIFFUSE | GLINT_FLAG_GLOSSY);
    assert_int_equal(info.component_count, 2); /* as declared */
    c = json_closure(fx, LAYERED, NULL);
    lcg_seed(&g, 2);
    for (i = 0; i < N; i++) {
        glint_vec3 wo = lcg_direction(&g, 1);
        float u_lobe = lcg_next(&g), u0 = lcg_next(&g), u1 = lcg_next(&g);
        glint_sample_result s = sample_result_init();
        if (glint_sample(c, wo, u_lobe, u0, u1, &s) != GLINT_OK)
            continue;
        expect_layered(&s, u_lobe, u0, wo);
        seen[s.component]++;
    }
    /* About 30% glossy. */
    assert_true(seen[1] > N / 5 && seen[0] > N / 2);
}

/* Sample batch outputs of N lanes. */
typedef struct batch {
    float wo_x[N], wo_y[N], wo_z[N], u_lobe[N], u0[N], u1[N];
    float wi_x[N], wi_y[N], wi_z[N], pdf[N], w_r[N], w_g[N], w_b[N];
    uint32_t flags[N], lobe[N], component[N];
} batch;

/* Random upper-hemisphere lanes, then one glint_sample_batch over c. */
static void sample_batch(const glint_closure *c, batch *b, uint64_t seed)
{
    glint_sample_batch_args a;
    lcg g;
    int i;
    lcg_seed(&g, seed);
    for (i = 0; i < N; i++) {
        glint_vec3 wo = lcg_direction(&g, 1);
        b->wo_x[i] = wo.x, b->wo_y[i] = wo.y, b->wo_z[i] = wo.z;
        b->u_lobe[i] = lcg_next(&g), b->u0[i] = lcg_next(&g), b->u1[i] = lcg_next(&g);
        b->component[i] = UINT32_MAX;
    }
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.count = N;
    a.closure = c;
    a.wo_x = b->wo_x, a.wo_y = b->wo_y, a.wo_z = b->wo_z;
    a.u_lobe = b->u_lobe, a.u0 = b->u0, a.u1 = b->u1;
    a.wi_x = b->wi_x, a.wi_y = b->wi_y, a.wi_z = b->wi_z, a.pdf = b->pdf;
    a.weight_r = b->w_r, a.weight_g = b->w_g, a.weight_b = b->w_b;
    a.flags = b->flags, a.lobe = b->lobe, a.component = b->component;
    assert_ok(glint_sample_batch(&a));
}

/* Lane i of the batch equals glint_sample with the same numbers, flags and component
 * included (0 and no flags where nothing was sampled). */
static void expect_lane_is_scalar(const glint_closure *c, const batch *b, int i)
{
    glint_vec3 wo = v3(b->wo_x[i], b->wo_y[i], b->wo_z[i]);
    glint_sample_result s = sample_result_init();
    if (glint_sample(c, wo, b->u_lobe[i], b->u0[i], b->u1[i], &s) != GLINT_OK) {
        assert_int_equal(b->flags[i], 0);
        assert_int_equal(b->component[i], 0);
        return;
    }
    assert_int_equal(b->flags[i], s.flags);
    assert_int_equal(b->lobe[i], s.lobe);
    assert_int_equal(b->component[i], s.component);
}

static void batches_carry_class_and_component(void **state)
{
    fixture *fx = *state;
    static batch b;
    const glint_closure *c;
    int i, layered[2] = {0, 0};
    load(fx, GLINT_TEST_V2_LAYERED_PATH);

    c = json_closure(fx, LAYERED, NULL);
    sample_batch(c, &b, 3);
    for (i = 0; i < N; i++) {
        glint_vec3 wo = v3(b.wo_x[i], b.wo_y[i], b.wo_z[i]);
        glint_sample_result s = sample_result_init();
        expect_lane_is_scalar(c, &b, i);
        if (b.flags[i] == 0)
            continue;
        s.flags = b.flags[i], s.component = b.component[i];
        s.wi = v3(b.wi_x[i], b.wi_y[i], b.wi_z[i]);
        s.weight[0] = b.w_r[i];
        expect_layered(&s, b.u_lobe[i], b.u0[i], wo);
    }

    /* Beside a built-in: the lambert lanes report DIFFUSE, component 0; the layered
     * lanes a class matching their component. */
    c = json_closure(fx, MIXED, NULL);
    sample_batch(c, &b, 4);
    for (i = 0; i < N; i++) {
        expect_lane_is_scalar(c, &b, i);
        if (b.flags[i] == 0)
            continue;
        if (b.lobe[i] == 0) {
            assert_int_equal(b.flags[i], GLINT_FLAG_REFLECTION | GLINT_FLAG_DIFFUSE);
            assert_int_equal(b.component[i], 0);
        } else {
            assert_int_equal(b.flags[i], GLINT_FLAG_REFLECTION | (b.component[i] == 1
                                                                      ? GLINT_FLAG_GLOSSY
                                                                      : GLINT_FLAG_DIFFUSE));
            layered[b.component[i]]++;
        }
    }
    assert_true(layered[0] > 20 && layered[1] > 20);
}

/* Version-1 plugins load beside version-2 ones; their samples report the type's class
 * and component 0, scalar and batched. */
static void v1_plugins_report_the_type_class(void **state)
{
    fixture *fx = *state;
    static batch b;
    static const struct {
        const char *json;
        uint32_t flags;
    } cases[] = {
        {"{\"lobes\": [{\"type\": \"matte\"}]}", GLINT_FLAG_REFLECTION | GLINT_FLAG_DIFFUSE},
        {"{\"lobes\": [{\"type\": \"charlie\", \"roughness\": 0.5}]}",
         GLINT_FLAG_REFLECTION | GLINT_FLAG_GLOSSY},
    };
    size_t k;
    int i, sampled = 0;
    load(fx, GLINT_TEST_V2_LAYERED_PATH);
    load(fx, GLINT_MINIMAL_PATH);
    load(fx, GLINT_CHARLIE_PATH);
    assert_int_equal(lobe_type(fx->rt, lobe_id(fx->rt, "charlie")).component_count, 1);
    for (k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const glint_closure *c = json_closure(fx, cases[k].json, NULL);
        sample_batch(c, &b, 5 + k);
        for (i = 0; i < N; i++) {
            expect_lane_is_scalar(c, &b, i);
            if (b.flags[i] == 0)
                continue;
            assert_int_equal(b.flags[i], cases[k].flags);
            assert_int_equal(b.component[i], 0);
            sampled++;
        }
    }
    assert_true(sampled > N);
}

typedef struct load_case {
    const char *path;
    const char *mention;        /* in the message */
    const char *not_registered; /* a valid lobe of the file that must not be registered */
} load_case;

static const load_case LOAD_CASES[] = {
    {GLINT_TEST_V2_STRUCT_SIZE_PATH, "glint_plugin_lobe_v2.struct_size", NULL},
    {GLINT_TEST_V2_NO_CLASS_PATH, "glint_test_v2_no_class", "glint_test_v2_class_ok"},
    {GLINT_TEST_V2_NO_COMPONENTS_PATH, "component_count 0", NULL},
};

static void v2_load_errors(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt), id;
    size_t i;
    for (i = 0; i < sizeof LOAD_CASES / sizeof LOAD_CASES[0]; i++) {
        const load_case *lc = &LOAD_CASES[i];
        print_message("load case %u: %s\n", (unsigned)i, lc->path);
        check_error(fx, glint_runtime_load_plugin(fx->rt, lc->path), GLINT_ERROR_PLUGIN_PARAMS);
        assert_error_mentions(strrchr(lc->path, '/') + 1);
        assert_error_mentions(lc->mention);
        assert_int_equal(lobe_type_count(fx->rt), n);
        if (lc->not_registered != NULL)
            check_error(fx, glint_lobe_type_find(fx->rt, lc->not_registered, &id),
                        GLINT_ERROR_UNKNOWN_NAME);
    }
    /* The runtime still loads a good version-2 plugin. */
    load(fx, GLINT_TEST_V2_LAYERED_PATH);
    assert_int_equal(lobe_type_count(fx->rt), n + 1);
}

static uint64_t sanitized(const fixture *fx, uint32_t id)
{
    uint64_t count = UINT64_MAX;
    assert_ok(glint_lobe_sanitized_count(fx->rt, id, &count));
    return count;
}

/* Each lobe of glint_test_v2_bad_samples breaks one rule in every sample: the sample
 * still reaches the caller, with the type's class (DIFFUSE) and component 0, and each
 * sample is counted once, scalar and batched. */
static void bad_samples_are_repaired_and_counted(void **state)
{
    fixture *fx = *state;
    static batch b;
    static const char *const names[] = {"glint_test_class_unset", "glint_test_class_undeclared",
                                        "glint_test_specular_not_delta",
                                        "glint_test_component_past_count"};
    size_t k;
    int i;
    load(fx, GLINT_TEST_V2_BAD_SAMPLES_PATH);
    for (k = 0; k < sizeof names / sizeof names[0]; k++) {
        uint32_t id = lobe_id(fx->rt, names[k]);
        const glint_closure *c = single_lobe_closure(fx, id, NULL, 0, NULL);
        glint_sample_result s = sample_result_init();
        uint64_t before = sanitized(fx, id), batched = 0;
        print_message("lobe %s\n", names[k]);
        assert_ok(glint_sample(c, test_wo(), 0.5f, 0.3f, 0.7f, &s));
        assert_int_equal(s.flags, GLINT_FLAG_REFLECTION | GLINT_FLAG_DIFFUSE);
        assert_int_equal(s.component, 0);
        assert_true(s.weight[0] > 0.0f && isfinite(s.weight[0]));
        assert_int_equal(sanitized(fx, id), before + 1);
        before = sanitized(fx, id);
        sample_batch(c, &b, 6 + k);
        for (i = 0; i < N; i++) {
            if (b.flags[i] == 0)
                continue;
            assert_int_equal(b.flags[i], GLINT_FLAG_REFLECTION | GLINT_FLAG_DIFFUSE);
            assert_int_equal(b.component[i], 0);
            batched++;
        }
        assert_true(batched > N / 2);
        assert_int_equal(sanitized(fx, id), before + batched);
    }
}

int main(void)
{
#define T(f) cmocka_unit_test_setup_teardown(f, fixture_setup, fixture_teardown)
    const struct CMUnitTest tests[] = {
        T(layered_samples_report_class_and_component),
        T(batches_carry_class_and_component),
        T(v1_plugins_report_the_type_class),
        T(v2_load_errors),
        T(bad_samples_are_repaired_and_counted),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
