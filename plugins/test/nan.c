/* A valid declaration whose eval returns a NaN value and a negative pdf: loads, and
 * Glint zeroes those outputs and counts them (glint_lobe_sanitized_count). Sample and
 * albedo are the valid test lobe's. */
#include "test_plugin.h"

static void nan_eval(const void *params, const float wo[3], const float wi[3],
                     uint32_t transport, float value[3], float *pdf)
{
    (void)params, (void)wo, (void)wi, (void)transport;
    value[0] = value[1] = value[2] = NAN;
    *pdf = -1.0f;
}

static const glint_plugin_lobe_v1 lobes[] = {
    TEST_LOBE_WITH("glint_test_nan", test_params, sizeof(float), nan_eval)};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V1)
