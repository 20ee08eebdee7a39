/* Threads: one finished closure evaluated concurrently, per-thread arenas on a shared
 * runtime, and per-thread glint_last_error(). cmocka's assertions are not thread-safe,
 * so the threads record what they saw and the main thread asserts. */
#define _POSIX_C_SOURCE 200809L

#include "common.h"

#include <pthread.h>
#include <stdlib.h>

#define THREADS 2
#define QUERIES 512
#define ROUNDS 8

typedef struct query {
    glint_vec3 wo, wi;
    float u[3];
    /* Single-threaded reference results. */
    glint_eval_result eval;
    glint_sample_result sample;
    glint_status sample_status;
    float pdf, albedo[3];
} query;

typedef struct shared_closure_job {
    const glint_closure *closure;
    const query *queries;
    int offset;
    int mismatches, errors, calls;
} shared_closure_job;

static int same_eval(const glint_eval_result *a, const glint_eval_result *b)
{
    return a->value[0] == b->value[0] && a->value[1] == b->value[1] && a->value[2] == b->value[2] &&
           a->pdf == b->pdf && a->pdf_reverse == b->pdf_reverse;
}

static int same_sample(const glint_sample_result *a, const glint_sample_result *b)
{
    return a->wi.x == b->wi.x && a->wi.y == b->wi.y && a->wi.z == b->wi.z &&
           a->value[0] == b->value[0] && a->value[1] == b->value[1] &&
           a->value[2] == b->value[2] && a->pdf == b->pdf && a->weight[0] == b->weight[0] &&
           a->weight[1] == b->weight[1] && a->weight[2] == b->weight[2] && a->flags == b->flags &&
           a->lobe == b->lobe && a->eta == b->eta && a->roughness == b->roughness;
}

static void *evaluate_shared_closure(void *arg)
{
    shared_closure_job *job = arg;
    int round, i;
    for (round = 0; round < ROUNDS; round++) {
        for (i = 0; i < QUERIES; i++) {
            const query *q = &job->queries[(i + job->offset + round * 37) % QUERIES];
            glint_eval_result e = eval_result_init();
            glint_sample_result s = sample_result_init();
            glint_status st;
            float pdf = -1.0f, albedo[3];
            job->calls += 4;
            if (glint_eval(job->closure, q->wo, q->wi, &e) != GLINT_OK)
                job->errors++;
            else if (!same_eval(&e, &q->eval))
                job->mismatches++;
            st = glint_sample(job->closure, q->wo, q->u[0], q->u[1], q->u[2], &s);
            if (st != q->sample_status)
                job->errors++;
            else if (!same_sample(&s, &q->sample))
                job->mismatches++;
            if (glint_pdf(job->closure, q->wo, q->wi, &pdf) != GLINT_OK)
                job->errors++;
            else if (pdf != q->pdf)
                job->mismatches++;
            if (glint_albedo(job->closure, q->wo, albedo) != GLINT_OK)
                job->errors++;
            else if (albedo[0] != q->albedo[0] || albedo[1] != q->albedo[1] ||
                     albedo[2] != q->albedo[2])
                job->mismatches++;
        }
    }
    return NULL;
}

static void one_closure_evaluated_concurrently(void **state)
{
    fixture *fx = *state;
    const glint_closure *c = all_types_closure(fx, NULL);
    query *queries = calloc(QUERIES, sizeof *queries);
    shared_closure_job jobs[THREADS];
    pthread_t threads[THREADS];
    lcg g;
    int i, t, valid_samples = 0;
    assert_non_null(queries);
    lcg_seed(&g, 31337);
    for (i = 0; i < QUERIES; i++) {
        query *q = &queries[i];
        q->wo = lcg_direction(&g, i % 4 != 3);
        q->wi = lcg_direction(&g, 0);
        q->u[0] = lcg_next(&g), q->u[1] = lcg_next(&g), q->u[2] = lcg_next(&g);
        q->eval = eval_result_init();
        q->sample = sample_result_init();
        assert_ok(glint_eval(c, q->wo, q->wi, &q->eval));
        q->sample_status = glint_sample(c, q->wo, q->u[0], q->u[1], q->u[2], &q->sample);
        assert_true(q->sample_status == GLINT_OK || q->sample_status == GLINT_NO_SAMPLE);
        valid_samples += q->sample_status == GLINT_OK;
        assert_ok(glint_pdf(c, q->wo, q->wi, &q->pdf));
        assert_ok(glint_albedo(c, q->wo, q->albedo));
    }
    assert_true(valid_samples > QUERIES / 2);

    for (t = 0; t < THREADS; t++) {
        memset(&jobs[t], 0, sizeof jobs[t]);
        jobs[t].closure = c;
        jobs[t].queries = queries;
        jobs[t].offset = t * (QUERIES / THREADS);
        assert_int_equal(pthread_create(&threads[t], NULL, evaluate_shared_closure, &jobs[t]), 0);
    }
    for (t = 0; t < THREADS; t++)
        assert_int_equal(pthread_join(threads[t], NULL), 0);
    for (t = 0; t < THREADS; t++) {
        assert_int_equal(jobs[t].calls, 4 * QUERIES * ROUNDS);
        assert_int_equal(jobs[t].errors, 0);
        assert_int_equal(jobs[t].mismatches, 0);
    }
    free(queries);
}

/* ---- per-thread glint_last_error ----------------------------------------------------------- */

typedef struct error_job {
    const glint_runtime *rt;
    pthread_barrier_t *barrier;
    const char *marker;
    int first; /* 1: fail before the other thread, 0: after */
    /* What the thread saw. */
    char initial[256];
    char own_after_other[512];
    char after_success[512];
    glint_status status;
    int success_status;
} error_job;

