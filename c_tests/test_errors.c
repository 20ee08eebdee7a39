/* Error paths of arenas, closure building, JSON and eval / sample / pdf / albedo.
 * Every failure must return its status, leave a message, and leave the library working
 * (check_error in common.h). */
#include "common.h"

#include <stdlib.h>

static const float WHITE[3] = {1.0f, 1.0f, 1.0f};

static glint_vec3 nan_vec(void)
{
    return v3(NAN, 0.0f, 1.0f);
}

static glint_vec3 inf_vec(void)
{
    return v3(0.0f, INFINITY, 1.0f);
}

static glint_vec3 zero_vec(void)
{
    return v3(0.0f, 0.0f, 0.0f);
}

/* ---- arenas ------------------------------------------------------------------------ */

static void arena_errors(void **state)
{
    fixture *fx = *state;
    glint_arena *arena = (glint_arena *)fx; /* garbage: must become NULL on failure */
    check_error(fx, glint_arena_create(0, &arena), GLINT_ERROR_INVALID_ARGUMENT);
    assert_null(arena);
    check_error(fx, glint_arena_create(SIZE_MAX, &arena), GLINT_ERROR_OUT_OF_RANGE);
    assert_null(arena);
    check_error(fx, glint_arena_create(4, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_arena_reset(NULL), GLINT_ERROR_NULL_POINTER);
}

static void arena_full(void **state)
{
    fixture *fx = *state;
    glint_arena *arena = NULL;
    glint_closure *a = NULL, *b = NULL, *c = (glint_closure *)fx;
    glint_eval_result e = eval_result_init();
    assert_ok(glint_arena_create(2, &arena));
    assert_ok(glint_closure_begin(fx->rt, arena, NULL, 0, &a));
    assert_ok(glint_closure_from_json(fx->rt, arena, "{\"lobes\": [{\"type\": \"lambert\"}]}",
                                      NULL, &b));

    check_error(fx, glint_closure_begin(fx->rt, arena, NULL, 0, &c), GLINT_ERROR_ARENA_FULL);
    assert_null(c);
    c = (glint_closure *)fx;
    check_error(fx,
                glint_closure_from_json(fx->rt, arena, "{\"lobes\": [{\"type\": \"lambert\"}]}",
                                        NULL, &c),
                GLINT_ERROR_ARENA_FULL);
    assert_null(c);

    /* The closures already in the arena are unaffected. */
    assert_ok(glint_closure_add_lobe(a, 0, WHITE, &(glint_frame){{0, 0, 1}, {0, 0, 0}}, NULL, 0,
                                     NULL));
    assert_ok(glint_closure_finish(a));
    assert_ok(glint_eval(a, test_wo(), test_wo(), &e));
    assert_ok(glint_eval(b, test_wo(), test_wo(), &e));

    /* After a reset there is room again. */
    assert_ok(glint_arena_reset(arena));
    assert_ok(glint_closure_begin(fx->rt, arena, NULL, 0, &c));
    assert_ok(glint_closure_begin(fx->rt, arena, NULL, 0, &c));
    check_error(fx, glint_closure_begin(fx->rt, arena, NULL, 0, &c), GLINT_ERROR_ARENA_FULL);
    glint_arena_destroy(arena);
}

/* ---- closure_begin / add_lobe / finish ------------------------------------------------ */

static void closure_begin_errors(void **state)
{
    fixture *fx = *state;
    glint_arena *arena = NULL;
    glint_closure *c = (glint_closure *)fx;
    glint_vec3 bad;
    assert_ok(glint_arena_create(1, &arena));

    check_error(fx, glint_closure_begin(NULL, arena, NULL, 0, &c), GLINT_ERROR_NULL_POINTER);
    assert_null(c);
    check_error(fx, glint_closure_begin(fx->rt, NULL, NULL, 0, &c), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_closure_begin(fx->rt, arena, NULL, 0, NULL), GLINT_ERROR_NULL_POINTER);
    bad = nan_vec();
    check_error(fx, glint_closure_begin(fx->rt, arena, &bad, 0, &c), GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("wo");
    bad = zero_vec();
    check_error(fx, glint_closure_begin(fx->rt, arena, &bad, 0, &c), GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("wo");
    bad = inf_vec();
    check_error(fx, glint_closure_begin(fx->rt, arena, &bad, 0, &c), GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_closure_begin(fx->rt, arena, NULL, 2, &c), GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_closure_begin(fx->rt, arena, NULL, GLINT_CLOSURE_IMPORTANCE | 4, &c),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_null(c);

    /* None of the failures used the arena's only slot. */
    assert_ok(glint_closure_begin(fx->rt, arena, NULL, GLINT_CLOSURE_IMPORTANCE, &c));
    assert_non_null(c);
    glint_arena_destroy(arena);
}

static void add_lobe_argument_errors(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt), count = 99, index = 12345;
    uint32_t lambert = lobe_id(fx->rt, "lambert");
    glint_lobe_info li = lobe_type(fx->rt, lambert);
    float *block = calloc(li.param_block_size + 1, sizeof *block);
    glint_closure *c = NULL;
    glint_frame f = frame_z();
    float w[3];
    assert_non_null(block);
    assert_ok(glint_lobe_param_defaults(fx->rt, lambert, block, li.param_block_size));
    assert_ok(glint_closure_begin(fx->rt, fx->arena, NULL, 0, &c));

    check_error(fx, glint_closure_add_lobe(NULL, lambert, WHITE, &f, NULL, 0, NULL),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_closure_add_lobe(c, lambert, NULL, &f, NULL, 0, NULL),
                GLINT_ERROR_NULL_POINTER);
    assert_error_mentions("weight");
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, NULL, NULL, 0, NULL),
                GLINT_ERROR_NULL_POINTER);
    assert_error_mentions("frame");
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, &f, NULL, li.param_block_size, NULL),
                GLINT_ERROR_NULL_POINTER);
    assert_error_mentions("params");
    /* A count longer than any block is refused as such (no slice of SIZE_MAX floats). */
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, &f, WHITE, SIZE_MAX, NULL),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("param_count");

    /* Bad frames. */
    f.normal = nan_vec();
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, &f, NULL, 0, &index),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("normal");
    f.normal = zero_vec();
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, &f, NULL, 0, &index),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("normal");
    f.normal = inf_vec();
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, &f, NULL, 0, &index),
                GLINT_ERROR_INVALID_ARGUMENT);
    f = frame_z();
    f.tangent = v3(NAN, 0.0f, 0.0f);
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, &f, NULL, 0, &index),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("tangent");
    f = frame_z();

    /* Unknown lobe type ids. */
    check_error(fx, glint_closure_add_lobe(c, n, WHITE, &f, NULL, 0, &index), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_closure_add_lobe(c, UINT32_MAX, WHITE, &f, NULL, 0, &index),
                GLINT_ERROR_OUT_OF_RANGE);

    /* Bad weights. */
    w[0] = 1.0f, w[1] = -0.5f, w[2] = 1.0f;
    check_error(fx, glint_closure_add_lobe(c, lambert, w, &f, NULL, 0, &index),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("weight");
    w[1] = NAN;
    check_error(fx, glint_closure_add_lobe(c, lambert, w, &f, NULL, 0, &index),
                GLINT_ERROR_INVALID_ARGUMENT);
    w[1] = INFINITY;
    check_error(fx, glint_closure_add_lobe(c, lambert, w, &f, NULL, 0, &index),
                GLINT_ERROR_INVALID_ARGUMENT);

    /* Parameter blocks of the wrong size. */
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, &f, block, li.param_block_size - 1, &index),
                GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, &f, block, li.param_block_size + 1, &index),
                GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, &f, block, 0, &index),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_int_equal(index, 0); /* zeroed on failure */

    /* No failed call added a lobe. */
    assert_ok(glint_closure_lobe_count(c, &count));
    assert_int_equal(count, 0);
    assert_ok(glint_closure_add_lobe(c, lambert, WHITE, &f, block, li.param_block_size, &index));
    assert_int_equal(index, 0);
    assert_ok(glint_closure_finish(c));
    free(block);
}

