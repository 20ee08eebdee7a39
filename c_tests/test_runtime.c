/* Version, status strings, runtime creation and the lobe registry / parameter schema. */
#include "common.h"

#include <stdlib.h>

static void version_matches_the_header(void **state)
{
    (void)state;
    assert_int_equal(glint_version(),
                     GLINT_VERSION_MAJOR * 10000 + GLINT_VERSION_MINOR * 100 + GLINT_VERSION_PATCH);
}

static void every_status_has_a_string(void **state)
{
    glint_status s;
    (void)state;
    for (s = GLINT_OK; s <= GLINT_ERROR_PLUGIN_BLOCK_SIZE; s++) {
        const char *text = glint_status_string(s);
        assert_non_null(text);
        assert_true(strlen(text) > 0);
    }
    /* Codes this library does not know still get a string. */
    assert_non_null(glint_status_string(GLINT_ERROR_PLUGIN_BLOCK_SIZE + 1));
    assert_non_null(glint_status_string(UINT32_MAX));
    assert_true(strlen(glint_status_string(UINT32_MAX)) > 0);
    /* Distinct codes, distinct descriptions. */
    assert_string_not_equal(glint_status_string(GLINT_OK),
                            glint_status_string(GLINT_ERROR_NULL_POINTER));
    assert_string_not_equal(glint_status_string(GLINT_ERROR_ARENA_FULL),
                            glint_status_string(GLINT_ERROR_CLOSURE_FULL));
}

static void runtime_create_accepts_valid_configs(void **state)
{
    static const char *const configs[] = {"",
                                          "isa=auto",
                                          "isa=scalar",
                                          " isa=scalar ; ",
                                          "isa=auto,isa=scalar",
                                          "isa=auto\tisa=auto",
                                          "threads=0",
                                          "threads=1",
                                          "isa=scalar threads=2",
                                          "stores=auto",
                                          "stores=held threads=1",
                                          "stores=direct"};
    size_t i;
    (void)state;
    for (i = 0; i < sizeof configs / sizeof configs[0]; i++) {
        glint_runtime *rt = NULL;
        assert_ok(glint_runtime_create(configs[i], &rt));
        assert_non_null(rt);
        assert_true(lobe_type_count(rt) > 0);
        glint_runtime_destroy(rt);
    }
    {
        glint_runtime *rt = NULL;
        assert_ok(glint_runtime_create(NULL, &rt));
        assert_non_null(rt);
        glint_runtime_destroy(rt);
    }
    glint_runtime_destroy(NULL); /* ignored */
}

/* Every ISA either runs (and is the one reported) or is refused as unsupported. */
static void every_isa_is_available_or_refused(void **state)
{
    static const char *const isas[] = {"scalar", "avx2", "avx512"};
    fixture *fx = *state;
    const char *isa = NULL;
    size_t i;
    assert_ok(glint_runtime_isa(fx->rt, &isa));
    assert_non_null(isa);
    for (i = 0; i < sizeof isas / sizeof isas[0]; i++) {
        char config[32];
        glint_runtime *rt = NULL;
        glint_status st;
        snprintf(config, sizeof config, "isa=%s", isas[i]);
        st = glint_runtime_create(config, &rt);
        if (st == GLINT_OK) {
            assert_ok(glint_runtime_isa(rt, &isa));
            assert_string_equal(isa, isas[i]);
            glint_runtime_destroy(rt);
        } else {
            check_error(fx, st, GLINT_ERROR_UNSUPPORTED);
            assert_null(rt);
            assert_error_mentions(isas[i]);
            assert_error_mentions("scalar"); /* names what is supported */
        }
    }
    check_error(fx, glint_runtime_isa(NULL, &isa), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_runtime_isa(fx->rt, NULL), GLINT_ERROR_NULL_POINTER);
}

