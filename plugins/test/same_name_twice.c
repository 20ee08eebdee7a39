/* Declares two lobes of the same name: GLINT_ERROR_DUPLICATE_NAME, and neither registered. */
#include "test_plugin.h"

static const glint_plugin_lobe_v1 lobes[] = {TEST_LOBE("glint_test_twice"),
                                             TEST_LOBE("glint_test_twice")};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V1)
