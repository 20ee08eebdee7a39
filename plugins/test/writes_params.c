/* A valid Lambert lobe that breaks the const of its parameter block: every callback
 * reads `reflectance`, then halves it in place. Glint hands each call a copy of the
 * closure's block, so a finished closure stays as it was built (and counts the writes,
 * glint_lobe_sanitized_count). */
#include "test_plugin.h"

/* Halve the block's one float through the const pointer the callback was given. */
static void scribble(const void *params)
{
    *(float *)(void *)(uintptr_t)params *= 0.5f;
}

static void writing_eval(const void *params, const float wo[3], const float wi[3],
                         uint32_t transport, float value[3], float *pdf)
{
    test_eval(params, wo, wi, transport, value, pdf);
    scribble(params);
}

static int32_t writing_sample(const void *params, const float wo[3], const float u[3],
                              uint32_t transport, glint_plugin_sample *out)
{
    int32_t produced = test_sample(params, wo, u, transport, out);
    scribble(params);
    return produced;
}

static void writing_albedo(const void *params, const float wo[3], uint32_t transport,
                           float albedo[3])
{
    test_albedo(params, wo, transport, albedo);
    scribble(params);
}

static const glint_plugin_lobe_v1 lobes[] = {
    TEST_LOBE_FULL("glint_test_writes_params", test_params, sizeof(float), writing_eval,
                   writing_sample, writing_albedo)};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V1)
