/* Materials: types and parameters, compiled materials from JSON and from blocks,
 * glint_material_closure with shading contexts and overrides, the material batch
 * calls (equal lane by lane to the closures glint_material_closure builds), and every
 * error path (unknown material, bad override index or type, NaN context, struct_size). */
#include "common.h"

#include <stdlib.h>

#define N 96
/* The documented batch-vs-scalar tolerances, as in test_batch.c. */
#define TOL 2.5e-4f
#define SAMPLE_TOL 2e-3f

static const char *PAINT = "{\"material\": \"disney\", \"base_color\": [0.8, 0.1, 0.1], "
                           "\"roughness\": 0.4, \"clearcoat\": 1, \"sheen\": 0.5, "
                           "\"metallic\": 0.2, \"anisotropic\": 0.3}";

static glint_shading_context context_init(void)
{
    glint_shading_context c;
    memset(&c, 0, sizeof c);
    c.struct_size = sizeof c;
    c.wo = test_wo();
    c.normal = v3(0.0f, 0.0f, 1.0f);
    return c;
}

static glint_material *paint(const fixture *fx)
{
    glint_material *m = NULL;
    assert_ok(glint_material_create(fx->rt, PAINT, &m));
    assert_non_null(m);
    return m;
}

static uint32_t disney_id(const fixture *fx)
{
    uint32_t id = 99;
    assert_ok(glint_material_type_find(fx->rt, "disney", &id));
    return id;
}

static uint32_t disney_param(const fixture *fx, const char *name)
{
    uint32_t index = 99;
    assert_ok(glint_material_param_find(fx->rt, disney_id(fx), name, &index));
    return index;
}

/* ---- types ------------------------------------------------------------------------- */

