/* A valid version-2 lobe, then one whose flags name a side but no class: its samples
 * could report none, so the load fails (GLINT_ERROR_PLUGIN_PARAMS), the valid lobe not
 * registered either. */
#include "test_plugin.h"

static const glint_plugin_lobe_v2 lobes[] = {
    TEST_LOBE_V2("glint_test_v2_class_ok",
                 GLINT_PLUGIN_FLAG_REFLECTION | GLINT_PLUGIN_FLAG_DIFFUSE, test_sample_v2, 1),
    TEST_LOBE_V2("glint_test_v2_no_class", GLINT_PLUGIN_FLAG_REFLECTION, test_sample_v2, 1),
};
TEST_PLUGIN_V2_ENTRY(lobes)