/* Every parameter of every lobe type: out of range, non-integral enum indices, NaN. */
static void add_lobe_parameter_errors(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt), id;
    glint_closure *c = NULL;
    glint_frame f = frame_z();
    int checked = 0;
    assert_ok(glint_closure_begin(fx->rt, fx->arena, NULL, 0, &c));
    for (id = 0; id < n; id++) {
        glint_lobe_info t = lobe_type(fx->rt, id);
        float *block = calloc(t.param_block_size, sizeof *block);
        uint32_t i, k;
        assert_non_null(block);
        assert_ok(glint_lobe_param_defaults(fx->rt, id, block, t.param_block_size));
        for (i = 0; i < t.param_count; i++) {
            glint_param_info p = param_info_init();
            float bad[6];
            glint_status expected[6];
            int nbad = 0, b;
            assert_ok(glint_lobe_param_info(fx->rt, id, i, &p));
            bad[nbad] = p.min - 1.0f, expected[nbad++] = GLINT_ERROR_OUT_OF_RANGE;
            bad[nbad] = p.max + 1.0f, expected[nbad++] = GLINT_ERROR_OUT_OF_RANGE;
            bad[nbad] = NAN, expected[nbad++] = GLINT_ERROR_INVALID_ARGUMENT;
            bad[nbad] = INFINITY, expected[nbad++] = GLINT_ERROR_INVALID_ARGUMENT;
            if (p.param_type == GLINT_PARAM_ENUM) {
                bad[nbad] = 0.5f, expected[nbad++] = GLINT_ERROR_OUT_OF_RANGE;
                bad[nbad] = (float)p.choice_count, expected[nbad++] = GLINT_ERROR_OUT_OF_RANGE;
            }
            for (k = 0; k < p.size; k++) {
                for (b = 0; b < nbad; b++) {
                    float saved = block[p.offset + k];
                    block[p.offset + k] = bad[b];
                    check_error(fx,
                                glint_closure_add_lobe(c, id, WHITE, &f, block, t.param_block_size,
                                                       NULL),
                                expected[b]);
                    assert_error_mentions(p.name);
                    block[p.offset + k] = saved;
                    checked++;
                }
            }
        }
        /* The restored block is valid. */
        assert_ok(glint_closure_add_lobe(c, id, WHITE, &f, block, t.param_block_size, NULL));
        free(block);
    }
    assert_true(checked > 0);
    assert_ok(glint_closure_finish(c));
}

