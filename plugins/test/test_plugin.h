/* A valid lobe type shared by the loader's test plugins, each of which breaks exactly one
 * rule of glint_plugin.h (c_tests/test_plugins.c checks the status and message of each).
 * The lobe is Lambert's: value = reflectance cos_i / pi, cosine-weighted sampling. */
#ifndef GLINT_TEST_PLUGIN_H
#define GLINT_TEST_PLUGIN_H

#include "glint_plugin.h"

#include <math.h>

/* One float parameter, `reflectance` in [0, 1]. */
static const glint_plugin_param test_params[] = {
    {"reflectance", GLINT_PLUGIN_PARAM_FLOAT, 0, {0.5f, 0.0f, 0.0f}, 0.0f, 1.0f, NULL, 0, NULL},
};

/* static inline: files that do not use one of these get no unused-function warning. */
static inline void test_eval(const void *params, const float wo[3], const float wi[3],
                             uint32_t transport, float value[3], float *pdf)
{
    float k = *(const float *)params, c = wi[2] > 0.0f && wo[2] > 0.0f ? wi[2] : 0.0f;
    (void)transport;
    value[0] = value[1] = value[2] = k * c * 0.318309886f;
    *pdf = c * 0.318309886f;
}

static inline int32_t test_sample(const void *params, const float wo[3], const float u[3],
                                  uint32_t transport, glint_plugin_sample *out)
{
    float r = sqrtf(u[1]), phi = 6.28318531f * u[2];
    if (!(wo[2] > 0.0f) || u[1] >= 1.0f)
        return 0;
    out->wi[0] = r * cosf(phi);
    out->wi[1] = r * sinf(phi);
    out->wi[2] = sqrtf(1.0f - u[1]);
    test_eval(params, wo, out->wi, transport, out->value, &out->pdf);
    out->events = 0;
    out->eta = 1.0f;
    out->roughness = 1.0f;
    return 1;
}

static inline void test_albedo(const void *params, const float wo[3], uint32_t transport,
                               float albedo[3])
{
    (void)transport;
    albedo[0] = albedo[1] = albedo[2] = wo[2] > 0.0f ? *(const float *)params : 0.0f;
}

/* A lobe declaration with the given name, parameter table, block size and callbacks. */
#define TEST_LOBE_FULL(name_, params_, block_size_, eval_, sample_, albedo_)               \
    {                                                                                      \
        sizeof(glint_plugin_lobe_v1), name_, "a test lobe",                                \
            GLINT_PLUGIN_FLAG_REFLECTION | GLINT_PLUGIN_FLAG_DIFFUSE, 1, params_,          \
            sizeof params_ / sizeof params_[0], block_size_, 4, eval_, sample_, albedo_,   \
            NULL                                                                           \
    }
/* The same with the valid lobe's sample and albedo. */
#define TEST_LOBE_WITH(name_, params_, block_size_, eval_)                                 \
    TEST_LOBE_FULL(name_, params_, block_size_, eval_, test_sample, test_albedo)
/* A valid lobe declaration named name_. */
#define TEST_LOBE(name_) TEST_LOBE_WITH(name_, test_params, sizeof(float), test_eval)

/* The plugin table and an entry point that hands it over as ABI version `version_`. */
#define TEST_PLUGIN_ENTRY(lobes_, version_)                                                \
    static const glint_plugin_v1 test_plugin = {                                           \
        sizeof(glint_plugin_v1), "glint_test", sizeof lobes_ / sizeof lobes_[0], lobes_};      \
    GLINT_PLUGIN_EXPORT int32_t glint_plugin_entry(uint32_t host_abi_version,              \
                                                   uint32_t *plugin_abi_version,           \
                                                   const void **table)                     \
    {                                                                                      \
        (void)host_abi_version;                                                            \
        *plugin_abi_version = (version_);                                                  \
        *table = &test_plugin;                                                             \
        return 0;                                                                          \
    }

/* ---- ABI version 2 ---------------------------------------------------------------------- */

/* The test lobe's sample as a version-2 sample of class DIFFUSE, component 0. */
static inline int32_t test_sample_v2(const void *params, const float wo[3], const float u[3],
                                     uint32_t transport, glint_plugin_sample_v2 *out)
{
    glint_plugin_sample v1;
    if (!test_sample(params, wo, u, transport, &v1))
        return 0;
    out->wi[0] = v1.wi[0], out->wi[1] = v1.wi[1], out->wi[2] = v1.wi[2];
    out->value[0] = v1.value[0], out->value[1] = v1.value[1], out->value[2] = v1.value[2];
    out->pdf = v1.pdf;
    out->events = v1.events;
    out->eta = v1.eta;
    out->roughness = v1.roughness;
    out->sample_class = GLINT_PLUGIN_CLASS_DIFFUSE;
    out->component = 0;
    return 1;
}

/* A version-2 test lobe with the given name, flags, sample callback and component count. */
#define TEST_LOBE_V2(name_, flags_, sample_, component_count_)                             \
    {                                                                                      \
        sizeof(glint_plugin_lobe_v2), name_, "a version-2 test lobe", flags_, 1,           \
            test_params, sizeof test_params / sizeof test_params[0], sizeof(float), 4,     \
            test_eval, sample_, test_albedo, NULL, component_count_                        \
    }

/* The version-2 table and an entry point that hands it over. */
#define TEST_PLUGIN_V2_ENTRY(lobes_)                                                       \
    static const glint_plugin_v2 test_plugin = {                                           \
        sizeof(glint_plugin_v2), "glint_test_v2", sizeof lobes_ / sizeof lobes_[0], lobes_};   \
    GLINT_PLUGIN_EXPORT int32_t glint_plugin_entry(uint32_t host_abi_version,              \
                                                   uint32_t *plugin_abi_version,           \
                                                   const void **table)                     \
    {                                                                                      \
        if (host_abi_version < GLINT_PLUGIN_ABI_V2)                                        \
            return 1;                                                                      \
        *plugin_abi_version = GLINT_PLUGIN_ABI_V2;                                         \
        *table = &test_plugin;                                                             \
        return 0;                                                                          \
    }

#endif /* GLINT_TEST_PLUGIN_H */
