/* Chi-square goodness-of-fit tests of sampling against the pdf, through the C ABI, for
 * every registered lobe type (after Mitsuba 3's chi2.py and pbrt-v4's bsdfs_test.cpp).
 *
 * For each lobe type (enumerated with glint_lobe_type_count / glint_lobe_type_info), a
 * closure of that one lobe with the default parameters and, when the type has a
 * "roughness" parameter, a second one with roughness 0.5; for each of a few wo:
 *
 * - draw M samples with glint_sample_lobe (PCG32, three independent uniforms each);
 *   GLINT_NO_SAMPLE counts as absorbed, SPECULAR samples are counted apart (a lobe whose
 *   every sample is SPECULAR is a delta lobe: no chi-square test, the samples are only
 *   checked to be finite), the others are histogrammed by (cos theta, phi) of wi over
 *   N_THETA x N_PHI equal-area cells covering the whole sphere;
 * - integrate glint_pdf_lobe over every cell (adaptive midpoint rule in (cos theta, phi),
 *   K x K points per sub-cell) to get the expected counts, and check that the pdf
 *   integrates over the sphere to the fraction of samples that were not absorbed;
 * - pool the cells with expected count < 5, compute Pearson's X^2 and its p-value
 *   Q(dof / 2, X^2 / 2) (regularized upper incomplete gamma, Numerical Recipes gammq).
 *
 * The overall significance is ALPHA with the Sidak correction over the T tests run:
 * every p-value must be >= 1 - (1 - ALPHA)^(1 / T). */
#include "common.h"

#include <float.h>
#include <stdlib.h>

#define N_THETA 20
#define N_PHI 40
#define N_CELLS (N_THETA * N_PHI)
#define M_SAMPLES 200000
/* Midpoint points per side of a (sub-)cell. */
#define K_SUB 8
/* Most halvings of a cell's sides by the adaptive integration. */
#define MAX_DEPTH 8
/* Integration tolerance of a cell, in expected counts, relative to sqrt(expected). */
#define TOL_SQRT_EXPECTED 0.02
#define POOL_THRESHOLD 5.0
#define ALPHA 0.01
/* |pdf integral - (1 - absorbed fraction)| allowed, relative to the latter. */
#define INTEGRAL_TOL 0.02
#define MAX_RUNS 64
#define MAX_WO 5

static const double TWO_PI = 6.283185307179586;

/* ---- PCG32 (O'Neill 2014, pcg32_random_r) ---------------------------------------- */

typedef struct pcg32 {
    uint64_t state;
    uint64_t inc;
} pcg32;

static uint32_t pcg32_next(pcg32 *g)
{
    uint64_t old = g->state;
    uint32_t xorshifted, rot;
    g->state = old * 6364136223846793005ULL + g->inc;
    xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

static void pcg32_seed(pcg32 *g, uint64_t seed, uint64_t stream)
{
    g->state = 0u;
    g->inc = (stream << 1u) | 1u;
    pcg32_next(g);
    g->state += seed;
    pcg32_next(g);
}

/* A float in [0, 1): the top 24 bits, exactly representable. */
static float pcg32_float(pcg32 *g)
{
    return (float)(pcg32_next(g) >> 8) * (1.0f / 16777216.0f);
}

/* ---- regularized incomplete gamma (Numerical Recipes gser / gcf / gammq) ---------- */

#define GAMMA_ITMAX 100000
#define GAMMA_EPS 1e-15
#define GAMMA_FPMIN (DBL_MIN / DBL_EPSILON)

/* P(a, x) by its series, for x < a + 1. */
static double gamma_p_series(double a, double x)
{
    double ap = a, del = 1.0 / a, sum = del;
    int n;
    for (n = 0; n < GAMMA_ITMAX; n++) {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if (fabs(del) < fabs(sum) * GAMMA_EPS)
            break;
    }
    assert_true(n < GAMMA_ITMAX);
    return sum * exp(-x + a * log(x) - lgamma(a));
}

/* Q(a, x) by its continued fraction (modified Lentz), for x >= a + 1. */
static double gamma_q_fraction(double a, double x)
{
    double b = x + 1.0 - a, c = 1.0 / GAMMA_FPMIN, d = 1.0 / b, h = d;
    int i;
    for (i = 1; i < GAMMA_ITMAX; i++) {
        double an = -i * (i - a), del;
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < GAMMA_FPMIN)
            d = GAMMA_FPMIN;
        c = b + an / c;
        if (fabs(c) < GAMMA_FPMIN)
            c = GAMMA_FPMIN;
        d = 1.0 / d;
        del = d * c;
        h *= del;
        if (fabs(del - 1.0) < GAMMA_EPS)
            break;
    }
    assert_true(i < GAMMA_ITMAX);
    return exp(-x + a * log(x) - lgamma(a)) * h;
}

