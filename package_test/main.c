/* A program outside the Glint tree, built against an installed Glint (found by CMake's
 * find_package or by pkg-config): checks that the library matches the header, builds a
 * closure from JSON and evaluates it. Exits non-zero on any failure. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <glint.h>

static int failed(const char *what, glint_status status)
{
    fprintf(stderr, "package_test: %s failed: %s (%s)\n", what, glint_last_error(),
            glint_status_string(status));
    return EXIT_FAILURE;
}

int main(void)
{
    static const char *const material =
        "{ \"lobes\": [ { \"type\": \"lambert\", \"weight\": 1.0, \"color\": [0.8, 0.5, 0.2] } ] }";
    const uint32_t header_version =
        GLINT_VERSION_MAJOR * 10000u + GLINT_VERSION_MINOR * 100u + GLINT_VERSION_PATCH;
    const glint_vec3 wo = {0.3f, 0.2f, 0.9f};
    const glint_vec3 wi = {-0.4f, 0.1f, 0.8f};
    glint_runtime *runtime = NULL;
    glint_arena *arena = NULL;
    glint_closure *closure = NULL;
    glint_eval_result e = {0};
    glint_status status;
    int ok;

    if (glint_version() != header_version) {
        fprintf(stderr, "package_test: library version %u, header version %u\n",
                (unsigned)glint_version(), (unsigned)header_version);
        return EXIT_FAILURE;
    }
    if ((status = glint_runtime_create(NULL, &runtime)) != GLINT_OK) {
        return failed("glint_runtime_create", status);
    }
    if ((status = glint_arena_create(4, &arena)) != GLINT_OK) {
        return failed("glint_arena_create", status);
    }
    if ((status = glint_closure_from_json(runtime, arena, material, &wo, &closure)) != GLINT_OK) {
        return failed("glint_closure_from_json", status);
    }
    e.struct_size = sizeof e;
    if ((status = glint_eval(closure, wo, wi, &e)) != GLINT_OK) {
        return failed("glint_eval", status);
    }
    /* Lambert: value = color / pi * cos(theta_i), pdf = cos(theta_i) / pi (no libm here:
     * pkg-config users link -lglint only). */
    ok = isfinite(e.pdf) && e.pdf > 0.0f && e.value[0] > e.value[1] && e.value[1] > e.value[2] &&
         e.value[2] > 0.0f && e.value[0] / e.pdf > 0.7999f && e.value[0] / e.pdf < 0.8001f;
    printf("glint %u.%u.%u: value = (%.4f, %.4f, %.4f), pdf = %.4f\n", GLINT_VERSION_MAJOR,
           GLINT_VERSION_MINOR, GLINT_VERSION_PATCH, e.value[0], e.value[1], e.value[2], e.pdf);
    glint_arena_destroy(arena);
    glint_runtime_destroy(runtime);
    if (!ok) {
        fprintf(stderr, "package_test: unexpected lambert evaluation\n");
        return EXIT_FAILURE;
    }
    return EXIT_SUCCESS;
}
