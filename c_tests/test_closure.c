/* Positive paths: every registered lobe type alone, a JSON closure mixing them all,
 * eval / sample / pdf / albedo on the closure and per lobe, frames and transport. */
#include "common.h"

#include <stdlib.h>

#define SAMPLES 96

/* Fixed test directions: above, grazing-ish, below (transmission side). */
static glint_vec3 fixed_wi(int i)
{
    switch (i) {
    case 0:
        return v3_normalize(v3(-0.4f, 0.1f, 0.8f));
    case 1:
        return v3_normalize(v3(-0.3f, -0.2f, 0.9f)); /* near the mirror direction of wo */
    case 2:
        return v3_normalize(v3(0.9f, -0.3f, 0.1f));
    case 3:
        return v3_normalize(v3(-0.2f, -0.1f, -0.9f)); /* below: transmission */
    default:
        return v3_normalize(v3(0.5f, 0.5f, -0.3f));
    }
}
#define FIXED_WI_COUNT 5

static int is_one_bit(uint32_t x)
{
    return x != 0 && (x & (x - 1)) == 0;
}

/* A sample carries exactly one side and one class, within what the lobe type declares. */
static void check_sample_flags(uint32_t flags, uint32_t allowed)
{
    const uint32_t side = GLINT_FLAG_REFLECTION | GLINT_FLAG_TRANSMISSION;
    const uint32_t cls = GLINT_FLAG_DIFFUSE | GLINT_FLAG_GLOSSY | GLINT_FLAG_SPECULAR;
    assert_true(is_one_bit(flags & side));
    assert_true(is_one_bit(flags & cls));
    assert_int_equal(flags & ~(side | cls), 0);
    if (allowed != 0) {
        if ((flags & ~allowed) != 0)
            print_error("flags %#x not within the lobe type's %#x\n", (unsigned)flags,
                        (unsigned)allowed);
        assert_int_equal(flags & ~allowed, 0);
    }
}

static void check_sample_basics(const glint_sample_result *s, uint32_t allowed)
{
    int k;
    assert_int_equal(s->struct_size, sizeof *s);
    assert_finite(s->wi.x);
    assert_finite(s->wi.y);
    assert_finite(s->wi.z);
    assert_close(v3_length(s->wi), 1.0f, 1e-5f);
    assert_finite(s->pdf);
    assert_true(s->pdf > 0.0f);
    for (k = 0; k < 3; k++) {
        assert_finite_nonneg(s->value[k]);
        assert_finite_nonneg(s->weight[k]);
        assert_close(s->weight[k], s->value[k] / s->pdf, 1e-5f);
    }
    check_sample_flags(s->flags, allowed);
    assert_finite(s->eta);
    assert_true(s->eta > 0.0f);
    assert_true(s->roughness >= 0.0f && s->roughness <= 1.0f);
    if (s->flags & GLINT_FLAG_SPECULAR)
        assert_true(s->roughness == 0.0f);
    if (s->flags & GLINT_FLAG_REFLECTION)
        assert_true(s->eta == 1.0f);
}

static void check_zeroed_sample(const glint_sample_result *s)
{
    assert_int_equal(s->struct_size, sizeof *s);
    assert_true(s->wi.x == 0.0f && s->wi.y == 0.0f && s->wi.z == 0.0f);
    assert_true(s->value[0] == 0.0f && s->value[1] == 0.0f && s->value[2] == 0.0f);
    assert_true(s->weight[0] == 0.0f && s->weight[1] == 0.0f && s->weight[2] == 0.0f);
    assert_true(s->pdf == 0.0f);
    assert_int_equal(s->flags, 0);
}

static void check_eval_result(const glint_eval_result *r)
{
    assert_int_equal(r->struct_size, sizeof *r);
    assert_finite_nonneg(r->value[0]);
    assert_finite_nonneg(r->value[1]);
    assert_finite_nonneg(r->value[2]);
    assert_finite_nonneg(r->pdf);
    assert_finite_nonneg(r->pdf_reverse);
}