static void runtime_create_errors(void **state)
{
    fixture *fx = *state;
    glint_runtime *rt = (glint_runtime *)fx; /* garbage: must be overwritten with NULL */

    check_error(fx, glint_runtime_create("frobnicate=1", &rt), GLINT_ERROR_UNKNOWN_NAME);
    assert_null(rt);
    assert_error_mentions("frobnicate");
    assert_error_mentions("isa"); /* lists the valid keys */

    check_error(fx, glint_runtime_create("isa=auto frobnicate=1", &rt), GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("frobnicate");

    check_error(fx, glint_runtime_create("isa", &rt), GLINT_ERROR_PARSE);
    assert_error_mentions("isa");
    check_error(fx, glint_runtime_create("isa=quantum", &rt), GLINT_ERROR_OUT_OF_RANGE);
    assert_error_mentions("quantum");
    assert_error_mentions("scalar");
    check_error(fx, glint_runtime_create("threads=-1", &rt), GLINT_ERROR_OUT_OF_RANGE);
    assert_error_mentions("threads");
    check_error(fx, glint_runtime_create("threads=many", &rt), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_runtime_create("stores=sometimes", &rt), GLINT_ERROR_OUT_OF_RANGE);
    assert_null(rt);
    assert_error_mentions("sometimes");
    assert_error_mentions("auto, held, direct");
    check_error(fx, glint_runtime_create("\xff\xfe=1", &rt), GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_runtime_create(NULL, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_runtime_create("isa=auto", NULL), GLINT_ERROR_NULL_POINTER);
}

static void lobe_types_enumerate_and_find(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt), id;
    assert_true(n >= 1);
    for (id = 0; id < n; id++) {
        glint_lobe_info info = lobe_type(fx->rt, id);
        uint32_t found = UINT32_MAX, other;
        assert_int_equal(info.struct_size, sizeof info);
        assert_non_null(info.name);
        assert_true(strlen(info.name) > 0);
        assert_non_null(info.summary);
        assert_true(strlen(info.summary) > 0);
        assert_true(info.reciprocal == 0 || info.reciprocal == 1);
        /* At least one side and one class, nothing else. */
        assert_true(info.flags & (GLINT_FLAG_REFLECTION | GLINT_FLAG_TRANSMISSION));
        assert_true(info.flags & (GLINT_FLAG_DIFFUSE | GLINT_FLAG_GLOSSY | GLINT_FLAG_SPECULAR));
        assert_int_equal(info.flags & ~(uint32_t)31, 0);
        assert_true(info.param_block_size >= info.param_count);
        assert_ok(glint_lobe_type_find(fx->rt, info.name, &found));
        assert_int_equal(found, id);
        /* Names are unique. */
        for (other = 0; other < id; other++)
            assert_string_not_equal(lobe_type(fx->rt, other).name, info.name);
    }
}

static void lobe_type_query_errors(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt), out = 12345;
    glint_lobe_info info = lobe_info_init();

    check_error(fx, glint_lobe_type_count(NULL, &out), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_type_count(fx->rt, NULL), GLINT_ERROR_NULL_POINTER);

    check_error(fx, glint_lobe_type_find(fx->rt, "velvet", &out), GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("velvet");
    assert_error_mentions(lobe_type(fx->rt, 0).name); /* lists the valid types */
    assert_int_equal(out, 0); /* zeroed on failure */
    check_error(fx, glint_lobe_type_find(fx->rt, "", &out), GLINT_ERROR_UNKNOWN_NAME);
    check_error(fx, glint_lobe_type_find(fx->rt, "\xc3\x28", &out), GLINT_ERROR_INVALID_ARGUMENT);
    check_error(fx, glint_lobe_type_find(NULL, "lambert", &out), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_type_find(fx->rt, NULL, &out), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_type_find(fx->rt, lobe_type(fx->rt, 0).name, NULL),
                GLINT_ERROR_NULL_POINTER);

    check_error(fx, glint_lobe_type_info(fx->rt, n, &info), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_lobe_type_info(fx->rt, UINT32_MAX, &info), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_lobe_type_info(NULL, 0, &info), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_type_info(fx->rt, 0, NULL), GLINT_ERROR_NULL_POINTER);
    info.struct_size = sizeof info - 1;
    check_error(fx, glint_lobe_type_info(fx->rt, 0, &info), GLINT_ERROR_STRUCT_SIZE);
    info.struct_size = 0;
    check_error(fx, glint_lobe_type_info(fx->rt, 0, &info), GLINT_ERROR_STRUCT_SIZE);
    assert_null(info.name); /* untouched */
}

/* A caller compiled against a newer, larger struct is accepted. */
static void larger_struct_size_is_accepted(void **state)
{
    fixture *fx = *state;
    struct {
        glint_lobe_info info;
        unsigned char future[32];
    } big;
    struct {
        glint_param_info info;
        unsigned char future[32];
    } bigp;
    memset(&big, 0xab, sizeof big);
    big.info.struct_size = sizeof big;
    assert_ok(glint_lobe_type_info(fx->rt, 0, &big.info));
    assert_int_equal(big.info.struct_size, sizeof big);
    assert_non_null(big.info.name);
    assert_int_equal(big.future[31], 0xab);

    memset(&bigp, 0xab, sizeof bigp);
    bigp.info.struct_size = sizeof bigp;
    assert_ok(glint_lobe_param_info(fx->rt, 0, 0, &bigp.info));
    assert_int_equal(bigp.info.struct_size, sizeof bigp);
    assert_non_null(bigp.info.name);
    assert_int_equal(bigp.future[31], 0xab);
}

/* component_count: 2 for the dielectric (reflection, transmission), 1 for the other
 * built-ins; every type's samples report a component below it, and the dielectric
 * reports both of its own. */
static void lobe_info_counts_components(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt), id;
    const glint_vec3 wo = test_wo();
    for (id = 0; id < n; id++) {
        glint_lobe_info t = lobe_type(fx->rt, id);
        int dielectric = strcmp(t.name, "dielectric") == 0;
        int seen[2] = {0, 0};
        glint_closure *c;
        lcg g;
        int i;
        assert_int_equal(t.component_count, dielectric ? 2u : 1u);
        assert_ok(glint_arena_reset(fx->arena));
        c = single_lobe_closure(fx, id, NULL, 0, &wo);
        lcg_seed(&g, id + 1);
        for (i = 0; i < 512; i++) {
            glint_sample_result s = sample_result_init();
            float u_c = lcg_next(&g), u0 = lcg_next(&g), u1 = lcg_next(&g);
            glint_status st = glint_sample_lobe(c, 0, wo, u_c, u0, u1, &s);
            assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
            assert_true(s.component < t.component_count);
            seen[s.component > 0]++;
        }
        if (dielectric)
            assert_true(seen[0] > 0 && seen[1] > 0);
    }
}

