/*
 * charlie.c: the "Charlie" sheen lobe as a Glint plugin (lobe type `charlie`).
 *
 * Model: Estevez & Kulla 2017, "Production Friendly Microfacet Sheen BRDF" (Sony
 * Pictures Imageworks, SIGGRAPH 2017 course "Physically Based Shading in Theory and
 * Practice"): a microfacet BRDF whose normals lie mostly flat on the surface, like the
 * fibres of cloth, so it reflects mostly at grazing angles.
 *
 *   f(wo, wi) = color D(h) G2(wo, wi) / (4 cos_o cos_i),     h = normalize(wo + wi)
 *
 *   D(h)  = (2 + 1/a) sin(theta_h)^(1/a) / (2 pi)    the Charlie distribution, normalized
 *                                                     so that int D(h) cos(theta_h) dh = 1
 *   G2    = 1 / (1 + Lambda(cos_o) + Lambda(cos_i))   height-correlated Smith shadowing
 *                                                     (Heitz 2014, "Understanding the
 *                                                     Masking-Shadowing Function in
 *                                                     Microfacet-Based BRDFs")
 *   Lambda(mu) = exp(L(mu))                  for mu < 1/2,
 *              = exp(2 L(1/2) - L(1 - mu))   otherwise,
 *   L(x) = A / (1 + B x^C) + D x + E         the paper's fit of the distribution's Lambda;
 *                                           each of A..E is t p0 + (1 - t) p1 with
 *                                           t = (1 - a)^2, p0 and p1 its r = 0 and r = 1
 *                                           rows (A 25.3245 21.5473, B 3.32435 3.82987,
 *                                           C 0.16801 0.19823, D -1.27393 -1.97760,
 *                                           E -4.85967 -4.32054).
 *
 * Parameters (the block is `charlie_params`, four floats):
 *   color      rgb [0, 1], default 1 1 1: the sheen tint; the albedo scales with it.
 *   roughness  float [0.07, 1], default 0.5: a = roughness, the distribution's parameter
 *              r as the paper writes D and interpolates its fit. Not roughness^2: the
 *              range's lower end would become a = 0.0049, D = sin^204, a ridge of
 *              microfacet normals in the plane of the surface whose reflections nearly all
 *              go below the horizon; 0.07 keeps 1/a <= 14.3, a smooth lobe.
 *
 * Choices, with the reasons:
 *   - Shadowing: the paper's fitted Lambda, not the Ashikhmin / Neubelt-Pettineo visibility
 *     V = 1 / (4 (cos_i + cos_o - cos_i cos_o)) (Ashikhmin & Premoze 2007; Neubelt &
 *     Pettineo 2013, "Crafting a Next-Gen Material Pipeline for The Order: 1886"): with
 *     this D that V creates energy at grazing angles, directional albedo up to 1.59 at
 *     roughness 0.07 and 1.02 at 0.2 (measured by quadrature), while the fitted Lambda
 *     keeps it below 0.99 (0.988 at cos_o 0.005, roughness 0.07). The fit is the paper's,
 *     not exact: against Lambda integrated numerically from D, its G1 = 1 / (1 + Lambda)
 *     is within 14% over the parameter range (worst at grazing).
 *   - The paper's "terminator softening" (Lambda(cos_i)^(1 + 2 (1 - cos_i)^8) on the light
 *     side only) is left out: it breaks reciprocity, and this lobe is reciprocal.
 *   - One-sided: value and pdf are 0 when wo or wi is below (or on) the surface. Cosines
 *     below 1e-4 are clamped to 1e-4 in Lambda and in the 1/(cos_o cos_i) factor: the fit
 *     is meant for visible angles, and under about 1e-5 its mu Lambda(mu) falls toward 0,
 *     which would make f grow without bound at the horizon.
 *   - Sampling: h is drawn with pdf D(h) cos(theta_h) (the normalization above makes it a
 *     density): the CDF of sin^(1/a) cos sin in theta is sin^(2 + 1/a), so
 *     sin(theta_h) = u1^(1 / (2 + 1/a)), phi_h = 2 pi u2; wi = reflect(wo, h), and
 *     pdf(wi) = D(h) cos(theta_h) / (4 |wo.h|) (the reflection Jacobian of Walter et al.
 *     2007). A reflection that ends below the surface is no sample (return 0): eval's pdf
 *     integrates to the rest. The sample's value and pdf come from eval at the sampled
 *     wi. Exact but wasteful near the normal, as D puts h near the plane of the surface:
 *     from wo along the normal 99.6% of the draws are lost at roughness 0.07, 65% at 1
 *     (about half at grazing wo); the weights value / pdf stay below 1 / cos_o (measured).
 *   - Albedo: a table of the albedo of color = 1 over (cos_o, roughness), computed once
 *     in glint_plugin_entry by quadrature of this file's own eval and read bilinearly
 *     (its measured accuracy is with the table below: 0.81% where E >= 0.01).
 *
 * Build (against glint_plugin.h only; no link to libglint):
 *   cc -O2 -shared -fPIC -fvisibility=hidden -I include plugins/charlie.c \
 *      -o glint_charlie.so -lm -pthread
 */
