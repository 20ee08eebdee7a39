/* Answers ABI version 99, newer than any host: GLINT_ERROR_PLUGIN_ABI_REFUSED. */
#include "test_plugin.h"

static const glint_plugin_lobe_v1 lobes[] = {TEST_LOBE("glint_test_abi99")};
TEST_PLUGIN_ENTRY(lobes, 99u)
