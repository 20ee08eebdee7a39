/* Each sample's class (GLINT_FLAG_DIFFUSE / _GLOSSY / _SPECULAR) and component
 * (glint_sample_result.component, the batch `component` array) for the dielectric:
 * reflection 0, transmission 1, specular when smooth and glossy when rough; callers
 * built against the header before `component` existed (the older struct_size) and
 * NULL component arrays. */
#include "common.h"

#include <stdlib.h>

#define N 96
#define ETA 1.5

static const char *SMOOTH = "{\"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0, \"eta\": 1.5}]}";
static const char *ROUGH = "{\"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0.4, \"eta\": 1.5}]}";
static const char *MIXED = "{\"lobes\": [{\"type\": \"lambert\", \"weight\": 0.5},"
                           " {\"type\": \"dielectric\", \"roughness\": 0.4, \"eta\": 1.5}]}";

/* Dielectric reflectance from outside (Walter 2007 eq. 22), in double. */
static double fresnel(double c, double eta)
{
    double g2 = eta * eta - 1.0 + c * c, g, a, b;
    if (g2 < 0.0)
        return 1.0;
    g = sqrt(g2);
    a = (g - c) / (g + c);
    b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * a * a * (1.0 + b * b);
}

/* The flags and component a dielectric sample must have, from its geometry. */
static void expect_dielectric(glint_vec3 wo, const glint_sample_result *s, uint32_t cls)
{
    int reflected = (s->wi.z > 0.0f) == (wo.z > 0.0f);
    uint32_t side = reflected ? GLINT_FLAG_REFLECTION : GLINT_FLAG_TRANSMISSION;
    assert_int_equal(s->flags, side | cls);
    assert_int_equal(s->component, reflected ? 0u : 1u);
}

static void smooth_dielectric_reflection_0_transmission_1(void **state)
{
    const fixture *fx = *state;
    glint_vec3 wo = test_wo();
    glint_closure *c = json_closure(fx, SMOOTH, &wo);
    float f = (float)fresnel(wo.z, ETA);
    glint_sample_result s = sample_result_init();
    assert_ok(glint_sample(c, wo, 0.5f * f, 0.3f, 0.7f, &s));
    assert_int_equal(s.flags, GLINT_FLAG_REFLECTION | GLINT_FLAG_SPECULAR);
    assert_int_equal(s.component, 0);
    expect_dielectric(wo, &s, GLINT_FLAG_SPECULAR);
    s = sample_result_init();
    assert_ok(glint_sample(c, wo, 0.5f + 0.5f * f, 0.3f, 0.7f, &s));
    assert_int_equal(s.flags, GLINT_FLAG_TRANSMISSION | GLINT_FLAG_SPECULAR);
    assert_int_equal(s.component, 1);
    expect_dielectric(wo, &s, GLINT_FLAG_SPECULAR);
}

static void rough_dielectric_is_glossy_with_both_components(void **state)
{
    const fixture *fx = *state;
    glint_closure *c = json_closure(fx, ROUGH, NULL);
    int seen[2] = {0, 0}, i;
    lcg g;
    lcg_seed(&g, 14);
    for (i = 0; i < 400; i++) {
        glint_vec3 wo = lcg_direction(&g, 1);
        glint_sample_result s = sample_result_init();
        if (glint_sample(c, wo, lcg_next(&g), lcg_next(&g), lcg_next(&g), &s) != GLINT_OK)
            continue;
        expect_dielectric(wo, &s, GLINT_FLAG_GLOSSY);
        seen[s.component]++;
    }
    assert_true(seen[0] > 10 && seen[1] > 10);
}

/* A caller compiled before `component`: its struct ends at `component`'s offset. The
 * call fills what it has and writes nothing past it. */
static void old_struct_size_caller_is_served(void **state)
{
    const fixture *fx = *state;
    glint_vec3 wo = test_wo();
    glint_closure *c = json_closure(fx, SMOOTH, &wo);
    size_t old = offsetof(glint_sample_result, component);
    union {
        glint_sample_result r;
        unsigned char b[sizeof(glint_sample_result) + 16];
    } u;
    unsigned char *buffer = u.b;
    glint_sample_result *s = &u.r;
    glint_sample_result full = sample_result_init();
    float f = (float)fresnel(wo.z, ETA);
    size_t i;
    memset(buffer, 0xab, sizeof u.b);
    s->struct_size = (uint32_t)old;
    assert_ok(glint_sample(c, wo, 0.5f + 0.5f * f, 0.3f, 0.7f, s));
    assert_ok(glint_sample(c, wo, 0.5f + 0.5f * f, 0.3f, 0.7f, &full));
    assert_int_equal(s->struct_size, old);
    assert_int_equal(s->flags, GLINT_FLAG_TRANSMISSION | GLINT_FLAG_SPECULAR);
    assert_memory_equal(buffer + sizeof(uint32_t), (unsigned char *)&full + sizeof(uint32_t),
                        old - sizeof(uint32_t));
    for (i = old; i < sizeof u.b; i++)
        assert_int_equal(buffer[i], 0xab);
    /* glint_sample_lobe takes the same struct. */
    memset(buffer, 0xab, sizeof u.b);
    s->struct_size = (uint32_t)old;
    assert_ok(glint_sample_lobe(c, 0, wo, 0.5f * f, 0.3f, 0.7f, s));
    assert_int_equal(s->flags, GLINT_FLAG_REFLECTION | GLINT_FLAG_SPECULAR);
    for (i = old; i < sizeof u.b; i++)
        assert_int_equal(buffer[i], 0xab);
    /* Smaller than any version: an error, nothing written. */
    memset(buffer, 0xab, sizeof u.b);
    s->struct_size = (uint32_t)old - 4;
    assert_int_equal(glint_sample(c, wo, 0.5f, 0.3f, 0.7f, s), GLINT_ERROR_STRUCT_SIZE);
    for (i = sizeof(uint32_t); i < sizeof u.b; i++)
        assert_int_equal(buffer[i], 0xab);
    s->struct_size = 0;
    assert_int_equal(glint_sample(c, wo, 0.5f, 0.3f, 0.7f, s), GLINT_ERROR_STRUCT_SIZE);
    assert_int_equal(glint_sample(c, wo, 0.5f, 0.3f, 0.7f, NULL), GLINT_ERROR_NULL_POINTER);
}

