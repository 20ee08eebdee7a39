/* Helpers shared by the glint C tests: a fixture (runtime, arena and a known-good
 * closure), error checks, float comparisons and a small random number generator. */
#ifndef GLINT_TEST_COMMON_H
#define GLINT_TEST_COMMON_H

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "glint.h"

/* ---- vectors ---------------------------------------------------------------- */

glint_vec3 v3(float x, float y, float z);
glint_vec3 v3_normalize(glint_vec3 v);
float v3_length(glint_vec3 v);
/* The standard view direction of the tests: normalize(0.3, 0.2, 0.9). */
glint_vec3 test_wo(void);
/* Normal +z, automatic tangent. */
glint_frame frame_z(void);

/* ---- random numbers: a 64-bit LCG (Knuth's MMIX constants) --------------------- */

typedef struct lcg {
    uint64_t state;
} lcg;

void lcg_seed(lcg *g, uint64_t seed);
/* A float in [0, 1). */
float lcg_next(lcg *g);
/* A unit direction, uniform on the sphere (upper == 1: on the upper hemisphere). */
glint_vec3 lcg_direction(lcg *g, int upper);

/* ---- result structs with struct_size set --------------------------------------- */

glint_eval_result eval_result_init(void);
glint_sample_result sample_result_init(void);
glint_lobe_info lobe_info_init(void);
glint_param_info param_info_init(void);

/* ---- fixture -------------------------------------------------------------------- */

typedef struct fixture {
    glint_runtime *rt;
    glint_arena *arena;
    /* A finished single-lambert closure, used to check that the library still works. */
    glint_closure *ok;
} fixture;

/* cmocka setup / teardown: *state becomes a fixture *. */
int fixture_setup(void **state);
int fixture_teardown(void **state);

/* Number of registered lobe types (asserts success). */
uint32_t lobe_type_count(const glint_runtime *rt);
/* Info of lobe type id (asserts success). */
glint_lobe_info lobe_type(const glint_runtime *rt, uint32_t id);
/* Id of the lobe type `name` (asserts success). */
uint32_t lobe_id(const glint_runtime *rt, const char *name);
/* Info of the parameter `name` of lobe type id (asserts success). */
glint_param_info lobe_param(const glint_runtime *rt, uint32_t id, const char *name);

/* A finished closure of one lobe of type `id` (weight 1, frame_z), built with
 * glint_closure_begin (wo may be NULL) / add_lobe / finish; asserts success. */
glint_closure *single_lobe_closure(const fixture *fx, uint32_t id, const float *params,
                                   size_t param_count, const glint_vec3 *wo);
/* A finished closure from JSON; asserts success. */
glint_closure *json_closure(const fixture *fx, const char *json, const glint_vec3 *wo);

/* A finished closure with one lobe of every registered type (weights [1/n, 0.5, 0.25]),
 * from JSON; asserts success. */
glint_closure *all_types_closure(const fixture *fx, const glint_vec3 *wo);

/* ---- assertions ------------------------------------------------------------------- */

/* Absolute tolerance for a relative comparison of a and b. */
float close_tol(float a, float b, float rel);

/* a[0 .. n) = v. */
void fill_floats(float *a, size_t n, float v);

/* |a - b| <= rel * max(|a|, |b|) + 1e-7 (prints both values with %g on failure). */
#define assert_close(a, b, rel)                                                          \
    do {                                                                                 \
        float ca_ = (float)(a), cb_ = (float)(b);                                        \
        float ct_ = close_tol(ca_, cb_, (rel));                                          \
        if (!(fabsf(ca_ - cb_) <= ct_))                                                  \
            print_error("%s = %.9g, %s = %.9g (tolerance %g)\n", #a, (double)ca_, #b,    \
                        (double)cb_, (double)ct_);                                       \
        assert_true(fabsf(ca_ - cb_) <= ct_);                                            \
    } while (0)

#define assert_finite(x) assert_true(isfinite(x))