static void material_types_are_listed_with_their_schemas(void **state)
{
    fixture *fx = *state;
    uint32_t n = 0, id = disney_id(fx), index = 0, p;
    glint_material_info info;
    glint_param_info param = param_info_init();
    assert_ok(glint_material_type_count(fx->rt, &n));
    assert_true(n >= 1);
    memset(&info, 0, sizeof info);
    info.struct_size = sizeof info;
    assert_ok(glint_material_type_info(fx->rt, id, &info));
    assert_string_equal(info.name, "disney");
    assert_true(strlen(info.summary) > 0);
    assert_int_equal(info.param_count, 11);
    assert_int_equal(info.param_block_size, 13);
    assert_int_equal(info.lobe_count, 4);
    for (p = 0; p < info.param_count; p++) {
        assert_ok(glint_material_param_info(fx->rt, id, p, &param));
        assert_ok(glint_material_param_find(fx->rt, id, param.name, &index));
        assert_int_equal(index, p);
        assert_true(param.min == 0.0f && param.max == 1.0f);
    }
    assert_ok(glint_material_param_info(fx->rt, id, 0, &param));
    assert_string_equal(param.name, "base_color");
    assert_int_equal(param.param_type, GLINT_PARAM_RGB);

    check_error(fx, glint_material_type_find(fx->rt, "plastic", &index),
                GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("disney");
    check_error(fx, glint_material_type_info(fx->rt, n, &info), GLINT_ERROR_OUT_OF_RANGE);
    assert_null(info.name);
    check_error(fx, glint_material_param_info(fx->rt, id, 11, &param),
                GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_material_param_find(fx->rt, id, "colour", &index),
                GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("base_color");
    info.struct_size = 4;
    check_error(fx, glint_material_type_info(fx->rt, id, &info), GLINT_ERROR_STRUCT_SIZE);
    check_error(fx, glint_material_type_count(NULL, &n), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_material_type_count(fx->rt, NULL), GLINT_ERROR_NULL_POINTER);
}

/* ---- creation ------------------------------------------------------------------------ */

static void materials_are_created_from_json_and_from_blocks(void **state)
{
    fixture *fx = *state;
    glint_material *json = paint(fx), *block = NULL, *defaults = NULL;
    glint_shading_context c = context_init();
    glint_closure *a = NULL, *b = NULL;
    glint_eval_result ea = eval_result_init(), eb = eval_result_init();
    /* The same parameters as PAINT, in schema order. */
    const float params[13] = {0.8f, 0.1f, 0.1f, 0.0f, 0.2f, 0.5f, 0.0f,
                              0.4f, 0.3f, 0.5f, 0.5f, 1.0f, 1.0f};
    assert_ok(glint_material_create_from_params(fx->rt, disney_id(fx), params, 13, &block));
    assert_ok(glint_material_create_from_params(fx->rt, disney_id(fx), NULL, 0, &defaults));
    assert_ok(glint_material_closure(json, fx->arena, &c, NULL, 0, &a));
    assert_ok(glint_material_closure(block, fx->arena, &c, NULL, 0, &b));
    assert_ok(glint_eval(a, test_wo(), v3(-0.3f, 0.1f, 0.8f), &ea));
    assert_ok(glint_eval(b, test_wo(), v3(-0.3f, 0.1f, 0.8f), &eb));
    assert_true(ea.value[0] > 0.0f);
    assert_memory_equal(&ea, &eb, sizeof ea);
    glint_material_destroy(json);
    glint_material_destroy(block);
    glint_material_destroy(defaults);
    glint_material_destroy(NULL);
}

static void creation_errors(void **state)
{
    fixture *fx = *state;
    glint_material *m = (glint_material *)fx; /* garbage: must become NULL */
    const float params[13] = {0};
    float bad[13] = {0};
    check_error(fx, glint_material_create(fx->rt, "{\"material\": \"plastic\"}", &m),
                GLINT_ERROR_UNKNOWN_NAME);
    assert_null(m);
    assert_error_mentions("disney");
    check_error(fx, glint_material_create(fx->rt, "{\"material\": \"disney\", \"gloss\": 1}", &m),
                GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("clearcoat_gloss");
    check_error(fx, glint_material_create(fx->rt, "{\"base_color\": 1}", &m), GLINT_ERROR_PARSE);
    check_error(fx, glint_material_create(fx->rt, "{\"material\": \"disney\"", &m),
                GLINT_ERROR_PARSE);
    check_error(fx,
                glint_material_create(fx->rt, "{\"material\": \"disney\", \"roughness\": 2}", &m),
                GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_material_create(fx->rt, NULL, &m), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_material_create(NULL, PAINT, &m), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_material_create(fx->rt, PAINT, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_material_create_from_params(fx->rt, 7, params, 13, &m),
                GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_material_create_from_params(fx->rt, disney_id(fx), params, 12, &m),
                GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_material_create_from_params(fx->rt, disney_id(fx), NULL, 13, &m),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_material_create_from_params(fx->rt, disney_id(fx), params, SIZE_MAX, &m),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("param_count");
    bad[5] = NAN;
    check_error(fx, glint_material_create_from_params(fx->rt, disney_id(fx), bad, 13, &m),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_null(m);
}

static void destroyed_materials_are_invalid_handles(void **state)
{
    fixture *fx = *state;
    glint_material *m = paint(fx);
    glint_shading_context c = context_init();
    glint_closure *closure = NULL, *out = (glint_closure *)fx;
    glint_eval_result e = eval_result_init();
    assert_ok(glint_material_closure(m, fx->arena, &c, NULL, 0, &closure));
    glint_material_destroy(m);
    check_error(fx, glint_material_closure(m, fx->arena, &c, NULL, 0, &out),
                GLINT_ERROR_INVALID_HANDLE);
    assert_null(out);
    assert_error_mentions("destroyed");
    glint_material_destroy(m); /* ignored */
    /* Closures built from it stay valid. */
    assert_ok(glint_eval(closure, test_wo(), v3(0.1f, 0.2f, 0.9f), &e));
    check_error(fx, glint_material_closure((glint_material *)fx->arena, fx->arena, &c, NULL, 0, &out),
                GLINT_ERROR_INVALID_HANDLE);
}

/* ---- closures ------------------------------------------------------------------------- */

static void overrides_set_textured_parameters(void **state)
{
    fixture *fx = *state;
    glint_material *m = paint(fx);
    glint_material *green = NULL;
    glint_shading_context c = context_init();
    glint_override o[2];
    glint_closure *a = NULL, *b = NULL;
    glint_eval_result ea = eval_result_init(), eb = eval_result_init();
    const char *green_json = "{\"material\": \"disney\", \"base_color\": [0.1, 0.8, 0.1], "
                             "\"roughness\": 0.9, \"clearcoat\": 1, \"sheen\": 0.5, "
                             "\"metallic\": 0.2, \"anisotropic\": 0.3}";
    memset(o, 0, sizeof o);
    o[0].param = disney_param(fx, "base_color");
    o[0].param_type = GLINT_PARAM_RGB;
    o[0].value[0] = 0.1f;
    o[0].value[1] = 0.8f;
    o[0].value[2] = 0.1f;
    o[1].param = disney_param(fx, "roughness");
    o[1].param_type = GLINT_PARAM_FLOAT;
    o[1].value[0] = 0.9f;
    assert_ok(glint_material_create(fx->rt, green_json, &green));
    assert_ok(glint_material_closure(m, fx->arena, &c, o, 2, &a));
    assert_ok(glint_material_closure(green, fx->arena, &c, NULL, 0, &b));
    assert_ok(glint_eval(a, test_wo(), v3(-0.3f, 0.1f, 0.8f), &ea));
    assert_ok(glint_eval(b, test_wo(), v3(-0.3f, 0.1f, 0.8f), &eb));
    assert_true(ea.value[1] > ea.value[0]);
    assert_memory_equal(&ea, &eb, sizeof ea);
    glint_material_destroy(m);
    glint_material_destroy(green);
}

static void closure_errors(void **state)
{
    fixture *fx = *state;
    glint_material *m = paint(fx);
    glint_shading_context c = context_init();
    glint_override o;
    glint_closure *out = (glint_closure *)fx;
    glint_arena *small = NULL;
    memset(&o, 0, sizeof o);
    o.param = 11; /* disney has 11 parameters */
    o.param_type = GLINT_PARAM_FLOAT;
    check_error(fx, glint_material_closure(m, fx->arena, &c, &o, 1, &out),
                GLINT_ERROR_OUT_OF_RANGE);
    assert_null(out);
    assert_error_mentions("overrides[0]");
    o.param = disney_param(fx, "metallic");
    o.param_type = GLINT_PARAM_RGB;
    check_error(fx, glint_material_closure(m, fx->arena, &c, &o, 1, &out),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("not an rgb");
    o.param_type = 7;
    check_error(fx, glint_material_closure(m, fx->arena, &c, &o, 1, &out),
                GLINT_ERROR_INVALID_ARGUMENT);
    o.param_type = GLINT_PARAM_FLOAT;
    o.value[0] = 1.5f;
    check_error(fx, glint_material_closure(m, fx->arena, &c, &o, 1, &out),
                GLINT_ERROR_OUT_OF_RANGE);
    o.value[0] = NAN;
    check_error(fx, glint_material_closure(m, fx->arena, &c, &o, 1, &out),
                GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_material_closure(m, fx->arena, &c, NULL, 1, &out),
                GLINT_ERROR_NULL_POINTER);

    c.position = v3(NAN, 0.0f, 0.0f);
    check_error(fx, glint_material_closure(m, fx->arena, &c, NULL, 0, &out),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("position");
    c = context_init();
    c.wo = v3(0.0f, 0.0f, 0.0f);
    check_error(fx, glint_material_closure(m, fx->arena, &c, NULL, 0, &out),
                GLINT_ERROR_INVALID_ARGUMENT);
    c = context_init();
    c.footprint = -1.0f;
    check_error(fx, glint_material_closure(m, fx->arena, &c, NULL, 0, &out),
                GLINT_ERROR_INVALID_ARGUMENT);
    c = context_init();
    c.struct_size = 8;
    check_error(fx, glint_material_closure(m, fx->arena, &c, NULL, 0, &out),
                GLINT_ERROR_STRUCT_SIZE);
    c = context_init();
    check_error(fx, glint_material_closure(m, fx->arena, NULL, NULL, 0, &out),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_material_closure(m, NULL, &c, NULL, 0, &out),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_material_closure(m, fx->arena, &c, NULL, 0, NULL),
                GLINT_ERROR_NULL_POINTER);

    /* A failing call uses no slot: a one-slot arena still takes a closure. */
    assert_ok(glint_arena_create(1, &small));
    o.value[0] = 2.0f;
    check_error(fx, glint_material_closure(m, small, &c, &o, 1, &out), GLINT_ERROR_OUT_OF_RANGE);
    assert_ok(glint_material_closure(m, small, &c, NULL, 0, &out));
    check_error(fx, glint_material_closure(m, small, &c, NULL, 0, &out), GLINT_ERROR_ARENA_FULL);
    glint_arena_destroy(small);
    glint_material_destroy(m);
}

static void json_closures_take_material_entries(void **state)
{
    fixture *fx = *state;
    glint_material *m = paint(fx);
    glint_shading_context c = context_init();
    glint_closure *from_material = NULL, *whole = NULL, *entry = NULL;
    glint_eval_result a = eval_result_init(), b = eval_result_init(), e = eval_result_init();
    glint_vec3 wo = v3_normalize(test_wo()), wi = v3(-0.3f, 0.1f, 0.8f);
    const char *in_lobes = "{\"lobes\": [{\"material\": \"disney\", \"base_color\": [0.8, 0.1, 0.1], "
                           "\"roughness\": 0.4, \"clearcoat\": 1, \"sheen\": 0.5, "
                           "\"metallic\": 0.2, \"anisotropic\": 0.3}, "
                           "{\"type\": \"lambert\", \"weight\": 0.1}]}";
    c.wo = wo;
    assert_ok(glint_material_closure(m, fx->arena, &c, NULL, 0, &from_material));
    assert_ok(glint_closure_from_json(fx->rt, fx->arena, PAINT, &wo, &whole));
    assert_ok(glint_closure_from_json(fx->rt, fx->arena, in_lobes, &wo, &entry));
    assert_ok(glint_eval(from_material, wo, wi, &a));
    assert_ok(glint_eval(whole, wo, wi, &b));
    assert_ok(glint_eval(entry, wo, wi, &e));
    assert_memory_equal(&a, &b, sizeof a);
    assert_true(e.value[1] > a.value[1]);
    check_error(fx,
                glint_closure_from_json(fx->rt, fx->arena,
                                        "{\"lobes\": [{\"material\": \"plastic\"}]}", &wo, &whole),
                GLINT_ERROR_UNKNOWN_NAME);
    /* A material entry's weight is checked as a lobe's: finite, >= 0 and at most
     * 1e16 (it scaled the material's lobes unchecked: -1 gave an empty closure,
     * 1e39 an infinite albedo). */
    {
        /* The last: an entry at the bound whose sheen lobe weighs 10 times it (a blue
         * base color's tint). */
        const char *bad[] = {"-1", "1e39", "1e17", "[0.5, -0.5, 0.5]",
                             "1e16, \"base_color\": [0, 0, 1], \"sheen\": 1, "
                             "\"sheen_tint\": 1"};
        const glint_status expected[] = {
            GLINT_ERROR_INVALID_ARGUMENT, GLINT_ERROR_INVALID_ARGUMENT, GLINT_ERROR_OUT_OF_RANGE,
            GLINT_ERROR_INVALID_ARGUMENT, GLINT_ERROR_OUT_OF_RANGE};
        size_t i;
        for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
            char json[192];
            glint_closure *out = (glint_closure *)fx;
            snprintf(json, sizeof json,
                     "{\"lobes\": [{\"material\": \"disney\", \"weight\": %s}]}", bad[i]);
            check_error(fx, glint_closure_from_json(fx->rt, fx->arena, json, &wo, &out),
                        expected[i]);
            assert_error_mentions("weight");
            assert_null(out);
        }
    }
    glint_material_destroy(m);
}

/* ---- batches --------------------------------------------------------------------------- */

typedef struct lanes_data {
    float wo[3][N], normal[3][N], wi[3][N], color[3][N], rough[N], u[3][N];
    uint8_t active[N];
    glint_override_lanes overrides[2];
} lanes_data;

static void lanes_init(const fixture *fx, lanes_data *d, glint_material_lanes *l,
                       const glint_material *m)
{
    lcg g;
    int i, k;
    lcg_seed(&g, 77);
    for (i = 0; i < N; i++) {
        glint_vec3 n = lcg_direction(&g, 1), wo = lcg_direction(&g, i % 9 != 8);
        glint_vec3 wi = lcg_direction(&g, 1);
        n = v3_normalize(v3(n.x * 0.3f, n.y * 0.3f, n.z + 0.5f));
        d->normal[0][i] = n.x, d->normal[1][i] = n.y, d->normal[2][i] = n.z;
        d->wo[0][i] = wo.x + n.x, d->wo[1][i] = wo.y + n.y, d->wo[2][i] = wo.z + n.z;
        d->wi[0][i] = wi.x, d->wi[1][i] = wi.y, d->wi[2][i] = wi.z;
        for (k = 0; k < 3; k++) {
            d->color[k][i] = lcg_next(&g);
            d->u[k][i] = lcg_next(&g);
        }
        d->rough[i] = lcg_next(&g);
        d->active[i] = (uint8_t)(i % 5 != 3);
    }
    memset(d->overrides, 0, sizeof d->overrides);
    d->overrides[0].param = disney_param(fx, "base_color");
    d->overrides[0].param_type = GLINT_PARAM_RGB;
    for (k = 0; k < 3; k++)
        d->overrides[0].value[k] = d->color[k];
    d->overrides[1].param = disney_param(fx, "roughness");
    d->overrides[1].param_type = GLINT_PARAM_FLOAT;
    d->overrides[1].value[0] = d->rough;
    memset(l, 0, sizeof *l);
    l->material = m;
    l->count = N;
    l->active = d->active;
    l->wo_x = d->wo[0], l->wo_y = d->wo[1], l->wo_z = d->wo[2];
    l->normal_x = d->normal[0], l->normal_y = d->normal[1], l->normal_z = d->normal[2];
    l->overrides = d->overrides;
    l->override_count = 2;
}

/* Lane i's closure, as glint_material_closure builds it. */
static glint_closure *lane_closure(glint_arena *arena, const lanes_data *d, const glint_material *m,
                                   int i)
{
    glint_shading_context c = context_init();
    glint_override o[2];
    glint_closure *closure = NULL;
    int k;
    c.wo = v3(d->wo[0][i], d->wo[1][i], d->wo[2][i]);
    c.normal = v3(d->normal[0][i], d->normal[1][i], d->normal[2][i]);
    memset(o, 0, sizeof o);
    o[0].param = d->overrides[0].param;
    o[0].param_type = GLINT_PARAM_RGB;
    for (k = 0; k < 3; k++)
        o[0].value[k] = d->color[k][i];
    o[1].param = d->overrides[1].param;
    o[1].param_type = GLINT_PARAM_FLOAT;
    o[1].value[0] = d->rough[i];
    assert_ok(glint_material_closure(m, arena, &c, o, 2, &closure));
    return closure;
}

static void batches_equal_the_lanes_closures(void **state)
{
    fixture *fx = *state;
    glint_material *m = paint(fx);
    lanes_data *d = calloc(1, sizeof *d);
    glint_material_lanes l;
    float value[3][N], pdf[N], pdf_only[N], albedo[3][N];
    float swi[3][N], spdf[N], sweight[3][N], svalue[3][N];
    uint32_t sflags[N], slobe[N];
    glint_material_eval_batch_args e;
    glint_material_pdf_batch_args p;
    glint_material_albedo_batch_args a;
    glint_material_sample_batch_args s;
    int i, k, sampled = 0;
    glint_arena *arena = NULL;
    assert_ok(glint_arena_create(1, &arena));
    assert_non_null(d);
    lanes_init(fx, d, &l, m);
    memset(&e, 0, sizeof e);
    e.struct_size = sizeof e;
    e.lanes = l;
    e.wi_x = d->wi[0], e.wi_y = d->wi[1], e.wi_z = d->wi[2];
    e.value_r = value[0], e.value_g = value[1], e.value_b = value[2];
    e.pdf = pdf;
    assert_ok(glint_material_eval_batch(&e));
    memset(&p, 0, sizeof p);
    p.struct_size = sizeof p;
    p.lanes = l;
    p.wi_x = d->wi[0], p.wi_y = d->wi[1], p.wi_z = d->wi[2];
    p.pdf = pdf_only;
    assert_ok(glint_material_pdf_batch(&p));
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.lanes = l;
    a.albedo_r = albedo[0], a.albedo_g = albedo[1], a.albedo_b = albedo[2];
    assert_ok(glint_material_albedo_batch(&a));
    memset(&s, 0, sizeof s);
    s.struct_size = sizeof s;
    s.lanes = l;
    s.u_lobe = d->u[0], s.u0 = d->u[1], s.u1 = d->u[2];
    s.wi_x = swi[0], s.wi_y = swi[1], s.wi_z = swi[2];
    s.pdf = spdf;
    s.weight_r = sweight[0], s.weight_g = sweight[1], s.weight_b = sweight[2];
    s.value_r = svalue[0], s.value_g = svalue[1], s.value_b = svalue[2];
    s.flags = sflags;
    s.lobe = slobe;
    assert_ok(glint_material_sample_batch(&s));

    for (i = 0; i < N; i++) {
        glint_closure *c;
        glint_eval_result r = eval_result_init();
        glint_sample_result sr = sample_result_init();
        glint_vec3 wo = v3(d->wo[0][i], d->wo[1][i], d->wo[2][i]);
        glint_vec3 wi = v3(d->wi[0][i], d->wi[1][i], d->wi[2][i]);
        float alb[3];
        glint_status st;
        if (!d->active[i])
            continue;
        assert_ok(glint_arena_reset(arena));
        c = lane_closure(arena, d, m, i);
        assert_ok(glint_eval(c, wo, wi, &r));
        assert_ok(glint_albedo(c, wo, alb));
        for (k = 0; k < 3; k++) {
            assert_batch_close(value[k][i], r.value[k], TOL);
            assert_batch_close(albedo[k][i], alb[k], TOL);
        }
        assert_batch_close(pdf[i], r.pdf, TOL);
        assert_batch_close(pdf_only[i], r.pdf, TOL);
        st = glint_sample(c, wo, d->u[0][i], d->u[1][i], d->u[2][i], &sr);
        if (st == GLINT_OK && spdf[i] > 0.0f) {
            assert_batch_close(swi[0][i], sr.wi.x, SAMPLE_TOL);
            assert_batch_close(swi[1][i], sr.wi.y, SAMPLE_TOL);
            assert_batch_close(swi[2][i], sr.wi.z, SAMPLE_TOL);
            assert_batch_close(spdf[i], sr.pdf, SAMPLE_TOL);
            for (k = 0; k < 3; k++)
                assert_batch_close(sweight[k][i], sr.weight[k], SAMPLE_TOL);
            assert_int_equal(sflags[i], sr.flags);
            sampled++;
        } else {
            assert_true(spdf[i] == 0.0f || st != GLINT_OK);
        }
    }
    assert_true(sampled > N / 2);
    glint_arena_destroy(arena);
    free(d);
    glint_material_destroy(m);
}

static void batch_errors(void **state)
{
    fixture *fx = *state;
    glint_material *m = paint(fx);
    lanes_data *d = calloc(1, sizeof *d);
    glint_material_lanes l;
    float value[3][N], pdf[N];
    glint_material_eval_batch_args e;
    assert_non_null(d);
    lanes_init(fx, d, &l, m);
    memset(&e, 0, sizeof e);
    e.struct_size = sizeof e;
    e.lanes = l;
    e.wi_x = d->wi[0], e.wi_y = d->wi[1], e.wi_z = d->wi[2];
    e.value_r = value[0], e.value_g = value[1], e.value_b = value[2];
    e.pdf = pdf;

    /* A lane whose override is out of range is zeroed and reported; others computed. */
    d->rough[10] = 1.5f;
    fill_floats(pdf, N, -1.0f);
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_OUT_OF_RANGE);
    assert_error_mentions("lane 10");
    assert_true(pdf[10] == 0.0f && value[0][10] == 0.0f);
    assert_true(pdf[11] >= 0.0f && pdf[3] == -1.0f /* inactive: untouched */);
    d->rough[10] = 0.5f;
    d->wo[0][12] = NAN;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("lane 12");
    d->wo[0][12] = 0.1f;

    d->overrides[1].param = 11;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_OUT_OF_RANGE);
    d->overrides[1].param = disney_param(fx, "roughness");
    d->overrides[1].param_type = GLINT_PARAM_RGB;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_INVALID_ARGUMENT);
    d->overrides[1].param_type = GLINT_PARAM_FLOAT;
    d->overrides[1].value[0] = NULL;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_NULL_POINTER);
    d->overrides[1].value[0] = d->rough;
    e.lanes.normal_y = NULL;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_NULL_POINTER);
    e.lanes.normal_y = d->normal[1];
    e.lanes.material = NULL;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_NULL_POINTER);
    e.lanes.material = m;
    e.struct_size = 8;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_STRUCT_SIZE);
    e.struct_size = sizeof e;
    e.lanes.count = (size_t)GLINT_MAX_BATCH_COUNT + 1;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_OUT_OF_RANGE);
    e.lanes.count = N;
    assert_ok(glint_material_eval_batch(&e));
    check_error(fx, glint_material_eval_batch(NULL), GLINT_ERROR_NULL_POINTER);

    /* Non-finite random numbers fail their lane, as glint_sample and closure sample
     * batches refuse them (the material batch sampled with them). */
    {
        glint_material_sample_batch_args a;
        float out[7][N];
        const float bad[] = {NAN, INFINITY, -INFINITY};
        int k;
        memset(&a, 0, sizeof a);
        a.struct_size = sizeof a;
        a.lanes = l;
        a.u_lobe = d->u[0], a.u0 = d->u[1], a.u1 = d->u[2];
        a.wi_x = out[0], a.wi_y = out[1], a.wi_z = out[2], a.pdf = out[3];
        a.weight_r = out[4], a.weight_g = out[5], a.weight_b = out[6];
        for (k = 0; k < 3; k++) {
            float keep = d->u[k][20 + k];
            d->u[k][20 + k] = bad[k];
            fill_floats(out[3], N, -1.0f);
            check_error(fx, glint_material_sample_batch(&a), GLINT_ERROR_INVALID_ARGUMENT);
            assert_error_mentions("random number");
            assert_true(out[3][20 + k] == 0.0f && out[4][20 + k] == 0.0f);
            assert_true(out[3][24] >= 0.0f);
            d->u[k][20 + k] = keep;
        }
        assert_ok(glint_material_sample_batch(&a));
    }
    free(d);
    glint_material_destroy(m);
}

