/* render.c: the integrator (unidirectional path tracing with next-event estimation and
 * multiple importance sampling), threads over tiles, progress and statistics.
 *
 * Every surface is shaded by Glint: per hit, the material's closure is built from its JSON
 * in the thread's arena, in the hit's shading frame. The host keeps that frame: directions
 * go to Glint in local coordinates (z = shading normal), so the material JSON keeps its
 * default normal [0, 0, 1], and sampled directions come back through the same frame.
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "pt.h"
#include "rng.h"

#define TILE 16

typedef struct shared {
    const pt_scene *scene;
    const glint_runtime *rt;
    const pt_settings *set;
    pt_accum *acc;
    int tiles_x, tiles_y, tile_count;
    atomic_int next_tile;
    atomic_int tiles_done;
    /* camera */
    vec3 eye, forward, right, up;
    float tan_half, aspect;
} shared;

typedef struct worker {
    shared *sh;
    pthread_t thread;
    glint_arena *arena;
    struct RTCIntersectContext ictx;
    uint64_t glint_ns[GLINT_KINDS], glint_calls[GLINT_KINDS];
    uint64_t rays, closures, nonfinite, errors, samples;
    double thread_seconds;
    char first_error[256];
} worker;

static uint64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
}

/* Run a glint call and, unless --no-timing, add its duration to the worker's Glint time. */
#define GLINT_TIMED(w, kind, status_var, call)                                               \
    do {                                                                                     \
        if ((w)->sh->set->timing) {                                                          \
            const uint64_t t0_ = now_ns();                                                   \
            status_var = (call);                                                             \
            (w)->glint_ns[kind] += now_ns() - t0_;                                           \
        } else {                                                                             \
            status_var = (call);                                                             \
        }                                                                                    \
        (w)->glint_calls[kind]++;                                                            \
    } while (0)

/* The timers' own cost: the mean interval two back-to-back reads measure (what a timed
 * call adds to the Glint time) and the mean cost of a read pair (what it adds to the
 * thread's time). Best of several batches, against preemption. */
static void calibrate_timer(double *inside_ns, double *pair_ns)
{
    int batch, i;
    *inside_ns = *pair_ns = 1e30;
    for (batch = 0; batch < 5; batch++) {
        uint64_t inside = 0;
        const uint64_t start = now_ns();
        double t;
        for (i = 0; i < 20000; i++) {
            const uint64_t t0 = now_ns();
            inside += now_ns() - t0;
        }
        t = (double)(now_ns() - start) / 20000.0;
        if ((double)inside / 20000.0 < *inside_ns)
            *inside_ns = (double)inside / 20000.0;
        if (t < *pair_ns)
            *pair_ns = t;
    }
}

static void record_error(worker *w, const char *what, glint_status st)
{
    if (w->errors++ == 0)
        snprintf(w->first_error, sizeof w->first_error, "%s: %s (%s)", what, glint_last_error(),
                 glint_status_string(st));
}

/* ---- rays ------------------------------------------------------------------------------ */

typedef struct hit {
    float t, u, v;
    unsigned geom, prim;
} hit;

static int intersect(worker *w, vec3 o, vec3 d, hit *h)
{
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = o.x;
    rh.ray.org_y = o.y;
    rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x;
    rh.ray.dir_y = d.y;
    rh.ray.dir_z = d.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = INFINITY;
    rh.ray.mask = 0xffffffffu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(w->sh->scene->rtc, &w->ictx, &rh);
    w->rays++;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return 0;
    h->t = rh.ray.tfar;
    h->u = rh.hit.u;
    h->v = rh.hit.v;
    h->geom = rh.hit.geomID;
    h->prim = rh.hit.primID;
    return 1;
}

static int occluded(worker *w, vec3 o, vec3 d, float tfar)
{
    struct RTCRay r;
    memset(&r, 0, sizeof r);
    r.org_x = o.x;
    r.org_y = o.y;
    r.org_z = o.z;
    r.dir_x = d.x;
    r.dir_y = d.y;
    r.dir_z = d.z;
    r.tnear = 0.0f;
    r.tfar = tfar;
    r.mask = 0xffffffffu;
    rtcOccluded1(w->sh->scene->rtc, &w->ictx, &r);
    w->rays++;
    return r.tfar < 0.0f; /* set to -inf on a hit */
}