#include "glint_plugin.h"

#include <math.h>
#include <pthread.h>
#include <stddef.h>

/* The parameter block: four floats, in the parameter table's order. */
typedef struct charlie_params {
    float color[3];
    float roughness;
} charlie_params;

/* The loader wants the packed layout (4 bytes per float, table order): fail the build,
 * not the load, if the struct ever differs. */
typedef char charlie_params_is_packed[sizeof(charlie_params) == 4 * sizeof(float) ? 1 : -1];

#define PI_F 3.14159265358979f
#define ROUGHNESS_MIN 0.07f
#define ROUGHNESS_MAX 1.0f
/* Smallest cosine used in Lambda and 1/(cos_o cos_i) (see the file doc). */
#define COS_MIN 1e-4f

/* ---- the model ----------------------------------------------------------------------- */

static float clampf(float x, float lo, float hi)
{
    /* NaN goes to lo: the host validates parameters, but no input may produce a NaN. */
    return x >= lo ? (x <= hi ? x : hi) : lo;
}

static float alpha_of(const charlie_params *p)
{
    return clampf(p->roughness, ROUGHNESS_MIN, ROUGHNESS_MAX);
}

/* The paper's L(x), coefficients interpolated in t = (1 - a)^2. */
static float fit_l(float a, float x)
{
    float t = (1.0f - a) * (1.0f - a), s = 1.0f - t;
    float ca = t * 25.3245f + s * 21.5473f;
    float cb = t * 3.32435f + s * 3.82987f;
    float cc = t * 0.16801f + s * 0.19823f;
    float cd = t * -1.27393f + s * -1.97760f;
    float ce = t * -4.85967f + s * -4.32054f;
    return ca / (1.0f + cb * powf(x, cc)) + cd * x + ce;
}

/* Lambda(mu) for mu in [COS_MIN, 1]. */
static float charlie_lambda(float a, float mu)
{
    return mu < 0.5f ? expf(fit_l(a, mu)) : expf(2.0f * fit_l(a, 0.5f) - fit_l(a, 1.0f - mu));
}

/* D(h) from sin^2(theta_h). */
static float charlie_d(float a, float sin2)
{
    return (2.0f + 1.0f / a) * (0.5f / PI_F) * powf(sin2, 0.5f / a);
}

/* value = color f cos_i and pdf, for an alpha already clamped. Every path writes finite
 * values >= 0; anything outside the lobe's support writes zeros. */