/* A caller built before component_count was appended passes the older struct_size: the
 * fields it knows are filled, nothing past them is written; a size that cuts the new
 * field is refused. */
static void lobe_info_takes_the_older_size(void **state)
{
    fixture *fx = *state;
    const size_t old_size = offsetof(glint_lobe_info, component_count);
    const uint32_t id = lobe_id(fx->rt, "dielectric");
    const glint_lobe_info full = lobe_type(fx->rt, id);
    union {
        glint_lobe_info info;
        unsigned char bytes[sizeof(glint_lobe_info) + 8];
    } u;
    size_t i;
    memset(&u, 0xab, sizeof u);
    u.info.struct_size = (uint32_t)old_size;
    assert_ok(glint_lobe_type_info(fx->rt, id, &u.info));
    assert_int_equal(u.info.struct_size, old_size);
    assert_string_equal(u.info.name, "dielectric");
    assert_int_equal(u.info.flags, full.flags);
    assert_int_equal(u.info.param_block_size, full.param_block_size);
    for (i = old_size; i < sizeof u.bytes; i++)
        assert_int_equal(u.bytes[i], 0xab);

    memset(&u, 0xab, sizeof u);
    u.info.struct_size = (uint32_t)old_size + 1;
    check_error(fx, glint_lobe_type_info(fx->rt, 0, &u.info), GLINT_ERROR_STRUCT_SIZE);
    assert_error_mentions("struct_size");
    for (i = sizeof u.info.struct_size; i < sizeof u.bytes; i++)
        assert_int_equal(u.bytes[i], 0xab);
}