/* The regularized upper incomplete gamma function Q(a, x) = Gamma(a, x) / Gamma(a). */
static double gamma_q(double a, double x)
{
    assert_true(a > 0.0);
    assert_true(x >= 0.0);
    if (x == 0.0)
        return 1.0;
    if (x < a + 1.0)
        return 1.0 - gamma_p_series(a, x);
    return gamma_q_fraction(a, x);
}

/* The p-value of a chi-square statistic: P(X >= x2) with dof degrees of freedom. */
static double chi2_p_value(double x2, int dof)
{
    return gamma_q(0.5 * dof, 0.5 * x2);
}

/* ---- the pdf over the (cos theta, phi) grid --------------------------------------- */

typedef struct pdf_ctx {
    const glint_closure *closure;
    glint_vec3 wo;
    long evals;
} pdf_ctx;

static glint_vec3 direction(double cos_theta, double phi)
{
    double s = sqrt(fmax(0.0, 1.0 - cos_theta * cos_theta));
    return v3((float)(s * cos(phi)), (float)(s * sin(phi)), (float)cos_theta);
}

static double pdf_at(pdf_ctx *ctx, double cos_theta, double phi)
{
    float pdf = -1.0f;
    glint_status st = glint_pdf_lobe(ctx->closure, 0, ctx->wo, direction(cos_theta, phi), &pdf);
    if (st != GLINT_OK)
        print_error("glint_pdf_lobe -> %u (%s): %s\n", (unsigned)st, glint_status_string(st),
                    glint_last_error());
    assert_int_equal(st, GLINT_OK);
    if (!(isfinite(pdf) && pdf >= 0.0f))
        print_error("glint_pdf_lobe(cos theta %.9g, phi %.9g) = %g\n", cos_theta, phi,
                    (double)pdf);
    assert_true(isfinite(pdf) && pdf >= 0.0f);
    ctx->evals++;
    return pdf;
}

/* K_SUB x K_SUB midpoint rule of the pdf over [u0, u1] x [p0, p1] in (cos theta, phi):
 * the probability of the cell (d omega = d cos theta d phi). */
static double midpoint(pdf_ctx *ctx, double u0, double u1, double p0, double p1)
{
    double du = (u1 - u0) / K_SUB, dp = (p1 - p0) / K_SUB, sum = 0.0;
    int i, j;
    for (i = 0; i < K_SUB; i++)
        for (j = 0; j < K_SUB; j++)
            sum += pdf_at(ctx, u0 + (i + 0.5) * du, p0 + (j + 0.5) * dp);
    return sum * du * dp;
}

/* Adaptive midpoint: `estimate` is the cell's K_SUB x K_SUB value; the four half-size
 * sub-cells give a finer one; accept it when the two agree within `tol`, otherwise
 * recurse into the sub-cells with tol / 2 each (their errors add in quadrature). */
