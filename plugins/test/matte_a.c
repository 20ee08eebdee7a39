/* One of two plugins that each declare a lobe named `matte` (c_tests/test_batch_hardening.c
 * loads each into its own runtime, where both get the same type id): this one is the test
 * plugins' Lambert lobe with a one-float block, reflectance 0.5 by default. */
#include "test_plugin.h"

static const glint_plugin_lobe_v1 lobes[] = {TEST_LOBE("matte")};
TEST_PLUGIN_ENTRY(lobes, GLINT_PLUGIN_ABI_V1)