/* Everything about a finished closure of one lobe of type `t`. */
static void check_single_lobe_closure(const glint_closure *c, uint32_t id, const glint_lobe_info *t,
                                      uint64_t seed)
{
    const glint_vec3 wo = test_wo();
    uint32_t count = 0, type_id = UINT32_MAX;
    float probability = -1.0f, albedo[3] = {-1, -1, -1}, albedo_lobe[3] = {-1, -1, -1};
    int i, k, valid = 0;
    lcg g;

    assert_ok(glint_closure_lobe_count(c, &count));
    assert_int_equal(count, 1);
    assert_ok(glint_closure_lobe(c, 0, &type_id, &probability));
    assert_int_equal(type_id, id);
    assert_true(probability == 1.0f);

    assert_ok(glint_albedo(c, wo, albedo));
    assert_ok(glint_albedo_lobe(c, 0, wo, albedo_lobe));
    for (k = 0; k < 3; k++) {
        assert_finite_nonneg(albedo[k]);
        assert_close(albedo_lobe[k], albedo[k], 1e-6f);
    }

    for (i = 0; i < FIXED_WI_COUNT; i++) {
        glint_vec3 wi = fixed_wi(i);
        glint_eval_result e = eval_result_init(), el = eval_result_init();
        float pdf = -1.0f, pdf_lobe = -1.0f, pdf_back = -1.0f;
        assert_ok(glint_eval(c, wo, wi, &e));
        check_eval_result(&e);
        assert_ok(glint_eval_lobe(c, 0, wo, wi, &el));
        check_eval_result(&el);
        /* The forward calls: the same value and pdf, bit for bit, and no reverse pdf. */
        {
            glint_eval_result f = eval_result_init(), fl = eval_result_init();
            f.pdf_reverse = fl.pdf_reverse = -7.0f;
            assert_ok(glint_eval_forward(c, wo, wi, &f));
            assert_ok(glint_eval_lobe_forward(c, 0, wo, wi, &fl));
            assert_memory_equal(f.value, e.value, sizeof f.value);
            assert_memory_equal(fl.value, el.value, sizeof fl.value);
            assert_memory_equal(&f.pdf, &e.pdf, sizeof f.pdf);
            assert_memory_equal(&fl.pdf, &el.pdf, sizeof fl.pdf);
            assert_true(f.pdf_reverse == 0.0f && fl.pdf_reverse == 0.0f);
        }
        assert_ok(glint_pdf(c, wo, wi, &pdf));
        assert_ok(glint_pdf_lobe(c, 0, wo, wi, &pdf_lobe));
        assert_ok(glint_pdf(c, wi, wo, &pdf_back));
        assert_close(e.pdf, pdf, 1e-6f);
        assert_close(e.pdf_reverse, pdf_back, 1e-6f);
        assert_close(el.pdf, pdf_lobe, 1e-6f);
        assert_close(pdf_lobe, pdf, 1e-6f);
        for (k = 0; k < 3; k++)
            assert_close(el.value[k], e.value[k], 1e-6f);
        /* Directions need not be normalized. */
        {
            glint_eval_result e2 = eval_result_init();
            assert_ok(glint_eval(c, v3(wo.x * 3, wo.y * 3, wo.z * 3),
                                 v3(wi.x * 0.5f, wi.y * 0.5f, wi.z * 0.5f), &e2));
            for (k = 0; k < 3; k++)
                assert_close(e2.value[k], e.value[k], 1e-5f);
            assert_close(e2.pdf, e.pdf, 1e-5f);
        }
    }

    lcg_seed(&g, seed);
    for (i = 0; i < SAMPLES; i++) {
        float u_lobe = lcg_next(&g), u0 = lcg_next(&g), u1 = lcg_next(&g);
        glint_sample_result s = sample_result_init(), sl = sample_result_init();
        glint_status st = glint_sample(c, wo, u_lobe, u0, u1, &s);
        glint_status stl = glint_sample_lobe(c, 0, wo, u_lobe, u0, u1, &sl);
        if (st != GLINT_OK && st != GLINT_NO_SAMPLE)
            print_error("glint_sample(%s): %u %s\n", t->name, (unsigned)st, glint_last_error());
        assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
        /* One lobe chosen with probability 1: the lobe's own sample is the same. */
        assert_int_equal(stl, st);
        if (st == GLINT_NO_SAMPLE) {
            check_zeroed_sample(&s);
            check_zeroed_sample(&sl);
            continue;
        }
        valid++;
        check_sample_basics(&s, t->flags);
        check_sample_basics(&sl, t->flags);
        assert_int_equal(s.lobe, 0);
        assert_int_equal(sl.flags, s.flags);
        assert_close(sl.wi.x, s.wi.x, 1e-6f);
        assert_close(sl.wi.y, s.wi.y, 1e-6f);
        assert_close(sl.wi.z, s.wi.z, 1e-6f);
        assert_close(sl.pdf, s.pdf, 1e-6f);
        for (k = 0; k < 3; k++)
            assert_close(sl.value[k], s.value[k], 1e-6f);
        /* The frame is +z: the side flag matches the hemisphere of wi. */
        if (s.flags & GLINT_FLAG_REFLECTION)
            assert_true(s.wi.z > 0.0f);
        else
            assert_true(s.wi.z < 0.0f);
        {
            glint_eval_result e = eval_result_init(), el = eval_result_init();
            float pdf = -1.0f, pdf_lobe = -1.0f;
            assert_ok(glint_eval(c, wo, s.wi, &e));
            assert_ok(glint_eval_lobe(c, 0, wo, s.wi, &el));
            assert_ok(glint_pdf(c, wo, s.wi, &pdf));
            assert_ok(glint_pdf_lobe(c, 0, wo, s.wi, &pdf_lobe));
            check_eval_result(&e);
            if (s.flags & GLINT_FLAG_SPECULAR) {
                /* A delta lobe: eval and pdf are 0 everywhere. */
                for (k = 0; k < 3; k++) {
                    assert_true(e.value[k] == 0.0f);
                    assert_true(el.value[k] == 0.0f);
                }
                assert_true(e.pdf == 0.0f);
                assert_true(pdf == 0.0f);
                assert_true(pdf_lobe == 0.0f);
            } else {
                assert_close(pdf, s.pdf, 1e-3f);
                assert_close(e.pdf, s.pdf, 1e-3f);
                assert_close(pdf_lobe, s.pdf, 1e-3f);
                for (k = 0; k < 3; k++) {
                    assert_close(e.value[k], s.value[k], 1e-3f);
                    assert_close(el.value[k], s.value[k], 1e-3f);
                }
            }
        }
    }
    /* From wo above the surface, every lobe type scatters most of the time. */
    if (valid < SAMPLES / 2)
        print_error("%s: only %d of %d samples valid\n", t->name, valid, SAMPLES);
    assert_true(valid >= SAMPLES / 2);
}

