/* Declares a lobe named like a built-in: GLINT_ERROR_DUPLICATE_NAME. */
#include "test_plugin.h"

static const glint_plugin_lobe_v1 lobes[] = {TEST_LOBE("lambert")};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V1)
