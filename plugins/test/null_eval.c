/* A valid lobe, then one without an eval callback: GLINT_ERROR_PLUGIN_PARAMS, and the
 * valid lobe not registered either. */
#include "test_plugin.h"

static const glint_plugin_lobe_v1 lobes[] = {
    TEST_LOBE("glint_test_null_eval_ok"),
    TEST_LOBE_WITH("glint_test_no_eval", test_params, sizeof(float), NULL)};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V1)