static void every_lobe_type_alone(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo();
    uint32_t n = lobe_type_count(fx->rt), id;
    for (id = 0; id < n; id++) {
        glint_lobe_info t = lobe_type(fx->rt, id);
        float *block = calloc(t.param_block_size, sizeof *block);
        uint32_t roughness = UINT32_MAX;
        assert_non_null(block);
        assert_ok(glint_lobe_param_defaults(fx->rt, id, block, t.param_block_size));
        print_message("lobe %u: %s (%u params, %u floats)\n", (unsigned)id, t.name,
                      (unsigned)t.param_count, (unsigned)t.param_block_size);

        /* Default parameters: params NULL, count 0; with and without a wo at creation. */
        check_single_lobe_closure(single_lobe_closure(fx, id, NULL, 0, NULL), id, &t, 1 + id);
        check_single_lobe_closure(single_lobe_closure(fx, id, NULL, 0, &wo), id, &t, 2 + id);
        /* The default block from glint_lobe_param_defaults. */
        check_single_lobe_closure(single_lobe_closure(fx, id, block, t.param_block_size, NULL),
                                  id, &t, 3 + id);

        /* Lobes with a roughness: also the smooth (delta) and a rough setting. */
        if (glint_lobe_param_find(fx->rt, id, "roughness", &roughness) == GLINT_OK) {
            glint_param_info p = param_info_init();
            assert_ok(glint_lobe_param_info(fx->rt, id, roughness, &p));
            block[p.offset] = p.min;
            check_single_lobe_closure(single_lobe_closure(fx, id, block, t.param_block_size, NULL),
                                      id, &t, 4 + id);
            block[p.offset] = p.min + 0.6f * (p.max - p.min);
            check_single_lobe_closure(single_lobe_closure(fx, id, block, t.param_block_size, NULL),
                                      id, &t, 5 + id);
        }
        free(block);
    }
}

