/* Exports a misspelt entry point: GLINT_ERROR_PLUGIN_NO_ENTRY. */
#include "glint_plugin.h"

GLINT_PLUGIN_EXPORT int32_t glint_plugin_entry_point(void)
{
    return 0;
}