static void param_schema_is_consistent(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt), id;
    for (id = 0; id < n; id++) {
        glint_lobe_info t = lobe_type(fx->rt, id);
        float *defaults = calloc(t.param_block_size + 1, sizeof *defaults);
        uint32_t i, covered = 0;
        assert_non_null(defaults);
        defaults[t.param_block_size] = -7.0f;
        assert_ok(glint_lobe_param_defaults(fx->rt, id, defaults, t.param_block_size + 1));
        assert_true(defaults[t.param_block_size] == -7.0f); /* writes only the block */
        assert_ok(glint_lobe_param_defaults(fx->rt, id, defaults, t.param_block_size));
        for (i = 0; i < t.param_count; i++) {
            glint_param_info p = param_info_init();
            uint32_t found = UINT32_MAX, k;
            assert_ok(glint_lobe_param_info(fx->rt, id, i, &p));
            assert_int_equal(p.struct_size, sizeof p);
            assert_non_null(p.name);
            assert_true(strlen(p.name) > 0);
            assert_non_null(p.doc);
            assert_non_null(p.choices);
            assert_true(p.offset + p.size <= t.param_block_size);
            /* Parameters are laid out one after the other. */
            assert_int_equal(p.offset, covered);
            covered += p.size;
            assert_true(p.min <= p.max);
            switch (p.param_type) {
            case GLINT_PARAM_FLOAT:
                assert_int_equal(p.size, 1);
                assert_int_equal(p.choice_count, 0);
                assert_string_equal(p.choices, "");
                break;
            case GLINT_PARAM_RGB:
                assert_int_equal(p.size, 3);
                assert_int_equal(p.choice_count, 0);
                assert_string_equal(p.choices, "");
                break;
            case GLINT_PARAM_ENUM: {
                /* choices: choice_count names separated by '|', each round-trips. */
                char buf[256];
                char *tok, *rest;
                uint32_t c = 0;
                assert_int_equal(p.size, 1);
                assert_true(p.choice_count >= 1);
                assert_true(p.min == 0.0f);
                assert_true(p.max == (float)(p.choice_count - 1));
                assert_true(strlen(p.choices) < sizeof buf);
                strcpy(buf, p.choices);
                for (tok = buf; tok != NULL; tok = rest, c++) {
                    float value = -1.0f;
                    rest = strchr(tok, '|');
                    if (rest != NULL)
                        *rest++ = '\0';
                    assert_true(strlen(tok) > 0);
                    assert_ok(glint_lobe_param_choice(fx->rt, id, i, tok, &value));
                    assert_true(value == (float)c);
                }
                assert_int_equal(c, p.choice_count);
                assert_true(p.default_value[0] == floorf(p.default_value[0]));
                break;
            }
            default:
                fail_msg("%s.%s: unknown param_type %u", t.name, p.name, (unsigned)p.param_type);
            }
            for (k = 0; k < p.size; k++) {
                assert_finite(p.default_value[k]);
                assert_true(p.default_value[k] >= p.min);
                assert_true(p.default_value[k] <= p.max);
                assert_true(defaults[p.offset + k] == p.default_value[k]);
            }
            assert_ok(glint_lobe_param_find(fx->rt, id, p.name, &found));
            assert_int_equal(found, i);
        }
        assert_int_equal(covered, t.param_block_size);
        free(defaults);
    }
}

static void param_choice_by_name(void **state)
{
    fixture *fx = *state;
    uint32_t conductor = lobe_id(fx->rt, "conductor");
    uint32_t distribution = UINT32_MAX, fresnel = UINT32_MAX;
    float value = -1.0f;
    assert_ok(glint_lobe_param_find(fx->rt, conductor, "distribution", &distribution));
    assert_ok(glint_lobe_param_choice(fx->rt, conductor, distribution, "beckmann", &value));
    assert_true(value == 1.0f);
    assert_ok(glint_lobe_param_choice(fx->rt, conductor, distribution, "ggx", &value));
    assert_true(value == 0.0f);
    assert_ok(glint_lobe_param_find(fx->rt, conductor, "fresnel", &fresnel));
    assert_ok(glint_lobe_param_choice(fx->rt, conductor, fresnel, "artistic", &value));
    assert_true(value == 2.0f);
}