/* Move a surface point off the surface, to the side of `dir`. */
static vec3 offset_point(vec3 p, vec3 ng, vec3 dir)
{
    const float eps = 2e-4f * (1.0f + v_max_abs(p));
    return v_madd(p, ng, v_dot(dir, ng) > 0.0f ? eps : -eps);
}

static float power_heuristic(float a, float b)
{
    if (isinf(a))
        return 1.0f;
    a *= a;
    b *= b;
    return a + b > 0.0f ? a / (a + b) : 0.0f;
}

/* ---- surfaces -------------------------------------------------------------------------- */

typedef struct surface {
    vec3 p, ng, ns, tangent;
    int material;
} surface;

static void surface_at(const pt_scene *s, const hit *h, vec3 o, vec3 d, surface *out)
{
    const pt_object *obj = &s->objects[h->geom];
    out->p = v_madd(o, d, h->t);
    if (obj->kind == OBJ_SPHERE) {
        const vec3 n = v_norm(v_sub(out->p, obj->center));
        out->p = v_madd(obj->center, n, obj->radius); /* back onto the sphere */
        out->ng = out->ns = n;
    } else {
        const uint32_t *tri = &obj->indices[3 * (size_t)h->prim];
        const float *P = obj->positions;
        const vec3 p0 = v3(P[3 * tri[0]], P[3 * tri[0] + 1], P[3 * tri[0] + 2]);
        const vec3 p1 = v3(P[3 * tri[1]], P[3 * tri[1] + 1], P[3 * tri[1] + 2]);
        const vec3 p2 = v3(P[3 * tri[2]], P[3 * tri[2] + 1], P[3 * tri[2] + 2]);
        out->ng = v_norm(v_cross(v_sub(p1, p0), v_sub(p2, p0)));
        out->ns = out->ng;
        if (obj->normals) {
            const float *N = obj->normals;
            const float b0 = 1.0f - h->u - h->v;
            vec3 n = v3(0, 0, 0);
            int k;
            for (k = 0; k < 3; k++) {
                const float b = k == 0 ? b0 : k == 1 ? h->u : h->v;
                n = v_madd(n, v3(N[3 * tri[k]], N[3 * tri[k] + 1], N[3 * tri[k] + 2]), b);
            }
            if (v_dot(n, n) > 0.0f) {
                n = v_norm(n);
                /* Keep the interpolated normal on the geometric normal's side. */
                out->ns = v_dot(n, out->ng) > 0.0f ? n : v_neg(n);
            }
        }
    }
    out->material = obj->material;
    if (obj->material2 >= 0) {
        const float sc = obj->checker_scale;
        const long cx = (long)floorf(out->p.x / sc), cz = (long)floorf(out->p.z / sc);
        if ((cx + cz) & 1)
            out->material = obj->material2;
    }
}

/* ---- lights ---------------------------------------------------------------------------- */

/* Pick a quad light for next-event estimation; returns its index or -1. */
static int pick_light(const pt_scene *s, float u)
{
    int i;
    for (i = 0; i < s->light_count; i++)
        if (u < s->lights[i].cdf)
            return i;
    return s->light_count - 1;
}

/* Solid-angle pdf of next-event estimation choosing the point `p` on light `l` from `ref`
 * (with the light's selection probability), 0 for the back side. */
static float light_pdf(const pt_quad_light *l, vec3 ref, vec3 p)
{
    const vec3 to = v_sub(p, ref);
    const float d2 = v_dot(to, to);
    const float cos_l = -v_dot(to, l->normal) / sqrtf(d2);
    if (cos_l <= 0.0f)
        return 0.0f;
    return l->select_prob * d2 / (cos_l * l->area);
}

/* ---- the path -------------------------------------------------------------------------- */