static double integrate_cell(pdf_ctx *ctx, double u0, double u1, double p0, double p1,
                             double estimate, double tol, int depth)
{
    double um = 0.5 * (u0 + u1), pm = 0.5 * (p0 + p1);
    double q[4], fine;
    q[0] = midpoint(ctx, u0, um, p0, pm);
    q[1] = midpoint(ctx, u0, um, pm, p1);
    q[2] = midpoint(ctx, um, u1, p0, pm);
    q[3] = midpoint(ctx, um, u1, pm, p1);
    fine = q[0] + q[1] + q[2] + q[3];
    if (depth >= MAX_DEPTH || fabs(fine - estimate) <= tol)
        return fine;
    return integrate_cell(ctx, u0, um, p0, pm, q[0], 0.5 * tol, depth + 1) +
           integrate_cell(ctx, u0, um, pm, p1, q[1], 0.5 * tol, depth + 1) +
           integrate_cell(ctx, um, u1, p0, pm, q[2], 0.5 * tol, depth + 1) +
           integrate_cell(ctx, um, u1, pm, p1, q[3], 0.5 * tol, depth + 1);
}

static double band_lo(int t)
{
    return -1.0 + 2.0 * t / N_THETA;
}

static double phi_lo(int f)
{
    return TWO_PI * f / N_PHI;
}

/* Expected probability of every cell; returns the integral over the sphere. */
static double expected_probabilities(pdf_ctx *ctx, double *prob)
{
    double total = 0.0;
    int t, f;
    for (t = 0; t < N_THETA; t++)
        for (f = 0; f < N_PHI; f++) {
            double u0 = band_lo(t), u1 = band_lo(t + 1), p0 = phi_lo(f), p1 = phi_lo(f + 1);
            double est = midpoint(ctx, u0, u1, p0, p1);
            double tol = TOL_SQRT_EXPECTED *
                         sqrt(fmax(est, POOL_THRESHOLD / M_SAMPLES) / M_SAMPLES);
            prob[t * N_PHI + f] = integrate_cell(ctx, u0, u1, p0, p1, est, tol, 0);
            total += prob[t * N_PHI + f];
        }
    return total;
}

static int cell_of(glint_vec3 wi)
{
    double z = fmin(1.0, fmax(-1.0, (double)wi.z));
    double phi = atan2((double)wi.y, (double)wi.x);
    int t, f;
    if (phi < 0.0)
        phi += TWO_PI;
    t = (int)((z + 1.0) * 0.5 * N_THETA);
    f = (int)(phi / TWO_PI * N_PHI);
    t = t < 0 ? 0 : (t >= N_THETA ? N_THETA - 1 : t);
    f = f < 0 ? 0 : (f >= N_PHI ? N_PHI - 1 : f);
    return t * N_PHI + f;
}

/* ---- Pearson's statistic with pooling ---------------------------------------------- */

typedef struct cell {
    double expected;
    double observed;
} cell;

static int by_expected(const void *a, const void *b)
{
    double x = ((const cell *)a)->expected, y = ((const cell *)b)->expected;
    return (x > y) - (x < y);
}

/* Sorts `cells` by expected count, pools those below POOL_THRESHOLD (and, in increasing
 * order, further cells until the pool reaches it), and returns X^2; *dof = bins - 1.
 * *zero_hits counts samples that fell in cells of expected count exactly 0. */
static double pearson(cell *cells, int n, int *dof, double *zero_hits, int *pooled)
{
    double x2 = 0.0, pool_exp = 0.0, pool_obs = 0.0;
    int i, bins = 0;
    *zero_hits = 0.0;
    *pooled = 0;
    qsort(cells, (size_t)n, sizeof *cells, by_expected);
    for (i = 0; i < n; i++) {
        double e = cells[i].expected, o = cells[i].observed;
        if (e <= 0.0) {
            *zero_hits += o;
            continue;
        }
        if (e < POOL_THRESHOLD || (*pooled > 0 && pool_exp < POOL_THRESHOLD)) {
            pool_exp += e;
            pool_obs += o;
            (*pooled)++;
        } else {
            x2 += (o - e) * (o - e) / e;
            bins++;
        }
    }
    if (pool_exp > 0.0) {
        x2 += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        bins++;
    }
    *dof = bins - 1;
    return x2;
}