static void eval_alpha(const float color[3], float a, const float wo[3], const float wi[3],
                       float value[3], float *pdf)
{
    float co = wo[2], ci = wi[2];
    float h[3], len2, inv_len, wo_h, sin2, d, g2, f, p, cl_o, cl_i;
    int k;
    value[0] = value[1] = value[2] = 0.0f;
    *pdf = 0.0f;
    /* One-sided; the negated tests also reject NaN inputs. */
    if (!(co > 0.0f && ci > 0.0f))
        return;
    h[0] = wo[0] + wi[0];
    h[1] = wo[1] + wi[1];
    h[2] = co + ci;
    len2 = h[0] * h[0] + h[1] * h[1] + h[2] * h[2];
    if (!(len2 > 1e-12f && len2 < 1e30f))
        return;
    inv_len = 1.0f / sqrtf(len2);
    h[0] *= inv_len, h[1] *= inv_len, h[2] *= inv_len;
    wo_h = wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2];
    if (!(wo_h > 0.0f))
        return;
    /* sin^2 from the tangential components: no cancellation near the normal. */
    sin2 = fminf(h[0] * h[0] + h[1] * h[1], 1.0f);
    d = charlie_d(a, sin2);
    cl_o = clampf(co, COS_MIN, 1.0f);
    cl_i = clampf(ci, COS_MIN, 1.0f);
    g2 = 1.0f / (1.0f + charlie_lambda(a, cl_o) + charlie_lambda(a, cl_i));
    f = d * g2 / (4.0f * cl_o * cl_i);
    p = d * h[2] / (4.0f * wo_h);
    if (!(isfinite(f) && isfinite(p) && f >= 0.0f && p >= 0.0f))
        return;
    for (k = 0; k < 3; k++)
        value[k] = clampf(color[k], 0.0f, 1.0f) * f * ci;
    *pdf = p;
}

/* ---- the albedo table ------------------------------------------------------------------
 *
 * E(cos_o, a): the albedo of color = 1 on ALBEDO_N_MU x ALBEDO_N_A nodes. cos_o =
 * COS_MIN + (1 - COS_MIN) sin^3(pi s / 2), s uniform in [0, 1]: dense at grazing, where E
 * changes fastest (cubic in s: E has a knee between 1e-4 and 1e-3), and near the normal,
 * where a narrow lobe's small E falls steeply (below COS_MIN the lobe is COS_MIN's, so
 * node 0 covers it); a log-uniform over [0.07, 1], as E varies about like exp(-c / a)
 * there. Each node is a midpoint quadrature of eval over the
 * upper hemisphere in (t, phi), cos_i = t^2 (nodes crowd the horizon, where the lobe
 * lives), phi in [0, pi] (the integrand is even in phi with wo in the xz plane).
 *
 * Measured by a throwaway program against an f64 quadrature of the same formulas (300 x
 * 150 nodes, converged to 1e-5) at 20000 random (cos_o, roughness), a quarter of them
 * with cos_o < 0.02 and a quarter with cos_o > 0.95: worst relative error 0.81% wherever
 * E >= 0.01 (mean 0.1%); worst absolute error 3.4e-3 (cos_o < 0.02); where E < 0.01
 * (near the normal at roughness < 0.1, E down to 2.6e-4) up to 3.2% relative, 2.7e-4
 * absolute. The quadrature alone is within 1.4e-3 at the nodes. Building the table takes
 * about 240 ms on one core (2.4M evals), once per process.
 */
#define ALBEDO_N_MU 64
#define ALBEDO_N_A 32
#define QUAD_N_T 48
#define QUAD_N_PHI 24

static float albedo_table[ALBEDO_N_MU][ALBEDO_N_A];
static pthread_once_t albedo_once = PTHREAD_ONCE_INIT;

static float node_mu(int i)
{
    float s = sinf(0.5f * PI_F * (float)i / (ALBEDO_N_MU - 1));
    return COS_MIN + (1.0f - COS_MIN) * s * s * s;
}

static float node_alpha(int j)
{
    return ROUGHNESS_MIN * powf(ROUGHNESS_MAX / ROUGHNESS_MIN, (float)j / (ALBEDO_N_A - 1));
}

static float albedo_quadrature(float mu, float a)
{
    static const float white[3] = {1.0f, 1.0f, 1.0f};
    const double pi = 3.14159265358979;
    float wo[3];
    double sum = 0.0;
    int i, j;
    wo[0] = sqrtf(fmaxf(0.0f, 1.0f - mu * mu));
    wo[1] = 0.0f;
    wo[2] = mu;
    for (i = 0; i < QUAD_N_T; i++) {
        double t = (i + 0.5) / QUAD_N_T, ci = t * t, si = sqrt(1.0 - ci * ci), row = 0.0;
        for (j = 0; j < QUAD_N_PHI; j++) {
            double phi = pi * (j + 0.5) / QUAD_N_PHI;
            float wi[3], value[3], pdf;
            wi[0] = (float)(si * cos(phi));
            wi[1] = (float)(si * sin(phi));
            wi[2] = (float)ci;
            eval_alpha(white, a, wo, wi, value, &pdf);
            row += value[0];
        }
        /* d omega = d cos_i d phi = 2 t dt d phi, and both halves of phi. */
        sum += row * (2.0 * t / QUAD_N_T) * (2.0 * pi / QUAD_N_PHI);
    }
    return (float)sum;
}