typedef struct lanes {
    float wo_x[N], wo_y[N], wo_z[N], u_lobe[N], u0[N], u1[N];
    float wi_x[N], wi_y[N], wi_z[N], pdf[N], w_r[N], w_g[N], w_b[N];
    uint32_t flags[N], component[N];
} lanes;

static glint_sample_batch_args batch_args(lanes *l, const glint_closure *c)
{
    glint_sample_batch_args a;
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.count = N;
    a.closure = c;
    a.wo_x = l->wo_x, a.wo_y = l->wo_y, a.wo_z = l->wo_z;
    a.u_lobe = l->u_lobe, a.u0 = l->u0, a.u1 = l->u1;
    a.wi_x = l->wi_x, a.wi_y = l->wi_y, a.wi_z = l->wi_z;
    a.pdf = l->pdf;
    a.weight_r = l->w_r, a.weight_g = l->w_g, a.weight_b = l->w_b;
    a.flags = l->flags;
    a.component = l->component;
    return a;
}

static void fill_lanes(lanes *l)
{
    lcg g;
    int i;
    lcg_seed(&g, 7);
    for (i = 0; i < N; i++) {
        glint_vec3 wo = lcg_direction(&g, 1);
        l->wo_x[i] = wo.x, l->wo_y[i] = wo.y, l->wo_z[i] = wo.z;
        l->u_lobe[i] = lcg_next(&g), l->u0[i] = lcg_next(&g), l->u1[i] = lcg_next(&g);
        l->flags[i] = 0xdeadbeefu;
        l->component[i] = 0xdeadbeefu;
    }
}

static void batch_component_matches_scalar(void **state)
{
    const fixture *fx = *state;
    const char *docs[] = {SMOOTH, ROUGH, MIXED};
    size_t d;
    lanes *l = calloc(1, sizeof *l);
    assert_non_null(l);
    for (d = 0; d < 3; d++) {
        glint_closure *c = json_closure(fx, docs[d], NULL);
        glint_sample_batch_args a;
        int i;
        fill_lanes(l);
        a = batch_args(l, c);
        assert_ok(glint_sample_batch(&a));
        for (i = 0; i < N; i++) {
            glint_sample_result s = sample_result_init();
            glint_status st = glint_sample(c, v3(l->wo_x[i], l->wo_y[i], l->wo_z[i]),
                                           l->u_lobe[i], l->u0[i], l->u1[i], &s);
            assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
            assert_int_equal(l->flags[i], s.flags);
            assert_int_equal(l->component[i], s.component);
        }
    }
    free(l);
}

static void batch_null_component_and_old_args_size(void **state)
{
    const fixture *fx = *state;
    glint_closure *c = json_closure(fx, ROUGH, NULL);
    lanes *l = calloc(1, sizeof *l);
    glint_sample_batch_args a;
    int i;
    assert_non_null(l);
    /* NULL component: not written, everything else is. */
    fill_lanes(l);
    a = batch_args(l, c);
    a.component = NULL;
    assert_ok(glint_sample_batch(&a));
    for (i = 0; i < N; i++)
        assert_true(l->flags[i] != 0xdeadbeefu);
    /* A caller built before `component`: the field past its struct_size is not read,
     * even when the memory there holds a pointer. */
    fill_lanes(l);
    a = batch_args(l, c);
    a.struct_size = (uint32_t)offsetof(glint_sample_batch_args, component);
    assert_ok(glint_sample_batch(&a));
    for (i = 0; i < N; i++) {
        assert_true(l->flags[i] != 0xdeadbeefu);
        assert_int_equal(l->component[i], 0xdeadbeefu);
    }
    /* Smaller than any version. */
    a.struct_size = (uint32_t)offsetof(glint_sample_batch_args, component) - 8;
    assert_int_equal(glint_sample_batch(&a), GLINT_ERROR_STRUCT_SIZE);
    assert_int_equal(glint_sample_batch(NULL), GLINT_ERROR_NULL_POINTER);
    free(l);
}

int main(void)
{
#define T(f) cmocka_unit_test_setup_teardown(f, fixture_setup, fixture_teardown)
    const struct CMUnitTest tests[] = {
        T(smooth_dielectric_reflection_0_transmission_1),
        T(rough_dielectric_is_glossy_with_both_components),
        T(old_struct_size_caller_is_served),
        T(batch_component_matches_scalar),
        T(batch_null_component_and_old_args_size),
    };
#undef T
    return cmocka_run_group_tests(tests, NULL, NULL);
}