/* Is `wi` on the same side of the geometric normal as of the shading normal? With
 * interpolated normals (meshes) they can disagree near silhouettes; such directions would
 * leak light through the surface, so they are dropped. Always true on spheres and quads. */
static int side_ok(vec3 wi, vec3 ng, vec3 ns)
{
    return (v_dot(wi, ng) > 0.0f) == (v_dot(wi, ns) > 0.0f);
}

static glint_status build_closure(worker *w, const pt_material *mat, const glint_vec3 *wo,
                                  glint_closure **out)
{
    const glint_status st = glint_arena_reset(w->arena);
    if (st != GLINT_OK)
        return st;
    if (w->sh->set->closures == CLOSURES_BLOCKS)
        return material_build(mat, w->sh->rt, w->arena, wo, out);
    return glint_closure_from_json(w->sh->rt, w->arena, mat->json, wo, out);
}

static vec3 trace(worker *w, rng *r, vec3 o, vec3 d, int *primary_hit)
{
    const pt_scene *s = w->sh->scene;
    const pt_settings *set = w->sh->set;
    const int use_nee = set->strategy != STRATEGY_BSDF;
    const int mis = set->strategy == STRATEGY_MIS;
    vec3 L = v3(0, 0, 0), beta = v3(1, 1, 1);
    /* Product of eta^2 over the transmissions so far: radiance transport scales beta by
     * 1/eta^2 on entering a denser medium, which Russian roulette should not mistake for
     * absorption (it is undone on the way out). */
    float eta_scale = 1.0f;
    int depth, specular = 1; /* the camera ray counts as specular: no MIS */
    float bsdf_pdf = 0.0f;
    vec3 prev_p = o;

    for (depth = 0;; depth++) {
        hit h;
        surface sf;
        const pt_material *mat;
        glint_closure *closure = NULL;
        glint_status st;
        frame fr;
        vec3 wo, wo_l;

        if (!intersect(w, o, d, &h)) {
            const vec3 le = env_radiance(&s->env, d);
            float weight = 1.0f;
            if (!specular && s->env.kind != ENV_NONE)
                weight = mis ? power_heuristic(bsdf_pdf, env_pdf(&s->env, d))
                             : (use_nee ? 0.0f : 1.0f);
            L = v_add(L, v_scale(v_mul(beta, le), weight));
            break;
        }
        if (depth == 0)
            *primary_hit = 1;
        if (s->objects[h.geom].kind == OBJ_LIGHT) {
            const pt_quad_light *l = &s->lights[s->objects[h.geom].light];
            if (v_dot(d, l->normal) < 0.0f) { /* the emitting side */
                float weight = 1.0f;
                if (!specular) {
                    const vec3 p = v_madd(o, d, h.t);
                    weight = mis ? power_heuristic(bsdf_pdf, light_pdf(l, prev_p, p))
                                 : (use_nee ? 0.0f : 1.0f);
                }
                L = v_add(L, v_scale(v_mul(beta, l->radiance), weight));
            }
            break; /* lights do not reflect */
        }
        if (depth >= set->max_depth)
            break;

        surface_at(s, &h, o, d, &sf);
        mat = &s->materials[sf.material];
        wo = v_neg(d);
        if (!mat->transmits && v_dot(wo, sf.ng) < 0.0f) { /* two-sided reflection */
            sf.ng = v_neg(sf.ng);
            sf.ns = v_neg(sf.ns);
        }
        if (v_dot(wo, sf.ns) * v_dot(wo, sf.ng) <= 0.0f)
            sf.ns = sf.ng;
        fr = frame_from_normal(sf.ns);
        wo_l = frame_to_local(&fr, wo);

        /* One timed interval: reset the arena, build the closure. */
        GLINT_TIMED(w, GLINT_BUILD, st, build_closure(w, mat, &wo_l, &closure));
        w->closures++;
        if (st != GLINT_OK) {
            record_error(w, set->closures == CLOSURES_BLOCKS ? "building a closure"
                                                             : "glint_closure_from_json",
                         st);
            break;
        }

        /* Next-event estimation: one point on a quad light, one environment direction. */
        if (use_nee && s->light_count > 0) {
            const pt_quad_light *l = &s->lights[pick_light(s, rng_float(r))];
            const float u1 = rng_float(r), u2 = rng_float(r);
            const vec3 pl = v_add(l->corner, v_add(v_scale(l->e1, u1), v_scale(l->e2, u2)));
            const vec3 to = v_sub(pl, sf.p);
            const float dist = v_len(to);
            const vec3 wi = v_scale(to, 1.0f / dist);
            const float p_light = light_pdf(l, sf.p, pl);
            if (p_light > 0.0f && side_ok(wi, sf.ng, sf.ns)) {
                glint_eval_result e;
                memset(&e, 0, sizeof e);
                e.struct_size = sizeof e;
                GLINT_TIMED(w, GLINT_EVAL, st,
                            glint_eval(closure, wo_l, frame_to_local(&fr, wi), &e));
                if (st != GLINT_OK)
                    record_error(w, "glint_eval", st);
                else if (e.value[0] + e.value[1] + e.value[2] > 0.0f) {
                    /* The shadow ray runs from the offset origin to the light point (not
                     * along wi: from the moved origin that line would end past the light's
                     * plane at grazing angles and hit the light itself). */
                    const vec3 po = offset_point(sf.p, sf.ng, wi);
                    const vec3 seg = v_sub(pl, po);
                    const float seg_len = v_len(seg);
                    const int occ = occluded(w, po, v_scale(seg, 1.0f / seg_len),
                                             seg_len * (1.0f - 1e-4f));
                    if (!occ) {
                        const float weight = mis ? power_heuristic(p_light, e.pdf) : 1.0f;
                        const vec3 f = v3(e.value[0], e.value[1], e.value[2]);
                        L = v_add(L, v_scale(v_mul(v_mul(beta, f), l->radiance),
                                             weight / p_light));
                    }
                }
            }
        }
        if (use_nee && s->env.kind != ENV_NONE) {
            float p_env;
            const float u0 = rng_float(r), u1 = rng_float(r), u2 = rng_float(r);
            const vec3 wi = env_sample(&s->env, u0, u1, u2, &p_env);
            if (p_env > 0.0f && side_ok(wi, sf.ng, sf.ns)) {
                glint_eval_result e;
                memset(&e, 0, sizeof e);
                e.struct_size = sizeof e;
                GLINT_TIMED(w, GLINT_EVAL, st,
                            glint_eval(closure, wo_l, frame_to_local(&fr, wi), &e));
                if (st != GLINT_OK)
                    record_error(w, "glint_eval", st);
                else if (e.value[0] + e.value[1] + e.value[2] > 0.0f &&
                         !occluded(w, offset_point(sf.p, sf.ng, wi), wi, INFINITY)) {
                    const float weight = mis ? power_heuristic(p_env, e.pdf) : 1.0f;
                    const vec3 f = v3(e.value[0], e.value[1], e.value[2]);
                    L = v_add(L, v_scale(v_mul(v_mul(beta, f), env_radiance(&s->env, wi)),
                                         weight / p_env));
                }
            }
        }

        /* Continue the path by sampling the closure. */
        {
            glint_sample_result smp;
            const float ul = rng_float(r), u0 = rng_float(r), u1 = rng_float(r);
            vec3 wi;
            memset(&smp, 0, sizeof smp);
            smp.struct_size = sizeof smp;
            GLINT_TIMED(w, GLINT_SAMPLE, st, glint_sample(closure, wo_l, ul, u0, u1, &smp));
            if (st == GLINT_NO_SAMPLE)
                break;
            if (st != GLINT_OK) {
                record_error(w, "glint_sample", st);
                break;
            }
            wi = frame_to_world(&fr, smp.wi);
            if (!side_ok(wi, sf.ng, sf.ns))
                break;
            beta = v_mul(beta, v3(smp.weight[0], smp.weight[1], smp.weight[2]));
            specular = (smp.flags & GLINT_FLAG_SPECULAR) != 0;
            if (smp.flags & GLINT_FLAG_TRANSMISSION)
                eta_scale *= smp.eta * smp.eta;
            bsdf_pdf = smp.pdf;
            prev_p = sf.p;
            o = offset_point(sf.p, sf.ng, wi);
            d = wi;
        }

        /* Russian roulette after a few bounces. */
        if (depth + 1 >= set->rr_depth) {
            const float q = fminf(0.95f, v_max_comp(beta) * eta_scale);
            if (!(q > 0.0f) || rng_float(r) >= q)
                break;
            beta = v_scale(beta, 1.0f / q);
        }
        if (v_is_zero(beta))
            break;
    }
    return L;
}