static float dot3(glint_vec3 a, glint_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

/* A random valid value for parameter p: enum indices, the range ends, or inside. */
static float random_param_value(lcg *g, const glint_param_info *p)
{
    float u = lcg_next(g);
    if (p->param_type == GLINT_PARAM_ENUM)
        return (float)(uint32_t)(u * (float)p->choice_count);
    if (u < 0.1f)
        return p->min;
    if (u > 0.9f)
        return p->max;
    u = lcg_next(g);
    if (p->min > 0.0f && p->max / p->min > 100.0f) /* wide ranges (IORs): log-uniform */
        return p->min * powf(p->max / p->min, u);
    return p->min + u * (p->max - p->min);
}

/* Every lobe type with random valid parameter blocks, in random frames, from random
 * directions on both sides: results finite and non-negative, non-specular samples
 * consistent with eval and pdf, reciprocal lobes reciprocal. */
static void random_parameters_and_frames(void **state)
{
    fixture *fx = *state;
    uint32_t n = lobe_type_count(fx->rt), id;
    lcg g;
    lcg_seed(&g, 4242);
    for (id = 0; id < n; id++) {
        glint_lobe_info t = lobe_type(fx->rt, id);
        float *block = calloc(t.param_block_size, sizeof *block);
        int trial, checked = 0;
        assert_non_null(block);
        for (trial = 0; trial < 48; trial++) {
            glint_closure *c = NULL;
            glint_frame frame;
            glint_vec3 wo, nn;
            float albedo[3];
            uint32_t i, k;
            int s;
            const float weight[3] = {1.0f, 0.7f, 0.4f};
            for (i = 0; i < t.param_count; i++) {
                glint_param_info p = param_info_init();
                assert_ok(glint_lobe_param_info(fx->rt, id, i, &p));
                for (k = 0; k < p.size; k++)
                    block[p.offset + k] = random_param_value(&g, &p);
            }
            frame.normal = lcg_direction(&g, 0);
            switch (trial % 3) {
            case 0: frame.tangent = v3(0.0f, 0.0f, 0.0f); break;   /* automatic */
            case 1: frame.tangent = lcg_direction(&g, 0); break;   /* made orthogonal */
            default: frame.tangent = frame.normal; break;          /* parallel: automatic */
            }
            nn = v3_normalize(frame.normal);
            wo = lcg_direction(&g, 0);
            assert_ok(glint_arena_reset(fx->arena));
            assert_ok(glint_closure_from_json(fx->rt, fx->arena,
                                              "{\"lobes\": [{\"type\": \"lambert\"}]}", NULL,
                                              &fx->ok)); /* keep the fixture's closure alive */
            assert_ok(glint_closure_begin(fx->rt, fx->arena, trial % 2 ? &wo : NULL,
                                          trial % 4 == 3 ? GLINT_CLOSURE_IMPORTANCE : 0, &c));
            assert_ok(glint_closure_add_lobe(c, id, weight, &frame, block, t.param_block_size,
                                             NULL));
            assert_ok(glint_closure_finish(c));
            assert_ok(glint_albedo(c, wo, albedo));
            for (k = 0; k < 3; k++)
                assert_finite_nonneg(albedo[k]);
            for (s = 0; s < 24; s++) {
                glint_sample_result r = sample_result_init();
                glint_eval_result e = eval_result_init(), back = eval_result_init();
                float pdf = -1.0f;
                glint_status st = glint_sample(c, wo, lcg_next(&g), lcg_next(&g), lcg_next(&g), &r);
                float side;
                assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
                /* An arbitrary direction first: finite and non-negative. */
                assert_ok(glint_eval(c, wo, lcg_direction(&g, 0), &e));
                check_eval_result(&e);
                if (st == GLINT_NO_SAMPLE) {
                    check_zeroed_sample(&r);
                    continue;
                }
                check_sample_basics(&r, t.flags);
                side = dot3(nn, wo) * dot3(nn, r.wi);
                if (r.flags & GLINT_FLAG_REFLECTION)
                    assert_true(side > -1e-6f);
                else
                    assert_true(side < 1e-6f);
                assert_ok(glint_eval(c, wo, r.wi, &e));
                assert_ok(glint_pdf(c, wo, r.wi, &pdf));
                check_eval_result(&e);
                if (r.flags & GLINT_FLAG_SPECULAR) {
                    assert_true(e.value[0] == 0.0f && e.pdf == 0.0f && pdf == 0.0f);
                    continue;
                }
                checked++;
                assert_close(pdf, r.pdf, 1e-3f);
                for (k = 0; k < 3; k++)
                    assert_close(e.value[k], r.value[k], 1e-3f);
                if (t.reciprocal) {
                    /* f(wo, wi) = f(wi, wo), with eval's |cos theta_i| divided out. */
                    float ci = fabsf(dot3(nn, r.wi)), co = fabsf(dot3(nn, wo));
                    assert_ok(glint_eval(c, r.wi, wo, &back));
                    if (ci > 1e-3f && co > 1e-3f)
                        for (k = 0; k < 3; k++)
                            assert_close(e.value[k] / ci, back.value[k] / co, 1e-3f);
                }
            }
        }
        print_message("%s: %d non-specular samples checked\n", t.name, checked);
        free(block);
    }
}

/* Random numbers at and beyond the ends of [0, 1) are clamped, never NaN. */
static void random_number_edges(void **state)
{
    fixture *fx = *state;
    static const float us[] = {0.0f, 1e-30f, 0.5f, 0.99999994f, 1.0f, -0.25f, 1.5f};
    const size_t nu = sizeof us / sizeof us[0];
    const glint_closure *c = all_types_closure(fx, NULL);
    const glint_vec3 wos[3] = {test_wo(), v3(0.0f, 0.0f, 1.0f), v3(0.3f, 0.2f, -0.9f)};
    uint32_t count = 0, lobe;
    size_t a, i, j, k;
    assert_ok(glint_closure_lobe_count(c, &count));
    for (a = 0; a < 3; a++)
        for (i = 0; i < nu; i++)
            for (j = 0; j < nu; j++)
                for (k = 0; k < nu; k++) {
                    glint_sample_result s = sample_result_init();
                    glint_status st = glint_sample(c, wos[a], us[i], us[j], us[k], &s);
                    assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
                    if (st == GLINT_OK)
                        check_sample_basics(&s, 0);
                    for (lobe = 0; lobe < count; lobe++) {
                        s = sample_result_init();
                        st = glint_sample_lobe(c, lobe, wos[a], us[i], us[j], us[k], &s);
                        assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
                        if (st == GLINT_OK)
                            check_sample_basics(&s, lobe_type(fx->rt, lobe).flags);
                    }
                }
}

/* The JSON example of the README (one lobe of each type) builds and evaluates. */
static void json_readme_example(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo();
    glint_closure *c = json_closure(
        fx,
        "{ \"lobes\": [\n"
        "  { \"type\": \"lambert\", \"weight\": 0.6, \"color\": [0.8, 0.3, 0.2] },\n"
        "  { \"type\": \"conductor\", \"distribution\": \"ggx\", \"roughness\": 0.35, \"anisotropic\": 0.5,\n"
        "    \"tangent\": [1, 0, 0], \"fresnel\": \"artistic\",\n"
        "    \"reflectivity\": [0.95, 0.64, 0.54], \"edge_tint\": [1.0, 0.98, 0.9] },\n"
        "  { \"type\": \"conductor\", \"distribution\": \"beckmann\", \"roughness\": 0.2,\n"
        "    \"fresnel\": \"conductor\", \"eta\": [0.2, 0.92, 1.1], \"k\": [3.9, 2.45, 2.14] },\n"
        "  { \"type\": \"dielectric\", \"roughness\": 0.1, \"eta\": 1.5 },\n"
        "  { \"type\": \"mirror\", \"fresnel\": \"schlick\", \"f0\": 0.9, \"f90\": 1.0 }\n"
        "] }",
        &wo);
    uint32_t count = 0;
    float albedo[3];
    glint_eval_result e = eval_result_init();
    assert_ok(glint_closure_lobe_count(c, &count));
    assert_int_equal(count, 5);
    assert_ok(glint_eval(c, wo, fixed_wi(0), &e));
    check_eval_result(&e);
    assert_true(e.value[0] > 0.0f);
    assert_ok(glint_albedo(c, wo, albedo));
    assert_finite_nonneg(albedo[0]);
}

/* Documented delta thresholds: microfacet lobes with alpha = roughness^2 < 1e-3 and
 * index-matched dielectrics (|eta - 1| < 1e-4) are specular; just above, glossy. */
static void delta_thresholds(void **state)
{
    fixture *fx = *state;
    static const struct {
        const char *json;
        uint32_t class_flag;
    } cases[] = {
        {"{\"lobes\": [{\"type\": \"conductor\", \"roughness\": 0.03}]}", GLINT_FLAG_SPECULAR},
        {"{\"lobes\": [{\"type\": \"conductor\", \"roughness\": 0.035}]}", GLINT_FLAG_GLOSSY},
        {"{\"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0.03}]}", GLINT_FLAG_SPECULAR},
        {"{\"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0.035}]}", GLINT_FLAG_GLOSSY},
        {"{\"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0.5, \"eta\": 1.00005}]}",
         GLINT_FLAG_SPECULAR},
        {"{\"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0.5, \"eta\": 1.01}]}",
         GLINT_FLAG_GLOSSY},
    };
    const glint_vec3 wo = test_wo();
    size_t i;
    int s;
    lcg g;
    lcg_seed(&g, 77);
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        glint_closure *c = json_closure(fx, cases[i].json, NULL);
        int valid = 0;
        for (s = 0; s < 32; s++) {
            glint_sample_result r = sample_result_init();
            glint_status st = glint_sample(c, wo, lcg_next(&g), lcg_next(&g), lcg_next(&g), &r);
            assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
            if (st != GLINT_OK)
                continue;
            valid++;
            if ((r.flags & cases[i].class_flag) == 0)
                print_error("%s: sample flags %#x\n", cases[i].json, (unsigned)r.flags);
            assert_true(r.flags & cases[i].class_flag);
        }
        assert_true(valid > 0);
    }
}