/* ---- one test --------------------------------------------------------------------- */

enum run_kind { RUN_CHI2, RUN_DELTA, RUN_ONE_SIDED };

typedef struct run {
    char lobe[32];
    char params[48];
    double cos_o;
    enum run_kind kind;
    double absorbed; /* fraction of GLINT_NO_SAMPLE */
    double integral; /* of the pdf over the sphere */
    double x2, p;
    int dof, pooled;
    double zero_hits;
    long evals;
    long specular;
} run;

/* wo at polar cosine cos_o, azimuth 0.5 (off the grid's phi = 0 boundary). */
static glint_vec3 wo_at(double cos_o)
{
    double s = sqrt(1.0 - cos_o * cos_o);
    return v3((float)(s * cos(0.5)), (float)(s * sin(0.5)), (float)cos_o);
}

static void run_one(const glint_closure *c, double cos_o, uint64_t seed, run *r)
{
    static double counts[N_CELLS], prob[N_CELLS];
    static cell cells[N_CELLS];
    pdf_ctx ctx;
    pcg32 g;
    long absorbed = 0, specular = 0, i;
    int k;

    ctx.closure = c;
    ctx.wo = wo_at(cos_o);
    ctx.evals = 0;
    r->cos_o = cos_o;
    memset(counts, 0, sizeof counts);
    pcg32_seed(&g, seed, 54u);
    for (i = 0; i < M_SAMPLES; i++) {
        float u_c = pcg32_float(&g), u0 = pcg32_float(&g), u1 = pcg32_float(&g);
        glint_sample_result s = sample_result_init();
        glint_status st = glint_sample_lobe(c, 0, ctx.wo, u_c, u0, u1, &s);
        if (st == GLINT_NO_SAMPLE) {
            absorbed++;
            continue;
        }
        if (st != GLINT_OK)
            print_error("%s [%s] cos_o %g: glint_sample_lobe -> %u (%s): %s\n", r->lobe,
                        r->params, cos_o, (unsigned)st, glint_status_string(st),
                        glint_last_error());
        assert_int_equal(st, GLINT_OK);
        if (!(isfinite(s.wi.x) && isfinite(s.wi.y) && isfinite(s.wi.z) && isfinite(s.pdf) &&
              s.pdf > 0.0f && fabsf(v3_length(s.wi) - 1.0f) < 1e-4f))
            print_error("%s [%s] cos_o %g: bad sample wi (%g, %g, %g) pdf %g\n", r->lobe,
                        r->params, cos_o, (double)s.wi.x, (double)s.wi.y, (double)s.wi.z,
                        (double)s.pdf);
        assert_true(isfinite(s.wi.x) && isfinite(s.wi.y) && isfinite(s.wi.z));
        assert_true(fabsf(v3_length(s.wi) - 1.0f) < 1e-4f);
        assert_true(isfinite(s.pdf) && s.pdf > 0.0f);
        for (k = 0; k < 3; k++)
            assert_true(isfinite(s.value[k]) && isfinite(s.weight[k]));
        if (s.flags & GLINT_FLAG_SPECULAR) {
            specular++;
            continue;
        }
        counts[cell_of(s.wi)] += 1.0;
    }
    r->absorbed = (double)absorbed / M_SAMPLES;
    r->specular = specular;
    if (absorbed == M_SAMPLES) {
        /* A one-sided lobe seen from below: nothing to test. From above it must scatter. */
        if (cos_o > 0.0)
            print_error("%s [%s] cos_o %g: every sample absorbed\n", r->lobe, r->params, cos_o);
        assert_true(cos_o < 0.0);
        r->kind = RUN_ONE_SIDED;
        return;
    }
    if (specular == M_SAMPLES - absorbed) {
        r->kind = RUN_DELTA; /* a delta lobe: the chi-square test does not apply */
        return;
    }
    /* A lobe with a density never returns SPECULAR samples. */
    if (specular != 0)
        print_error("%s [%s] cos_o %g: %ld SPECULAR samples from a non-delta lobe\n", r->lobe,
                    r->params, cos_o, specular);
    assert_int_equal(specular, 0);

    r->kind = RUN_CHI2;
    r->integral = expected_probabilities(&ctx, prob);
    r->evals = ctx.evals;
    for (k = 0; k < N_CELLS; k++) {
        cells[k].expected = prob[k] * M_SAMPLES;
        cells[k].observed = counts[k];
    }
    r->x2 = pearson(cells, N_CELLS, &r->dof, &r->zero_hits, &r->pooled);
    assert_true(r->dof > 0);
    r->p = chi2_p_value(r->x2, r->dof);
}

