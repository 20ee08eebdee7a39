#include "common.h"

#include <stdlib.h>

glint_vec3 v3(float x, float y, float z)
{
    glint_vec3 v;
    v.x = x;
    v.y = y;
    v.z = z;
    return v;
}

float v3_length(glint_vec3 v)
{
    return sqrtf(v.x * v.x + v.y * v.y + v.z * v.z);
}

glint_vec3 v3_normalize(glint_vec3 v)
{
    float len = v3_length(v);
    return v3(v.x / len, v.y / len, v.z / len);
}

glint_vec3 test_wo(void)
{
    return v3_normalize(v3(0.3f, 0.2f, 0.9f));
}

glint_frame frame_z(void)
{
    glint_frame f;
    f.normal = v3(0.0f, 0.0f, 1.0f);
    f.tangent = v3(0.0f, 0.0f, 0.0f);
    return f;
}

void lcg_seed(lcg *g, uint64_t seed)
{
    g->state = seed * 2862933555777941757ULL + 3037000493ULL;
}

float lcg_next(lcg *g)
{
    g->state = g->state * 6364136223846793005ULL + 1442695040888963407ULL;
    /* The top 24 bits: exactly representable, so the result is < 1. */
    return (float)(g->state >> 40) * (1.0f / 16777216.0f);
}

glint_vec3 lcg_direction(lcg *g, int upper)
{
    float z = upper ? lcg_next(g) * 0.98f + 0.01f : 1.0f - 2.0f * lcg_next(g);
    float phi = 6.2831853f * lcg_next(g);
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return v3(r * cosf(phi), r * sinf(phi), z);
}

glint_eval_result eval_result_init(void)
{
    glint_eval_result r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    return r;
}

glint_sample_result sample_result_init(void)
{
    glint_sample_result r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    return r;
}

glint_lobe_info lobe_info_init(void)
{
    glint_lobe_info r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    return r;
}

glint_param_info param_info_init(void)
{
    glint_param_info r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    return r;
}

int fixture_setup(void **state)
{
    fixture *fx = calloc(1, sizeof *fx);
    if (fx == NULL)
        return -1;
    if (glint_runtime_create(NULL, &fx->rt) != GLINT_OK ||
        glint_arena_create(256, &fx->arena) != GLINT_OK ||
        glint_closure_from_json(fx->rt, fx->arena,
                                "{\"lobes\": [{\"type\": \"lambert\", \"color\": 0.5}]}",
                                NULL, &fx->ok) != GLINT_OK) {
        fprintf(stderr, "fixture_setup: %s\n", glint_last_error());
        glint_arena_destroy(fx->arena);
        glint_runtime_destroy(fx->rt);
        free(fx);
        return -1;
    }
    *state = fx;
    return 0;
}

int fixture_teardown(void **state)
{
    fixture *fx = *state;
    glint_arena_destroy(fx->arena);
    glint_runtime_destroy(fx->rt);
    free(fx);
    return 0;
}

uint32_t lobe_type_count(const glint_runtime *rt)
{
    uint32_t n = 0;
    assert_ok(glint_lobe_type_count(rt, &n));
    return n;
}

glint_lobe_info lobe_type(const glint_runtime *rt, uint32_t id)
{
    glint_lobe_info info = lobe_info_init();
    assert_ok(glint_lobe_type_info(rt, id, &info));
    return info;
}

uint32_t lobe_id(const glint_runtime *rt, const char *name)
{
    uint32_t id = UINT32_MAX;
    assert_ok(glint_lobe_type_find(rt, name, &id));
    return id;
}

glint_param_info lobe_param(const glint_runtime *rt, uint32_t id, const char *name)
{
    uint32_t index = UINT32_MAX;
    glint_param_info info = param_info_init();
    assert_ok(glint_lobe_param_find(rt, id, name, &index));
    assert_ok(glint_lobe_param_info(rt, id, index, &info));
    return info;
}

glint_closure *single_lobe_closure(const fixture *fx, uint32_t id, const float *params,
                                   size_t param_count, const glint_vec3 *wo)
{
    static const float white[3] = {1.0f, 1.0f, 1.0f};
    glint_closure *c = NULL;
    glint_frame frame = frame_z();
    uint32_t index = UINT32_MAX;
    assert_ok(glint_closure_begin(fx->rt, fx->arena, wo, 0, &c));
    assert_non_null(c);
    assert_ok(glint_closure_add_lobe(c, id, white, &frame, params, param_count, &index));
    assert_int_equal(index, 0);
    assert_ok(glint_closure_finish(c));
    return c;
}

glint_closure *json_closure(const fixture *fx, const char *json, const glint_vec3 *wo)
{
    glint_closure *c = NULL;
    assert_ok(glint_closure_from_json(fx->rt, fx->arena, json, wo, &c));
    assert_non_null(c);
    return c;
}

void fill_floats(float *a, size_t n, float v)
{
    size_t i;
    for (i = 0; i < n; i++)
        a[i] = v;
}

float close_tol(float a, float b, float rel)
{
    return rel * fmaxf(fabsf(a), fabsf(b)) + 1e-7f;
}

glint_closure *all_types_closure(const fixture *fx, const glint_vec3 *wo)
{
    char json[2048];
    size_t len;
    uint32_t n = lobe_type_count(fx->rt), id;
    len = (size_t)snprintf(json, sizeof json, "{\"transport\": \"radiance\", \"lobes\": [");
    for (id = 0; id < n; id++) {
        glint_lobe_info t = lobe_type(fx->rt, id);
        len += (size_t)snprintf(json + len, sizeof json - len,
                                "%s{\"type\": \"%s\", \"weight\": [%g, 0.5, 0.25], "
                                "\"normal\": [0, 0, 1]}",
                                id ? ", " : "", t.name, 1.0 / n);
        assert_true(len < sizeof json);
    }
    len += (size_t)snprintf(json + len, sizeof json - len, "]}");
    assert_true(len < sizeof json);
    return json_closure(fx, json, wo);
}