static void build_albedo_table(void)
{
    int i, j;
    for (i = 0; i < ALBEDO_N_MU; i++)
        for (j = 0; j < ALBEDO_N_A; j++)
            albedo_table[i][j] = albedo_quadrature(node_mu(i), node_alpha(j));
}

/* Bilinear lookup of E(cos_o, a), a in [ROUGHNESS_MIN, ROUGHNESS_MAX]. */
static float albedo_lookup(float mu, float a)
{
    float m = (clampf(mu, COS_MIN, 1.0f) - COS_MIN) / (1.0f - COS_MIN);
    float x = asinf(cbrtf(m)) * (2.0f / PI_F) * (ALBEDO_N_MU - 1);
    float y = logf(a / ROUGHNESS_MIN) / logf(ROUGHNESS_MAX / ROUGHNESS_MIN) * (ALBEDO_N_A - 1);
    int i, j;
    float fx, fy;
    x = clampf(x, 0.0f, (float)(ALBEDO_N_MU - 1));
    y = clampf(y, 0.0f, (float)(ALBEDO_N_A - 1));
    i = (int)x < ALBEDO_N_MU - 2 ? (int)x : ALBEDO_N_MU - 2;
    j = (int)y < ALBEDO_N_A - 2 ? (int)y : ALBEDO_N_A - 2;
    fx = x - (float)i;
    fy = y - (float)j;
    return (1.0f - fx) * ((1.0f - fy) * albedo_table[i][j] + fy * albedo_table[i][j + 1]) +
           fx * ((1.0f - fy) * albedo_table[i + 1][j] + fy * albedo_table[i + 1][j + 1]);
}

/* ---- the callbacks --------------------------------------------------------------------- */

static void charlie_eval(const void *params, const float wo[3], const float wi[3],
                         uint32_t transport, float value[3], float *pdf)
{
    const charlie_params *p = params;
    (void)transport; /* reflection only: radiance and importance agree */
    eval_alpha(p->color, alpha_of(p), wo, wi, value, pdf);
}

static int32_t charlie_sample(const void *params, const float wo[3], const float u[3],
                              uint32_t transport, glint_plugin_sample *out)
{
    const charlie_params *p = params;
    float a = alpha_of(p), sin_h, cos2_h, cos_h, phi, h[3], wo_h, wi[3], len;
    (void)transport;
    if (!(wo[2] > 0.0f))
        return 0;
    /* sin(theta_h) = u1^(1 / (2 + 1/a)); cos^2 = 1 - u1^(2 / (2 + 1/a)) by expm1, exact
     * near u1 = 1 where the microfacet lies flat. u[0] (a discrete choice) is unused. */
    sin_h = powf(u[1], 1.0f / (2.0f + 1.0f / a));
    cos2_h = -expm1f(2.0f / (2.0f + 1.0f / a) * logf(u[1]));
    cos_h = sqrtf(clampf(cos2_h, 0.0f, 1.0f));
    phi = 2.0f * PI_F * u[2];
    h[0] = sin_h * cosf(phi);
    h[1] = sin_h * sinf(phi);
    h[2] = cos_h;
    wo_h = wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2];
    wi[0] = 2.0f * wo_h * h[0] - wo[0];
    wi[1] = 2.0f * wo_h * h[1] - wo[1];
    wi[2] = 2.0f * wo_h * h[2] - wo[2];
    len = sqrtf(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2]);
    if (!(len > 0.5f && len < 2.0f))
        return 0;
    wi[0] /= len, wi[1] /= len, wi[2] /= len;
    if (!(wi[2] > 0.0f))
        return 0; /* reflected below the surface: absorbed */
    /* Value and pdf from eval itself, so they agree with it exactly. */
    eval_alpha(p->color, a, wo, wi, out->value, &out->pdf);
    if (!(out->pdf > 0.0f))
        return 0;
    out->wi[0] = wi[0];
    out->wi[1] = wi[1];
    out->wi[2] = wi[2];
    out->events = 0;
    out->eta = 1.0f;
    out->roughness = a;
    return 1;
}

