/* Glint quickstart: build a closure from JSON, then evaluate, sample and integrate it.
 *
 * Build (after `cargo build --release`):
 *   cmake -S . -B build && cmake --build build && ./build/examples/quickstart
 */
#include <stdio.h>
#include <stdlib.h>

#include "glint.h"

/* Every fallible glint call returns a status; on failure, glint_last_error() says why. */
#define CHECK(call)                                                                          \
    do {                                                                                     \
        glint_status status_ = (call);                                                       \
        if (status_ != GLINT_OK) {                                                           \
            fprintf(stderr, "%s failed: %s (%s)\n", #call, glint_last_error(),              \
                    glint_status_string(status_));                                           \
            exit(EXIT_FAILURE);                                                              \
        }                                                                                    \
    } while (0)

/* A plastic-like material: a diffuse base under a rough gold-ish metal coat. */
static const char *const MATERIAL =
    "{ \"lobes\": ["
    "    { \"type\": \"lambert\", \"weight\": 0.6, \"color\": [0.8, 0.2, 0.1] },"
    "    { \"type\": \"conductor\", \"weight\": 0.4, \"roughness\": 0.3,"
    "      \"fresnel\": \"artistic\", \"reflectivity\": [0.9, 0.6, 0.3],"
    "      \"edge_tint\": [1.0, 0.9, 0.7] }"
    "] }";

int main(void)
{
    glint_runtime *runtime = NULL;
    glint_arena *arena = NULL;
    glint_closure *closure = NULL;

    /* Directions are world space, point away from the surface and need not be unit
     * length. The JSON lobes use the default normal, +z. */
    const glint_vec3 wo = {0.3f, 0.2f, 0.9f}; /* toward the viewer */
    const glint_vec3 wi = {-0.4f, 0.1f, 0.8f}; /* toward the light */

    printf("glint %d.%d.%d\n", GLINT_VERSION_MAJOR, GLINT_VERSION_MINOR, GLINT_VERSION_PATCH);

    /* 1. One runtime per process (NULL: default configuration). */
    CHECK(glint_runtime_create(NULL, &runtime));

    /* 2. An arena holds the closures of, say, one shading point or one bundle of rays. */
    CHECK(glint_arena_create(16, &arena));

    /* 3. A closure: weighted lobes, built and finished in one call from JSON. Passing
     *    wo lets glint choose lobe sampling probabilities for this view. */
    CHECK(glint_closure_from_json(runtime, arena, MATERIAL, &wo, &closure));

    /* 4. Evaluate: f(wo, wi) |cos theta_i| and the pdf of sampling wi. */
    {
        glint_eval_result e = {.struct_size = sizeof e};
        CHECK(glint_eval(closure, wo, wi, &e));
        printf("eval:   value = (%.4f, %.4f, %.4f), pdf = %.4f\n", e.value[0], e.value[1],
               e.value[2], e.pdf);
    }

    /* 5. Sample directions from three random numbers in [0, 1); weight = value / pdf
     *    is what a path tracer multiplies its throughput by. */
    {
        static const float u[4][3] = {
            {0.1f, 0.3f, 0.7f}, {0.5f, 0.5f, 0.5f}, {0.8f, 0.2f, 0.9f}, {0.95f, 0.6f, 0.1f}};
        int i;
        for (i = 0; i < 4; i++) {
            glint_sample_result s = {.struct_size = sizeof s};
            glint_status status = glint_sample(closure, wo, u[i][0], u[i][1], u[i][2], &s);
            if (status == GLINT_NO_SAMPLE) { /* not an error: nothing scatters this way */
                printf("sample %d: none\n", i);
                continue;
            }
            CHECK(status);
            printf("sample %d: wi = (%+.3f, %+.3f, %+.3f), pdf = %7.4f, weight = (%.3f, %.3f, "
                   "%.3f), lobe %u%s\n",
                   i, s.wi.x, s.wi.y, s.wi.z, s.pdf, s.weight[0], s.weight[1], s.weight[2],
                   s.lobe, (s.flags & GLINT_FLAG_SPECULAR) ? " (specular)" : "");
        }
    }

    /* 6. Albedo: the fraction of light reflected toward wo, per channel. */
    {
        float albedo[3];
        CHECK(glint_albedo(closure, wo, albedo));
        printf("albedo: (%.4f, %.4f, %.4f)\n", albedo[0], albedo[1], albedo[2]);
    }

    /* 7. Clean up: destroying the arena frees its closures. */
    glint_arena_destroy(arena);
    glint_runtime_destroy(runtime);
    return EXIT_SUCCESS;
}