/* ---- tiles and threads ------------------------------------------------------------------ */

static void render_tile(worker *w, int tile)
{
    shared *sh = w->sh;
    const pt_settings *set = sh->set;
    const int tx = tile % sh->tiles_x, ty = tile / sh->tiles_x;
    const int x0 = tx * TILE, y0 = ty * TILE;
    const int x1 = x0 + TILE < set->width ? x0 + TILE : set->width;
    const int y1 = y0 + TILE < set->height ? y0 + TILE : set->height;
    int x, y, k;
    for (y = y0; y < y1; y++)
        for (x = x0; x < x1; x++) {
            const size_t pix = (size_t)y * (size_t)set->width + (size_t)x;
            rng r = rng_seed(set->seed, pix);
            double sum[3] = {0, 0, 0}, sum_sq[3] = {0, 0, 0};
            uint32_t hits = 0;
            for (k = 0; k < set->spp; k++) {
                const float px = ((float)x + rng_float(&r)) / (float)set->width * 2.0f - 1.0f;
                const float py = 1.0f - ((float)y + rng_float(&r)) / (float)set->height * 2.0f;
                const vec3 dir = v_norm(v_add(
                    sh->forward, v_add(v_scale(sh->right, px * sh->tan_half * sh->aspect),
                                       v_scale(sh->up, py * sh->tan_half))));
                int primary = 0;
                const vec3 L = trace(w, &r, sh->eye, dir, &primary);
                w->samples++;
                if (!isfinite(L.x) || !isfinite(L.y) || !isfinite(L.z))
                    w->nonfinite++; /* kept: the image shows it and the checker fails */
                hits += (uint32_t)primary;
                sum[0] += L.x;
                sum[1] += L.y;
                sum[2] += L.z;
                sum_sq[0] += (double)L.x * L.x;
                sum_sq[1] += (double)L.y * L.y;
                sum_sq[2] += (double)L.z * L.z;
            }
            for (k = 0; k < 3; k++) {
                sh->acc->sum[3 * pix + (size_t)k] = sum[k];
                sh->acc->sum_sq[3 * pix + (size_t)k] = sum_sq[k];
            }
            sh->acc->hits[pix] = hits;
        }
}

