/* Ten runtime lifetimes, each loading every plugin (the good ones, the broken ones, a
 * text file, a directory, /dev/null, a plugins= directory) and using the plugin lobes in
 * closures and batches. Run under valgrind by the plugin_cycles_valgrind ctest: Glint
 * must free everything it allocates for a plugin when the runtime goes (the libraries
 * themselves stay loaded: still reachable, never lost). Exits non-zero on a failed
 * check; CMake passes the paths (GLINT_*_PATH, GLINT_PLUGIN_DIR). */
#include "glint.h"

#include <stdio.h>
#include <string.h>

#define CHECK(cond)                                                                      \
    do {                                                                                 \
        if (!(cond)) {                                                                   \
            fprintf(stderr, "%s:%d: %s failed (last error: %s)\n", __FILE__, __LINE__,   \
                    #cond, glint_last_error());                                          \
            return 1;                                                                    \
        }                                                                                \
    } while (0)

static const char *const GOOD[] = {GLINT_CHARLIE_PATH, GLINT_MINIMAL_PATH, GLINT_TEST_NAN_PATH,
                                   GLINT_TEST_HUGE_PATH, GLINT_TEST_WRITES_PARAMS_PATH};
static const char *const BAD[] = {
    GLINT_TEST_NO_ENTRY_PATH,        GLINT_TEST_REFUSE_PATH,    GLINT_TEST_ABI99_PATH,
    GLINT_TEST_BUILTIN_NAME_PATH,    GLINT_TEST_BAD_RANGE_PATH, GLINT_TEST_NULL_EVAL_PATH,
    GLINT_TEST_SAME_NAME_TWICE_PATH, GLINT_TEST_BLOCK_SIZE_PATH, GLINT_NOT_A_LIBRARY_PATH,
    GLINT_PLUGIN_DIR,                "/dev/null",               "/nonexistent/plugin.so"};
#define COUNT(a) (sizeof a / sizeof a[0])

/* One runtime: load, build, evaluate, destroy. */
static int cycle(void)
{
    static const char *const JSON =
        "{\"lobes\": [{\"type\": \"charlie\", \"roughness\": 0.4}, {\"type\": \"lambert\"},"
        " {\"type\": \"glint_test_nan\"}, {\"type\": \"glint_test_huge\"},"
        " {\"type\": \"glint_test_writes_params\"}]}";
    const glint_vec3 wo = {0.3f, 0.2f, 0.93f}, wi = {-0.4f, 0.1f, 0.91f};
    float wo_x[8], wo_y[8], wo_z[8], wi_x[8], wi_y[8], wi_z[8], r[8], g[8], b[8], pdf[8];
    glint_runtime *rt = NULL, *from_dir = NULL;
    glint_arena *arena = NULL;
    glint_closure *c = NULL;
    glint_eval_result e;
    glint_sample_result s;
    glint_eval_batch_args a;
    size_t i;

    CHECK(glint_runtime_create("threads=1", &rt) == GLINT_OK);
    for (i = 0; i < COUNT(GOOD); i++)
        CHECK(glint_runtime_load_plugin(rt, GOOD[i]) == GLINT_OK);
    for (i = 0; i < COUNT(BAD); i++)
        CHECK(glint_runtime_load_plugin(rt, BAD[i]) != GLINT_OK);
    CHECK(glint_runtime_load_plugin(rt, GLINT_CHARLIE_PATH) == GLINT_ERROR_DUPLICATE_NAME);

    CHECK(glint_arena_create(4, &arena) == GLINT_OK);
    CHECK(glint_closure_from_json(rt, arena, JSON, NULL, &c) == GLINT_OK);
    memset(&e, 0, sizeof e);
    e.struct_size = sizeof e;
    CHECK(glint_eval(c, wo, wi, &e) == GLINT_OK);
    memset(&s, 0, sizeof s);
    s.struct_size = sizeof s;
    for (i = 0; i < 8; i++)
        (void)glint_sample(c, wo, (float)i / 8.0f, 0.5f, 0.25f, &s);
    for (i = 0; i < 8; i++) {
        wo_x[i] = wo.x, wo_y[i] = wo.y, wo_z[i] = wo.z;
        wi_x[i] = wi.x, wi_y[i] = wi.y, wi_z[i] = wi.z;
    }
    memset(&a, 0, sizeof a);
    a.struct_size = sizeof a;
    a.count = 8;
    a.closure = c;
    a.wo_x = wo_x, a.wo_y = wo_y, a.wo_z = wo_z, a.wi_x = wi_x, a.wi_y = wi_y, a.wi_z = wi_z;
    a.value_r = r, a.value_g = g, a.value_b = b, a.pdf = pdf;
    CHECK(glint_eval_batch(&a) == GLINT_OK);
    glint_arena_destroy(arena);
    glint_runtime_destroy(rt);

    CHECK(glint_runtime_create("threads=1 plugins=" GLINT_PLUGIN_DIR, &from_dir) == GLINT_OK);
    glint_runtime_destroy(from_dir);
    return 0;
}

int main(void)
{
    int i;
    for (i = 0; i < 10; i++)
        if (cycle() != 0)
            return 1;
    printf("10 runtime cycles with plugins: ok\n");
    return 0;
}