#define assert_finite_nonneg(x)                                                          \
    do {                                                                                 \
        float fx_ = (float)(x);                                                          \
        if (!(isfinite(fx_) && fx_ >= 0.0f))                                             \
            print_error("%s = %g\n", #x, (double)fx_);                                   \
        assert_true(isfinite(fx_));                                                      \
        assert_true(fx_ >= 0.0f);                                                        \
    } while (0)

/* A call succeeds (prints glint_last_error() otherwise). */
#define assert_ok(call)                                                                  \
    do {                                                                                 \
        glint_status ok_ = (call);                                                       \
        if (ok_ != GLINT_OK)                                                             \
            print_error("%s -> %u (%s): %s\n", #call, (unsigned)ok_,                     \
                        glint_status_string(ok_), glint_last_error());                   \
        assert_int_equal(ok_, GLINT_OK);                                                 \
    } while (0)

/* The library still works after an error: a valid runtime query and a valid eval
 * succeed, and (since they succeed) leave glint_last_error() unchanged. */
#define assert_still_works(fx)                                                           \
    do {                                                                                 \
        char saved_[1024];                                                               \
        uint32_t n_ = 0;                                                                 \
        glint_eval_result r_ = eval_result_init();                                       \
        snprintf(saved_, sizeof saved_, "%s", glint_last_error());                       \
        assert_ok(glint_lobe_type_count((fx)->rt, &n_));                                 \
        assert_true(n_ > 0);                                                             \
        assert_ok(glint_eval((fx)->ok, test_wo(), v3(-0.2f, 0.1f, 0.9f), &r_));          \
        assert_true(r_.value[0] > 0.0f);                                                 \
        assert_string_equal(glint_last_error(), saved_);                                 \
    } while (0)

/* `call` fails with `expected`: non-zero status, a non-empty glint_last_error(), a
 * non-NULL glint_status_string(), and the library keeps working. */
#define check_error(fx, call, expected)                                                  \
    do {                                                                                 \
        glint_status st_ = (call);                                                       \
        if (st_ != (glint_status)(expected))                                             \
            print_error("%s -> %u (%s), expected %u; last error: %s\n", #call,           \
                        (unsigned)st_, glint_status_string(st_), (unsigned)(expected),   \
                        glint_last_error());                                             \
        assert_int_equal(st_, (expected));                                               \
        assert_int_not_equal(st_, GLINT_OK);                                             \
        assert_non_null(glint_last_error());                                             \
        assert_true(strlen(glint_last_error()) > 0);                                     \
        assert_non_null(glint_status_string(st_));                                       \
        assert_true(strlen(glint_status_string(st_)) > 0);                               \
        assert_still_works(fx);                                                          \
    } while (0)

/* Batch against scalar: |a - b| <= tol * max(|a|, |b|, 1e-2). */
#define assert_batch_close(a, b, tol)                                                    \
    do {                                                                                 \
        float ba_ = (float)(a), bb_ = (float)(b);                                        \
        float bt_ = (tol) * fmaxf(fmaxf(fabsf(ba_), fabsf(bb_)), 1e-2f);                 \
        if (!(fabsf(ba_ - bb_) <= bt_))                                                  \
            print_error("%s = %.9g, %s = %.9g (tolerance %g)\n", #a, (double)ba_, #b,    \
                        (double)bb_, (double)bt_);                                       \
        assert_true(fabsf(ba_ - bb_) <= bt_);                                            \
    } while (0)

/* glint_last_error() contains `needle`. */
#define assert_error_mentions(needle)                                                    \
    do {                                                                                 \
        const char *msg_ = glint_last_error();                                           \
        if (strstr(msg_, (needle)) == NULL)                                              \
            print_error("glint_last_error() = \"%s\" does not mention \"%s\"\n", msg_,   \
                        (needle));                                                       \
        assert_non_null(strstr(msg_, (needle)));                                         \
    } while (0)

#endif /* GLINT_TEST_COMMON_H */
