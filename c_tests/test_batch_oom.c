/* Batch calls when memory runs out (issue 12, D2): GLINT_ERROR_OUT_OF_MEMORY, never an
 * abort. A forked child (an abort shows as its signal, the cap stays in it) caps its
 * address space (RLIMIT_AS) and fills its heap, then runs per-lane batches of mixed
 * closure shapes. Staging is per block of at most 4096 lanes (src/batch), well under a
 * megabyte, so a large count alone cannot exhaust a cap with room to spare: the heap is
 * filled instead, once leaving scattered 4 KB holes (small requests succeed, a staging
 * row of a block does not) and once completely.
 *
 * Skipped in sanitizer builds (GLINT_SANITIZED: ASan maps terabytes of shadow memory
 * and replaces malloc) and under valgrind (RUNNING_ON_VALGRIND, when CMake finds
 * valgrind/valgrind.h: its malloc keeps freed blocks from reuse for a while, so memory
 * the test frees does not come back). */
#define _POSIX_C_SOURCE 200809L
#include "common.h"

#include <signal.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#ifdef GLINT_HAVE_VALGRIND_H
#include <valgrind/valgrind.h>
#else
#define RUNNING_ON_VALGRIND 0
#endif

/* Two of the library's 4096-lane blocks; the warm-up batch takes the first SMALL. */
#define COUNT 8192
#define SMALL 16
#define SHAPES 6
/* Headroom above the current address-space size; the heap filling takes all of it. */
#define HEADROOM ((rlim_t)16 << 20)
/* Heap blocks of the first filling: every second one is freed again, so the holes are
 * never adjacent and no request much above this size can be served. */
#define HOLE 4000