/* One eval call at three directions per lane with the albedo (a scanline host's lights
 * and ambient term): each direction's rows equal a one-direction call's, the albedo the
 * albedo call's, bit for bit; inactive lanes untouched. A caller passing the struct's
 * first size gets one direction; a bad direction count or a partial albedo is an error. */
static void several_directions_in_one_call(void **state)
{
    enum { K = 3 };
    fixture *fx = *state;
    glint_material *m = paint(fx);
    lanes_data *d = calloc(1, sizeof *d);
    float *wi = calloc(3 * K * N, sizeof *wi), *all = calloc(4 * K * N, sizeof *all);
    float one[4][N], albedo[3][N], albedo_alone[3][N];
    glint_material_lanes l;
    glint_material_eval_batch_args e, single;
    glint_material_albedo_batch_args a;
    int i, c, dir;
    assert_non_null(d);
    assert_non_null(wi);
    assert_non_null(all);
    lanes_init(fx, d, &l, m);
    for (dir = 0; dir < K; dir++)
        for (i = 0; i < N; i++)
            for (c = 0; c < 3; c++) /* rotated and mirrored copies of the lanes' wi */
                wi[(c * K + dir) * N + i] = (dir == 2 ? -1.0f : 1.0f) * d->wi[(c + dir) % 3][i];
    fill_floats(all, 4 * K * N, -1.0f);
    fill_floats(albedo[0], 3 * N, -1.0f);
    memset(&e, 0, sizeof e);
    e.struct_size = sizeof e;
    e.lanes = l;
    e.wi_x = wi, e.wi_y = wi + K * N, e.wi_z = wi + 2 * K * N;
    e.value_r = all, e.value_g = all + K * N, e.value_b = all + 2 * K * N;
    e.pdf = all + 3 * K * N;
    e.direction_count = K;
    e.albedo_r = albedo[0], e.albedo_g = albedo[1], e.albedo_b = albedo[2];
    assert_ok(glint_material_eval_batch(&e));
    for (dir = 0; dir < K; dir++) {
        memset(&single, 0, sizeof single);
        single.struct_size = sizeof single;
        single.lanes = l;
        single.wi_x = wi + dir * N, single.wi_y = wi + (K + dir) * N;
        single.wi_z = wi + (2 * K + dir) * N;
        single.value_r = one[0], single.value_g = one[1], single.value_b = one[2];
        single.pdf = one[3];
        fill_floats(one[0], 4 * N, -1.0f);
        assert_ok(glint_material_eval_batch(&single));
        for (c = 0; c < 4; c++)
            assert_memory_equal(all + (c * K + dir) * N, one[c], N * sizeof(float));
    }
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.lanes = l;
    a.albedo_r = albedo_alone[0], a.albedo_g = albedo_alone[1], a.albedo_b = albedo_alone[2];
    fill_floats(albedo_alone[0], 3 * N, -1.0f);
    assert_ok(glint_material_albedo_batch(&a));
    assert_memory_equal(albedo, albedo_alone, sizeof albedo);
    assert_true(all[3 * K * N + N + 3] == -1.0f && albedo[1][3] == -1.0f /* inactive */);

    /* The first version's size: direction_count and albedo are not read. */
    fill_floats(all, 4 * K * N, -1.0f);
    e.struct_size = (uint32_t)offsetof(glint_material_eval_batch_args, direction_count);
    assert_ok(glint_material_eval_batch(&e));
    assert_true(all[3 * K * N] >= 0.0f && all[3 * K * N + N] == -1.0f);
    e.struct_size = (uint32_t)offsetof(glint_material_eval_batch_args, albedo_g);
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_STRUCT_SIZE);
    e.struct_size = sizeof e;

    e.direction_count = SIZE_MAX;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_OUT_OF_RANGE);
    assert_error_mentions("directions");
    e.direction_count = K;
    e.albedo_g = NULL;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_NULL_POINTER);
    assert_error_mentions("albedo");
    e.albedo_g = albedo[1];
    /* A bad wi fails its lane in its direction only; the error names both. */
    wi[(0 * K + 1) * N + 4] = NAN;
    fill_floats(all, 4 * K * N, -1.0f);
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("direction 1, lane 4");
    assert_true(all[3 * K * N + N + 4] == 0.0f && all[3 * K * N + 4] >= 0.0f);
    assert_true(all[3 * K * N + 2 * N + 4] >= 0.0f);
    /* A lane's own input fails it in every direction: the error names no direction. */
    d->normal[1][2] = NAN;
    check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("lane 2: normal");
    assert_null(strstr(glint_last_error(), "direction"));
    free(wi);
    free(all);
    free(d);
    glint_material_destroy(m);
}