static void copy_message(char *dst, size_t size)
{
    snprintf(dst, size, "%s", glint_last_error());
}

static void fail_with(error_job *job)
{
    uint32_t id;
    job->status = glint_lobe_type_find(job->rt, job->marker, &id);
}

static void *error_thread(void *arg)
{
    error_job *job = arg;
    uint32_t n = 0;
    copy_message(job->initial, sizeof job->initial); /* a fresh thread: no error yet */
    if (job->first)
        fail_with(job);
    pthread_barrier_wait(job->barrier); /* 1: the first thread has failed */
    if (!job->first)
        fail_with(job);
    pthread_barrier_wait(job->barrier); /* 2: both have failed */
    copy_message(job->own_after_other, sizeof job->own_after_other);
    pthread_barrier_wait(job->barrier); /* 3: both have read */
    job->success_status = (int)glint_lobe_type_count(job->rt, &n);
    copy_message(job->after_success, sizeof job->after_success);
    return NULL;
}

static void last_error_is_per_thread(void **state)
{
    fixture *fx = *state;
    pthread_barrier_t barrier;
    pthread_t threads[2];
    error_job jobs[2];
    uint32_t id;
    int t;

    /* The main thread's own message, which the threads must not disturb. */
    assert_int_equal(glint_lobe_type_find(fx->rt, "main-thread-marker", &id), GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("main-thread-marker");

    assert_int_equal(pthread_barrier_init(&barrier, NULL, 2), 0);
    memset(jobs, 0, sizeof jobs);
    jobs[0].marker = "alpha-thread-marker";
    jobs[0].first = 1;
    jobs[1].marker = "beta-thread-marker";
    jobs[1].first = 0;
    for (t = 0; t < 2; t++) {
        jobs[t].rt = fx->rt;
        jobs[t].barrier = &barrier;
        assert_int_equal(pthread_create(&threads[t], NULL, error_thread, &jobs[t]), 0);
    }
    for (t = 0; t < 2; t++)
        assert_int_equal(pthread_join(threads[t], NULL), 0);
    pthread_barrier_destroy(&barrier);

    for (t = 0; t < 2; t++) {
        const char *other = jobs[1 - t].marker;
        print_message("thread %d: initial \"%s\", after \"%s\"\n", t, jobs[t].initial,
                      jobs[t].own_after_other);
        assert_string_equal(jobs[t].initial, "");
        assert_int_equal(jobs[t].status, GLINT_ERROR_UNKNOWN_NAME);
        assert_non_null(strstr(jobs[t].own_after_other, jobs[t].marker));
        assert_null(strstr(jobs[t].own_after_other, other));
        assert_null(strstr(jobs[t].own_after_other, "main-thread-marker"));
        assert_int_equal(jobs[t].success_status, GLINT_OK);
        assert_string_equal(jobs[t].after_success, jobs[t].own_after_other);
    }
    assert_error_mentions("main-thread-marker");
}

/* ---- concurrent building in per-thread arenas, with errors interleaved ------------------------ */

typedef struct build_job {
    const glint_runtime *rt;
    int index;
    int built, wrong_message, failures;
} build_job;

static void *build_thread(void *arg)
{
    build_job *job = arg;
    glint_arena *arena = NULL;
    int i;
    if (glint_arena_create(8, &arena) != GLINT_OK) {
        job->failures++;
        return NULL;
    }
    for (i = 0; i < 400; i++) {
        char name[64], json[256];
        glint_closure *c = NULL;
        glint_eval_result e = eval_result_init();
        uint32_t id;
        if (i % 8 == 0 && glint_arena_reset(arena) != GLINT_OK)
            job->failures++;
        snprintf(json, sizeof json,
                 "{\"lobes\": [{\"type\": \"lambert\", \"color\": %g},"
                 " {\"type\": \"conductor\", \"roughness\": %g}]}",
                 0.1 + 0.002 * i, 0.05 + 0.002 * i);
        if (glint_closure_from_json(job->rt, arena, json, NULL, &c) != GLINT_OK ||
            glint_eval(c, test_wo(), v3(-0.2f, 0.1f, 0.9f), &e) != GLINT_OK || !(e.value[0] > 0.0f))
            job->failures++;
        else
            job->built++;
        /* An error whose message names this thread and iteration. */
        snprintf(name, sizeof name, "thread-%d-iteration-%d", job->index, i);
        if (glint_lobe_type_find(job->rt, name, &id) != GLINT_ERROR_UNKNOWN_NAME)
            job->failures++;
        if (strstr(glint_last_error(), name) == NULL)
            job->wrong_message++;
    }
    glint_arena_destroy(arena);
    return NULL;
}

static void concurrent_building_on_a_shared_runtime(void **state)
{
    fixture *fx = *state;
    pthread_t threads[THREADS];
    build_job jobs[THREADS];
    int t;
    for (t = 0; t < THREADS; t++) {
        memset(&jobs[t], 0, sizeof jobs[t]);
        jobs[t].rt = fx->rt;
        jobs[t].index = t;
        assert_int_equal(pthread_create(&threads[t], NULL, build_thread, &jobs[t]), 0);
    }
    for (t = 0; t < THREADS; t++)
        assert_int_equal(pthread_join(threads[t], NULL), 0);
    for (t = 0; t < THREADS; t++) {
        assert_int_equal(jobs[t].failures, 0);
        assert_int_equal(jobs[t].wrong_message, 0);
        assert_int_equal(jobs[t].built, 400);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(one_closure_evaluated_concurrently, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(last_error_is_per_thread, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(concurrent_building_on_a_shared_runtime, fixture_setup,
                                        fixture_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