/* ---- the tests -------------------------------------------------------------------- */

static void chi2_every_lobe_type(void **state)
{
    fixture *fx = *state;
    static run runs[MAX_RUNS];
    uint32_t n = lobe_type_count(fx->rt), id;
    int nruns = 0, tests = 0, failures = 0, i;
    double alpha;

    for (id = 0; id < n; id++) {
        glint_lobe_info t = lobe_type(fx->rt, id);
        float *block = calloc(t.param_block_size + 1, sizeof *block);
        uint32_t rough_index = UINT32_MAX, eta_index = UINT32_MAX;
        glint_param_info rough = param_info_init();
        int has_rough = glint_lobe_param_find(fx->rt, id, "roughness", &rough_index) == GLINT_OK;
        int has_eta = glint_lobe_param_find(fx->rt, id, "eta", &eta_index) == GLINT_OK;
        double cos_os[MAX_WO] = {0.9, 0.5, 0.1, -0.7, 0.0};
        int n_wo = 4, config, w;
        assert_non_null(block);
        assert_ok(glint_lobe_param_defaults(fx->rt, id, block, t.param_block_size));
        if (has_rough) {
            assert_ok(glint_lobe_param_info(fx->rt, id, rough_index, &rough));
            assert_int_equal(rough.param_type, GLINT_PARAM_FLOAT);
        }
        /* A refracting lobe with an IOR: also from inside, within the critical angle. */
        if (has_eta && (t.flags & GLINT_FLAG_TRANSMISSION))
            cos_os[n_wo++] = -0.95;

        for (config = 0; config < (has_rough ? 2 : 1); config++) {
            const glint_closure *c;
            char params[48];
            if (config == 0) {
                c = single_lobe_closure(fx, id, NULL, 0, NULL);
                if (has_rough)
                    snprintf(params, sizeof params, "defaults (roughness %g)",
                             (double)rough.default_value[0]);
                else
                    snprintf(params, sizeof params, "defaults");
            } else {
                block[rough.offset] = 0.5f;
                c = single_lobe_closure(fx, id, block, t.param_block_size, NULL);
                snprintf(params, sizeof params, "roughness 0.5");
            }
            for (w = 0; w < n_wo; w++) {
                run *r;
                assert_true(nruns < MAX_RUNS);
                r = &runs[nruns++];
                memset(r, 0, sizeof *r);
                snprintf(r->lobe, sizeof r->lobe, "%s", t.name);
                snprintf(r->params, sizeof r->params, "%s", params);
                run_one(c, cos_os[w], 0x9e3779b97f4a7c15ULL ^ (1000u * id + 100u * config + w),
                        r);
                if (r->kind == RUN_CHI2)
                    tests++;
            }
        }
        free(block);
    }

    assert_true(tests > 0);
    alpha = 1.0 - pow(1.0 - ALPHA, 1.0 / tests);
    print_message("chi-square: %d tests, %d samples each, %d x %d cells, overall alpha %g, "
                  "per-test alpha (Sidak) %.3g\n",
                  tests, M_SAMPLES, N_THETA, N_PHI, ALPHA, alpha);
    print_message("%-10s %-26s %6s %8s %4s %9s %8s %8s %9s %6s %9s\n", "lobe", "params", "cos_o",
                  "X^2", "dof", "p", "absorbed", "integral", "int-(1-a)", "pooled", "pdf evals");
    for (i = 0; i < nruns; i++) {
        const run *r = &runs[i];
        if (r->kind == RUN_ONE_SIDED) {
            print_message("%-10s %-26s %6.2f  one-sided: every sample absorbed, skipped\n",
                          r->lobe, r->params, r->cos_o);
            continue;
        }
        if (r->kind == RUN_DELTA) {
            print_message("%-10s %-26s %6.2f  delta: %ld SPECULAR samples (absorbed %.4f), "
                          "skipped\n",
                          r->lobe, r->params, r->cos_o, r->specular, r->absorbed);
            continue;
        }
        print_message("%-10s %-26s %6.2f %8.1f %4d %9.3g %8.4f %8.5f %+9.5f %6d %9ld\n", r->lobe,
                      r->params, r->cos_o, r->x2, r->dof, r->p, r->absorbed, r->integral,
                      r->integral - (1.0 - r->absorbed), r->pooled, r->evals);
        if (r->zero_hits > 0.0) {
            print_error("  FAIL: %g samples in cells where the pdf integrates to 0 (each sample "
                        "has a positive pdf, so the pdf is 0 on the grid but not at them)\n",
                        r->zero_hits);
            failures++;
        }
        if (!(fabs(r->integral - (1.0 - r->absorbed)) <= INTEGRAL_TOL * (1.0 - r->absorbed))) {
            print_error("  FAIL: the pdf integrates to %.5f, but %.5f of the samples were "
                        "not absorbed\n",
                        r->integral, 1.0 - r->absorbed);
            failures++;
        }
        if (!(r->p >= alpha)) {
            print_error("  FAIL: p = %.3g < %.3g: samples do not follow the pdf\n", r->p,
                        alpha);
            failures++;
        }
    }
    assert_int_equal(failures, 0);
}