/* The child's checks: report and exit non-zero (cmocka stays in the parent). */
#define CHILD_CHECK(cond, ...)                                                           \
    do {                                                                                 \
        if (!(cond)) {                                                                   \
            fprintf(stderr, "child, line %d: %s: ", __LINE__, #cond);                    \
            fprintf(stderr, __VA_ARGS__);                                                \
            fprintf(stderr, " (last error: %s)\n", glint_last_error());                  \
            _exit(1);                                                                    \
        }                                                                                \
    } while (0)

/* Inputs and outputs of every lane. */
typedef struct lanes {
    const glint_closure *closures[COUNT];
    float wo_x[COUNT], wo_y[COUNT], wo_z[COUNT], wi_x[COUNT], wi_y[COUNT], wi_z[COUNT];
    float u_lobe[COUNT], u0[COUNT], u1[COUNT];
    float value_r[COUNT], value_g[COUNT], value_b[COUNT], pdf[COUNT], pdf_only[COUNT];
    float albedo_r[COUNT], albedo_g[COUNT], albedo_b[COUNT];
    float s_wi_x[COUNT], s_wi_y[COUNT], s_wi_z[COUNT], s_pdf[COUNT];
    float weight_r[COUNT], weight_g[COUNT], weight_b[COUNT];
    uint32_t flags[COUNT];
} lanes;

/* The outputs of the four batch calls on a few lanes. */
typedef struct outputs {
    float value[SMALL], pdf[SMALL], pdf_only[SMALL], albedo[SMALL], s_pdf[SMALL],
        weight[SMALL];
    uint32_t flags[SMALL];
} outputs;

#define CALLS 4
static const char *const call_names[CALLS] = {"eval", "pdf", "albedo", "sample"};

/* Batch call `which` (of call_names) on the first `count` lanes. */
static glint_status run_batch(lanes *l, size_t count, int which)
{
    glint_eval_batch_args e = {sizeof e, count, NULL, l->closures, NULL,
                               l->wo_x, l->wo_y, l->wo_z, l->wi_x, l->wi_y, l->wi_z,
                               l->value_r, l->value_g, l->value_b, l->pdf, NULL};
    glint_pdf_batch_args p = {sizeof p, count, NULL, l->closures, NULL, l->wo_x, l->wo_y,
                              l->wo_z, l->wi_x, l->wi_y, l->wi_z, l->pdf_only};
    glint_albedo_batch_args a = {sizeof a, count, NULL, l->closures, NULL,
                                 l->wo_x, l->wo_y, l->wo_z,
                                 l->albedo_r, l->albedo_g, l->albedo_b};
    glint_sample_batch_args s = {sizeof s, count, NULL, l->closures, NULL,
                                 l->wo_x, l->wo_y, l->wo_z, l->u_lobe, l->u0, l->u1,
                                 l->s_wi_x, l->s_wi_y, l->s_wi_z, l->s_pdf,
                                 l->weight_r, l->weight_g, l->weight_b,
                                 NULL, NULL, NULL, l->flags, NULL, NULL, NULL, NULL};
    switch (which) {
    case 0:
        return glint_eval_batch(&e);
    case 1:
        return glint_pdf_batch(&p);
    case 2:
        return glint_albedo_batch(&a);
    default:
        return glint_sample_batch(&s);
    }
}

static outputs first_lanes(const lanes *l)
{
    outputs o;
    int i;
    for (i = 0; i < SMALL; i++) {
        o.value[i] = l->value_r[i], o.pdf[i] = l->pdf[i], o.pdf_only[i] = l->pdf_only[i];
        o.albedo[i] = l->albedo_r[i], o.s_pdf[i] = l->s_pdf[i];
        o.weight[i] = l->weight_r[i], o.flags[i] = l->flags[i];
    }
    return o;
}

/* Every batch call succeeds on the first `count` lanes; `when` names the phase. */
static void run_batches(lanes *l, size_t count, const char *when)
{
    int k;
    for (k = 0; k < CALLS; k++) {
        glint_status status = run_batch(l, count, k);
        CHILD_CHECK(status == GLINT_OK, "%s: %s batch of %zu lanes -> %u", when,
                    call_names[k], count, (unsigned)status);
    }
}

/* As run_batches, and the first SMALL lanes' results are `expected` (each lane's
 * result depends only on its own inputs). */
static void check_batches_work(lanes *l, size_t count, const outputs *expected,
                               const char *when)
{
    outputs got;
    run_batches(l, count, when);
    got = first_lanes(l);
    CHILD_CHECK(memcmp(&got, expected, sizeof got) == 0, "%s: results differ", when);
}

/* malloc(size) until it fails; the blocks form a list through their first word, the
 * latest first. */
static void **fill_heap(void **list, size_t size)
{
    void **block;
    while ((block = malloc(size)) != NULL) {
        *block = list;
        list = block;
    }
    return list;
}

/* Free every second block of `list`; returns the rest. */
static void **punch_holes(void **list)
{
    void **kept = NULL;
    int i = 0;
    while (list != NULL) {
        void **next = *list;
        if (i++ % 2 == 0) {
            *list = kept;
            kept = list;
        } else {
            free(list);
        }
        list = next;
    }
    return kept;
}

static void free_list(void **list)
{
    while (list != NULL) {
        void **next = *list;
        free(list);
        list = next;
    }
}

/* Fill the heap to the last byte: blocks of HOLE / 2 bytes, then of half that size,
 * down to a pointer's. */
static void **fill_heap_completely(void **list)
{
    size_t size;
    for (size = HOLE / 2; size >= sizeof(void *); size /= 2)
        list = fill_heap(list, size);
    return list;
}

/* Every batch call on COUNT lanes returns OUT_OF_MEMORY, its message saying so and
 * containing `detail`. With `refill`, the heap is filled completely before each call
 * (a call's message frees the previous one's); returns the heap's list. */
static void **check_batches_run_out(lanes *l, void **heap, int refill, const char *detail,
                                    const char *when)
{
    int k;
    for (k = 0; k < CALLS; k++) {
        glint_status status;
        if (refill)
            heap = fill_heap_completely(heap);
        status = run_batch(l, COUNT, k);
        CHILD_CHECK(status == GLINT_ERROR_OUT_OF_MEMORY, "%s: %s batch -> %u", when,
                    call_names[k], (unsigned)status);
        CHILD_CHECK(strstr(glint_last_error(), "out of memory") != NULL, "%s: %s batch",
                    when, call_names[k]);
        CHILD_CHECK(strstr(glint_last_error(), detail) != NULL, "%s: %s batch: no \"%s\"",
                    when, call_names[k], detail);
    }
    return heap;
}

/* The address space in use, from /proc/self/statm (its first field, in pages). */
static rlim_t address_space_bytes(void)
{
    unsigned long pages = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    CHILD_CHECK(f != NULL, "cannot open /proc/self/statm");
    CHILD_CHECK(fscanf(f, "%lu", &pages) == 1, "cannot read /proc/self/statm");
    fclose(f);
    return (rlim_t)pages * (rlim_t)sysconf(_SC_PAGESIZE);
}

static void child(void)
{
    static const char *const json[SHAPES] = {
        "{\"lobes\": [{\"type\": \"lambert\", \"color\": 0.5}]}",
        "{\"lobes\": [{\"type\": \"lambert\", \"color\": 0.8}]}",
        "{\"lobes\": [{\"type\": \"lambert\", \"weight\": 0.5}, "
        "{\"type\": \"conductor\", \"roughness\": 0.3}]}",
        "{\"lobes\": [{\"type\": \"lambert\", \"weight\": 0.7}, "
        "{\"type\": \"conductor\", \"roughness\": 0.6}]}",
        "{\"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0.2, \"eta\": 1.5}]}",
        "{\"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0.4, \"eta\": 1.33}]}",
    };
    glint_runtime *rt = NULL;
    glint_arena *arena = NULL;
    glint_closure *closures[SHAPES];
    glint_closure *grown = NULL;
    const glint_frame frame = {{0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}};
    const float weight[3] = {1.0f, 1.0f, 1.0f};
    uint32_t conductor = 0;
    glint_status status;
    lanes *l = calloc(1, sizeof *l);
    struct rlimit limit;
    outputs warm;
    void **heap;
    lcg g;
    int i;
    CHILD_CHECK(l != NULL, "calloc");
    /* threads=1: batches stay on this thread, whose heap is the one filled. */
    CHILD_CHECK(glint_runtime_create("threads=1", &rt) == GLINT_OK, "runtime");
    CHILD_CHECK(glint_arena_create(SHAPES + 1, &arena) == GLINT_OK, "arena");
    CHILD_CHECK(glint_lobe_type_find(rt, "conductor", &conductor) == GLINT_OK, "conductor");
    for (i = 0; i < SHAPES; i++)
        CHILD_CHECK(glint_closure_from_json(rt, arena, json[i], NULL, &closures[i]) ==
                        GLINT_OK,
                    "closure %d", i);
    lcg_seed(&g, 21);
    for (i = 0; i < COUNT; i++) {
        glint_vec3 wo = lcg_direction(&g, 1), wi = lcg_direction(&g, 1);
        /* Neighbouring lanes differ in shape, and each shape has two closures. */
        l->closures[i] = closures[i % SHAPES];
        l->wo_x[i] = wo.x, l->wo_y[i] = wo.y, l->wo_z[i] = wo.z;
        l->wi_x[i] = wi.x, l->wi_y[i] = wi.y, l->wi_z[i] = wi.z;
        l->u_lobe[i] = lcg_next(&g), l->u0[i] = lcg_next(&g), l->u1[i] = lcg_next(&g);
    }
    /* Warm up with a few lanes: the library's per-thread staging and error state exist
     * (small) before memory runs out. */
    (void)glint_last_error();
    run_batches(l, SMALL, "warm-up");
    warm = first_lanes(l);

    CHILD_CHECK(getrlimit(RLIMIT_AS, &limit) == 0, "getrlimit");
    limit.rlim_cur = address_space_bytes() + HEADROOM;
    CHILD_CHECK(limit.rlim_max == RLIM_INFINITY || limit.rlim_cur <= limit.rlim_max,
                "hard RLIMIT_AS too low");
    CHILD_CHECK(setrlimit(RLIMIT_AS, &limit) == 0, "setrlimit");

    /* Memory short: small requests still fit the holes, a block's staging does not. */
    heap = punch_holes(fill_heap(NULL, HOLE));
    heap = check_batches_run_out(l, heap, 0, "staging buffers", "heap full but for holes");
    /* A batch within the staging already there needs no memory. */
    check_batches_work(l, SMALL, &warm, "small batch, heap full but for holes");

    /* No memory at all: a call allocates nothing but its staging, and the message is the
     * status's static description. */
    heap = check_batches_run_out(l, heap, 1, "could not be allocated", "heap full");
    check_batches_work(l, SMALL, &warm, "small batch, heap full");

    /* A closure's lobes and blocks live in storage it grows: none to be had is an error,
     * and the closure stays as it was (empty, still open). */
    heap = fill_heap_completely(heap);
    status = glint_closure_begin(rt, arena, NULL, 0, &grown);
    CHILD_CHECK(status == GLINT_OK, "begin on a fresh slot, heap full -> %u", (unsigned)status);
    status = glint_closure_add_lobe(grown, conductor, weight, &frame, NULL, 0, NULL);
    CHILD_CHECK(status == GLINT_ERROR_OUT_OF_MEMORY, "add_lobe, heap full -> %u",
                (unsigned)status);
    CHILD_CHECK(strstr(glint_last_error(), "out of memory") != NULL, "add_lobe, heap full");

    /* Memory back: the whole batch works, and so does the closure. */
    free_list(heap);
    check_batches_work(l, COUNT, &warm, "memory freed");
    CHILD_CHECK(glint_closure_add_lobe(grown, conductor, weight, &frame, NULL, 0, NULL) ==
                    GLINT_OK,
                "add_lobe, memory freed");
    CHILD_CHECK(glint_closure_finish(grown) == GLINT_OK, "finish, memory freed");
    {
        const glint_vec3 wo = {0.0f, 0.6f, 0.8f}, wi = {0.0f, -0.6f, 0.8f};
        glint_eval_result r;
        r.struct_size = sizeof r;
        CHILD_CHECK(glint_eval(grown, wo, wi, &r) == GLINT_OK && r.value[0] > 0.0f,
                    "eval, memory freed");
    }
    fprintf(stderr, "child: OK\n");
    free(l);
    glint_arena_destroy(arena);
    glint_runtime_destroy(rt);
    _exit(0);
}

static void staging_out_of_memory_is_an_error_not_an_abort(void **state)
{
    pid_t pid;
    int wstatus = 0;
    (void)state;
#ifdef GLINT_SANITIZED
    print_message("skipped: sanitizer build (ASan's shadow memory does not fit RLIMIT_AS, "
                  "and it replaces malloc)\n");
    skip();
#endif
    if (RUNNING_ON_VALGRIND) {
        print_message("skipped: under valgrind, whose malloc does not reuse freed memory "
                      "at once\n");
        skip();
    }
    fflush(stdout);
    fflush(stderr);
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0)
        child();
    assert_int_equal(waitpid(pid, &wstatus, 0), pid);
    if (WIFSIGNALED(wstatus))
        print_error("the child was killed by signal %d (%s): the library aborted\n",
                    WTERMSIG(wstatus), strsignal(WTERMSIG(wstatus)));
    assert_true(WIFEXITED(wstatus));
    assert_int_equal(WEXITSTATUS(wstatus), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(staging_out_of_memory_is_an_error_not_an_abort),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