static void json_closure_of_every_type(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo();
    uint32_t n = lobe_type_count(fx->rt), count = 0, k;
    const glint_vec3 *wos[2];
    int variant;
    wos[0] = NULL;
    wos[1] = &wo;
    for (variant = 0; variant < 2; variant++) {
        glint_closure *c = all_types_closure(fx, wos[variant]);
        float probability[GLINT_MAX_LOBES], sum = 0.0f, albedo[3], lobe_sum[3] = {0, 0, 0};
        lcg g;
        int i, j, specular = 0, rough = 0;

        assert_ok(glint_closure_lobe_count(c, &count));
        assert_int_equal(count, n);
        for (k = 0; k < count; k++) {
            uint32_t type_id = UINT32_MAX;
            float albedo_k[3];
            assert_ok(glint_closure_lobe(c, k, &type_id, &probability[k]));
            assert_int_equal(type_id, k);
            assert_true(probability[k] >= 0.0f && probability[k] <= 1.0f);
            sum += probability[k];
            assert_ok(glint_albedo_lobe(c, k, wo, albedo_k));
            for (j = 0; j < 3; j++) {
                assert_finite_nonneg(albedo_k[j]);
                lobe_sum[j] += albedo_k[j];
            }
        }
        assert_close(sum, 1.0f, 1e-5f);
        assert_ok(glint_albedo(c, wo, albedo));
        for (j = 0; j < 3; j++)
            assert_close(albedo[j], lobe_sum[j], 1e-5f);

        /* eval is the sum of the lobes; pdf the probability-weighted mixture. */
        for (i = 0; i < FIXED_WI_COUNT; i++) {
            glint_vec3 wi = fixed_wi(i);
            glint_eval_result e = eval_result_init();
            float value[3] = {0, 0, 0}, pdf = 0.0f, pdf_direct = -1.0f;
            assert_ok(glint_eval(c, wo, wi, &e));
            check_eval_result(&e);
            for (k = 0; k < count; k++) {
                glint_eval_result el = eval_result_init();
                assert_ok(glint_eval_lobe(c, k, wo, wi, &el));
                check_eval_result(&el);
                for (j = 0; j < 3; j++)
                    value[j] += el.value[j];
                pdf += probability[k] * el.pdf;
            }
            for (j = 0; j < 3; j++)
                assert_close(e.value[j], value[j], 1e-5f);
            assert_close(e.pdf, pdf, 1e-5f);
            assert_ok(glint_pdf(c, wo, wi, &pdf_direct));
            assert_close(pdf_direct, e.pdf, 1e-6f);
        }

        lcg_seed(&g, 99 + (uint64_t)variant);
        for (i = 0; i < 4 * SAMPLES; i++) {
            float u_lobe = lcg_next(&g), u0 = lcg_next(&g), u1 = lcg_next(&g);
            glint_sample_result s = sample_result_init();
            glint_eval_result e = eval_result_init(), el = eval_result_init();
            float pdf = -1.0f, pdf_lobe = -1.0f;
            glint_status st = glint_sample(c, wo, u_lobe, u0, u1, &s);
            assert_true(st == GLINT_OK || st == GLINT_NO_SAMPLE);
            if (st == GLINT_NO_SAMPLE) {
                check_zeroed_sample(&s);
                continue;
            }
            assert_true(s.lobe < count);
            check_sample_basics(&s, lobe_type(fx->rt, s.lobe).flags);
            assert_ok(glint_eval(c, wo, s.wi, &e));
            assert_ok(glint_pdf(c, wo, s.wi, &pdf));
            assert_ok(glint_eval_lobe(c, s.lobe, wo, s.wi, &el));
            assert_ok(glint_pdf_lobe(c, s.lobe, wo, s.wi, &pdf_lobe));
            if (s.flags & GLINT_FLAG_SPECULAR) {
                specular++;
                /* The sampled (delta) lobe contributes nothing to eval and pdf. */
                for (j = 0; j < 3; j++)
                    assert_true(el.value[j] == 0.0f);
                assert_true(el.pdf == 0.0f);
                assert_true(pdf_lobe == 0.0f);
                assert_true(s.pdf <= probability[s.lobe] * (1.0f + 1e-5f));
            } else {
                rough++;
                /* Non-specular samples describe the whole mixture. */
                assert_close(pdf, s.pdf, 1e-3f);
                assert_close(e.pdf, s.pdf, 1e-3f);
                for (j = 0; j < 3; j++)
                    assert_close(e.value[j], s.value[j], 1e-3f);
            }
        }
        assert_true(rough > 0);
        print_message("mixture (wo %s): %d rough and %d specular samples\n",
                      variant ? "given" : "NULL", rough, specular);
    }
}