static void *worker_main(void *arg)
{
    worker *w = arg;
    const uint64_t t0 = now_ns();
    for (;;) {
        const int tile = atomic_fetch_add(&w->sh->next_tile, 1);
        if (tile >= w->sh->tile_count)
            break;
        render_tile(w, tile);
        atomic_fetch_add(&w->sh->tiles_done, 1);
    }
    w->thread_seconds = (double)(now_ns() - t0) * 1e-9;
    return NULL;
}

static void progress(int done, int total, double elapsed, int final)
{
    const int width = 40;
    const int fill = total ? done * width / total : width;
    char bar[64];
    int i;
    for (i = 0; i < width; i++)
        bar[i] = i < fill ? '#' : '.';
    bar[width] = '\0';
    if (done > 0 && done < total) {
        const double eta = elapsed * (double)(total - done) / (double)done;
        fprintf(stderr, "\r[%s] %3d%%  %6.1f s elapsed, ETA %6.1f s ", bar, done * 100 / total,
                elapsed, eta);
    } else {
        fprintf(stderr, "\r[%s] %3d%%  %6.1f s elapsed               ", bar,
                total ? done * 100 / total : 100, elapsed);
    }
    if (final)
        fputc('\n', stderr);
    fflush(stderr);
}

int render(const pt_scene *scene, const glint_runtime *rt, const pt_settings *set,
           pt_accum *acc, pt_stats *stats)
{
    shared sh;
    worker *workers;
    int i, k, started = 0;
    const int tty = isatty(STDERR_FILENO);
    const uint64_t t0 = now_ns();
    int last_shown = -1;

    memset(&sh, 0, sizeof sh);
    memset(stats, 0, sizeof *stats);
    sh.scene = scene;
    sh.rt = rt;
    sh.set = set;
    sh.acc = acc;
    sh.tiles_x = (set->width + TILE - 1) / TILE;
    sh.tiles_y = (set->height + TILE - 1) / TILE;
    sh.tile_count = sh.tiles_x * sh.tiles_y;
    atomic_init(&sh.next_tile, 0);
    atomic_init(&sh.tiles_done, 0);
    sh.eye = scene->camera.eye;
    sh.forward = v_norm(v_sub(scene->camera.target, scene->camera.eye));
    sh.right = v_norm(v_cross(sh.forward, scene->camera.up));
    sh.up = v_cross(sh.right, sh.forward);
    sh.tan_half = tanf(0.5f * scene->camera.vfov_deg * PT_PI / 180.0f);
    sh.aspect = (float)set->width / (float)set->height;

    workers = calloc((size_t)set->threads, sizeof *workers);
    if (!workers)
        return -1;
    for (i = 0; i < set->threads; i++) {
        worker *w = &workers[i];
        w->sh = &sh;
        rtcInitIntersectContext(&w->ictx);
        if (glint_arena_create(4, &w->arena) != GLINT_OK) {
            fprintf(stderr, "pathtracer: glint_arena_create: %s\n", glint_last_error());
            break;
        }
        if (pthread_create(&w->thread, NULL, worker_main, w) != 0) {
            fprintf(stderr, "pathtracer: pthread_create failed\n");
            glint_arena_destroy(w->arena);
            w->arena = NULL;
            break;
        }
        started++;
    }
    if (started == 0) {
        free(workers);
        return -1;
    }
    /* With fewer threads than asked, the started ones still take every tile. */
    for (;;) {
        const int done = atomic_load(&sh.tiles_done);
        const double elapsed = (double)(now_ns() - t0) * 1e-9;
        if (done >= sh.tile_count)
            break;
        if (!set->quiet) {
            const int decile = done * 10 / sh.tile_count;
            if (tty)
                progress(done, sh.tile_count, elapsed, 0);
            else if (decile != last_shown) { /* logs: one line per 10% */
                last_shown = decile;
                progress(done, sh.tile_count, elapsed, 1);
            }
        }
        {
            const struct timespec ts = {0, 200 * 1000 * 1000};
            nanosleep(&ts, NULL);
        }
    }
    for (i = 0; i < started; i++)
        pthread_join(workers[i].thread, NULL);
    stats->seconds = (double)(now_ns() - t0) * 1e-9;
    if (set->timing)
        calibrate_timer(&stats->timer_inside_ns, &stats->timer_pair_ns);
    if (!set->quiet)
        progress(sh.tile_count, sh.tile_count, stats->seconds, 1);

    for (i = 0; i < started; i++) {
        worker *w = &workers[i];
        stats->thread_seconds += w->thread_seconds;
        for (k = 0; k < GLINT_KINDS; k++) {
            stats->glint_kind_seconds[k] += (double)w->glint_ns[k] * 1e-9;
            stats->glint_kind_calls[k] += w->glint_calls[k];
            stats->glint_seconds += (double)w->glint_ns[k] * 1e-9;
            stats->glint_calls += w->glint_calls[k];
        }
        stats->rays += w->rays;
        stats->samples += w->samples;
        stats->closures += w->closures;
        stats->nonfinite += w->nonfinite;
        if (w->errors && !stats->glint_errors)
            memcpy(stats->first_error, w->first_error, sizeof stats->first_error);
        stats->glint_errors += w->errors;
        glint_arena_destroy(w->arena);
    }
    free(workers);
    return 0;
}