/* Counts far beyond the arrays are refused by every material batch before any lane is
 * read or written (the arrays hold N lanes). */
static void huge_material_batch_counts_are_refused(void **state)
{
    fixture *fx = *state;
    glint_material *m = paint(fx);
    lanes_data *d = calloc(1, sizeof *d);
    const size_t counts[] = {(size_t)1 << 40, (size_t)1 << 62, SIZE_MAX};
    float out[10][N];
    glint_material_lanes l;
    size_t k;
    int i;
    assert_non_null(d);
    lanes_init(fx, d, &l, m);
    for (i = 0; i < 10; i++)
        fill_floats(out[i], N, -7.0f);
    for (k = 0; k < sizeof counts / sizeof counts[0]; k++) {
        glint_material_eval_batch_args e;
        glint_material_pdf_batch_args p;
        glint_material_sample_batch_args s;
        glint_material_albedo_batch_args a;
        memset(&e, 0, sizeof e);
        memset(&p, 0, sizeof p);
        memset(&s, 0, sizeof s);
        memset(&a, 0, sizeof a);
        l.count = counts[k];
        e.struct_size = sizeof e, p.struct_size = sizeof p;
        s.struct_size = sizeof s, a.struct_size = sizeof a;
        e.lanes = p.lanes = s.lanes = a.lanes = l;
        e.wi_x = p.wi_x = d->wi[0], e.wi_y = p.wi_y = d->wi[1], e.wi_z = p.wi_z = d->wi[2];
        e.value_r = out[0], e.value_g = out[1], e.value_b = out[2], e.pdf = out[3];
        p.pdf = out[3];
        s.u_lobe = d->u[0], s.u0 = d->u[1], s.u1 = d->u[2];
        s.wi_x = out[4], s.wi_y = out[5], s.wi_z = out[6], s.pdf = out[3];
        s.weight_r = out[7], s.weight_g = out[8], s.weight_b = out[9];
        a.albedo_r = out[0], a.albedo_g = out[1], a.albedo_b = out[2];
        check_error(fx, glint_material_eval_batch(&e), GLINT_ERROR_OUT_OF_RANGE);
        check_error(fx, glint_material_pdf_batch(&p), GLINT_ERROR_OUT_OF_RANGE);
        check_error(fx, glint_material_sample_batch(&s), GLINT_ERROR_OUT_OF_RANGE);
        check_error(fx, glint_material_albedo_batch(&a), GLINT_ERROR_OUT_OF_RANGE);
        assert_error_mentions("count");
    }
    /* So are override counts beyond a material's 64 parameter values, before any
     * override past the two given is read. */
    l.count = N;
    for (k = 0; k < 3; k++) {
        glint_material_albedo_batch_args a;
        const size_t override_counts[] = {65, (size_t)1 << 40, SIZE_MAX};
        memset(&a, 0, sizeof a);
        a.struct_size = sizeof a;
        l.override_count = override_counts[k];
        a.lanes = l;
        a.albedo_r = out[0], a.albedo_g = out[1], a.albedo_b = out[2];
        check_error(fx, glint_material_albedo_batch(&a), GLINT_ERROR_OUT_OF_RANGE);
        assert_error_mentions("override_count");
    }
    for (i = 0; i < 10; i++) {
        int j;
        for (j = 0; j < N; j++)
            assert_true(out[i][j] == -7.0f);
    }
    free(d);
    glint_material_destroy(m);
}