/* JSON parameters land in the same block glint_closure_add_lobe takes. */
static void json_matches_param_blocks(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo();
    uint32_t conductor = lobe_id(fx->rt, "conductor"), lambert = lobe_id(fx->rt, "lambert");
    glint_lobe_info ci = lobe_type(fx->rt, conductor), li = lobe_type(fx->rt, lambert);
    float *cb = calloc(ci.param_block_size, sizeof *cb), *lb = calloc(li.param_block_size, sizeof *lb);
    glint_param_info p;
    glint_closure *from_json, *built = NULL;
    const float cw[3] = {1.0f, 0.9f, 0.8f}, lw[3] = {0.5f, 0.5f, 0.5f};
    glint_frame frame = frame_z();
    int i, k;
    assert_non_null(cb);
    assert_non_null(lb);

    from_json = json_closure(
        fx,
        "{\"lobes\": ["
        " {\"type\": \"lambert\", \"weight\": 0.5, \"color\": [0.2, 0.4, 0.6]},"
        " {\"type\": \"conductor\", \"weight\": [1, 0.9, 0.8], \"normal\": [0, 0, 1],"
        "  \"distribution\": \"beckmann\", \"roughness\": 0.4, \"fresnel\": \"artistic\","
        "  \"reflectivity\": [0.9, 0.6, 0.3], \"edge_tint\": 0.7}"
        "]}",
        NULL);

    assert_ok(glint_lobe_param_defaults(fx->rt, lambert, lb, li.param_block_size));
    p = lobe_param(fx->rt, lambert, "color");
    lb[p.offset] = 0.2f;
    lb[p.offset + 1] = 0.4f;
    lb[p.offset + 2] = 0.6f;

    assert_ok(glint_lobe_param_defaults(fx->rt, conductor, cb, ci.param_block_size));
    p = lobe_param(fx->rt, conductor, "distribution");
    {
        uint32_t index = 0;
        assert_ok(glint_lobe_param_find(fx->rt, conductor, "distribution", &index));
        assert_ok(glint_lobe_param_choice(fx->rt, conductor, index, "beckmann", &cb[p.offset]));
        assert_ok(glint_lobe_param_find(fx->rt, conductor, "fresnel", &index));
        p = lobe_param(fx->rt, conductor, "fresnel");
        assert_ok(glint_lobe_param_choice(fx->rt, conductor, index, "artistic", &cb[p.offset]));
    }
    p = lobe_param(fx->rt, conductor, "roughness");
    cb[p.offset] = 0.4f;
    p = lobe_param(fx->rt, conductor, "reflectivity");
    cb[p.offset] = 0.9f;
    cb[p.offset + 1] = 0.6f;
    cb[p.offset + 2] = 0.3f;
    p = lobe_param(fx->rt, conductor, "edge_tint");
    cb[p.offset] = cb[p.offset + 1] = cb[p.offset + 2] = 0.7f;

    assert_ok(glint_closure_begin(fx->rt, fx->arena, NULL, 0, &built));
    assert_ok(glint_closure_add_lobe(built, lambert, lw, &frame, lb, li.param_block_size, NULL));
    assert_ok(glint_closure_add_lobe(built, conductor, cw, &frame, cb, ci.param_block_size, NULL));
    assert_ok(glint_closure_finish(built));

    for (i = 0; i < FIXED_WI_COUNT; i++) {
        glint_eval_result a = eval_result_init(), b = eval_result_init();
        assert_ok(glint_eval(from_json, wo, fixed_wi(i), &a));
        assert_ok(glint_eval(built, wo, fixed_wi(i), &b));
        for (k = 0; k < 3; k++)
            assert_close(a.value[k], b.value[k], 1e-6f);
        assert_close(a.pdf, b.pdf, 1e-6f);
        assert_close(a.pdf_reverse, b.pdf_reverse, 1e-6f);
    }
    {
        float pa = -1.0f, pb = -2.0f;
        uint32_t ta = UINT32_MAX, tb = UINT32_MAX;
        assert_ok(glint_closure_lobe(from_json, 1, &ta, &pa));
        assert_ok(glint_closure_lobe(built, 1, &tb, &pb));
        assert_int_equal(ta, conductor);
        assert_int_equal(tb, conductor);
        assert_close(pa, pb, 1e-6f);
    }
    /* The non-default parameters matter: the default conductor differs. */
    {
        glint_closure *plain = json_closure(
            fx, "{\"lobes\": [{\"type\": \"lambert\", \"weight\": 0.5, \"color\": [0.2, 0.4, 0.6]},"
                " {\"type\": \"conductor\", \"weight\": [1, 0.9, 0.8]}]}", NULL);
        glint_eval_result a = eval_result_init(), b = eval_result_init();
        assert_ok(glint_eval(from_json, wo, fixed_wi(1), &a));
        assert_ok(glint_eval(plain, wo, fixed_wi(1), &b));
        assert_true(fabsf(a.value[2] - b.value[2]) > 1e-4f);
    }
    free(cb);
    free(lb);
}

/* Radiance transmission through a dielectric is importance / eta^2. */
static void transport_modes(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo();
    const glint_vec3 wi = fixed_wi(3); /* below the surface */
    uint32_t dielectric = lobe_id(fx->rt, "dielectric");
    const float white[3] = {1, 1, 1};
    glint_frame frame = frame_z();
    glint_closure *radiance, *importance, *begun = NULL, *begun_radiance = NULL;
    glint_eval_result r = eval_result_init(), im = eval_result_init(), b = eval_result_init(),
                      br = eval_result_init();
    float eta = lobe_param(fx->rt, dielectric, "eta").default_value[0];

    radiance = json_closure(fx, "{\"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0.5}]}",
                            NULL);
    importance = json_closure(fx,
                              "{\"transport\": \"importance\","
                              " \"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0.5}]}",
                              NULL);
    {
        glint_lobe_info t = lobe_type(fx->rt, dielectric);
        float *block = calloc(t.param_block_size, sizeof *block);
        assert_non_null(block);
        assert_ok(glint_lobe_param_defaults(fx->rt, dielectric, block, t.param_block_size));
        block[lobe_param(fx->rt, dielectric, "roughness").offset] = 0.5f;
        assert_ok(glint_closure_begin(fx->rt, fx->arena, NULL, GLINT_CLOSURE_IMPORTANCE, &begun));
        assert_ok(glint_closure_add_lobe(begun, dielectric, white, &frame, block,
                                         t.param_block_size, NULL));
        assert_ok(glint_closure_finish(begun));
        assert_ok(glint_closure_begin(fx->rt, fx->arena, NULL, 0, &begun_radiance));
        assert_ok(glint_closure_add_lobe(begun_radiance, dielectric, white, &frame, block,
                                         t.param_block_size, NULL));
        assert_ok(glint_closure_finish(begun_radiance));
        free(block);
    }
    assert_ok(glint_eval(radiance, wo, wi, &r));
    assert_ok(glint_eval(importance, wo, wi, &im));
    assert_ok(glint_eval(begun, wo, wi, &b));
    assert_ok(glint_eval(begun_radiance, wo, wi, &br));
    assert_true(im.value[0] > 0.0f);
    assert_close(r.value[0], im.value[0] / (eta * eta), 1e-4f);
    assert_close(b.value[0], im.value[0], 1e-6f);
    assert_close(br.value[0], r.value[0], 1e-6f);
    assert_close(r.pdf, im.pdf, 1e-6f);
}