static void charlie_albedo(const void *params, const float wo[3], uint32_t transport,
                           float albedo[3])
{
    const charlie_params *p = params;
    float e = 0.0f;
    int k;
    (void)transport;
    if (wo[2] > 0.0f)
        e = albedo_lookup(wo[2], alpha_of(p));
    for (k = 0; k < 3; k++)
        albedo[k] = clampf(p->color[k], 0.0f, 1.0f) * e;
}

/* The batch path: a plain loop over the lanes (the host then skips its own loop). */
static void charlie_eval_batch(const glint_plugin_eval_batch *b)
{
    size_t i;
    for (i = 0; i < b->count; i++) {
        float wo[3], wi[3], value[3], pdf;
        wo[0] = b->wo_x[i], wo[1] = b->wo_y[i], wo[2] = b->wo_z[i];
        wi[0] = b->wi_x[i], wi[1] = b->wi_y[i], wi[2] = b->wi_z[i];
        charlie_eval(b->params[i], wo, wi, b->transport, value, &pdf);
        b->value_r[i] = value[0];
        b->value_g[i] = value[1];
        b->value_b[i] = value[2];
        b->pdf[i] = pdf;
    }
}

/* ---- the plugin table ------------------------------------------------------------------ */

static const glint_plugin_param charlie_param_table[] = {
    {.name = "color",
     .type = GLINT_PLUGIN_PARAM_RGB,
     .offset = offsetof(charlie_params, color),
     .default_value = {1.0f, 1.0f, 1.0f},
     .min = 0.0f,
     .max = 1.0f,
     .doc = "sheen tint (scales the albedo)"},
    {.name = "roughness",
     .type = GLINT_PLUGIN_PARAM_FLOAT,
     .offset = offsetof(charlie_params, roughness),
     .default_value = {0.5f, 0.0f, 0.0f},
     .min = ROUGHNESS_MIN,
     .max = ROUGHNESS_MAX,
     .doc = "alpha of the Charlie distribution (not squared)"},
};

static const glint_plugin_lobe_v1 charlie_lobe = {
    .struct_size = sizeof(glint_plugin_lobe_v1),
    .name = "charlie",
    .summary = "Charlie sheen (Estevez & Kulla 2017): cloth-like grazing reflection",
    .flags = GLINT_PLUGIN_FLAG_REFLECTION | GLINT_PLUGIN_FLAG_GLOSSY,
    .reciprocal = 1,
    .params = charlie_param_table,
    .param_count = sizeof charlie_param_table / sizeof charlie_param_table[0],
    .block_size = sizeof(charlie_params),
    .block_align = 4,
    .eval = charlie_eval,
    .sample = charlie_sample,
    .albedo = charlie_albedo,
    .eval_batch = charlie_eval_batch,
};

static const glint_plugin_v1 charlie_plugin = {
    .struct_size = sizeof(glint_plugin_v1),
    .name = "glint_charlie",
    .lobe_count = 1,
    .lobes = &charlie_lobe,
};

GLINT_PLUGIN_EXPORT int32_t glint_plugin_entry(uint32_t host_abi_version,
                                               uint32_t *plugin_abi_version,
                                               const void **table)
{
    if (host_abi_version < GLINT_PLUGIN_ABI_V1 || plugin_abi_version == NULL || table == NULL)
        return 1;
    /* Once per process, however many runtimes load this file and from which threads;
     * the callbacks only read the table afterwards. */
    if (pthread_once(&albedo_once, build_albedo_table) != 0)
        return 1;
    *plugin_abi_version = GLINT_PLUGIN_ABI_V1;
    *table = &charlie_plugin;
    return 0;
}