/* A material may outlive its runtime (destroying a runtime does not destroy its
 * materials): its calls then fail as invalid handles, naming the runtime, and it can
 * still be destroyed. Closures built before stay valid until the runtime goes. */
static void materials_outliving_their_runtime_are_invalid(void **state)
{
    fixture *fx = *state;
    glint_runtime *rt = NULL;
    glint_arena *arena = NULL;
    glint_material *m = NULL;
    glint_closure *out = (glint_closure *)fx;
    glint_shading_context c = context_init();
    lanes_data *d = calloc(1, sizeof *d);
    glint_material_lanes l;
    glint_material_albedo_batch_args a;
    float albedo[3][N];
    assert_non_null(d);
    assert_ok(glint_runtime_create("threads=1", &rt));
    assert_ok(glint_arena_create(2, &arena));
    assert_ok(glint_material_create(rt, PAINT, &m));
    lanes_init(fx, d, &l, m);
    glint_runtime_destroy(rt);
    check_error(fx, glint_material_closure(m, arena, &c, NULL, 0, &out),
                GLINT_ERROR_INVALID_HANDLE);
    assert_error_mentions("runtime");
    assert_null(out);
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.lanes = l;
    a.albedo_r = albedo[0], a.albedo_g = albedo[1], a.albedo_b = albedo[2];
    check_error(fx, glint_material_albedo_batch(&a), GLINT_ERROR_INVALID_HANDLE);
    assert_error_mentions("runtime");
    glint_material_destroy(m);
    glint_arena_destroy(arena);
    free(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(material_types_are_listed_with_their_schemas,
                                        fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(materials_are_created_from_json_and_from_blocks,
                                        fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(creation_errors, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(destroyed_materials_are_invalid_handles, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(overrides_set_textured_parameters, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(closure_errors, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(json_closures_take_material_entries, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(batches_equal_the_lanes_closures, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(batch_errors, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(several_directions_in_one_call, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(huge_material_batch_counts_are_refused, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(materials_outliving_their_runtime_are_invalid,
                                        fixture_setup, fixture_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
