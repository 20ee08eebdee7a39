/* include/glint.h compiles alone as strict C99 with -Wall -Wextra -Wpedantic -Werror
 * (being built is the test); running it checks that the declarations link. */
#include "glint.h"

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
