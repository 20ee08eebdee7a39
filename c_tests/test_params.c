/* Parameter schemas through the C API: every lobe and material schema walked as a
 * host walks a nested one (shape, parent, members, capacity, count and element
 * offsets covering the block exactly once, names found back), the first version of
 * glint_param_info still accepted, and element addresses (GLINT_PARAM_ELEMENT_SHIFT)
 * in lookups and overrides, with their errors. No built-in type has a nested schema
 * yet: tests/params.rs lays out, parses and overrides one (groups, arrays, a table). */
#include "common.h"

#include <stdlib.h>

/* glint_param_info as first published (through `doc`). */
typedef struct param_info_v1 {
    uint32_t struct_size;
    const char *name;
    uint32_t param_type;
    uint32_t offset;
    uint32_t size;
    float default_value[3];
    float min;
    float max;
    uint32_t choice_count;
    const char *choices;
    const char *doc;
} param_info_v1;

typedef glint_status (*info_fn)(const glint_runtime *, uint32_t, uint32_t, glint_param_info *);
typedef glint_status (*find_fn)(const glint_runtime *, uint32_t, const char *, uint32_t *);

/* Mark block[at .. at + n) covered, each float once. */
static void cover(unsigned char *covered, uint32_t block_size, uint32_t at, uint32_t n)
{
    assert_true(at + n <= block_size);
    for (uint32_t k = at; k < at + n; k++) {
        assert_int_equal(covered[k], 0);
        covered[k] = 1;
    }
}

/* Walk schema `id` of `param_count` entries over a block of `block_size` floats. */
static void walk(const fixture *fx, info_fn info, find_fn find, uint32_t id, uint32_t param_count,
                 uint32_t block_size)
{
    unsigned char *covered = calloc(block_size + 1, 1);
    assert_non_null(covered);
    for (uint32_t i = 0; i < param_count; i++) {
        glint_param_info p = param_info_init();
        assert_ok(info(fx->rt, id, i, &p));
        assert_non_null(p.name);
        uint32_t found = GLINT_PARAM_NO_INDEX;
        assert_ok(find(fx->rt, id, p.name, &found));
        assert_int_equal(found, i);
        if (p.parent != GLINT_PARAM_NO_INDEX) {
            glint_param_info h = param_info_init();
            assert_true(p.parent < i);
            assert_ok(info(fx->rt, id, p.parent, &h));
            assert_true(h.shape == GLINT_SHAPE_GROUP || h.shape == GLINT_SHAPE_TABLE);
            assert_true(p.parent + h.member_count >= i);
            size_t n = strlen(h.name);
            assert_int_equal(strncmp(p.name, h.name, n), 0);
            assert_int_equal(p.name[n], '.');
            assert_int_equal(p.shape == GLINT_SHAPE_COLUMN, h.shape == GLINT_SHAPE_TABLE);
        }
        switch (p.shape) {
        case GLINT_SHAPE_VALUE:
            assert_true(p.param_type <= GLINT_PARAM_ENUM);
            assert_int_equal(p.capacity, 0);
            assert_int_equal(p.count_offset, GLINT_PARAM_NO_INDEX);
            cover(covered, block_size, p.offset, p.size);
            break;
        case GLINT_SHAPE_ARRAY:
            assert_int_equal(p.count_offset + 1, p.offset);
            cover(covered, block_size, p.count_offset, 1);
            /* fall through - the elements */
        case GLINT_SHAPE_COLUMN:
            assert_true(p.capacity >= 1 && p.capacity <= 16);
            assert_true(p.param_type == GLINT_PARAM_FLOAT || p.param_type == GLINT_PARAM_RGB);
            cover(covered, block_size, p.offset, p.capacity * p.size);
            break;
        case GLINT_SHAPE_TABLE:
            assert_int_equal(p.count_offset, p.offset);
            assert_true(p.default_count <= p.capacity);
            cover(covered, block_size, p.offset, 1);
            /* fall through - a header */
        case GLINT_SHAPE_GROUP:
            assert_int_equal(p.param_type, GLINT_PARAM_NONE);
            assert_true(p.member_count >= 1 && i + p.member_count < param_count);
            break;
        default:
            fail_msg("%s: unknown shape %u", p.name, p.shape);
        }
        if (p.shape != GLINT_SHAPE_GROUP && p.shape != GLINT_SHAPE_TABLE)
            assert_int_equal(p.member_count, 0);
    }
    for (uint32_t k = 0; k < block_size; k++)
        assert_int_equal(covered[k], 1);
    free(covered);
}

static void every_schema_walks(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt);
    for (uint32_t id = 0; id < n; id++) {
        glint_lobe_info t = lobe_type(fx->rt, id);
        walk(fx, glint_lobe_param_info, glint_lobe_param_find, id, t.param_count,
             t.param_block_size);
    }
    uint32_t m = 0;
    assert_ok(glint_material_type_count(fx->rt, &m));
    assert_true(m >= 1);
    for (uint32_t id = 0; id < m; id++) {
        glint_material_info t;
        memset(&t, 0, sizeof t);
        t.struct_size = sizeof t;
        assert_ok(glint_material_type_info(fx->rt, id, &t));
        walk(fx, glint_material_param_info, glint_material_param_find, id, t.param_count,
             t.param_block_size);
    }
}

