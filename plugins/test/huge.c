/* A valid declaration whose outputs are finite but extreme: eval returns FLT_MAX values
 * and pdf, sample returns FLT_MAX values with a pdf of 1e-30, albedo FLT_MAX. Glint
 * bounds them (the rule glint_plugin.h states) so that no closure output becomes
 * infinite, and counts them (glint_lobe_sanitized_count). */
#include "test_plugin.h"

#include <float.h>

static void huge_eval(const void *params, const float wo[3], const float wi[3],
                      uint32_t transport, float value[3], float *pdf)
{
    (void)params, (void)wo, (void)wi, (void)transport;
    value[0] = value[1] = value[2] = FLT_MAX;
    *pdf = FLT_MAX;
}

static int32_t huge_sample(const void *params, const float wo[3], const float u[3],
                           uint32_t transport, glint_plugin_sample *out)
{
    if (!test_sample(params, wo, u, transport, out))
        return 0;
    out->value[0] = out->value[1] = out->value[2] = FLT_MAX;
    out->pdf = 1e-30f;
    return 1;
}

static void huge_albedo(const void *params, const float wo[3], uint32_t transport,
                        float albedo[3])
{
    (void)params, (void)wo, (void)transport;
    albedo[0] = albedo[1] = albedo[2] = FLT_MAX;
}

static const glint_plugin_lobe_v1 lobes[] = {TEST_LOBE_FULL(
    "glint_test_huge", test_params, sizeof(float), huge_eval, huge_sample, huge_albedo)};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V1)
