/* Plugins (include/glint_plugin.h, plugins/): loading and listing, plugin lobes through
 * every entry point, alone and mixed with built-ins, from C and from JSON, in batches;
 * a chi-square test of the Charlie plugin's sampling; every loader error with its own
 * status, a message naming the file or lobe, and nothing half registered; sanitized
 * outputs of lobes that return NaN or finite extremes, and of one that writes to its
 * parameter block; the plugins= config key. CMake passes the plugin
 * paths and directories (GLINT_*_PATH, GLINT_PLUGIN_DIR, GLINT_PLUGIN_BUILD_DIR). */
#include "common.h"

#include <stdlib.h>

/* Batch vs scalar: the tolerances of test_batch.c (plugin lobes run their scalar
 * callbacks in batches, the built-ins beside them run the SIMD kernels). */
#define TOL 2.5e-4f
#define SAMPLE_TOL 2e-3f
#define SENTINEL (-7.0f)

static const float WHITE[3] = {1.0f, 1.0f, 1.0f};

static void load(const fixture *fx, const char *path)
{
    assert_ok(glint_runtime_load_plugin(fx->rt, path));
}

static double dot3(glint_vec3 a, glint_vec3 b)
{
    return (double)a.x * b.x + (double)a.y * b.y + (double)a.z * b.z;
}

/* ---- an f64 reference of the Charlie lobe (the formulas of plugins/charlie.c) ----------- */

static double charlie_fit_l(double a, double x)
{
    double t = (1.0 - a) * (1.0 - a), s = 1.0 - t;
    double ca = t * 25.3245 + s * 21.5473, cb = t * 3.32435 + s * 3.82987;
    double cc = t * 0.16801 + s * 0.19823, cd = t * -1.27393 + s * -1.97760;
    double ce = t * -4.85967 + s * -4.32054;
    return ca / (1.0 + cb * pow(x, cc)) + cd * x + ce;
}

static double charlie_lambda(double a, double mu)
{
    mu = fmax(mu, 1e-4);
    return mu < 0.5 ? exp(charlie_fit_l(a, mu))
                    : exp(2.0 * charlie_fit_l(a, 0.5) - charlie_fit_l(a, 1.0 - mu));
}

/* value = color f cos_i and pdf of roughness `a` with unit normal n (world space). */
static void charlie_reference(const float color[3], double a, glint_vec3 n, glint_vec3 wo,
                              glint_vec3 wi, double value[3], double *pdf)
{
    double co = dot3(wo, n), ci = dot3(wi, n), h[3], len, hn, wo_h, d, g2, f;
    int k;
    value[0] = value[1] = value[2] = *pdf = 0.0;
    if (co <= 0.0 || ci <= 0.0)
        return;
    h[0] = (double)wo.x + wi.x, h[1] = (double)wo.y + wi.y, h[2] = (double)wo.z + wi.z;
    len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    hn = (h[0] * n.x + h[1] * n.y + h[2] * n.z) / len;
    wo_h = (h[0] * wo.x + h[1] * wo.y + h[2] * wo.z) / len;
    d = (2.0 + 1.0 / a) / (2.0 * 3.14159265358979) * pow(fmax(0.0, 1.0 - hn * hn), 0.5 / a);
    g2 = 1.0 / (1.0 + charlie_lambda(a, co) + charlie_lambda(a, ci));
    f = d * g2 / (4.0 * fmax(co, 1e-4) * fmax(ci, 1e-4));
    for (k = 0; k < 3; k++)
        value[k] = color[k] * f * ci;
    *pdf = d * hn / (4.0 * wo_h);
}

/* ---- listing --------------------------------------------------------------------------- */

static void charlie_is_listed(void **state)
{
    fixture *fx = *state;
    uint32_t before = lobe_type_count(fx->rt), id, index = UINT32_MAX;
    glint_lobe_info info;
    glint_param_info color, rough, by_index = param_info_init();
    float block[5] = {0, 0, 0, 0, SENTINEL};
    glint_runtime *other = NULL;

    assert_ok(glint_runtime_load_plugin(fx->rt, GLINT_CHARLIE_PATH));
    assert_int_equal(lobe_type_count(fx->rt), before + 1);
    id = lobe_id(fx->rt, "charlie");
    assert_int_equal(id, before); /* after the built-ins */
    info = lobe_type(fx->rt, id);
    assert_string_equal(info.name, "charlie");
    assert_non_null(info.summary);
    assert_true(strlen(info.summary) > 0);
    assert_int_equal(info.flags, GLINT_FLAG_REFLECTION | GLINT_FLAG_GLOSSY);
    assert_int_equal(info.reciprocal, 1);
    assert_int_equal(info.param_count, 2);
    assert_int_equal(info.param_block_size, 4);

    color = lobe_param(fx->rt, id, "color");
    assert_int_equal(color.param_type, GLINT_PARAM_RGB);
    assert_int_equal(color.offset, 0);
    assert_int_equal(color.size, 3);
    assert_true(color.default_value[0] == 1.0f && color.default_value[1] == 1.0f &&
                color.default_value[2] == 1.0f);
    assert_true(color.min == 0.0f && color.max == 1.0f);
    assert_int_equal(color.choice_count, 0);
    assert_string_equal(color.choices, "");
    assert_non_null(color.doc);
    rough = lobe_param(fx->rt, id, "roughness");
    assert_int_equal(rough.param_type, GLINT_PARAM_FLOAT);
    assert_int_equal(rough.offset, 3);
    assert_int_equal(rough.size, 1);
    assert_true(rough.default_value[0] == 0.5f);
    assert_true(rough.min == 0.07f && rough.max == 1.0f);
    /* Indices follow the plugin's table order. */
    assert_ok(glint_lobe_param_find(fx->rt, id, "roughness", &index));
    assert_int_equal(index, 1);
    assert_ok(glint_lobe_param_info(fx->rt, id, 0, &by_index));
    assert_string_equal(by_index.name, "color");
    check_error(fx, glint_lobe_param_info(fx->rt, id, 2, &by_index), GLINT_ERROR_OUT_OF_RANGE);
    assert_ok(glint_lobe_param_defaults(fx->rt, id, block, 4));
    assert_true(block[0] == 1.0f && block[1] == 1.0f && block[2] == 1.0f && block[3] == 0.5f);
    assert_true(block[4] == SENTINEL);

    /* Registration is per runtime: another runtime loads the same file as well. */
    assert_ok(glint_runtime_create("threads=1", &other));
    check_error(fx, glint_lobe_type_find(other, "charlie", &index), GLINT_ERROR_UNKNOWN_NAME);
    assert_ok(glint_runtime_load_plugin(other, GLINT_CHARLIE_PATH));
    assert_int_equal(lobe_id(other, "charlie"), before);
    glint_runtime_destroy(other);

    /* The example of docs/writing-a-plugin.md. */
    load(fx, GLINT_MINIMAL_PATH);
    assert_int_equal(lobe_type_count(fx->rt), before + 2);
    color = lobe_param(fx->rt, lobe_id(fx->rt, "matte"), "color");
    assert_true(color.default_value[0] == 0.8f && color.max == 1.0f);
}