static void param_query_errors(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt);
    uint32_t conductor = lobe_id(fx->rt, "conductor");
    glint_lobe_info ci = lobe_type(fx->rt, conductor);
    uint32_t distribution = UINT32_MAX, roughness = UINT32_MAX, out = 777;
    glint_param_info p = param_info_init();
    float value = -1.0f;
    float *block = calloc(ci.param_block_size, sizeof *block);
    assert_non_null(block);
    assert_ok(glint_lobe_param_find(fx->rt, conductor, "distribution", &distribution));
    assert_ok(glint_lobe_param_find(fx->rt, conductor, "roughness", &roughness));

    /* glint_lobe_param_info */
    check_error(fx, glint_lobe_param_info(NULL, conductor, 0, &p), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_param_info(fx->rt, conductor, 0, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_param_info(fx->rt, n, 0, &p), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_lobe_param_info(fx->rt, conductor, ci.param_count, &p),
                GLINT_ERROR_OUT_OF_RANGE);
    assert_error_mentions("conductor");
    p.struct_size = sizeof p - 1;
    check_error(fx, glint_lobe_param_info(fx->rt, conductor, 0, &p), GLINT_ERROR_STRUCT_SIZE);
    p.struct_size = 4;
    check_error(fx, glint_lobe_param_info(fx->rt, conductor, 0, &p), GLINT_ERROR_STRUCT_SIZE);
    assert_null(p.name); /* untouched */

    /* glint_lobe_param_find */
    check_error(fx, glint_lobe_param_find(fx->rt, conductor, "roughnes", &out),
                GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("roughnes");
    assert_error_mentions("roughness"); /* lists the valid names */
    assert_error_mentions("distribution");
    assert_int_equal(out, 0);
    check_error(fx, glint_lobe_param_find(fx->rt, conductor, "", &out), GLINT_ERROR_UNKNOWN_NAME);
    check_error(fx, glint_lobe_param_find(NULL, conductor, "roughness", &out),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_param_find(fx->rt, conductor, NULL, &out), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_param_find(fx->rt, conductor, "roughness", NULL),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_param_find(fx->rt, n, "roughness", &out), GLINT_ERROR_OUT_OF_RANGE);

    /* glint_lobe_param_choice */
    check_error(fx, glint_lobe_param_choice(fx->rt, conductor, distribution, "phong", &value),
                GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("phong");
    assert_error_mentions("ggx");
    assert_error_mentions("beckmann");
    assert_true(value == 0.0f); /* zeroed on failure */
    check_error(fx, glint_lobe_param_choice(fx->rt, conductor, distribution, "GGX", &value),
                GLINT_ERROR_UNKNOWN_NAME);
    check_error(fx, glint_lobe_param_choice(fx->rt, conductor, roughness, "ggx", &value),
                GLINT_ERROR_INVALID_ARGUMENT);
    assert_error_mentions("roughness");
    check_error(fx, glint_lobe_param_choice(fx->rt, conductor, ci.param_count, "ggx", &value),
                GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_lobe_param_choice(fx->rt, n, 0, "ggx", &value), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_lobe_param_choice(NULL, conductor, distribution, "ggx", &value),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_param_choice(fx->rt, conductor, distribution, NULL, &value),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_param_choice(fx->rt, conductor, distribution, "ggx", NULL),
                GLINT_ERROR_NULL_POINTER);

    /* glint_lobe_param_defaults */
    check_error(fx, glint_lobe_param_defaults(fx->rt, conductor, block, ci.param_block_size - 1),
                GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_lobe_param_defaults(fx->rt, conductor, block, 0), GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_lobe_param_defaults(fx->rt, n, block, ci.param_block_size),
                GLINT_ERROR_OUT_OF_RANGE);
    check_error(fx, glint_lobe_param_defaults(NULL, conductor, block, ci.param_block_size),
                GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_param_defaults(fx->rt, conductor, NULL, ci.param_block_size),
                GLINT_ERROR_NULL_POINTER);
    free(block);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(version_matches_the_header),
        cmocka_unit_test(every_status_has_a_string),
        cmocka_unit_test(runtime_create_accepts_valid_configs),
        cmocka_unit_test_setup_teardown(runtime_create_errors, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(every_isa_is_available_or_refused, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(lobe_types_enumerate_and_find, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(lobe_type_query_errors, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(larger_struct_size_is_accepted, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(lobe_info_counts_components, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(lobe_info_takes_the_older_size, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(param_schema_is_consistent, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(param_choice_by_name, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(param_query_errors, fixture_setup, fixture_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
