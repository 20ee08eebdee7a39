/* A version-2 lobe declaring component_count 0, so that no component its samples
 * could report is valid: the load fails (GLINT_ERROR_PLUGIN_PARAMS). */
#include "test_plugin.h"

static const glint_plugin_lobe_v2 lobes[] = {TEST_LOBE_V2(
    "glint_test_v2_no_components", GLINT_PLUGIN_FLAG_REFLECTION | GLINT_PLUGIN_FLAG_DIFFUSE,
    test_sample_v2, 0)};
TEST_PLUGIN_V2_ENTRY(lobes)