/* ---- evaluation ------------------------------------------------------------------------ */

/* Through the host, from a C parameter block and from JSON, in a tilted frame: the
 * Charlie lobe equals its f64 reference (the host passes parameters and local
 * directions as declared). */
static void charlie_matches_reference(void **state)
{
    fixture *fx = *state;
    const float color[3] = {0.9f, 0.6f, 0.3f}, block[4] = {0.9f, 0.6f, 0.3f, 0.3f};
    const glint_vec3 n = v3_normalize(v3(0.3f, -0.2f, 1.0f));
    glint_vec3 t, bt;
    glint_frame frame;
    glint_closure *from_c = NULL, *from_json;
    uint32_t id;
    lcg g;
    int i, k, nonzero = 0;

    load(fx, GLINT_CHARLIE_PATH);
    id = lobe_id(fx->rt, "charlie");
    frame.normal = v3(0.3f, -0.2f, 1.0f); /* as in the JSON: the same closure either way */
    frame.tangent = v3(0.0f, 0.0f, 0.0f);
    assert_ok(glint_closure_begin(fx->rt, fx->arena, NULL, 0, &from_c));
    assert_ok(glint_closure_add_lobe(from_c, id, WHITE, &frame, block, 4, NULL));
    assert_ok(glint_closure_finish(from_c));
    from_json = json_closure(fx,
                             "{\"lobes\": [{\"type\": \"charlie\", \"color\": [0.9, 0.6, 0.3], "
                             "\"roughness\": 0.3, \"normal\": [0.3, -0.2, 1]}]}",
                             NULL);

    /* Directions drawn about n: an orthonormal basis (t, bt, n). */
    t = v3_normalize(v3(1.0f, 0.0f, -n.x / n.z));
    bt = v3(n.y * t.z - n.z * t.y, n.z * t.x - n.x * t.z, n.x * t.y - n.y * t.x);
    lcg_seed(&g, 17);
    for (i = 0; i < 200; i++) {
        /* wo above, cos down to 0.01; every fourth wi from the whole sphere. */
        glint_vec3 lo = lcg_direction(&g, 1), li = lcg_direction(&g, i % 4 != 3);
        glint_vec3 wo = v3(lo.x * t.x + lo.y * bt.x + lo.z * n.x,
                           lo.x * t.y + lo.y * bt.y + lo.z * n.y,
                           lo.x * t.z + lo.y * bt.z + lo.z * n.z);
        glint_vec3 wi = v3(li.x * t.x + li.y * bt.x + li.z * n.x,
                           li.x * t.y + li.y * bt.y + li.z * n.y,
                           li.x * t.z + li.y * bt.z + li.z * n.z);
        glint_eval_result a = eval_result_init(), b = eval_result_init();
        double value[3], pdf, pdf_reverse, unused[3];
        assert_ok(glint_eval_lobe(from_c, 0, wo, wi, &a));
        assert_ok(glint_eval_lobe(from_json, 0, wo, wi, &b));
        charlie_reference(color, 0.3, n, wo, wi, value, &pdf);
        charlie_reference(color, 0.3, n, wi, wo, unused, &pdf_reverse);
        for (k = 0; k < 3; k++) {
            assert_close(a.value[k], value[k], 2e-4f);
            assert_true(b.value[k] == a.value[k]);
        }
        assert_close(a.pdf, pdf, 2e-4f);
        assert_close(a.pdf_reverse, pdf_reverse, 2e-4f);
        assert_true(b.pdf == a.pdf);
        nonzero += value[0] > 0.0;
    }
    assert_true(nonzero > 100);
}

/* A closure of built-in and plugin lobes, built lobe by lobe and from JSON: the same
 * closure either way; eval, pdf and albedo are the weighted sums of the lobes'; samples
 * agree with eval. */
static void mixed_closures_from_c_and_json(void **state)
{
    fixture *fx = *state;
    const float w_lambert[3] = {0.5f, 0.25f, 0.25f}, w_charlie[3] = {0.75f, 0.5f, 0.5f},
                w_conductor[3] = {0.25f, 0.25f, 0.5f}, block[4] = {0.5f, 0.75f, 1.0f, 0.25f};
    const glint_vec3 wo = test_wo();
    glint_frame frame = frame_z();
    glint_closure *from_c = NULL, *from_json;
    uint32_t lambert, charlie, conductor, count = 0, type = UINT32_MAX, i;
    float probability = -1.0f, albedo_c[3], albedo_json[3], lobe_albedo[3], sum[3];
    lcg g;
    int k, samples = 0;

    load(fx, GLINT_CHARLIE_PATH);
    lambert = lobe_id(fx->rt, "lambert");
    charlie = lobe_id(fx->rt, "charlie");
    conductor = lobe_id(fx->rt, "conductor");
    assert_ok(glint_closure_begin(fx->rt, fx->arena, &wo, 0, &from_c));
    assert_ok(glint_closure_add_lobe(from_c, lambert, w_lambert, &frame, NULL, 0, NULL));
    assert_ok(glint_closure_add_lobe(from_c, charlie, w_charlie, &frame, block, 4, NULL));
    assert_ok(glint_closure_add_lobe(from_c, conductor, w_conductor, &frame, NULL, 0, NULL));
    assert_ok(glint_closure_finish(from_c));
    from_json = json_closure(fx,
                             "{\"lobes\": ["
                             "{\"type\": \"lambert\", \"weight\": [0.5, 0.25, 0.25]}, "
                             "{\"type\": \"charlie\", \"weight\": [0.75, 0.5, 0.5], "
                             "\"color\": [0.5, 0.75, 1], \"roughness\": 0.25}, "
                             "{\"type\": \"conductor\", \"weight\": [0.25, 0.25, 0.5]}]}",
                             &wo);

    assert_ok(glint_closure_lobe_count(from_c, &count));
    assert_int_equal(count, 3);
    assert_ok(glint_closure_lobe(from_json, 1, &type, &probability));
    assert_int_equal(type, charlie);
    assert_true(probability > 0.0f && probability < 1.0f);

    assert_ok(glint_albedo(from_c, wo, albedo_c));
    assert_ok(glint_albedo(from_json, wo, albedo_json));
    sum[0] = sum[1] = sum[2] = 0.0f;
    for (i = 0; i < count; i++) {
        assert_ok(glint_albedo_lobe(from_c, i, wo, lobe_albedo));
        for (k = 0; k < 3; k++)
            sum[k] += lobe_albedo[k];
    }
    for (k = 0; k < 3; k++) {
        assert_true(albedo_json[k] == albedo_c[k]);
        assert_close(albedo_c[k], sum[k], 1e-5f);
        assert_finite_nonneg(albedo_c[k]);
    }

    lcg_seed(&g, 5);
    for (i = 0; i < 300; i++) {
        glint_vec3 wi = lcg_direction(&g, 1);
        glint_eval_result a = eval_result_init(), b = eval_result_init();
        glint_sample_result s = sample_result_init();
        float value[3] = {0, 0, 0}, pdf = 0.0f, lobe_pdf, probability_j, p_scalar = -1.0f;
        uint32_t j;
        assert_ok(glint_eval(from_c, wo, wi, &a));
        assert_ok(glint_eval(from_json, wo, wi, &b));
        for (j = 0; j < count; j++) {
            glint_eval_result r = eval_result_init();
            assert_ok(glint_eval_lobe(from_c, j, wo, wi, &r));
            assert_ok(glint_pdf_lobe(from_c, j, wo, wi, &lobe_pdf));
            assert_ok(glint_closure_lobe(from_c, j, &type, &probability_j));
            for (k = 0; k < 3; k++)
                value[k] += r.value[k];
            pdf += probability_j * lobe_pdf;
        }
        for (k = 0; k < 3; k++) {
            assert_true(b.value[k] == a.value[k]);
            assert_close(a.value[k], value[k], 1e-5f);
        }
        assert_close(a.pdf, pdf, 1e-5f);
        assert_ok(glint_pdf(from_c, wo, wi, &p_scalar));
        assert_close(p_scalar, a.pdf, 1e-6f);

        /* Samples: value and pdf are the closure's eval at the sampled direction. */
        if (glint_sample(from_c, wo, lcg_next(&g), lcg_next(&g), lcg_next(&g), &s) == GLINT_OK) {
            glint_eval_result e = eval_result_init();
            samples++;
            assert_ok(glint_eval(from_c, wo, s.wi, &e));
            assert_close(s.pdf, e.pdf, 1e-4f);
            for (k = 0; k < 3; k++) {
                assert_close(s.value[k], e.value[k], 1e-4f);
                assert_close(s.weight[k], s.value[k] / s.pdf, 1e-4f);
            }
            if (s.lobe == 1)
                assert_int_equal(s.flags, GLINT_FLAG_REFLECTION | GLINT_FLAG_GLOSSY);
        }
    }
    assert_true(samples > 100);
}