/* Frames: the normal need not be unit length; a tilted normal tilts the lobe. */
static void frames(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo(), wi = fixed_wi(0);
    uint32_t lambert = lobe_id(fx->rt, "lambert"), conductor = lobe_id(fx->rt, "conductor");
    const float white[3] = {1, 1, 1};
    const glint_vec3 n = v3_normalize(v3(0.2f, -0.3f, 0.9f));
    glint_frame unit = frame_z(), scaled = frame_z(), tilted = frame_z(), tangent = frame_z();
    glint_closure *a = NULL, *b = NULL, *c = NULL, *d = NULL;
    glint_eval_result ea = eval_result_init(), eb = eval_result_init(), ec = eval_result_init(),
                      ed = eval_result_init();
    float color = lobe_param(fx->rt, lambert, "color").default_value[0];
    float cos_n = n.x * wi.x + n.y * wi.y + n.z * wi.z;
    int k;

    scaled.normal = v3(0.0f, 0.0f, 2.5f);
    tilted.normal = v3(n.x * 4, n.y * 4, n.z * 4);
    tangent.tangent = v3(1.0f, 0.5f, 0.3f); /* not orthogonal: made so */

    assert_ok(glint_closure_begin(fx->rt, fx->arena, &wo, 0, &a));
    assert_ok(glint_closure_add_lobe(a, lambert, white, &unit, NULL, 0, NULL));
    assert_ok(glint_closure_finish(a));
    assert_ok(glint_closure_begin(fx->rt, fx->arena, &wo, 0, &b));
    assert_ok(glint_closure_add_lobe(b, lambert, white, &scaled, NULL, 0, NULL));
    assert_ok(glint_closure_finish(b));
    assert_ok(glint_closure_begin(fx->rt, fx->arena, &wo, 0, &c));
    assert_ok(glint_closure_add_lobe(c, lambert, white, &tilted, NULL, 0, NULL));
    assert_ok(glint_closure_finish(c));
    assert_ok(glint_closure_begin(fx->rt, fx->arena, &wo, 0, &d));
    assert_ok(glint_closure_add_lobe(d, conductor, white, &tangent, NULL, 0, NULL));
    assert_ok(glint_closure_finish(d));

    assert_ok(glint_eval(a, wo, wi, &ea));
    assert_ok(glint_eval(b, wo, wi, &eb));
    assert_ok(glint_eval(c, wo, wi, &ec));
    assert_ok(glint_eval(d, wo, fixed_wi(1), &ed));
    check_eval_result(&ed);
    for (k = 0; k < 3; k++) {
        assert_close(eb.value[k], ea.value[k], 1e-6f);
        /* Lambert: color / pi * cos(n, wi). */
        assert_close(ea.value[k], color / 3.14159265f * wi.z, 1e-4f);
        assert_close(ec.value[k], color / 3.14159265f * cos_n, 1e-4f);
    }
}

/* A lobe weight scales value and albedo but not the pdf. */
static void weights_scale_values(void **state)
{
    fixture *fx = *state;
    const glint_vec3 wo = test_wo(), wi = fixed_wi(0);
    uint32_t lambert = lobe_id(fx->rt, "lambert");
    const float w[3] = {0.5f, 0.25f, 0.0f};
    glint_frame f = frame_z();
    glint_closure *c = NULL, *plain = single_lobe_closure(fx, lambert, NULL, 0, NULL);
    glint_eval_result e = eval_result_init(), ep = eval_result_init();
    float albedo[3], albedo_plain[3];
    int k;
    assert_ok(glint_closure_begin(fx->rt, fx->arena, NULL, 0, &c));
    assert_ok(glint_closure_add_lobe(c, lambert, w, &f, NULL, 0, NULL));
    assert_ok(glint_closure_finish(c));
    assert_ok(glint_eval(c, wo, wi, &e));
    assert_ok(glint_eval(plain, wo, wi, &ep));
    assert_ok(glint_albedo(c, wo, albedo));
    assert_ok(glint_albedo(plain, wo, albedo_plain));
    for (k = 0; k < 3; k++) {
        assert_close(e.value[k], w[k] * ep.value[k], 1e-6f);
        assert_close(albedo[k], w[k] * albedo_plain[k], 1e-6f);
    }
    assert_close(e.pdf, ep.pdf, 1e-6f);
}

/* Below the surface a one-sided lobe cannot scatter: GLINT_NO_SAMPLE, a zeroed result,
 * and glint_last_error() untouched (it is not an error). */