/* The incomplete gamma function against closed forms and tabulated chi-square quantiles,
 * on both sides of the series / continued fraction switch. */
static void incomplete_gamma_known_values(void **state)
{
    static const double xs[] = {0.01, 0.5, 1.0, 1.9, 2.1, 5.0, 30.0};
    size_t i;
    (void)state;
    for (i = 0; i < sizeof xs / sizeof xs[0]; i++) {
        double x = xs[i];
        /* Q(1, x) = exp(-x); Q(1/2, x) = erfc(sqrt(x)); Q(2, x) = (1 + x) exp(-x). */
        assert_true(fabs(gamma_q(1.0, x) - exp(-x)) <= 1e-12);
        assert_true(fabs(gamma_q(0.5, x) - erfc(sqrt(x))) <= 1e-12);
        assert_true(fabs(gamma_q(2.0, x) - (1.0 + x) * exp(-x)) <= 1e-12);
    }
    /* Upper 1% points of the chi-square distribution. */
    assert_true(fabs(chi2_p_value(6.634897, 1) - 0.01) < 1e-6);
    assert_true(fabs(chi2_p_value(23.209251, 10) - 0.01) < 1e-6);
    assert_true(fabs(chi2_p_value(135.806723, 100) - 0.01) < 1e-6);
    /* A large dof: the median is near dof (1 - 2 / (9 dof))^3. */
    {
        double median = 800.0 * pow(1.0 - 2.0 / (9.0 * 800.0), 3.0);
        assert_true(fabs(chi2_p_value(median, 800) - 0.5) < 1e-3);
    }
    /* Continuous across the switch at x = a + 1 and monotonic. */
    assert_true(fabs(gamma_q(400.0, 401.0 - 1e-9) - gamma_q(400.0, 401.0 + 1e-9)) < 1e-9);
    assert_true(gamma_q(400.0, 380.0) > gamma_q(400.0, 420.0));
    assert_true(gamma_q(3.0, 0.0) == 1.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(incomplete_gamma_known_values),
        cmocka_unit_test_setup_teardown(chi2_every_lobe_type, fixture_setup, fixture_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