static void closure_full(void **state)
{
    fixture *fx = *state;
    uint32_t lambert = lobe_id(fx->rt, "lambert"), i, index = 0, count = 0;
    glint_closure *c = NULL;
    glint_frame f = frame_z();
    glint_eval_result e = eval_result_init();
    char json[4096];
    size_t len;
    assert_ok(glint_closure_begin(fx->rt, fx->arena, NULL, 0, &c));
    for (i = 0; i < GLINT_MAX_LOBES; i++) {
        assert_ok(glint_closure_add_lobe(c, lambert, WHITE, &f, NULL, 0, &index));
        assert_int_equal(index, i);
    }
    check_error(fx, glint_closure_add_lobe(c, lambert, WHITE, &f, NULL, 0, &index),
                GLINT_ERROR_CLOSURE_FULL);
    assert_int_equal(index, 0);
    assert_ok(glint_closure_lobe_count(c, &count));
    assert_int_equal(count, GLINT_MAX_LOBES);
    /* Still usable: finish and evaluate the 16 lobes. */
    assert_ok(glint_closure_finish(c));
    assert_ok(glint_eval(c, test_wo(), test_wo(), &e));
    assert_true(e.value[0] > 0.0f);

    /* The same from JSON. */
    len = (size_t)snprintf(json, sizeof json, "{\"lobes\": [");
    for (i = 0; i <= GLINT_MAX_LOBES; i++)
        len += (size_t)snprintf(json + len, sizeof json - len, "%s{\"type\": \"lambert\"}",
                                i ? ", " : "");
    snprintf(json + len, sizeof json - len, "]}");
    check_error(fx, glint_closure_from_json(fx->rt, fx->arena, json, NULL, &c),
                GLINT_ERROR_CLOSURE_FULL);
}

