/* render.c: the integrator (unidirectional path tracing with next-event estimation and
 * multiple importance sampling), threads over tiles, progress and statistics.
 *
 * Every surface is shaded by Glint: per hit, the material's closure is built in the thread's
 * arena from what was prepared once per scene material, never from JSON (surface_closure):
 * a compiled material's with glint_material_closure and the hit's shading context in world
 * space; a closure given as lobes from its decoded blocks in the hit's shading frame, where
 * its lobes keep their default normal [0, 0, 1]. Directions go to Glint and come back in
 * the hit's `space` (world, or that frame).
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "host.h"
#include "pt.h"
#include "rng.h"

#define TILE 16

typedef struct shared {
    const ex_scene *scene;
    const glint_runtime *rt;
    const pt_settings *set;
    pt_accum *acc;
    int tiles_x, tiles_y, tile_count;
    atomic_int next_tile;
    atomic_int tiles_done;
    ex_view view;
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

/* Run a glint call and, unless --no-timing, add its duration to the worker's Glint time. */
#define GLINT_TIMED(w, kind, status_var, call)                                               \
    do {                                                                                     \
        if ((w)->sh->set->timing) {                                                          \
            const uint64_t t0_ = host_now_ns();                                                   \
            status_var = (call);                                                             \
            (w)->glint_ns[kind] += host_now_ns() - t0_;                                           \
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
        const uint64_t start = host_now_ns();
        double t;
        for (i = 0; i < 20000; i++) {
            const uint64_t t0 = host_now_ns();
            inside += host_now_ns() - t0;
        }
        t = (double)(host_now_ns() - start) / 20000.0;
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

static float power_heuristic(float a, float b)
{
    if (isinf(a))
        return 1.0f;
    a *= a;
    b *= b;
    return a + b > 0.0f ? a / (a + b) : 0.0f;
}

/* ---- lights ---------------------------------------------------------------------------- */

/* Pick a quad light for next-event estimation; returns its index or -1. */
static int pick_light(const ex_scene *s, float u)
{
    int i;
    for (i = 0; i < s->light_count; i++)
        if (u < s->lights[i].cdf)
            return i;
    return s->light_count - 1;
}

/* Solid-angle pdf of next-event estimation choosing the point `p` on light `l` from `ref`
 * (with the light's selection probability), 0 for the back side. */
static float light_pdf(const ex_quad_light *l, vec3 ref, vec3 p)
{
    const vec3 to = v_sub(p, ref);
    const float d2 = v_dot(to, to);
    const float cos_l = -v_dot(to, l->normal) / sqrtf(d2);
    if (cos_l <= 0.0f)
        return 0.0f;
    return l->select_prob * d2 / (cos_l * l->area);
}

/* ---- the path -------------------------------------------------------------------------- */

/* f(wo, wi) |cos| of the closure toward a light, or 0 when the shadow ray o + t d,
 * t < len, is blocked (or the evaluation fails); *pdf is the closure's pdf of wi. */
static vec3 unoccluded_f(worker *w, const glint_closure *closure, const ex_surface *sf, vec3 wi,
                         vec3 o, vec3 d, float len, float *pdf)
{
    glint_eval_result e;
    glint_status st;
    memset(&e, 0, sizeof e);
    e.struct_size = sizeof e;
    *pdf = 0.0f;
    GLINT_TIMED(w, GLINT_EVAL, st,
                glint_eval(closure, sf->wo_space, frame_to_local(&sf->space, wi), &e));
    if (st != GLINT_OK) {
        record_error(w, "glint_eval", st);
        return v3(0, 0, 0);
    }
    if (!(e.value[0] + e.value[1] + e.value[2] > 0.0f))
        return v3(0, 0, 0);
    w->rays++;
    if (scene_occluded(w->sh->scene, &w->ictx, o, d, len))
        return v3(0, 0, 0);
    *pdf = e.pdf;
    return v3(e.value[0], e.value[1], e.value[2]);
}

static glint_status build_closure(worker *w, const ex_surface *sf, glint_closure **out)
{
    const glint_status st = glint_arena_reset(w->arena);
    if (st != GLINT_OK)
        return st;
    return surface_closure(w->sh->scene, w->sh->rt, w->arena, sf, out);
}

static vec3 trace(worker *w, rng *r, vec3 o, vec3 d, int *primary_hit)
{
    const ex_scene *s = w->sh->scene;
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
        ex_hit h;
        ex_surface sf;
        glint_closure *closure = NULL;
        glint_status st;
        int i, compiled;

        w->rays++;
        if (!scene_intersect(s, &w->ictx, o, d, &h)) {
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
            const ex_quad_light *l = &s->lights[s->objects[h.geom].light];
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

        /* One timed interval: reset the arena, build the closure. */
        compiled = s->materials[sf.material].compiled != NULL;
        GLINT_TIMED(w, compiled ? GLINT_BUILD_MATERIAL : GLINT_BUILD_LOBES, st,
                    build_closure(w, &sf, &closure));
        w->closures++;
        if (st != GLINT_OK) {
            record_error(w, compiled ? "glint_material_closure" : "building a closure", st);
            break;
        }

        /* Next-event estimation: one point on a quad light, one environment direction,
         * every delta light (which only this strategy can reach: BSDF sampling never hits a
         * point, so they are added whatever the strategy, with weight 1). */
        if (use_nee && s->light_count > 0) {
            const ex_quad_light *l = &s->lights[pick_light(s, rng_float(r))];
            const float u1 = rng_float(r), u2 = rng_float(r);
            const vec3 pl = v_add(l->corner, v_add(v_scale(l->e1, u1), v_scale(l->e2, u2)));
            const vec3 wi = v_norm(v_sub(pl, sf.p));
            const float p_light = light_pdf(l, sf.p, pl);
            if (p_light > 0.0f && side_ok(wi, sf.ng, sf.ns)) {
                /* The shadow ray runs from the offset origin to the light point (not along
                 * wi: from the moved origin that line would end past the light's plane at
                 * grazing angles and hit the light itself). */
                const vec3 po = offset_point(sf.p, sf.ng, wi);
                const vec3 seg = v_sub(pl, po);
                const float seg_len = v_len(seg);
                float pdf;
                const vec3 f = unoccluded_f(w, closure, &sf, wi, po, v_scale(seg, 1.0f / seg_len),
                                            seg_len * (1.0f - 1e-4f), &pdf);
                const float weight = mis ? power_heuristic(p_light, pdf) : 1.0f;
                L = v_add(L, v_scale(v_mul(v_mul(beta, f), l->radiance), weight / p_light));
            }
        }
        if (use_nee && s->env.kind != ENV_NONE) {
            float p_env;
            const float u0 = rng_float(r), u1 = rng_float(r), u2 = rng_float(r);
            const vec3 wi = env_sample(&s->env, u0, u1, u2, &p_env);
            if (p_env > 0.0f && side_ok(wi, sf.ng, sf.ns)) {
                float pdf;
                const vec3 f = unoccluded_f(w, closure, &sf, wi,
                                            offset_point(sf.p, sf.ng, wi), wi, INFINITY, &pdf);
                const float weight = mis ? power_heuristic(p_env, pdf) : 1.0f;
                L = v_add(L, v_scale(v_mul(v_mul(beta, f), env_radiance(&s->env, wi)),
                                     weight / p_env));
            }
        }
        for (i = 0; i < delta_light_count(s); i++) {
            vec3 wi, so, sd, irradiance;
            float len, pdf;
            if (delta_light_at(s, i, &sf, &wi, &so, &sd, &len, &irradiance)) {
                const vec3 f = unoccluded_f(w, closure, &sf, wi, so, sd, len, &pdf);
                L = v_add(L, v_mul(v_mul(beta, f), irradiance));
            }
        }

        /* Continue the path by sampling the closure. */
        {
            glint_sample_result smp;
            const float ul = rng_float(r), u0 = rng_float(r), u1 = rng_float(r);
            vec3 wi;
            memset(&smp, 0, sizeof smp);
            smp.struct_size = sizeof smp;
            GLINT_TIMED(w, GLINT_SAMPLE, st, glint_sample(closure, sf.wo_space, ul, u0, u1, &smp));
            if (st == GLINT_NO_SAMPLE)
                break;
            if (st != GLINT_OK) {
                record_error(w, "glint_sample", st);
                break;
            }
            wi = frame_to_world(&sf.space, smp.wi);
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
                const float jx = set->pixel_center ? 0.5f : rng_float(&r);
                const float jy = set->pixel_center ? 0.5f : rng_float(&r);
                const vec3 dir = camera_ray(&sh->view, (float)x + jx, (float)y + jy);
                int primary = 0;
                const vec3 L = trace(w, &r, sh->view.eye, dir, &primary);
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
    const uint64_t t0 = host_now_ns();
    for (;;) {
        const int tile = atomic_fetch_add(&w->sh->next_tile, 1);
        if (tile >= w->sh->tile_count)
            break;
        render_tile(w, tile);
        atomic_fetch_add(&w->sh->tiles_done, 1);
    }
    w->thread_seconds = (double)(host_now_ns() - t0) * 1e-9;
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

int render(const ex_scene *scene, const glint_runtime *rt, const pt_settings *set,
           pt_accum *acc, pt_stats *stats)
{
    shared sh;
    worker *workers;
    int i, k, started = 0;
    const int tty = isatty(STDERR_FILENO);
    const uint64_t t0 = host_now_ns();
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
    sh.view = camera_view(&scene->camera, set->width, set->height);

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
        const double elapsed = (double)(host_now_ns() - t0) * 1e-9;
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
    stats->seconds = (double)(host_now_ns() - t0) * 1e-9;
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