static void no_sample_is_not_an_error(void **state)
{
    fixture *fx = *state;
    uint32_t lambert = lobe_id(fx->rt, "lambert");
    glint_closure *c = single_lobe_closure(fx, lambert, NULL, 0, NULL);
    glint_sample_result s = sample_result_init();
    const glint_vec3 below = v3(0.3f, 0.2f, -0.9f);
    float albedo[3] = {-1, -1, -1};
    glint_eval_result e = eval_result_init();
    uint32_t dummy;

    /* Leave a known message behind. */
    assert_int_equal(glint_lobe_type_find(fx->rt, "marker-error", &dummy), GLINT_ERROR_UNKNOWN_NAME);
    assert_error_mentions("marker-error");

    memset(&s.wi, 0x55, sizeof s - offsetof(glint_sample_result, wi));
    assert_int_equal(glint_sample(c, below, 0.5f, 0.5f, 0.5f, &s), GLINT_NO_SAMPLE);
    check_zeroed_sample(&s);
    memset(&s.wi, 0x55, sizeof s - offsetof(glint_sample_result, wi));
    assert_int_equal(glint_sample_lobe(c, 0, below, 0.5f, 0.5f, 0.5f, &s), GLINT_NO_SAMPLE);
    check_zeroed_sample(&s);
    assert_error_mentions("marker-error");
    assert_non_null(glint_status_string(GLINT_NO_SAMPLE));

    /* eval / albedo below the surface: zero, not an error. */
    assert_ok(glint_eval(c, below, fixed_wi(0), &e));
    assert_true(e.value[0] == 0.0f && e.pdf == 0.0f);
    assert_ok(glint_albedo(c, below, albedo));
    assert_true(albedo[0] == 0.0f && albedo[1] == 0.0f && albedo[2] == 0.0f);
    assert_error_mentions("marker-error");
}

/* glint_eval at the direction glint_sample returned gives back the sample's value and
 * pdf bit for bit: the sample is valued at that direction as eval reads it (normalized
 * again). Narrow lobes in tilted frames at grazing angles, where one ulp of the local
 * direction moved the value by up to 1.3% before the sample took eval's normalization. */
static void eval_at_a_sampled_direction_gives_the_sample_back(void **state)
{
    static const char *const json[] = {
        "{\"lobes\": [{\"type\": \"conductor\", \"roughness\": 0.06, "
        "\"normal\": [0.3, -0.5, 0.8], \"tangent\": [1, 0.2, 0.1]}]}",
        "{\"lobes\": [{\"type\": \"conductor\", \"roughness\": 0.1, \"anisotropic\": 0.7, "
        "\"distribution\": \"beckmann\", \"normal\": [-0.2, 0.4, 0.9]}]}",
        "{\"lobes\": [{\"type\": \"dielectric\", \"roughness\": 0.06, \"eta\": 2.4, "
        "\"normal\": [0.3, -0.5, 0.8]}]}",
        "{\"lobes\": [{\"type\": \"lambert\", \"normal\": [0.6, 0.0, 0.8]}]}",
    };
    fixture *fx = *state;
    size_t k;
    int i, compared = 0;
    lcg g;
    lcg_seed(&g, 77);
    for (k = 0; k < sizeof json / sizeof json[0]; k++) {
        glint_closure *c = NULL;
        assert_ok(glint_arena_reset(fx->arena));
        assert_ok(glint_closure_from_json(fx->rt, fx->arena, json[k], NULL, &c));
        for (i = 0; i < 4000; i++) {
            glint_sample_result s = sample_result_init();
            glint_eval_result e = eval_result_init();
            const glint_vec3 wo = lcg_direction(&g, 0);
            if (glint_sample(c, wo, lcg_next(&g), lcg_next(&g), lcg_next(&g), &s) != GLINT_OK ||
                (s.flags & GLINT_FLAG_SPECULAR) != 0)
                continue;
            assert_ok(glint_eval(c, wo, s.wi, &e));
            assert_memory_equal(e.value, s.value, sizeof e.value);
            assert_memory_equal(&e.pdf, &s.pdf, sizeof e.pdf);
            compared++;
        }
    }
    assert_true(compared > 5000);
}

/* Arenas: reset frees every slot at once; closures are independent of each other. */
static void arena_lifecycle(void **state)
{
    fixture *fx = *state;
    glint_arena *arena = NULL;
    glint_closure *c = NULL;
    glint_eval_result e = eval_result_init();
    int round, i;
    assert_ok(glint_arena_create(3, &arena));
    assert_non_null(arena);
    for (round = 0; round < 3; round++) {
        for (i = 0; i < 3; i++) {
            assert_ok(glint_closure_from_json(fx->rt, arena,
                                              "{\"lobes\": [{\"type\": \"lambert\"}]}", NULL, &c));
            assert_ok(glint_eval(c, test_wo(), fixed_wi(0), &e));
        }
        assert_ok(glint_arena_reset(arena));
    }
    /* An empty closure is valid and scatters nothing. */
    assert_ok(glint_closure_begin(fx->rt, arena, NULL, 0, &c));
    assert_ok(glint_closure_finish(c));
    {
        uint32_t count = 99;
        glint_sample_result s = sample_result_init();
        float albedo[3] = {-1, -1, -1};
        assert_ok(glint_closure_lobe_count(c, &count));
        assert_int_equal(count, 0);
        assert_ok(glint_eval(c, test_wo(), fixed_wi(0), &e));
        assert_true(e.value[0] == 0.0f && e.pdf == 0.0f);
        assert_ok(glint_albedo(c, test_wo(), albedo));
        assert_true(albedo[0] == 0.0f);
        assert_int_equal(glint_sample(c, test_wo(), 0.5f, 0.5f, 0.5f, &s), GLINT_NO_SAMPLE);
    }
    glint_arena_destroy(arena);
    glint_arena_destroy(NULL); /* ignored */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(every_lobe_type_alone, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(json_closure_of_every_type, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(json_matches_param_blocks, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(json_readme_example, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(delta_thresholds, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(transport_modes, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(frames, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(weights_scale_values, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(random_parameters_and_frames, fixture_setup,
                                        fixture_teardown),
        cmocka_unit_test_setup_teardown(random_number_edges, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(no_sample_is_not_an_error, fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(eval_at_a_sampled_direction_gives_the_sample_back,
                                        fixture_setup, fixture_teardown),
        cmocka_unit_test_setup_teardown(arena_lifecycle, fixture_setup, fixture_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
