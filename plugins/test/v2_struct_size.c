/* Answers ABI version 2 with a version-1 lobe table: its struct_size is
 * sizeof(glint_plugin_lobe_v1), smaller than glint_plugin_lobe_v2's, so the load fails
 * with GLINT_ERROR_PLUGIN_PARAMS before any field past it is read. */
#include "test_plugin.h"

static const glint_plugin_lobe_v1 lobes[] = {TEST_LOBE("glint_test_v1_as_v2")};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V2)