static void first_version_of_param_info_still_works(void **state)
{
    fixture *fx = *state;
    uint32_t conductor = lobe_id(fx->rt, "conductor");
    assert_int_equal(offsetof(glint_param_info, shape), sizeof(param_info_v1));
    glint_param_info full = param_info_init();
    assert_ok(glint_lobe_param_info(fx->rt, conductor, 1, &full));
    struct {
        param_info_v1 info;
        unsigned char after[32];
    } old;
    memset(&old, 0xab, sizeof old);
    old.info.struct_size = sizeof old.info;
    assert_ok(glint_lobe_param_info(fx->rt, conductor, 1, (glint_param_info *)&old.info));
    assert_int_equal(old.info.struct_size, sizeof old.info);
    assert_ptr_equal(old.info.name, full.name);
    assert_string_equal(old.info.name, "roughness");
    assert_int_equal(old.info.offset, full.offset);
    assert_int_equal(old.info.size, 1);
    assert_true(old.info.min == full.min && old.info.max == full.max);
    assert_ptr_equal(old.info.doc, full.doc);
    for (size_t k = 0; k < sizeof old.after; k++)
        assert_int_equal(old.after[k], 0xab);
    /* A failure leaves the old struct's failure state, and still writes nothing more. */
    check_error(fx, glint_lobe_param_info(fx->rt, conductor, 999, (glint_param_info *)&old.info),
                GLINT_ERROR_OUT_OF_RANGE);
    assert_null(old.info.name);
    assert_int_equal(old.after[0], 0xab);
    /* Sizes between the two versions, or below the first, are refused untouched. */
    glint_param_info p = param_info_init();
    uint32_t bad[] = {(uint32_t)sizeof(param_info_v1) + 4, (uint32_t)sizeof p - 1,
                      (uint32_t)sizeof(param_info_v1) - 1, 0};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        p = param_info_init();
        p.struct_size = bad[k];
        p.name = "untouched";
        check_error(fx, glint_lobe_param_info(fx->rt, conductor, 0, &p), GLINT_ERROR_STRUCT_SIZE);
        assert_string_equal(p.name, "untouched");
        check_error(fx, glint_material_param_info(fx->rt, 0, 0, &p), GLINT_ERROR_STRUCT_SIZE);
        assert_error_mentions("struct_size");
    }
    check_error(fx, glint_material_param_info(fx->rt, 0, 0, NULL), GLINT_ERROR_NULL_POINTER);
    check_error(fx, glint_lobe_param_info(NULL, 0, 0, &full), GLINT_ERROR_NULL_POINTER);
    assert_null(full.name);
}

static void element_addresses_and_their_errors(void **state)
{
    fixture *fx = *state;
    uint32_t disney = 99, roughness = 99, out = 7;
    assert_ok(glint_material_type_find(fx->rt, "disney", &disney));
    assert_ok(glint_material_param_find(fx->rt, disney, "roughness", &roughness));
    const char *bad_names[] = {"roughness[0]", "roughness[1]", "base_color.r", "[0]",
                               "roughness[", "roughness[]x", ""};
    for (size_t k = 0; k < sizeof bad_names / sizeof bad_names[0]; k++) {
        check_error(fx, glint_material_param_find(fx->rt, disney, bad_names[k], &out),
                    GLINT_ERROR_UNKNOWN_NAME);
        assert_int_equal(out, 0);
    }
    check_error(fx, glint_material_param_find(fx->rt, disney, NULL, &out),
                GLINT_ERROR_NULL_POINTER);
    /* Info takes entry indices only. */
    glint_param_info p = param_info_init();
    check_error(fx, glint_material_param_info(fx->rt, disney, roughness | 1u << GLINT_PARAM_ELEMENT_SHIFT, &p),
                GLINT_ERROR_OUT_OF_RANGE);

    glint_material *m = NULL;
    assert_ok(glint_material_create(fx->rt, "{\"material\": \"disney\"}", &m));
    glint_shading_context ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.struct_size = sizeof ctx;
    ctx.wo = test_wo();
    ctx.normal = v3(0.0f, 0.0f, 1.0f);
    glint_override o = {.param = roughness, .param_type = GLINT_PARAM_FLOAT, .value = {0.2f}};
    glint_closure *c = NULL;
    assert_ok(glint_material_closure(m, fx->arena, &ctx, &o, 1, &c));
    /* Element 0 of a single value is the value itself; any other element is not. */
    o.param = roughness | 0u << GLINT_PARAM_ELEMENT_SHIFT;
    assert_ok(glint_material_closure(m, fx->arena, &ctx, &o, 1, &c));
    o.param = roughness | 1u << GLINT_PARAM_ELEMENT_SHIFT;
    check_error(fx, glint_material_closure(m, fx->arena, &ctx, &o, 1, &c), GLINT_ERROR_OUT_OF_RANGE);
    assert_error_mentions("element 1 of disney.roughness does not exist");
    assert_null(c);
    o.param = UINT32_MAX;
    check_error(fx, glint_material_closure(m, fx->arena, &ctx, &o, 1, &c), GLINT_ERROR_OUT_OF_RANGE);
    assert_error_mentions("overrides[0]");
    glint_material_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(every_schema_walks, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(first_version_of_param_info_still_works, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(element_addresses_and_their_errors, fixture_setup,
                                        fixture_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
