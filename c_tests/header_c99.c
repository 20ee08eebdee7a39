/* include/glint.h and include/glint_plugin.h compile as strict C99 with -Wall -Wextra
 * -Wpedantic -Werror, together (being built is the test); running it checks that the
 * declarations link. */
#include "glint.h"
#include "glint_plugin.h"

/* The plugin ABI's flag values are glint.h's. */
typedef char flags_agree[(GLINT_PLUGIN_FLAG_SPECULAR == GLINT_FLAG_SPECULAR &&
                          GLINT_PLUGIN_FLAG_TRANSMISSION == GLINT_FLAG_TRANSMISSION)
                             ? 1
                             : -1];

int main(void)
{
    glint_eval_result r;
    r.struct_size = sizeof r;
    (void)r;
    return glint_version() == GLINT_VERSION_MAJOR * 10000 + GLINT_VERSION_MINOR * 100 +
                                  GLINT_VERSION_PATCH &&
                   glint_status_string(GLINT_OK) != NULL
               ? 0
               : 1;
}
