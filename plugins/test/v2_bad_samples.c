/* Valid version-2 declarations whose samples each break one rule of
 * glint_plugin_sample_v2: the class left 0, a class the flags do not declare, SPECULAR
 * without a delta event, a component past component_count. They load; Glint reports
 * the type's class and component 0 for those samples instead, and counts each repair
 * (glint_lobe_sanitized_count). */
#include "test_plugin.h"

/* The valid sample, then `class_` and `component_` written over its own. */
#define BAD_SAMPLE(fn_, class_, component_)                                                \
    static int32_t fn_(const void *params, const float wo[3], const float u[3],            \
                       uint32_t transport, glint_plugin_sample_v2 *out)                    \
    {                                                                                      \
        if (!test_sample_v2(params, wo, u, transport, out))                                \
            return 0;                                                                      \
        out->sample_class = (class_);                                                      \
        out->component = (component_);                                                     \
        return 1;                                                                          \
    }

BAD_SAMPLE(class_unset, 0u, 0u)
BAD_SAMPLE(class_undeclared, GLINT_PLUGIN_CLASS_GLOSSY, 0u)
BAD_SAMPLE(specular_not_delta, GLINT_PLUGIN_CLASS_SPECULAR, 0u)
BAD_SAMPLE(component_past_count, GLINT_PLUGIN_CLASS_DIFFUSE, 2u)

#define DIFFUSE (GLINT_PLUGIN_FLAG_REFLECTION | GLINT_PLUGIN_FLAG_DIFFUSE)

static const glint_plugin_lobe_v2 lobes[] = {
    TEST_LOBE_V2("glint_test_class_unset", DIFFUSE, class_unset, 1),
    TEST_LOBE_V2("glint_test_class_undeclared", DIFFUSE, class_undeclared, 1),
    TEST_LOBE_V2("glint_test_specular_not_delta", DIFFUSE | GLINT_PLUGIN_FLAG_SPECULAR,
                 specular_not_delta, 1),
    TEST_LOBE_V2("glint_test_component_past_count", DIFFUSE, component_past_count, 2),
};
TEST_PLUGIN_V2_ENTRY(lobes)
