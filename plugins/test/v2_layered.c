/* A version-2 lobe with two components of different classes, `glint_test_v2_layered`:
 *
 *   f(wo, wi) = kd / pi + ks (n + 1) / (2 pi) (cos_o cos_i)^(n - 1),   cos_o, cos_i > 0
 *
 * component 0, DIFFUSE: Lambert, kd = albedo (1 - glossy);
 * component 1, GLOSSY: a cosine-power lobe about the normal, ks = albedo glossy. Its
 * f cos_i integrates over wi to ks cos_o^(n - 1) (the (n + 1) / (2 pi) cos_i^n density
 * integrates to 1), so the directional albedo is exactly kd + ks cos_o^(n - 1) <= albedo,
 * and f is symmetric in wo, wi (reciprocal).
 *
 * Sampling picks component 1 when u[0] < glossy (cos_i = u1^(1 / (n + 1))), else 0
 * (cosine-weighted, cos_i = sqrt(1 - u1)), phi = 2 pi u2; the pdf is the mixture
 * (1 - glossy) cos_i / pi + glossy (n + 1) / (2 pi) cos_i^n, and the sample reports the
 * class and component it drew. c_tests/test_plugins_v2.c checks both through the C API;
 * glint-verify checks the lobe like any other. */
#include "glint_plugin.h"

#include <math.h>

#define PI_F 3.14159265358979f

typedef struct layered_params {
    float albedo, glossy, exponent;
} layered_params;

static void layered_eval(const void *params, const float wo[3], const float wi[3],
                         uint32_t transport, float value[3], float *pdf)
{
    const layered_params *p = params;
    float co = wo[2], ci = wi[2], n = p->exponent, kd, ks, lobe;
    (void)transport;
    value[0] = value[1] = value[2] = *pdf = 0.0f;
    if (!(co > 0.0f && ci > 0.0f))
        return;
    kd = p->albedo * (1.0f - p->glossy);
    ks = p->albedo * p->glossy;
    lobe = (n + 1.0f) / (2.0f * PI_F) * powf(ci, n);
    value[0] = value[1] = value[2] = kd * ci / PI_F + ks * powf(co, n - 1.0f) * lobe;
    *pdf = (1.0f - p->glossy) * ci / PI_F + p->glossy * lobe;
}

static int32_t layered_sample(const void *params, const float wo[3], const float u[3],
                              uint32_t transport, glint_plugin_sample_v2 *out)
{
    const layered_params *p = params;
    int glossy = u[0] < p->glossy;
    float ci = glossy ? powf(u[1], 1.0f / (p->exponent + 1.0f)) : sqrtf(1.0f - u[1]);
    float si = sqrtf(fmaxf(0.0f, 1.0f - ci * ci)), phi = 2.0f * PI_F * u[2];
    if (!(wo[2] > 0.0f && ci > 0.0f))
        return 0;
    out->wi[0] = si * cosf(phi);
    out->wi[1] = si * sinf(phi);
    out->wi[2] = ci;
    layered_eval(params, wo, out->wi, transport, out->value, &out->pdf);
    out->events = 0;
    out->eta = 1.0f;
    /* A Phong exponent's Beckmann-equivalent roughness sqrt(2 / (n + 2)). */
    out->roughness = glossy ? sqrtf(2.0f / (p->exponent + 2.0f)) : 1.0f;
    out->sample_class = glossy ? GLINT_PLUGIN_CLASS_GLOSSY : GLINT_PLUGIN_CLASS_DIFFUSE;
    out->component = glossy ? 1u : 0u;
    return 1;
}

static void layered_albedo(const void *params, const float wo[3], uint32_t transport,
                           float albedo[3])
{
    const layered_params *p = params;
    float co = wo[2];
    (void)transport;
    albedo[0] = albedo[1] = albedo[2] =
        co > 0.0f ? p->albedo * ((1.0f - p->glossy) + p->glossy * powf(co, p->exponent - 1.0f))
                  : 0.0f;
}

static const glint_plugin_param layered_param_table[] = {
    {"albedo", GLINT_PLUGIN_PARAM_FLOAT, 0, {0.8f, 0.0f, 0.0f}, 0.0f, 1.0f, NULL, 0,
     "total reflectance at normal incidence"},
    {"glossy", GLINT_PLUGIN_PARAM_FLOAT, 4, {0.5f, 0.0f, 0.0f}, 0.0f, 1.0f, NULL, 0,
     "share of the glossy component (and its sampling probability)"},
    {"exponent", GLINT_PLUGIN_PARAM_FLOAT, 8, {8.0f, 0.0f, 0.0f}, 1.0f, 64.0f, NULL, 0,
     "power n of the glossy component"},
};

static const glint_plugin_lobe_v2 layered_lobe = {
    .struct_size = sizeof(glint_plugin_lobe_v2),
    .name = "glint_test_v2_layered",
    .summary = "a diffuse and a glossy component, each sample reporting its own",
    .flags = GLINT_PLUGIN_FLAG_REFLECTION | GLINT_PLUGIN_FLAG_DIFFUSE | GLINT_PLUGIN_FLAG_GLOSSY,
    .reciprocal = 1,
    .params = layered_param_table,
    .param_count = sizeof layered_param_table / sizeof layered_param_table[0],
    .block_size = sizeof(layered_params),
    .block_align = 4,
    .eval = layered_eval,
    .sample = layered_sample,
    .albedo = layered_albedo,
    .component_count = 2,
};

static const glint_plugin_v2 layered_plugin = {
    .struct_size = sizeof(glint_plugin_v2),
    .name = "glint_test_v2_layered",
    .lobe_count = 1,
    .lobes = &layered_lobe,
};

GLINT_PLUGIN_EXPORT int32_t glint_plugin_entry(uint32_t host_abi_version,
                                               uint32_t *plugin_abi_version,
                                               const void **table)
{
    if (host_abi_version < GLINT_PLUGIN_ABI_V2 || plugin_abi_version == NULL || table == NULL)
        return 1;
    *plugin_abi_version = GLINT_PLUGIN_ABI_V2;
    *table = &layered_plugin;
    return 0;
}