static void closure_state_errors(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo();
    glint_closure *c = NULL;
    glint_frame f = frame_z();
    glint_eval_result e = eval_result_init();
    glint_sample_result s = sample_result_init();
    float pdf, rgb[3];
    uint32_t count = 99, type_id = 99;

    /* Unfinished: nothing can be evaluated yet. */
    assert_ok(glint_closure_begin(fx->rt, fx->arena, NULL, 0, &c));
    assert_ok(glint_closure_add_lobe(c, 0, WHITE, &f, NULL, 0, NULL));
    check_error(fx, glint_eval(c, wo, wo, &e), GLINT_ERROR_INVALID_STATE);
    assert_error_mentions("finish");
    check_error(fx, glint_sample(c, wo, 0.5f, 0.5f, 0.5f, &s), GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_pdf(c, wo, wo, &pdf), GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_albedo(c, wo, rgb), GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_eval_lobe(c, 0, wo, wo, &e), GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_eval_forward(c, wo, wo, &e), GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_eval_lobe_forward(c, 0, wo, wo, &e), GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_sample_lobe(c, 0, wo, 0.5f, 0.5f, 0.5f, &s), GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_pdf_lobe(c, 0, wo, wo, &pdf), GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_albedo_lobe(c, 0, wo, rgb), GLINT_ERROR_INVALID_STATE);
    /* Its lobe count can be read while building, selection probabilities only once finished. */
    assert_ok(glint_closure_lobe_count(c, &count));
    assert_int_equal(count, 1);
    check_error(fx, glint_closure_lobe(c, 0, &type_id, &pdf), GLINT_ERROR_INVALID_STATE);
    assert_int_equal(type_id, 0);

    /* Finished: no more lobes, no second finish. */
    assert_ok(glint_closure_finish(c));
    check_error(fx, glint_closure_add_lobe(c, 0, WHITE, &f, NULL, 0, NULL),
                GLINT_ERROR_INVALID_STATE);
    assert_error_mentions("finish");
    check_error(fx, glint_closure_finish(c), GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_closure_add_lobe(fx->ok, 0, WHITE, &f, NULL, 0, NULL),
                GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_closure_finish(fx->ok), GLINT_ERROR_INVALID_STATE);
    check_error(fx, glint_closure_finish(NULL), GLINT_ERROR_NULL_POINTER);
    assert_ok(glint_closure_lobe_count(c, &count));
    assert_int_equal(count, 1);
    assert_ok(glint_eval(c, wo, wo, &e));
}

/* ---- eval / sample / pdf / albedo on a finished closure ---------------------------------- */

