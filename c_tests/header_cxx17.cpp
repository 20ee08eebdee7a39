// include/glint.h and include/glint_plugin.h compile as C++17 with -Wall -Wextra
// -Wpedantic -Werror (being built is the test); running it checks the extern "C" linkage.
#include "glint.h"
#include "glint_plugin.h"

#include <type_traits>

static_assert(std::is_standard_layout<glint_sample_result>::value, "C layout");
static_assert(std::is_trivially_copyable<glint_eval_batch_args>::value, "C layout");
static_assert(std::is_standard_layout<glint_plugin_lobe_v1>::value, "C layout");
static_assert(GLINT_PLUGIN_FLAG_GLOSSY == GLINT_FLAG_GLOSSY, "one set of flag values");

int main()
{
    glint_eval_result r{};
    r.struct_size = sizeof r;
    static_cast<void>(r);
    const bool ok = glint_version() == GLINT_VERSION_MAJOR * 10000 + GLINT_VERSION_MINOR * 100 +
                                           GLINT_VERSION_PATCH &&
                    glint_status_string(GLINT_OK) != nullptr &&
                    glint_last_error() != nullptr;
    return ok ? 0 : 1;
}
