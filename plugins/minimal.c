/* A complete Glint plugin with one lobe type, `matte`: Lambert's diffuse reflection
 * tinted by an rgb parameter `color`. (plugins/minimal.c, shown verbatim in
 * docs/writing-a-plugin.md; a test keeps the two identical.) */
#include "glint_plugin.h"

#include <math.h>
#include <stddef.h>

#define INV_PI 0.318309886f

/* The parameter block: one float per value, in the parameter table's order. */
typedef struct matte_params {
    float color[3];
} matte_params;

/* value = f cos_i = color cos_i / pi; pdf = cos_i / pi (what sample draws). */
static void matte_eval(const void *params, const float wo[3], const float wi[3],
                       uint32_t transport, float value[3], float *pdf)
{
    const matte_params *p = params;
    /* One-sided: nothing when either direction is below the surface. */
    float cos_i = (wo[2] > 0.0f && wi[2] > 0.0f) ? wi[2] : 0.0f;
    int k;
    (void)transport; /* no refraction: radiance and importance agree */
    for (k = 0; k < 3; k++)
        value[k] = p->color[k] * INV_PI * cos_i;
    *pdf = INV_PI * cos_i;
}

/* Cosine-weighted sampling: a uniform point on the unit disk, lifted to the hemisphere. */
static int32_t matte_sample(const void *params, const float wo[3], const float u[3],
                            uint32_t transport, glint_plugin_sample *out)
{
    float r = sqrtf(u[1]), phi = 6.28318531f * u[2];
    if (!(wo[2] > 0.0f))
        return 0; /* seen from below: nothing to scatter */
    out->wi[0] = r * cosf(phi);
    out->wi[1] = r * sinf(phi);
    out->wi[2] = sqrtf(fmaxf(0.0f, 1.0f - u[1]));
    /* Value and pdf from eval itself, so that the two always agree. */
    matte_eval(params, wo, out->wi, transport, out->value, &out->pdf);
    if (!(out->pdf > 0.0f))
        return 0; /* wi on the horizon */
    out->events = 0; /* a reflection, not a delta event */
    out->eta = 1.0f;
    out->roughness = 1.0f;
    return 1;
}

/* The integral of value over all wi: color itself. */
static void matte_albedo(const void *params, const float wo[3], uint32_t transport,
                         float albedo[3])
{
    const matte_params *p = params;
    int k;
    (void)transport;
    for (k = 0; k < 3; k++)
        albedo[k] = wo[2] > 0.0f ? p->color[k] : 0.0f;
}

static const glint_plugin_param matte_param_table[] = {
    {.name = "color",
     .type = GLINT_PLUGIN_PARAM_RGB,
     .offset = offsetof(matte_params, color),
     .default_value = {0.8f, 0.8f, 0.8f},
     .min = 0.0f,
     .max = 1.0f,
     .doc = "diffuse reflectance"},
};

static const glint_plugin_lobe_v1 matte_lobe = {
    .struct_size = sizeof(glint_plugin_lobe_v1),
    .name = "matte",
    .summary = "Lambertian diffuse reflection (the plugin guide's example)",
    .flags = GLINT_PLUGIN_FLAG_REFLECTION | GLINT_PLUGIN_FLAG_DIFFUSE,
    .reciprocal = 1,
    .params = matte_param_table,
    .param_count = sizeof matte_param_table / sizeof matte_param_table[0],
    .block_size = sizeof(matte_params),
    .block_align = 4,
    .eval = matte_eval,
    .sample = matte_sample,
    .albedo = matte_albedo,
    .eval_batch = NULL, /* optional: Glint loops over eval */
};

static const glint_plugin_v1 matte_plugin = {
    .struct_size = sizeof(glint_plugin_v1),
    .name = "matte",
    .lobe_count = 1,
    .lobes = &matte_lobe,
};

GLINT_PLUGIN_EXPORT int32_t glint_plugin_entry(uint32_t host_abi_version,
                                               uint32_t *plugin_abi_version,
                                               const void **table)
{
    if (host_abi_version < GLINT_PLUGIN_ABI_V1)
        return 1; /* refuse a host that predates this ABI */
    *plugin_abi_version = GLINT_PLUGIN_ABI_V1;
    *table = &matte_plugin;
    return 0;
}