static void query_errors(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo(), wi = v3_normalize(v3(-0.4f, 0.1f, 0.8f));
    const glint_vec3 bad[3] = {nan_vec(), zero_vec(), inf_vec()};
    glint_closure *c = json_closure(
        fx, "{\"lobes\": [{\"type\": \"lambert\"}, {\"type\": \"conductor\"}]}", NULL);
    glint_eval_result e = eval_result_init();
    glint_sample_result s = sample_result_init();
    float pdf = -7.0f, rgb[3] = {-7, -7, -7}, prob = -7.0f;
    uint32_t count = 0, type_id = 777;
    int b;
    assert_ok(glint_closure_lobe_count(c, &count));
    assert_int_equal(count, 2);

    /* NULL handles and outputs. */
    check_error(fx, glint_eval(NULL, wo, wi, &e), GLINT_ERROR_NULL_POINTER);
    assert_error_mentions("closure");
    check_error(fx, glint_eval(c, wo, wi, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_sample(NULL, wo, 0.5f, 0.5f, 0.5f, &s), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_sample(c, wo, 0.5f, 0.5f, 0.5f, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_pdf(NULL, wo, wi, &pdf), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_pdf(c, wo, wi, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_albedo(NULL, wo, rgb), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_albedo(c, wo, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_eval_lobe(NULL, 0, wo, wi, &e), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_eval_lobe(c, 0, wo, wi, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_eval_forward(NULL, wo, wi, &e), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_eval_forward(c, wo, wi, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_eval_lobe_forward(NULL, 0, wo, wi, &e), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_eval_lobe_forward(c, 0, wo, wi, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_eval_lobe_forward(c, 2, wo, wi, &e), GLINT_ERROR_OUT_OF_RANGE);
    assert_error_mentions("lobe index");
    check_error(fx, glint_eval_forward(c, v3(NAN, 0, 1), wi, &e), GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_sample_lobe(NULL, 0, wo, 0.5f, 0.5f, 0.5f, &s), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_sample_lobe(c, 0, wo, 0.5f, 0.5f, 0.5f, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_pdf_lobe(NULL, 0, wo, wi, &pdf), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_pdf_lobe(c, 0, wo, wi, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_albedo_lobe(NULL, 0, wo, rgb), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_albedo_lobe(c, 0, wo, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_closure_lobe_count(NULL, &count), GLINT_ERROR_NULL_POINTER);
    assert_int_equal(count, 0); /* zeroed on failure */
    count = 2;
    check_error(fx, glint_closure_lobe_count(c, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_closure_lobe(NULL, 0, &type_id, &prob), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_closure_lobe(c, 0, NULL, &prob), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_closure_lobe(c, 0, &type_id, NULL), GLINT_ERROR_NULL_POINTER);

    /* NaN, zero-length and infinite directions, in wo and in wi. */
    for (b = 0; b < 3; b++) {
        e.value[0] = -7.0f;
        pdf = -7.0f;
        rgb[0] = -7.0f;
        check_error(fx, glint_eval(c, bad[b], wi, &e), GLINT_ERROR_INVALID_ARGUMENT);
        assert_error_mentions("wo");
        check_error(fx, glint_eval(c, wo, bad[b], &e), GLINT_ERROR_INVALID_ARGUMENT);
        assert_error_mentions("wi");
        assert_true(e.value[0] == 0.0f); /* zeroed */
        check_error(fx, glint_sample(c, bad[b], 0.5f, 0.5f, 0.5f, &s), GLINT_ERROR_INVALID_ARGUMENT);
        assert_error_mentions("wo");
        check_error(fx, glint_pdf(c, bad[b], wi, &pdf), GLINT_ERROR_INVALID_ARGUMENT);
        check_error(fx, glint_pdf(c, wo, bad[b], &pdf), GLINT_ERROR_INVALID_ARGUMENT);
        assert_error_mentions("wi");
        assert_true(pdf == 0.0f);
        check_error(fx, glint_albedo(c, bad[b], rgb), GLINT_ERROR_INVALID_ARGUMENT);
        assert_true(rgb[0] == 0.0f);
        check_error(fx, glint_eval_lobe(c, 1, bad[b], wi, &e), GLINT_ERROR_INVALID_ARGUMENT);
        check_error(fx, glint_eval_lobe(c, 1, wo, bad[b], &e), GLINT_ERROR_INVALID_ARGUMENT);
        check_error(fx, glint_sample_lobe(c, 1, bad[b], 0.5f, 0.5f, 0.5f, &s),
                    GLINT_ERROR_INVALID_ARGUMENT);
        check_error(fx, glint_pdf_lobe(c, 1, bad[b], wi, &pdf), GLINT_ERROR_INVALID_ARGUMENT);
        check_error(fx, glint_pdf_lobe(c, 1, wo, bad[b], &pdf), GLINT_ERROR_INVALID_ARGUMENT);
        check_error(fx, glint_albedo_lobe(c, 1, bad[b], rgb), GLINT_ERROR_INVALID_ARGUMENT);
    }

    /* Non-finite random numbers. */
    check_error(fx, glint_sample(c, wo, NAN, 0.5f, 0.5f, &s), GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_sample(c, wo, 0.5f, NAN, 0.5f, &s), GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_sample(c, wo, 0.5f, 0.5f, INFINITY, &s), GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_sample_lobe(c, 0, wo, NAN, 0.5f, 0.5f, &s), GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_sample_lobe(c, 0, wo, 0.5f, -INFINITY, 0.5f, &s),
                GLINT_ERROR_INVALID_ARGUMENT);

    /* Lobe indices out of range. */
    check_error(fx, glint_eval_lobe(c, count, wo, wi, &e), GLINT_ERROR_OUT_OF_RANGE);
    assert_error_mentions("2");
    check_error(fx, glint_eval_lobe(c, UINT32_MAX, wo, wi, &e), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_sample_lobe(c, count, wo, 0.5f, 0.5f, 0.5f, &s), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_sample_lobe(c, UINT32_MAX, wo, 0.5f, 0.5f, 0.5f, &s),
                GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_pdf_lobe(c, count, wo, wi, &pdf), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_pdf_lobe(c, UINT32_MAX, wo, wi, &pdf), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_albedo_lobe(c, count, wo, rgb), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_albedo_lobe(c, UINT32_MAX, wo, rgb), GLINT_ERROR_OUT_OF_RANGE);
    type_id = 777;
    check_error(fx, glint_closure_lobe(c, count, &type_id, &prob), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_closure_lobe(c, UINT32_MAX, &type_id, &prob), GLINT_ERROR_OUT_OF_RANGE);
    assert_int_equal(type_id, 0);
}

static void result_struct_size_errors(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo();
    glint_eval_result e = eval_result_init();
    glint_sample_result s = sample_result_init();
    const uint32_t small_eval[2] = {0, sizeof(glint_eval_result) - 1};
    const uint32_t small_sample[2] = {0, sizeof(glint_sample_result) - 1};
    int i;
    for (i = 0; i < 2; i++) {
        e.struct_size = small_eval[i];
        e.value[0] = -7.0f;
        check_error(fx, glint_eval(fx->ok, wo, wo, &e), GLINT_ERROR_STRUCT_SIZE);
        assert_error_mentions("struct_size");
        check_error(fx, glint_eval_lobe(fx->ok, 0, wo, wo, &e), GLINT_ERROR_STRUCT_SIZE);
        check_error(fx, glint_eval_forward(fx->ok, wo, wo, &e), GLINT_ERROR_STRUCT_SIZE);
        check_error(fx, glint_eval_lobe_forward(fx->ok, 0, wo, wo, &e), GLINT_ERROR_STRUCT_SIZE);
        assert_true(e.value[0] == -7.0f);
        assert_int_equal(e.struct_size, small_eval[i]);
        s.struct_size = small_sample[i];
        s.pdf = -7.0f;
        check_error(fx, glint_sample(fx->ok, wo, 0.5f, 0.5f, 0.5f, &s), GLINT_ERROR_STRUCT_SIZE);
        check_error(fx, glint_sample_lobe(fx->ok, 0, wo, 0.5f, 0.5f, 0.5f, &s),
                    GLINT_ERROR_STRUCT_SIZE);
        assert_true(s.pdf == -7.0f);
        assert_int_equal(s.struct_size, small_sample[i]);
    }
    /* Larger (a newer caller) is fine, and struct_size is preserved. */
    {
        struct {
            glint_sample_result s;
            unsigned char future[16];
        } big;
        memset(&big, 0xcd, sizeof big);
        big.s.struct_size = sizeof big;
        assert_ok(glint_sample(fx->ok, wo, 0.5f, 0.5f, 0.5f, &big.s));
        assert_int_equal(big.s.struct_size, sizeof big);
        assert_int_equal(big.future[0], 0xcd);
        assert_true(big.s.pdf > 0.0f);
    }
}

/* ---- JSON ---------------------------------------------------------------------------- */

typedef struct json_case {
    const char *json;
    glint_status status;
    const char *mentions[8]; /* NULL-terminated */
} json_case;

static const json_case JSON_CASES[] = {
    {"", GLINT_ERROR_PARSE, {"JSON", NULL}},
    {"{", GLINT_ERROR_PARSE, {NULL}},
    {"{\"lobes\": [}", GLINT_ERROR_PARSE, {NULL}},
    {"{\"lobes\": []} trailing", GLINT_ERROR_PARSE, {NULL}},
    {"[]", GLINT_ERROR_PARSE, {"object", NULL}},
    {"42", GLINT_ERROR_PARSE, {NULL}},
    {"{}", GLINT_ERROR_PARSE, {"lobes", NULL}},
    {"{\"lobes\": 3}", GLINT_ERROR_PARSE, {"lobes", NULL}},
    {"{\"lobes\": [3]}", GLINT_ERROR_PARSE, {"lobes[0]", NULL}},
    {"{\"lobes\": [{}]}", GLINT_ERROR_PARSE, {"type", "lambert", NULL}},
    {"{\"lobes\": [{\"type\": 5}]}", GLINT_ERROR_PARSE, {"type", NULL}},
    /* unknown names */
    {"{\"lobes\": [{\"type\": \"velvet\"}]}",
     GLINT_ERROR_UNKNOWN_NAME,
     {"velvet", "lambert", "conductor", "dielectric", "mirror", NULL}},
    {"{\"lobes\": [], \"colour\": 1}", GLINT_ERROR_UNKNOWN_NAME, {"colour", "lobes", "transport", NULL}},
    {"{\"lobes\": [{\"type\": \"conductor\", \"roughnes\": 0.3}]}",
     GLINT_ERROR_UNKNOWN_NAME,
     {"roughnes", "roughness", "distribution", "fresnel", "type", "weight", "normal", "tangent"}},
    {"{\"lobes\": [{\"type\": \"lambert\"}, {\"type\": \"lambert\", \"colour\": [1, 0, 0]}]}",
     GLINT_ERROR_UNKNOWN_NAME,
     {"colour", "color", "lobes[1]", NULL}},
    {"{\"lobes\": [{\"type\": \"conductor\", \"distribution\": \"phong\"}]}",
     GLINT_ERROR_UNKNOWN_NAME,
     {"phong", "ggx", "beckmann", NULL}},
    {"{\"lobes\": [{\"type\": \"mirror\", \"fresnel\": \"metal\"}]}",
     GLINT_ERROR_UNKNOWN_NAME,
     {"metal", "schlick", "conductor", "artistic", NULL}},
    {"{\"transport\": \"photons\", \"lobes\": []}",
     GLINT_ERROR_UNKNOWN_NAME,
     {"photons", "radiance", "importance", NULL}},
    {"{\"transport\": 1, \"lobes\": []}", GLINT_ERROR_UNKNOWN_NAME, {"transport", NULL}},
    /* wrong value types and shapes */
    {"{\"lobes\": [{\"type\": \"conductor\", \"distribution\": 1}]}",
     GLINT_ERROR_PARSE,
     {"distribution", "ggx", NULL}},
    {"{\"lobes\": [{\"type\": \"conductor\", \"roughness\": \"rough\"}]}",
     GLINT_ERROR_PARSE,
     {"roughness", NULL}},
    {"{\"lobes\": [{\"type\": \"lambert\", \"color\": [1, 1]}]}", GLINT_ERROR_PARSE, {"color", NULL}},
    {"{\"lobes\": [{\"type\": \"lambert\", \"weight\": \"x\"}]}", GLINT_ERROR_PARSE, {"weight", NULL}},
    {"{\"lobes\": [{\"type\": \"lambert\", \"normal\": [0, 1]}]}", GLINT_ERROR_PARSE, {"normal", NULL}},
    {"{\"lobes\": [{\"type\": \"conductor\", \"tangent\": \"x\"}]}", GLINT_ERROR_PARSE, {"tangent", NULL}},
    /* out-of-range and invalid values */
    {"{\"lobes\": [{\"type\": \"conductor\", \"roughness\": 1.5}]}",
     GLINT_ERROR_OUT_OF_RANGE,
     {"roughness", NULL}},
    {"{\"lobes\": [{\"type\": \"conductor\", \"roughness\": -0.1}]}",
     GLINT_ERROR_OUT_OF_RANGE,
     {"roughness", NULL}},
    {"{\"lobes\": [{\"type\": \"lambert\", \"color\": [0.5, 2, 0.5]}]}",
     GLINT_ERROR_OUT_OF_RANGE,
     {"color", NULL}},
    {"{\"lobes\": [{\"type\": \"dielectric\", \"eta\": 0}]}", GLINT_ERROR_OUT_OF_RANGE, {"eta", NULL}},
    {"{\"lobes\": [{\"type\": \"lambert\", \"weight\": -1}]}",
     GLINT_ERROR_INVALID_ARGUMENT,
     {"weight", NULL}},
    {"{\"lobes\": [{\"type\": \"lambert\", \"normal\": [0, 0, 0]}]}",
     GLINT_ERROR_INVALID_ARGUMENT,
     {"normal", NULL}},
    {"{\"lobes\": [{\"type\": \"lambert\", \"tangent\": [NaN, 0, 0]}]}", GLINT_ERROR_PARSE, {NULL}},
    /* not UTF-8 */
    {"{\"lobes\": [{\"type\": \"lam\xff\"}]}", GLINT_ERROR_INVALID_ARGUMENT, {NULL}},
};

static void json_errors(void **state)
{
    fixture *fx = *state;
    glint_arena *arena = NULL;
    glint_closure *c = NULL;
    glint_vec3 bad_wo = nan_vec();
    size_t i;
    int m;
    /* One slot: a failed parse must not use it. */
    assert_ok(glint_arena_create(1, &arena));
    for (i = 0; i < sizeof JSON_CASES / sizeof JSON_CASES[0]; i++) {
        const json_case *jc = &JSON_CASES[i];
        print_message("json case %u: %s\n", (unsigned)i, jc->json);
        c = (glint_closure *)fx;
        check_error(fx, glint_closure_from_json(fx->rt, arena, jc->json, NULL, &c), jc->status);
        assert_null(c);
        for (m = 0; m < 8 && jc->mentions[m] != NULL; m++)
            assert_error_mentions(jc->mentions[m]);
    }
    check_error(fx, glint_closure_from_json(NULL, arena, "{\"lobes\": []}", NULL, &c),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_closure_from_json(fx->rt, NULL, "{\"lobes\": []}", NULL, &c),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_closure_from_json(fx->rt, arena, NULL, NULL, &c), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_closure_from_json(fx->rt, arena, "{\"lobes\": []}", NULL, NULL),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_closure_from_json(fx->rt, arena, "{\"lobes\": []}", &bad_wo, &c),
                GLINT_ERROR_INVALID_ARGUMENT);
    bad_wo = zero_vec();
    check_error(fx, glint_closure_from_json(fx->rt, arena, "{\"lobes\": []}", &bad_wo, &c),
                GLINT_ERROR_INVALID_ARGUMENT);

    assert_ok(glint_closure_from_json(fx->rt, arena, "{\"lobes\": [{\"type\": \"lambert\"}]}", NULL,
                                      &c));
    assert_non_null(c);
    glint_arena_destroy(arena);
}

int main(void)
{
#define T(f) cmocka_unit_test_setup_teardown(f, fixture_setup, fixture_teardown)
    const struct CMUnitTest tests[] = {
        T(arena_errors),
        T(arena_full),
        T(closure_begin_errors),
        T(add_lobe_argument_errors),
        T(add_lobe_parameter_errors),
        T(closure_full),
        T(closure_state_errors),
        T(query_errors),
        T(result_struct_size_errors),
        T(json_errors),
    };
#undef T
    return cmocka_run_group_tests(tests, NULL, NULL);
}
