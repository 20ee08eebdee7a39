/* Refuses every host (returns nonzero): GLINT_ERROR_PLUGIN_ABI_REFUSED. */
#include "glint_plugin.h"

GLINT_PLUGIN_EXPORT int32_t glint_plugin_entry(uint32_t host_abi_version,
                                               uint32_t *plugin_abi_version, const void **table)
{
    (void)host_abi_version, (void)plugin_abi_version, (void)table;
    return 1;
}
