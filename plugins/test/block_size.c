/* A valid lobe, then one whose block_size (8) is not 4 x its one float:
 * GLINT_ERROR_PLUGIN_BLOCK_SIZE, and the valid lobe not registered either. */
#include "test_plugin.h"

static const glint_plugin_lobe_v1 lobes[] = {
    TEST_LOBE("glint_test_block_ok"),
    TEST_LOBE_WITH("glint_test_wrong_block", test_params, 2 * sizeof(float), test_eval)};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V1)