/* JSON names plugin lobes and checks their parameters like the built-ins'. */
static void json_errors_name_plugin_lobes(void **state)
{
    fixture *fx = *state;
    glint_closure *c = NULL;
    const char *too_smooth = "{\"lobes\": [{\"type\": \"charlie\", \"roughness\": 0.05}]}";
    const char *unknown_key = "{\"lobes\": [{\"type\": \"charlie\", \"sheen\": 1}]}";
    load(fx, GLINT_CHARLIE_PATH);
    check_error(fx, glint_closure_from_json(fx->rt, fx->arena, too_smooth, NULL, &c),
                GLINT_ERROR_OUT_OF_RANGE);
    assert_error_mentions("roughness");
    check_error(fx, glint_closure_from_json(fx->rt, fx->arena, unknown_key, NULL, &c),
                GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("sheen");
    assert_error_mentions("roughness");
    check_error(fx,
                glint_closure_from_json(fx->rt, fx->arena, "{\"lobes\": [{\"type\": \"velvet\"}]}",
                                        NULL, &c),
                GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("charlie"); /* among the valid types */
}

/* The guide's example lobe: Lambert's values. */
static void minimal_plugin_works(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo(), wi = v3_normalize(v3(-0.4f, 0.1f, 0.7f));
    glint_closure *c;
    glint_eval_result e = eval_result_init();
    glint_sample_result s = sample_result_init();
    float albedo[3];
    load(fx, GLINT_MINIMAL_PATH);
    c = json_closure(fx, "{\"lobes\": [{\"type\": \"matte\", \"color\": [0.2, 0.4, 0.6]}]}", NULL);
    assert_ok(glint_eval(c, wo, wi, &e));
    assert_close(e.value[0], 0.2f * wi.z / 3.14159265f, 1e-5f);
    assert_close(e.value[2], 0.6f * wi.z / 3.14159265f, 1e-5f);
    assert_close(e.pdf, wi.z / 3.14159265f, 1e-5f);
    assert_close(e.pdf_reverse, wo.z / 3.14159265f, 1e-5f);
    assert_ok(glint_albedo(c, wo, albedo));
    assert_close(albedo[1], 0.4f, 1e-6f);
    assert_ok(glint_sample(c, wo, 0.5f, 0.3f, 0.7f, &s));
    assert_int_equal(s.flags, GLINT_FLAG_REFLECTION | GLINT_FLAG_DIFFUSE);
    assert_close(s.weight[0], 0.2f, 1e-5f);
    /* One-sided. */
    assert_ok(glint_eval(c, wo, v3(wi.x, wi.y, -wi.z), &e));
    assert_true(e.value[0] == 0.0f && e.pdf == 0.0f);
    assert_int_equal(glint_sample(c, v3(wo.x, wo.y, -wo.z), 0.5f, 0.3f, 0.7f, &s), GLINT_NO_SAMPLE);
}

/* ---- batches ------------------------------------------------------------------------------ */

/* More lanes than one block of 4096, so blocks may run on several threads at once. */
#define NB 5000

typedef struct lanes {
    const glint_closure *per_lane[NB];
    float wo_x[NB], wo_y[NB], wo_z[NB], wi_x[NB], wi_y[NB], wi_z[NB];
    float u_lobe[NB], u0[NB], u1[NB];
    uint8_t active[NB];
    /* outputs */
    float r[NB], g[NB], b[NB], pdf[NB], pdf_reverse[NB];
    float w_r[NB], w_g[NB], w_b[NB], s_pdf[NB];
    uint32_t flags[NB], lobe[NB];
} lanes;

static glint_vec3 lane_wo(const lanes *l, int i)
{
    return v3(l->wo_x[i], l->wo_y[i], l->wo_z[i]);
}

static glint_vec3 lane_wi(const lanes *l, int i)
{
    return v3(l->wi_x[i], l->wi_y[i], l->wi_z[i]);
}

static void fill(float *a, float v)
{
    fill_floats(a, NB, v);
}

/* Lanes of four closures: mixed built-in + plugin, charlie alone (per-lane roughness),
 * matte alone, lambert alone. */
static void make_lanes(const fixture *fx, lanes *l)
{
    uint32_t charlie = lobe_id(fx->rt, "charlie");
    const glint_closure *pool[6];
    lcg g;
    int i;
    float block[4] = {0.8f, 0.7f, 0.6f, 0.07f};
    pool[0] = json_closure(fx,
                           "{\"lobes\": ["
                           "{\"type\": \"charlie\", \"weight\": 0.5, \"roughness\": 0.4}, "
                           "{\"type\": \"conductor\", \"weight\": 0.5}, "
                           "{\"type\": \"matte\", \"weight\": 0.25}]}",
                           NULL);
    pool[1] = single_lobe_closure(fx, charlie, block, 4, NULL);
    block[3] = 1.0f;
    pool[2] = single_lobe_closure(fx, charlie, block, 4, NULL);
    pool[3] = single_lobe_closure(fx, charlie, NULL, 0, NULL);
    pool[4] = json_closure(fx, "{\"lobes\": [{\"type\": \"matte\"}]}", NULL);
    pool[5] = json_closure(fx, "{\"lobes\": [{\"type\": \"lambert\"}]}", NULL);
    lcg_seed(&g, 99);
    for (i = 0; i < NB; i++) {
        glint_vec3 wo = lcg_direction(&g, i % 8 != 7), wi = lcg_direction(&g, i % 5 != 4);
        glint_sample_result s = sample_result_init();
        l->per_lane[i] = pool[i % 6];
        l->wo_x[i] = wo.x, l->wo_y[i] = wo.y, l->wo_z[i] = wo.z;
        l->u_lobe[i] = lcg_next(&g), l->u0[i] = lcg_next(&g), l->u1[i] = lcg_next(&g);
        l->active[i] = (uint8_t)(i % 7 != 3);
        /* Half the lanes evaluate at a sampled direction, where the lobes are large. */
        if (i % 2 == 0 && glint_sample(l->per_lane[i], wo, l->u_lobe[i], l->u0[i], l->u1[i],
                                       &s) == GLINT_OK)
            wi = s.wi;
        l->wi_x[i] = wi.x, l->wi_y[i] = wi.y, l->wi_z[i] = wi.z;
    }
}

static void batches_match_scalar(void **state)
{
    fixture *fx = *state;
    lanes *l = calloc(1, sizeof *l);
    glint_eval_batch_args e;
    glint_pdf_batch_args p;
    glint_sample_batch_args s;
    glint_albedo_batch_args a;
    int i, k, nonzero = 0, sampled = 0;
    assert_non_null(l);
    load(fx, GLINT_CHARLIE_PATH);
    load(fx, GLINT_MINIMAL_PATH);
    make_lanes(fx, l);

    memset(&e, 0, sizeof e);
    e.struct_size = sizeof e;
    e.count = NB;
    e.closures = l->per_lane;
    e.active = l->active;
    e.wo_x = l->wo_x, e.wo_y = l->wo_y, e.wo_z = l->wo_z;
    e.wi_x = l->wi_x, e.wi_y = l->wi_y, e.wi_z = l->wi_z;
    e.value_r = l->r, e.value_g = l->g, e.value_b = l->b, e.pdf = l->pdf;
    e.pdf_reverse = l->pdf_reverse;
    fill(l->r, SENTINEL), fill(l->pdf, SENTINEL), fill(l->pdf_reverse, SENTINEL);
    assert_ok(glint_eval_batch(&e));
    for (i = 0; i < NB; i++) {
        glint_eval_result r = eval_result_init();
        if (!l->active[i]) {
            assert_true(l->r[i] == SENTINEL && l->pdf[i] == SENTINEL);
            continue;
        }
        assert_ok(glint_eval(l->per_lane[i], lane_wo(l, i), lane_wi(l, i), &r));
        assert_batch_close(l->r[i], r.value[0], TOL);
        assert_batch_close(l->g[i], r.value[1], TOL);
        assert_batch_close(l->b[i], r.value[2], TOL);
        assert_batch_close(l->pdf[i], r.pdf, TOL);
        assert_batch_close(l->pdf_reverse[i], r.pdf_reverse, TOL);
        nonzero += r.value[0] > 0.0f;
    }
    assert_true(nonzero > NB / 4);

    memset(&p, 0, sizeof p);
    p.struct_size = sizeof p;
    p.count = NB;
    p.closures = l->per_lane;
    p.wo_x = l->wo_x, p.wo_y = l->wo_y, p.wo_z = l->wo_z;
    p.wi_x = l->wi_x, p.wi_y = l->wi_y, p.wi_z = l->wi_z;
    p.pdf = l->pdf;
    assert_ok(glint_pdf_batch(&p));
    for (i = 0; i < NB; i++) {
        float expected = -1.0f;
        assert_ok(glint_pdf(l->per_lane[i], lane_wo(l, i), lane_wi(l, i), &expected));
        assert_batch_close(l->pdf[i], expected, TOL);
    }

    memset(&s, 0, sizeof s);
    s.struct_size = sizeof s;
    s.count = NB;
    s.closures = l->per_lane;
    s.wo_x = l->wo_x, s.wo_y = l->wo_y, s.wo_z = l->wo_z;
    s.u_lobe = l->u_lobe, s.u0 = l->u0, s.u1 = l->u1;
    /* The eval inputs' wi arrays receive the sampled directions. */
    s.wi_x = l->wi_x, s.wi_y = l->wi_y, s.wi_z = l->wi_z;
    s.pdf = l->s_pdf;
    s.weight_r = l->w_r, s.weight_g = l->w_g, s.weight_b = l->w_b;
    s.flags = l->flags, s.lobe = l->lobe;
    assert_ok(glint_sample_batch(&s));
    for (i = 0; i < NB; i++) {
        glint_sample_result r = sample_result_init();
        glint_status st = glint_sample(l->per_lane[i], lane_wo(l, i), l->u_lobe[i], l->u0[i],
                                       l->u1[i], &r);
        assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
        sampled += st == GLINT_OK;
        assert_batch_close(l->wi_x[i], r.wi.x, SAMPLE_TOL);
        assert_batch_close(l->wi_y[i], r.wi.y, SAMPLE_TOL);
        assert_batch_close(l->wi_z[i], r.wi.z, SAMPLE_TOL);
        assert_batch_close(l->s_pdf[i], r.pdf, SAMPLE_TOL);
        assert_batch_close(l->w_r[i], r.weight[0], SAMPLE_TOL);
        assert_batch_close(l->w_g[i], r.weight[1], SAMPLE_TOL);
        assert_batch_close(l->w_b[i], r.weight[2], SAMPLE_TOL);
        assert_int_equal(l->flags[i], r.flags);
        assert_int_equal(l->lobe[i], r.lobe);
    }
    assert_true(sampled > NB / 4);

    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.count = NB;
    a.closures = l->per_lane;
    a.wo_x = l->wo_x, a.wo_y = l->wo_y, a.wo_z = l->wo_z;
    a.albedo_r = l->r, a.albedo_g = l->g, a.albedo_b = l->b;
    assert_ok(glint_albedo_batch(&a));
    for (i = 0; i < NB; i++) {
        float expected[3];
        assert_ok(glint_albedo(l->per_lane[i], lane_wo(l, i), expected));
        for (k = 0; k < 3; k++)
            assert_finite_nonneg(expected[k]);
        assert_batch_close(l->r[i], expected[0], TOL);
        assert_batch_close(l->g[i], expected[1], TOL);
        assert_batch_close(l->b[i], expected[2], TOL);
    }
    free(l);
}

/* ---- chi-square of the Charlie plugin through glint_sample_lobe / glint_pdf_lobe --------
 *
 * The approach of test_chi2.c, cut to the upper hemisphere (the lobe is one-sided):
 * M samples histogrammed over N_T x N_P equal-area cells in (cos theta, phi); expected
 * counts from a K x K midpoint rule of the pdf per cell; cells expected below 5 pooled;
 * the p-value of Pearson's X^2 by the Wilson-Hilferty approximation (ample for the
 * hundreds of degrees of freedom here); Sidak-corrected overall significance 1%. The
 * pdf integrates to the fraction of samples not absorbed (reflected below the
 * surface), within 1% plus 4 binomial standard errors. The same samples' mean weight
 * estimates the albedo: glint_albedo_lobe agrees within 2% plus 4 standard errors and
 * 5e-4 (charlie's table is measured to 0.8%, 3.4e-3 absolute at cos_o < 0.02). */
#define CHI_M 100000
#define CHI_NT 10
#define CHI_NP 20
#define CHI_K 12

typedef struct chi_run {
    const char *name;
    float roughness, cos_o;
} chi_run;

static int chi_cell(glint_vec3 wi)
{
    double phi = atan2((double)wi.y, (double)wi.x);
    int t = (int)(fmin(fmax(wi.z, 0.0f), 1.0f) * CHI_NT), f;
    if (phi < 0.0)
        phi += 6.283185307179586;
    f = (int)(phi / 6.283185307179586 * CHI_NP);
    t = t >= CHI_NT ? CHI_NT - 1 : t;
    f = f >= CHI_NP ? CHI_NP - 1 : f;
    return t * CHI_NP + f;
}

/* Runs one test; returns its p-value. */
static double chi_square(const glint_closure *c, float cos_o, uint64_t seed)
{
    static double observed[CHI_NT * CHI_NP];
    const double two_pi = 6.283185307179586;
    glint_vec3 wo = v3(sqrtf(1.0f - cos_o * cos_o) * cosf(0.5f),
                       sqrtf(1.0f - cos_o * cos_o) * sinf(0.5f), cos_o);
    double x2 = 0.0, pool_e = 0.0, pool_o = 0.0, integral = 0.0, kept, se, z;
    double w_sum = 0.0, w_sum2 = 0.0, w_mean, w_se;
    float albedo[3];
    long absorbed = 0, i;
    int cell, dof = -1, a, b;
    lcg g;
    memset(observed, 0, sizeof observed);
    lcg_seed(&g, seed);
    for (i = 0; i < CHI_M; i++) {
        glint_sample_result s = sample_result_init();
        float u_c = lcg_next(&g), u0 = lcg_next(&g), u1 = lcg_next(&g);
        glint_status status = glint_sample_lobe(c, 0, wo, u_c, u0, u1, &s);
        if (status == GLINT_NO_SAMPLE) {
            absorbed++;
            continue;
        }
        assert_int_equal(status, GLINT_OK);
        assert_true(s.pdf > 0.0f && isfinite(s.pdf) && s.wi.z > 0.0f);
        observed[chi_cell(s.wi)] += 1.0;
        w_sum += s.weight[0];
        w_sum2 += (double)s.weight[0] * s.weight[0];
    }
    for (cell = 0; cell < CHI_NT * CHI_NP; cell++) {
        int t = cell / CHI_NP, f = cell % CHI_NP;
        double p = 0.0, e;
        for (a = 0; a < CHI_K; a++)
            for (b = 0; b < CHI_K; b++) {
                double ct = (t + (a + 0.5) / CHI_K) / CHI_NT, sn = sqrt(1.0 - ct * ct);
                double phi = two_pi * (f + (b + 0.5) / CHI_K) / CHI_NP;
                glint_vec3 wi = v3((float)(sn * cos(phi)), (float)(sn * sin(phi)), (float)ct);
                float pdf = -1.0f;
                assert_ok(glint_pdf_lobe(c, 0, wo, wi, &pdf));
                assert_finite_nonneg(pdf);
                p += pdf;
            }
        p *= (1.0 / CHI_NT / CHI_K) * (two_pi / CHI_NP / CHI_K);
        integral += p;
        e = p * CHI_M;
        if (e <= 0.0) {
            assert_true(observed[cell] == 0.0); /* samples where the pdf is 0 */
        } else if (e < 5.0) {
            pool_e += e, pool_o += observed[cell];
        } else {
            x2 += (observed[cell] - e) * (observed[cell] - e) / e;
            dof++;
        }
    }
    if (pool_e > 0.0) {
        x2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof++;
    }
    kept = 1.0 - (double)absorbed / CHI_M;
    se = sqrt(kept * (1.0 - kept) / CHI_M);
    if (!(fabs(integral - kept) <= 0.01 * kept + 4.0 * se))
        print_error("cos_o %g: the pdf integrates to %.5f, %.5f of the samples were kept\n",
                    (double)cos_o, integral, kept);
    assert_true(fabs(integral - kept) <= 0.01 * kept + 4.0 * se);
    assert_true(dof > 0);
    w_mean = w_sum / CHI_M;
    w_se = sqrt(fmax(0.0, w_sum2 / CHI_M - w_mean * w_mean) / CHI_M);
    assert_ok(glint_albedo_lobe(c, 0, wo, albedo));
    print_message("  cos_o %.2f: albedo %.5f, sampled %.5f +- %.5f\n", (double)cos_o,
                  (double)albedo[0], w_mean, w_se);
    assert_true(fabs(albedo[0] - w_mean) <= 0.02 * w_mean + 4.0 * w_se + 5e-4);
    z = (pow(x2 / dof, 1.0 / 3.0) - (1.0 - 2.0 / (9.0 * dof))) / sqrt(2.0 / (9.0 * dof));
    print_message("  cos_o %.2f: kept %.4f, pdf integral %.4f, X^2 %.1f, dof %d\n",
                  (double)cos_o, kept, integral, x2, dof);
    return 0.5 * erfc(z / sqrt(2.0));
}

static void charlie_chi_square(void **state)
{
    static const chi_run runs[] = {
        {"charlie", 0.07f, 0.9f}, {"charlie", 0.07f, 0.4f}, {"charlie", 0.07f, 0.05f},
        {"charlie", 0.5f, 0.9f},  {"charlie", 0.5f, 0.4f},  {"charlie", 0.5f, 0.05f},
        {"charlie", 1.0f, 0.9f},  {"charlie", 1.0f, 0.4f},  {"charlie", 1.0f, 0.05f},
        {"matte", 0.0f, 0.6f},
    };
    const size_t n = sizeof runs / sizeof runs[0];
    const double alpha = 1.0 - pow(1.0 - 0.01, 1.0 / (double)n);
    fixture *fx = *state;
    size_t i;
    load(fx, GLINT_CHARLIE_PATH);
    load(fx, GLINT_MINIMAL_PATH);
    for (i = 0; i < n; i++) {
        float block[4] = {1.0f, 1.0f, 1.0f, runs[i].roughness};
        uint32_t id = lobe_id(fx->rt, runs[i].name);
        const glint_closure *c = runs[i].roughness > 0.0f
                                     ? single_lobe_closure(fx, id, block, 4, NULL)
                                     : single_lobe_closure(fx, id, NULL, 0, NULL);
        double p;
        print_message("%s roughness %g:\n", runs[i].name, (double)runs[i].roughness);
        p = chi_square(c, runs[i].cos_o, 1000u + i);
        if (!(p >= alpha))
            print_error("p = %.3g < %.3g: the samples do not follow the pdf\n", p, alpha);
        assert_true(p >= alpha);
    }
}

/* ---- loader errors ------------------------------------------------------------------------- */

typedef struct load_case {
    const char *path;
    glint_status status;
    const char *mention;        /* in glint_last_error() besides the file (a lobe), or NULL */
    const char *not_registered; /* a valid lobe of the plugin that must not be registered */
} load_case;

static const load_case LOAD_CASES[] = {
    {"/nonexistent/glint_no_such_plugin.so", GLINT_ERROR_PLUGIN_NOT_FOUND, NULL, NULL},
    {GLINT_NOT_A_LIBRARY_PATH, GLINT_ERROR_PLUGIN_NOT_LIBRARY, NULL, NULL},
    /* Files that exist but are no library: not "no such file". */
    {GLINT_PLUGIN_DIR, GLINT_ERROR_PLUGIN_NOT_LIBRARY, "is a directory", NULL},
    {"/dev/null", GLINT_ERROR_PLUGIN_NOT_LIBRARY, "not a loadable shared library", NULL},
    {GLINT_TEST_NO_ENTRY_PATH, GLINT_ERROR_PLUGIN_NO_ENTRY, NULL, NULL},
    {GLINT_TEST_REFUSE_PATH, GLINT_ERROR_PLUGIN_ABI_REFUSED, NULL, NULL},
    {GLINT_TEST_ABI99_PATH, GLINT_ERROR_PLUGIN_ABI_REFUSED, NULL, "glint_test_abi99"},
    {GLINT_TEST_BUILTIN_NAME_PATH, GLINT_ERROR_DUPLICATE_NAME, "lambert", NULL},
    {GLINT_TEST_SAME_NAME_TWICE_PATH, GLINT_ERROR_DUPLICATE_NAME, "glint_test_twice",
     "glint_test_twice"},
    {GLINT_TEST_BAD_RANGE_PATH, GLINT_ERROR_PLUGIN_PARAMS, "glint_test_inverted_range",
     "glint_test_range_ok"},
    {GLINT_TEST_NULL_EVAL_PATH, GLINT_ERROR_PLUGIN_PARAMS, "glint_test_no_eval",
     "glint_test_null_eval_ok"},
    {GLINT_TEST_BLOCK_SIZE_PATH, GLINT_ERROR_PLUGIN_BLOCK_SIZE, "glint_test_wrong_block",
     "glint_test_block_ok"},
};

static void loader_errors(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt), id;
    size_t i;
    int pass;
    glint_closure *c;
    glint_eval_result e = eval_result_init();

    check_error(fx, glint_runtime_load_plugin(NULL, GLINT_CHARLIE_PATH), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_runtime_load_plugin(fx->rt, NULL), GLINT_ERROR_NULL_POINTER);
    /* Twice: a plugin that failed fails the same way again (the loader keeps no state). */
    for (pass = 0; pass < 2; pass++)
        for (i = 0; i < sizeof LOAD_CASES / sizeof LOAD_CASES[0]; i++) {
            const load_case *lc = &LOAD_CASES[i];
            print_message("load case %u: %s\n", (unsigned)i, lc->path);
            check_error(fx, glint_runtime_load_plugin(fx->rt, lc->path), lc->status);
            assert_error_mentions(strrchr(lc->path, '/') + 1); /* the file */
            if (lc->mention != NULL)
                assert_error_mentions(lc->mention);
            assert_int_equal(lobe_type_count(fx->rt), n); /* nothing half registered */
            if (lc->not_registered != NULL)
                check_error(fx, glint_lobe_type_find(fx->rt, lc->not_registered, &id),
                            GLINT_ERROR_UNKNOWN_NAME);
        }

    /* The runtime still loads plugins; loading one twice declares its names twice. */
    load(fx, GLINT_CHARLIE_PATH);
    assert_int_equal(lobe_type_count(fx->rt), n + 1);
    check_error(fx, glint_runtime_load_plugin(fx->rt, GLINT_CHARLIE_PATH),
                GLINT_ERROR_DUPLICATE_NAME);
    assert_error_mentions("charlie");
    assert_int_equal(lobe_type_count(fx->rt), n + 1);

    /* And builds and evaluates new closures. */
    c = json_closure(fx, "{\"lobes\": [{\"type\": \"lambert\"}, {\"type\": \"charlie\"}]}", NULL);
    assert_ok(glint_eval(c, test_wo(), v3_normalize(v3(-0.5f, 0.2f, 0.3f)), &e));
    assert_true(e.value[0] > 0.0f && e.pdf > 0.0f);
}

/* ---- sanitizing ---------------------------------------------------------------------------- */

static uint64_t sanitized(const fixture *fx, uint32_t id)
{
    uint64_t count = UINT64_MAX;
    assert_ok(glint_lobe_sanitized_count(fx->rt, id, &count));
    return count;
}

/* Directions and outputs of up to 64 eval lanes. */
typedef struct eval_lanes {
    float wo_x[64], wo_y[64], wo_z[64], wi_x[64], wi_y[64], wi_z[64], r[64], g[64], b[64],
        pdf[64];
} eval_lanes;

/* glint_eval_batch_args for the first n lanes of l on closure c. */
static glint_eval_batch_args eval_args(const glint_closure *c, eval_lanes *l, size_t n)
{
    glint_eval_batch_args a;
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.count = n;
    a.closure = c;
    a.wo_x = l->wo_x, a.wo_y = l->wo_y, a.wo_z = l->wo_z;
    a.wi_x = l->wi_x, a.wi_y = l->wi_y, a.wi_z = l->wi_z;
    a.value_r = l->r, a.value_g = l->g, a.value_b = l->b, a.pdf = l->pdf;
    return a;
}

/* glint_test_nan's eval returns NaN values and pdf -1: every output reaching the caller
 * is zeroed, and counted; a well-behaved lobe (charlie, over hard inputs) counts none. */
static void nan_outputs_are_zeroed_and_counted(void **state)
{
    fixture *fx = *state;
    uint32_t nan_id, charlie, lambert, n;
    uint64_t before, after, out = 0;
    const glint_closure *c;
    const glint_vec3 wo = test_wo(), wi = v3_normalize(v3(-0.3f, 0.1f, 0.8f));
    glint_eval_result e = eval_result_init();
    glint_sample_result s = sample_result_init();
    glint_eval_batch_args a;
    eval_lanes l;
    float p = -1.0f, u0;
    glint_status st;
    lcg rng;
    int i, k;

    load(fx, GLINT_TEST_NAN_PATH);
    load(fx, GLINT_CHARLIE_PATH);
    nan_id = lobe_id(fx->rt, "glint_test_nan");
    charlie = lobe_id(fx->rt, "charlie");
    lambert = lobe_id(fx->rt, "lambert");
    assert_true(sanitized(fx, nan_id) == 0);
    assert_true(sanitized(fx, lambert) == 0);

    c = single_lobe_closure(fx, nan_id, NULL, 0, NULL);
    before = sanitized(fx, nan_id);
    assert_ok(glint_eval_lobe(c, 0, wo, wi, &e));
    for (k = 0; k < 3; k++)
        assert_true(e.value[k] == 0.0f);
    assert_true(e.pdf == 0.0f && e.pdf_reverse == 0.0f);
    after = sanitized(fx, nan_id);
    assert_true(after > before);
    assert_ok(glint_eval(c, wo, wi, &e));
    assert_true(e.value[0] == 0.0f && e.pdf == 0.0f);
    assert_ok(glint_pdf(c, wo, wi, &p));
    assert_true(p == 0.0f);
    st = glint_sample(c, wo, 0.5f, 0.5f, 0.5f, &s);
    assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
    for (k = 0; k < 3; k++) {
        assert_finite_nonneg(s.value[k]);
        assert_finite_nonneg(s.weight[k]);
    }
    assert_finite_nonneg(s.pdf);
    assert_true(sanitized(fx, nan_id) > after);

    /* Batches: every lane zeroed, at least one count per lane. */
    lcg_seed(&rng, 3);
    for (i = 0; i < 64; i++) {
        glint_vec3 o = lcg_direction(&rng, 1), d = lcg_direction(&rng, 1);
        l.wo_x[i] = o.x, l.wo_y[i] = o.y, l.wo_z[i] = o.z;
        l.wi_x[i] = d.x, l.wi_y[i] = d.y, l.wi_z[i] = d.z;
    }
    a = eval_args(c, &l, 64);
    before = sanitized(fx, nan_id);
    assert_ok(glint_eval_batch(&a));
    for (i = 0; i < 64; i++)
        assert_true(l.r[i] == 0.0f && l.g[i] == 0.0f && l.b[i] == 0.0f && l.pdf[i] == 0.0f);
    assert_true(sanitized(fx, nan_id) >= before + 64);

    /* Charlie over hard inputs: grazing, along the normal, below, equal and opposite. */
    c = single_lobe_closure(fx, charlie, NULL, 0, NULL);
    for (i = 0; i < 2000; i++) {
        glint_vec3 o = lcg_direction(&rng, 0), d = lcg_direction(&rng, 0);
        switch (i % 8) {
        case 0: o = v3(0.0f, 0.0f, 1.0f); break;
        case 1: o = v3_normalize(v3(1.0f, 0.0f, 1e-6f)); break;
        case 2: d = o; break;
        case 3: d = v3(-o.x, -o.y, o.z); break;
        case 4: d = v3(-o.x, -o.y, -o.z); break;
        case 5: o = v3(0.6f, 0.8f, 0.0f); break;
        default: break;
        }
        assert_ok(glint_eval(c, o, d, &e));
        for (k = 0; k < 3; k++)
            assert_finite_nonneg(e.value[k]);
        assert_finite_nonneg(e.pdf);
        assert_finite_nonneg(e.pdf_reverse);
        /* u0 next to 1: the microfacet lies flat. */
        u0 = i % 16 == 0 ? 0.99999994f : lcg_next(&rng);
        st = glint_sample(c, o, 0.5f, u0, lcg_next(&rng), &s);
        assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
    }
    assert_true(sanitized(fx, charlie) == 0);

    n = lobe_type_count(fx->rt);
    check_error(fx, glint_lobe_sanitized_count(NULL, nan_id, &out), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_sanitized_count(fx->rt, nan_id, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_sanitized_count(fx->rt, n, &out), GLINT_ERROR_OUT_OF_RANGE);
}

/* Every output of closure c finite and >= 0 at (wo, wi), and its samples' over a few u. */
static void assert_outputs_finite(const glint_closure *c, glint_vec3 wo, glint_vec3 wi)
{
    glint_eval_result e = eval_result_init();
    glint_sample_result s = sample_result_init();
    float albedo[3] = {-1.0f, -1.0f, -1.0f}, p = -1.0f;
    glint_status st;
    int i, k;

    assert_ok(glint_eval(c, wo, wi, &e));
    assert_ok(glint_pdf(c, wo, wi, &p));
    assert_ok(glint_albedo(c, wo, albedo));
    for (k = 0; k < 3; k++) {
        assert_finite_nonneg(e.value[k]);
        assert_finite_nonneg(albedo[k]);
    }
    assert_finite_nonneg(e.pdf);
    assert_finite_nonneg(e.pdf_reverse);
    assert_finite_nonneg(p);
    for (i = 0; i < 16; i++) {
        st = glint_sample(c, wo, (float)i / 16.0f, 0.3f + 0.04f * (float)i, 0.7f, &s);
        assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
        for (k = 0; k < 3; k++) {
            assert_finite_nonneg(s.value[k]);
            assert_finite_nonneg(s.weight[k]);
        }
        assert_finite_nonneg(s.pdf);
    }
}

/* glint_test_huge returns FLT_MAX values, pdfs and albedo, and samples of pdf 1e-30:
 * finite, but FLT_MAX x weight 2 and FLT_MAX / 1e-30 are infinite. No closure output
 * may be, alone or mixed with a built-in, scalar or batch; each bound output counts. */
static void extreme_outputs_stay_finite(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo(), wi = v3_normalize(v3(-0.3f, 0.1f, 0.8f));
    glint_closure *c;
    glint_sample_result s = sample_result_init();
    glint_eval_batch_args a;
    eval_lanes l;
    uint32_t huge;
    uint64_t before;
    int i;

    load(fx, GLINT_TEST_HUGE_PATH);
    huge = lobe_id(fx->rt, "glint_test_huge");
    c = json_closure(fx, "{\"lobes\": [{\"type\": \"glint_test_huge\", \"weight\": 2}]}", NULL);
    before = sanitized(fx, huge);
    assert_outputs_finite(c, wo, wi);
    /* A sample of pdf 1e-30 is no sample (its weight would be FLT_MAX / 1e-30). */
    check_error(fx, glint_sample_lobe(c, 0, wo, 0.5f, 0.5f, 0.5f, &s), GLINT_NO_SAMPLE);
    assert_true(sanitized(fx, huge) > before);

    c = json_closure(fx,
                     "{\"lobes\": [{\"type\": \"glint_test_huge\", \"weight\": 2},"
                     " {\"type\": \"lambert\", \"weight\": 3}]}",
                     NULL);
    assert_outputs_finite(c, wo, wi);

    for (i = 0; i < 8; i++) {
        l.wo_x[i] = wo.x, l.wo_y[i] = wo.y, l.wo_z[i] = wo.z;
        l.wi_x[i] = wi.x, l.wi_y[i] = wi.y, l.wi_z[i] = wi.z;
    }
    a = eval_args(c, &l, 8);
    assert_ok(glint_eval_batch(&a));
    for (i = 0; i < 8; i++) {
        assert_finite_nonneg(l.r[i]);
        assert_finite_nonneg(l.g[i]);
        assert_finite_nonneg(l.b[i]);
        assert_finite_nonneg(l.pdf[i]);
    }
}

/* glint_test_writes_params halves its `reflectance` in place on every call: the
 * finished closure must not change (each call sees reflectance 0.8), and the writes
 * are counted. */
static void plugins_cannot_change_their_parameters(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo(), wi = v3_normalize(v3(-0.3f, 0.1f, 0.8f));
    const float reflectance = 0.8f;
    glint_closure *c;
    glint_eval_result first = eval_result_init(), e = eval_result_init();
    glint_sample_result s0 = sample_result_init(), s = sample_result_init();
    float albedo[3];
    uint32_t id;
    uint64_t before;
    int i;

    load(fx, GLINT_TEST_WRITES_PARAMS_PATH);
    id = lobe_id(fx->rt, "glint_test_writes_params");
    c = single_lobe_closure(fx, id, &reflectance, 1, NULL);
    before = sanitized(fx, id);
    assert_ok(glint_eval(c, wo, wi, &first));
    assert_ok(glint_sample(c, wo, 0.5f, 0.3f, 0.6f, &s0));
    for (i = 0; i < 4; i++) {
        assert_ok(glint_eval(c, wo, wi, &e));
        assert_true(e.value[0] == first.value[0] && e.pdf == first.pdf);
        assert_ok(glint_sample(c, wo, 0.5f, 0.3f, 0.6f, &s));
        assert_true(s.value[0] == s0.value[0] && s.weight[0] == s0.weight[0]);
        assert_ok(glint_albedo(c, wo, albedo));
        assert_true(albedo[0] == reflectance);
    }
    /* Lambert: value = reflectance cos_i / pi. */
    assert_close(first.value[0], reflectance * wi.z / 3.14159265f, 1e-5f);
    assert_true(sanitized(fx, id) >= before + 13);
}

/* ---- the plugins= config key --------------------------------------------------------------- */

static void plugins_config_key(void **state)
{
    fixture *fx = *state;
    glint_runtime *rt = NULL;
    glint_arena *arena = NULL;
    uint32_t before;
    glint_closure *c = NULL;
    glint_eval_result e = eval_result_init();
    uint32_t id = UINT32_MAX;

    /* GLINT_PLUGIN_DIR (the build tree's plugin-dir/) holds glint_charlie.so only. */
    assert_ok(glint_runtime_create("threads=1 plugins=" GLINT_PLUGIN_DIR, &rt));
    assert_ok(glint_lobe_type_find(rt, "charlie", &id));
    assert_ok(glint_arena_create(2, &arena));
    assert_ok(glint_closure_from_json(rt, arena,
                                      "{\"lobes\": [{\"type\": \"charlie\", \"roughness\": 0.3}]}",
                                      NULL, &c));
    assert_ok(glint_eval(c, test_wo(), v3_normalize(v3(-0.6f, 0.1f, 0.2f)), &e));
    assert_true(e.value[0] > 0.0f && e.pdf > 0.0f);
    glint_arena_destroy(arena);
    glint_runtime_destroy(rt);

    rt = (glint_runtime *)fx; /* garbage: must be overwritten with NULL */
    check_error(fx, glint_runtime_create("plugins=/nonexistent", &rt),
                GLINT_ERROR_PLUGIN_NOT_FOUND);
    assert_error_mentions("/nonexistent");
    assert_null(rt);

    /* The plugins' build directory: glint_charlie.so and glint_minimal.so load, then
     * glint_test_abi99.so, first of the broken ones in file-name order, fails the whole
     * creation with its status. */
    rt = (glint_runtime *)fx;
    check_error(fx, glint_runtime_create("plugins=" GLINT_PLUGIN_BUILD_DIR, &rt),
                GLINT_ERROR_PLUGIN_ABI_REFUSED);
    assert_error_mentions("glint_test_abi99.so");
    assert_null(rt);

    /* None of this touched the fixture's runtime. */
    before = lobe_type_count(fx->rt);
    check_error(fx, glint_lobe_type_find(fx->rt, "charlie", &id), GLINT_ERROR_UNKNOWN_NAME);
    assert_int_equal(lobe_type_count(fx->rt), before);
}

int main(void)
{
#define T(f) cmocka_unit_test_setup_teardown(f, fixture_setup, fixture_teardown)
    const struct CMUnitTest tests[] = {
        T(charlie_is_listed),
        T(charlie_matches_reference),
        T(mixed_closures_from_c_and_json),
        T(json_errors_name_plugin_lobes),
        T(minimal_plugin_works),
        T(batches_match_scalar),
        T(charlie_chi_square),
        T(loader_errors),
        T(nan_outputs_are_zeroed_and_counted),
        T(extreme_outputs_stay_finite),
        T(plugins_cannot_change_their_parameters),
        T(plugins_config_key),
    };
#undef T
    return cmocka_run_group_tests(tests, NULL, NULL);
}
