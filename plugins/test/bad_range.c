/* A valid lobe, then one whose parameter has min > max: GLINT_ERROR_PLUGIN_PARAMS, and
 * the valid lobe not registered either. */
#include "test_plugin.h"

static const glint_plugin_param bad_params[] = {
    {"reflectance", GLINT_PLUGIN_PARAM_FLOAT, 0, {0.5f, 0.0f, 0.0f}, 1.0f, 0.0f, NULL, 0, NULL},
};

static const glint_plugin_lobe_v1 lobes[] = {
    TEST_LOBE("glint_test_range_ok"),
    TEST_LOBE_WITH("glint_test_inverted_range", bad_params, sizeof(float), test_eval)};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V1)
