/* The other `matte` (see matte_a.c): the same Lambert lobe (test_plugin.h), but with a
 * block of 13 floats, twelve unused ones before the reflectance (default 0.9), so that a
 * batch running one with the other's block layout reads the wrong value or past the end
 * of a block. */
#include "test_plugin.h"

#define PAD(n)                                                                             \
    {"pad" #n, GLINT_PLUGIN_PARAM_FLOAT, 4 * (n), {0.0f, 0.0f, 0.0f}, 0.0f, 1.0f, NULL, 0, NULL}

static const glint_plugin_param params[] = {
    PAD(0), PAD(1), PAD(2), PAD(3), PAD(4), PAD(5), PAD(6), PAD(7), PAD(8), PAD(9), PAD(10),
    PAD(11),
    {"reflectance", GLINT_PLUGIN_PARAM_FLOAT, 48, {0.9f, 0.0f, 0.0f}, 0.0f, 1.0f, NULL, 0, NULL},
};

typedef struct matte_b_params {
    float pad[12];
    float reflectance;
} matte_b_params;

static void eval(const void *p, const float wo[3], const float wi[3], uint32_t transport,
                 float value[3], float *pdf)
{
    test_eval(&((const matte_b_params *)p)->reflectance, wo, wi, transport, value, pdf);
}

static int32_t sample(const void *p, const float wo[3], const float u[3], uint32_t transport,
                      glint_plugin_sample *out)
{
    return test_sample(&((const matte_b_params *)p)->reflectance, wo, u, transport, out);
}

static void albedo(const void *p, const float wo[3], uint32_t transport, float out[3])
{
    test_albedo(&((const matte_b_params *)p)->reflectance, wo, transport, out);
}

static const glint_plugin_lobe_v1 lobes[] = {
    {sizeof(glint_plugin_lobe_v1), "matte", "a test lobe with a 13-float block",
     GLINT_PLUGIN_FLAG_REFLECTION | GLINT_PLUGIN_FLAG_DIFFUSE, 1, params,
     sizeof params / sizeof params[0], sizeof(matte_b_params), 4, eval, sample, albedo, NULL}};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V1)
