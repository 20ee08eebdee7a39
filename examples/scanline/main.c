/* scanline: a deferred scanline host in the spirit of seed 004's scanline renderer and seed
 * 001's reflection equation, on Glint's batch API.
 *
 * Pass 1 fills a G-buffer: one Embree primary ray through each pixel's center gives the
 * shading point (position, normals, frame, material, wo), or the radiance of the light or
 * environment the ray sees. Pass 2 shades the image a scanline at a time,
 *   L = L_ambient * albedo(wo) + sum over lights of f(wo, wi) |cos| E_light V,
 * with the row's surface pixels as lanes grouped by material:
 *  - compiled materials (material documents): per material, one glint_material_eval_batch
 *    over its lanes (world-space wo, normal and tangent per lane) at every delta light's
 *    direction (direction_count) with the albedo in the same call: each lane is expanded
 *    once for the ambient term and all lights; no closure is built;
 *  - closures given as lobes: each pixel's closure built lobe by lobe in the thread's arena,
 *    then one glint_albedo_batch and one glint_eval_batch per light over per-lane closures.
 * Shadowed or unlit lanes are masked off (a compiled material's are evaluated at their
 * view direction and weighted by zero).
 *
 * Lights: the scene's point and directional lights; a quad light, which a scanline renderer
 * has no way to sample, is stood in for by a point light at its center with its on-axis
 * intensity (radiance x area). The ambient radiance defaults to the environment's mean.
 * See README.md in this directory.
 */
#define _POSIX_C_SOURCE 200809L

#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host.h"
#include "image_io.h"

typedef struct settings {
    int width, height, threads, quiet;
    int ambient_given;
    vec3 ambient;
} settings;

enum { PIX_MISS, PIX_LIGHT, PIX_SURFACE };

/* Kinds of timed Glint calls: building closures (glint_arena_reset, the lobe-by-lobe
 * calls), batch calls over closures (glint_albedo_batch, glint_eval_batch), material batch
 * calls (glint_material_albedo_batch, glint_material_eval_batch). */
enum { GLINT_BUILD, GLINT_BATCH, GLINT_MATERIAL_BATCH, GLINT_KINDS };

/* One G-buffer pixel: what the primary ray saw. */
typedef struct gpixel {
    int kind;
    vec3 radiance; /* PIX_MISS, PIX_LIGHT: what the pixel shows */
    ex_surface sf; /* PIX_SURFACE */
} gpixel;

typedef struct shared {
    const ex_scene *scene;
    const glint_runtime *rt;
    const settings *set;
    ex_view view;
    vec3 ambient;
    gpixel *gbuf;
    float *rgb; /* 3 per pixel */
    int pass;   /* 0: G-buffer, 1: shading */
    atomic_int next_row;
} shared;

/* Per-thread state. The row's surface pixels are lanes grouped by material: closures given
 * as lobes first, lanes [group[0], group[1]), then compiled material m's lanes
 * [group[m + 1], group[m + 2]). The lane arrays hold up to one row. */
typedef struct worker {
    shared *sh;
    pthread_t thread;
    struct RTCIntersectContext ictx;
    glint_arena *arena;
    int *group;     /* material_count + 2 lane offsets */
    int *pixel;     /* the pixel (x) of each lane */
    const glint_closure **closures;
    uint8_t *has_closure;
    /* In the lane's Glint space (ex_surface.space): wo, wi. In world space: the shading
     * normal and tangent compiled materials are given. */
    float *wo[3], *normal[3], *tangent[3], *albedo[3];
    /* Per lane and delta light (light_slot): whether lit, wi, E, the eval's value and
     * pdf; a group's lanes [first, first + count) hold count entries a light. */
    uint8_t *lit;
    float *wi[3], *value[3], *pdf;
    vec3 *irradiance;
    size_t *slot0; /* lane l's entry of light 0; light d's is slot0[l] + d * stride[l] */
    int *stride;
    uint64_t glint_ns[GLINT_KINDS], glint_calls[GLINT_KINDS], rays, closures_built;
    uint64_t material_lanes, errors;
    double seconds[2];
    char first_error[256];
} worker;

static void record_error(worker *w, const char *what, glint_status st)
{
    if (w->errors++ == 0)
        snprintf(w->first_error, sizeof w->first_error, "%s: %s (%s)", what, glint_last_error(),
                 glint_status_string(st));
}

/* ---- pass 1: the G-buffer --------------------------------------------------------------- */

static void gbuffer_row(worker *w, int y)
{
    const shared *sh = w->sh;
    const ex_scene *s = sh->scene;
    int x;
    for (x = 0; x < sh->view.width; x++) {
        gpixel *g = &sh->gbuf[(size_t)y * (size_t)sh->view.width + (size_t)x];
        const vec3 d = camera_ray(&sh->view, (float)x + 0.5f, (float)y + 0.5f);
        ex_hit h;
        w->rays++;
        if (!scene_intersect(s, &w->ictx, sh->view.eye, d, &h)) {
            g->kind = PIX_MISS;
            g->radiance = env_radiance(&s->env, d);
        } else if (s->objects[h.geom].kind == OBJ_LIGHT) {
            const ex_quad_light *l = &s->lights[s->objects[h.geom].light];
            g->kind = PIX_LIGHT;
            g->radiance = v_dot(d, l->normal) < 0.0f ? l->radiance : v3(0, 0, 0);
        } else {
            g->kind = PIX_SURFACE;
            surface_at(s, &h, sh->view.eye, d, &g->sf);
        }
    }
}

/* ---- pass 2: shading -------------------------------------------------------------------- */

/* Time a Glint call into the worker's Glint time of its kind. */
#define GLINT_TIMED(w, kind, status_var, call)                                               \
    do {                                                                                     \
        const uint64_t t0_ = host_now_ns();                                                       \
        status_var = (call);                                                                 \
        (w)->glint_ns[kind] += host_now_ns() - t0_;                                               \
        (w)->glint_calls[kind]++;                                                            \
    } while (0)

static void put_lane(float *const soa[3], int lane, vec3 v)
{
    soa[0][lane] = v.x;
    soa[1][lane] = v.y;
    soa[2][lane] = v.z;
}

/* The per-light arrays' blocks: one per delta light, at least one. */
static int light_rows(const ex_scene *s)
{
    const int n = delta_light_count(s);
    return n > 0 ? n : 1;
}

/* Lane l's entry for delta light d in the per-light arrays. */
static size_t light_slot(const worker *w, int l, int d)
{
    return w->slot0[l] + (size_t)d * (size_t)w->stride[l];
}

/* A surface pixel's bucket: 0 for the materials given as lobes, m + 1 for compiled
 * material m. */
static int lane_bucket(const ex_scene *s, const ex_surface *sf)
{
    return s->materials[sf->material].compiled ? sf->material + 1 : 0;
}

/* Group the row's surface pixels into lanes by bucket (a counting sort) and fill the lanes'
 * wo, normal and tangent. Returns the number of lanes. */
static int group_row(worker *w, const gpixel *row)
{
    const ex_scene *s = w->sh->scene;
    const int width = w->sh->view.width, buckets = s->material_count + 1;
    int *group = w->group;
    int x, b;
    memset(group, 0, (size_t)(buckets + 1) * sizeof *group);
    for (x = 0; x < width; x++)
        if (row[x].kind == PIX_SURFACE)
            group[lane_bucket(s, &row[x].sf) + 1]++;
    for (b = 0; b < buckets; b++)
        group[b + 1] += group[b];
    /* Placing a lane advances its bucket's offset to the next bucket's start: shift back. */
    for (x = 0; x < width; x++)
        if (row[x].kind == PIX_SURFACE) {
            const ex_surface *sf = &row[x].sf;
            const int l = group[lane_bucket(s, sf)]++;
            w->pixel[l] = x;
            put_lane(w->wo, l, sf->wo_space);
            put_lane(w->normal, l, sf->ns);
            put_lane(w->tangent, l, sf->fr.t);
        }
    for (b = buckets; b > 0; b--)
        group[b] = group[b - 1];
    group[0] = 0;
    for (b = 0; b < buckets; b++) {
        const int first = group[b], count = group[b + 1] - first;
        int l;
        for (l = first; l < first + count; l++) {
            w->slot0[l] = (size_t)light_rows(s) * (size_t)first + (size_t)(l - first);
            w->stride[l] = count;
        }
    }
    w->material_lanes += (uint64_t)(group[buckets] - group[1]);
    return group[buckets];
}

/* Build the closure of every lane whose material is given as lobes. */
static void build_lobe_closures(worker *w, const gpixel *row)
{
    const shared *sh = w->sh;
    glint_status st;
    int l;
    if (w->group[1] == 0)
        return;
    GLINT_TIMED(w, GLINT_BUILD, st, glint_arena_reset(w->arena));
    if (st != GLINT_OK) {
        record_error(w, "glint_arena_reset", st);
        memset(w->has_closure, 0, (size_t)w->group[1]);
        return;
    }
    for (l = 0; l < w->group[1]; l++) {
        const ex_surface *sf = &row[w->pixel[l]].sf;
        glint_closure *c = NULL;
        GLINT_TIMED(w, GLINT_BUILD, st,
                    material_build(&sh->scene->materials[sf->material], sh->rt, w->arena,
                                   &sf->wo_space, &c));
        w->closures_built++;
        if (st != GLINT_OK)
            record_error(w, "building a closure", st);
        w->closures[l] = c;
        w->has_closure[l] = st == GLINT_OK;
    }
}

/* Lanes [first, first + count) of compiled material m, with an optional active mask. */
static glint_material_lanes material_lanes(const worker *w, int m, int first, int count,
                                           const uint8_t *active)
{
    glint_material_lanes ln;
    memset(&ln, 0, sizeof ln);
    ln.material = w->sh->scene->materials[m].compiled;
    ln.count = (size_t)count;
    ln.active = active ? active + first : NULL;
    ln.wo_x = w->wo[0] + first;
    ln.wo_y = w->wo[1] + first;
    ln.wo_z = w->wo[2] + first;
    ln.normal_x = w->normal[0] + first;
    ln.normal_y = w->normal[1] + first;
    ln.normal_z = w->normal[2] + first;
    ln.tangent_x = w->tangent[0] + first;
    ln.tangent_y = w->tangent[1] + first;
    ln.tangent_z = w->tangent[2] + first;
    return ln;
}

/* Each delta light's direction, irradiance and visibility at every lane (light_slot). An
 * unlit lane's wi is its view direction (a valid direction its material is evaluated at). */
static void light_lanes(worker *w, const gpixel *row, int lanes)
{
    const shared *sh = w->sh;
    const int lobe_lanes = w->group[1];
    int d, l;
    for (d = 0; d < delta_light_count(sh->scene); d++)
        for (l = 0; l < lanes; l++) {
            const ex_surface *sf = &row[w->pixel[l]].sf;
            const size_t i = light_slot(w, l, d);
            vec3 wi, so, sd;
            float len;
            w->lit[i] = 0;
            put_lane(w->wi, (int)i, sf->wo_space);
            if ((l < lobe_lanes && !w->has_closure[l]) ||
                !delta_light_at(sh->scene, d, sf, &wi, &so, &sd, &len, &w->irradiance[i]) ||
                v_is_zero(w->irradiance[i]))
                continue;
            w->rays++;
            if (scene_occluded(sh->scene, &w->ictx, so, sd, len))
                continue;
            put_lane(w->wi, (int)i, frame_to_local(&sf->space, wi));
            w->lit[i] = 1;
        }
}

/* The closures given as lobes: albedo (when `ambient`) and, per delta light, the eval at
 * the lit lanes, over per-lane closures. */
static void shade_lobe_lanes(worker *w, int ambient)
{
    const int lanes = w->group[1];
    glint_status st;
    int d;
    if (lanes == 0)
        return;
    if (ambient) {
        glint_albedo_batch_args args;
        memset(&args, 0, sizeof args);
        args.struct_size = sizeof args;
        args.count = (size_t)lanes;
        args.closures = w->closures;
        args.active = w->has_closure;
        args.wo_x = w->wo[0];
        args.wo_y = w->wo[1];
        args.wo_z = w->wo[2];
        args.albedo_r = w->albedo[0];
        args.albedo_g = w->albedo[1];
        args.albedo_b = w->albedo[2];
        GLINT_TIMED(w, GLINT_BATCH, st, glint_albedo_batch(&args));
        if (st != GLINT_OK)
            record_error(w, "glint_albedo_batch", st);
    }
    for (d = 0; d < delta_light_count(w->sh->scene); d++) {
        const size_t at = (size_t)d * (size_t)lanes;
        glint_eval_batch_args args;
        if (!memchr(w->lit + at, 1, (size_t)lanes))
            continue;
        memset(&args, 0, sizeof args);
        args.struct_size = sizeof args;
        args.count = (size_t)lanes;
        args.closures = w->closures;
        args.active = w->lit + at;
        args.wo_x = w->wo[0];
        args.wo_y = w->wo[1];
        args.wo_z = w->wo[2];
        args.wi_x = w->wi[0] + at;
        args.wi_y = w->wi[1] + at;
        args.wi_z = w->wi[2] + at;
        args.value_r = w->value[0] + at;
        args.value_g = w->value[1] + at;
        args.value_b = w->value[2] + at;
        args.pdf = w->pdf + at;
        GLINT_TIMED(w, GLINT_BATCH, st, glint_eval_batch(&args));
        if (st != GLINT_OK)
            record_error(w, "glint_eval_batch", st);
    }
}

/* Compiled material m's lanes: one call for the albedo (when `ambient`) and the eval at
 * every delta light's direction, each lane expanded once; the albedo call alone when
 * the scene has no delta lights. */
static void shade_material_lanes(worker *w, int m, int ambient)
{
    const int first = w->group[m + 1], count = w->group[m + 2] - first;
    const int lights = delta_light_count(w->sh->scene);
    const size_t at = (size_t)light_rows(w->sh->scene) * (size_t)first;
    glint_status st;
    if (count == 0 || (!ambient && lights == 0))
        return;
    if (lights == 0) {
        glint_material_albedo_batch_args args;
        memset(&args, 0, sizeof args);
        args.struct_size = sizeof args;
        args.lanes = material_lanes(w, m, first, count, NULL);
        args.albedo_r = w->albedo[0] + first;
        args.albedo_g = w->albedo[1] + first;
        args.albedo_b = w->albedo[2] + first;
        GLINT_TIMED(w, GLINT_MATERIAL_BATCH, st, glint_material_albedo_batch(&args));
        if (st != GLINT_OK)
            record_error(w, "glint_material_albedo_batch", st);
        return;
    }
    {
        glint_material_eval_batch_args args;
        memset(&args, 0, sizeof args);
        args.struct_size = sizeof args;
        args.lanes = material_lanes(w, m, first, count, NULL);
        args.direction_count = (size_t)lights;
        args.wi_x = w->wi[0] + at;
        args.wi_y = w->wi[1] + at;
        args.wi_z = w->wi[2] + at;
        args.value_r = w->value[0] + at;
        args.value_g = w->value[1] + at;
        args.value_b = w->value[2] + at;
        args.pdf = w->pdf + at;
        if (ambient) {
            args.albedo_r = w->albedo[0] + first;
            args.albedo_g = w->albedo[1] + first;
            args.albedo_b = w->albedo[2] + first;
        }
        GLINT_TIMED(w, GLINT_MATERIAL_BATCH, st, glint_material_eval_batch(&args));
        if (st != GLINT_OK)
            record_error(w, "glint_material_eval_batch", st);
    }
}

/* rgb += ambient * albedo(wo) + sum over lit lights of f(wo, wi) |cos| E. */
static void accumulate(worker *w, int lanes, int ambient, float *rgb)
{
    const vec3 a = w->sh->ambient;
    const int lobe_lanes = w->group[1];
    int l, d;
    for (l = 0; l < lanes; l++) {
        float *px = &rgb[3 * w->pixel[l]];
        if (l < lobe_lanes && !w->has_closure[l])
            continue;
        if (ambient) {
            px[0] += a.x * w->albedo[0][l];
            px[1] += a.y * w->albedo[1][l];
            px[2] += a.z * w->albedo[2][l];
        }
        for (d = 0; d < delta_light_count(w->sh->scene); d++) {
            const size_t i = light_slot(w, l, d);
            if (w->lit[i]) {
                const vec3 e = w->irradiance[i];
                px[0] += w->value[0][i] * e.x;
                px[1] += w->value[1][i] * e.y;
                px[2] += w->value[2][i] * e.z;
            }
        }
    }
}

static void shade_row(worker *w, int y)
{
    const shared *sh = w->sh;
    const int width = sh->view.width;
    const gpixel *row = &sh->gbuf[(size_t)y * (size_t)width];
    float *rgb = &sh->rgb[3 * (size_t)y * (size_t)width];
    int x, m, lanes, ambient;
    for (x = 0; x < width; x++) {
        const vec3 e = row[x].kind == PIX_SURFACE ? v3(0, 0, 0) : row[x].radiance;
        rgb[3 * x + 0] = e.x;
        rgb[3 * x + 1] = e.y;
        rgb[3 * x + 2] = e.z;
    }
    lanes = group_row(w, row);
    if (lanes == 0)
        return;
    build_lobe_closures(w, row);
    light_lanes(w, row, lanes);
    ambient = !v_is_zero(sh->ambient);
    shade_lobe_lanes(w, ambient);
    for (m = 0; m < sh->scene->material_count; m++)
        shade_material_lanes(w, m, ambient);
    accumulate(w, lanes, ambient, rgb);
}

/* ---- threads ---------------------------------------------------------------------------- */

static void *worker_main(void *arg)
{
    worker *w = arg;
    shared *sh = w->sh;
    const uint64_t t0 = host_now_ns();
    for (;;) {
        const int y = atomic_fetch_add(&sh->next_row, 1);
        if (y >= sh->view.height)
            break;
        if (sh->pass == 0)
            gbuffer_row(w, y);
        else
            shade_row(w, y);
    }
    w->seconds[sh->pass] = (double)(host_now_ns() - t0) * 1e-9;
    return NULL;
}

/* Run one pass over the rows on `count` workers; its wall time in seconds, or -1. */
static double run_pass(shared *sh, worker *workers, int count, int pass)
{
    const uint64_t t0 = host_now_ns();
    int i, started = 0;
    sh->pass = pass;
    atomic_store(&sh->next_row, 0);
    for (i = 0; i < count; i++) {
        if (pthread_create(&workers[i].thread, NULL, worker_main, &workers[i]) != 0)
            break;
        started++;
    }
    if (started == 0) {
        fprintf(stderr, "scanline: pthread_create failed\n");
        return -1.0;
    }
    for (i = 0; i < started; i++)
        pthread_join(workers[i].thread, NULL);
    return (double)(host_now_ns() - t0) * 1e-9;
}

static int worker_init(worker *w, shared *sh, int width)
{
    const size_t n = (size_t)width, nl = n * (size_t)light_rows(sh->scene);
    int k;
    memset(w, 0, sizeof *w);
    w->sh = sh;
    rtcInitIntersectContext(&w->ictx);
    if (glint_arena_create(n, &w->arena) != GLINT_OK) {
        fprintf(stderr, "scanline: glint_arena_create: %s\n", glint_last_error());
        return -1;
    }
    w->group = calloc((size_t)sh->scene->material_count + 2, sizeof *w->group);
    w->pixel = calloc(n, sizeof *w->pixel);
    w->closures = calloc(n, sizeof *w->closures);
    w->has_closure = calloc(n, 1);
    w->lit = calloc(nl, 1);
    w->pdf = calloc(nl, sizeof(float));
    w->irradiance = calloc(nl, sizeof *w->irradiance);
    w->slot0 = calloc(n, sizeof *w->slot0);
    w->stride = calloc(n, sizeof *w->stride);
    if (!w->group || !w->pixel || !w->closures || !w->has_closure || !w->lit || !w->pdf ||
        !w->irradiance || !w->slot0 || !w->stride)
        return -1;
    for (k = 0; k < 3; k++) {
        w->wo[k] = calloc(n, sizeof(float));
        w->wi[k] = calloc(nl, sizeof(float));
        w->normal[k] = calloc(n, sizeof(float));
        w->tangent[k] = calloc(n, sizeof(float));
        w->albedo[k] = calloc(n, sizeof(float));
        w->value[k] = calloc(nl, sizeof(float));
        if (!w->wo[k] || !w->wi[k] || !w->normal[k] || !w->tangent[k] || !w->albedo[k] ||
            !w->value[k])
            return -1;
    }
    return 0;
}

static void worker_free(worker *w)
{
    int k;
    glint_arena_destroy(w->arena);
    free(w->group);
    free(w->pixel);
    free((void *)w->closures);
    free(w->has_closure);
    free(w->lit);
    free(w->pdf);
    free(w->irradiance);
    free(w->slot0);
    free(w->stride);
    for (k = 0; k < 3; k++) {
        free(w->wo[k]);
        free(w->wi[k]);
        free(w->normal[k]);
        free(w->tangent[k]);
        free(w->albedo[k]);
        free(w->value[k]);
    }
}

/* ---- main ------------------------------------------------------------------------------- */

static void usage(FILE *f)
{
    fprintf(f,
            "usage: scanline [options]\n"
            "  --width W, --height H   image size (default 640 x 360)\n"
            "  --threads T             threads over scanlines (default 2)\n"
            "  --out PREFIX            write PREFIX.exr (linear) and PREFIX.png (sRGB)\n"
            "                          (default: scanline)\n"
            "  --ambient R G B         ambient radiance (default: the environment's mean)\n"
            "  --scene FILE.json       render a scene file instead of the showcase\n"
            "  --plugin PATH           load a Glint plugin (default: " CHARLIE_FILE
            " next to\n"
            "                          the executable, if there)\n"
            "  --furnace               one sphere in a uniform environment of radiance 1\n"
            "  --material M            the furnace sphere's material: a name (see\n"
            "                          --list-materials) or JSON: a closure or a material\n"
            "                          document (default: white)\n"
            "  --quiet                 print only the summary\n"
            "  --list-materials        print the named materials and exit\n");
}

static int parse_float(const char *opt, const char *s, float *out)
{
    char *end;
    const double v = strtod(s, &end);
    if (*end || end == s || !isfinite(v) || v < 0.0 || v > 1e30) {
        fprintf(stderr, "scanline: %s expects non-negative numbers, got \"%s\"\n", opt, s);
        return -1;
    }
    *out = (float)v;
    return 0;
}

static int write_image(const char *out, const settings *set, const float *rgb,
                       const char *scene_name)
{
    static const char *const names[3] = {"R", "G", "B"};
    char path[PATH_MAX], err[512];
    image_attr attrs[3];
    snprintf(attrs[0].name, sizeof attrs[0].name, "glint:host");
    snprintf(attrs[0].value, sizeof attrs[0].value, "scanline");
    /* One deterministic sample per pixel, for the checks that read glint:spp. */
    snprintf(attrs[1].name, sizeof attrs[1].name, "glint:spp");
    snprintf(attrs[1].value, sizeof attrs[1].value, "1");
    snprintf(attrs[2].name, sizeof attrs[2].name, "glint:scene");
    snprintf(attrs[2].value, sizeof attrs[2].value, "%s", scene_name);
    snprintf(path, sizeof path, "%s.exr", out);
    if (image_write_exr(path, set->width, set->height, 3, names, rgb, attrs, 3, err,
                        sizeof err) != 0) {
        fprintf(stderr, "scanline: %s\n", err);
        return -1;
    }
    snprintf(path, sizeof path, "%s.png", out);
    if (image_write_png(path, set->width, set->height, 3, rgb, err, sizeof err) != 0) {
        fprintf(stderr, "scanline: %s\n", err);
        return -1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    settings set;
    const char *out = "scanline", *scene_file = NULL, *plugin = NULL, *material = "white";
    int furnace = 0, i, status = EXIT_FAILURE, ready = 0;
    glint_runtime *rt = NULL;
    ex_scene scene;
    shared sh;
    worker *workers = NULL;
    double seconds[2];
    size_t npix, nonfinite = 0;
    uint64_t rays = 0, closures = 0, material_lanes = 0, errors = 0;
    uint64_t glint_calls[GLINT_KINDS] = {0, 0, 0};
    double glint_s[GLINT_KINDS] = {0.0, 0.0, 0.0}, thread_s = 0.0;
    int k;
    char first_error[256] = "";

    scene_program = "scanline";
    memset(&set, 0, sizeof set);
    memset(&sh, 0, sizeof sh);
    set.width = 640;
    set.height = 360;
    set.threads = 2;

    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        long n = 0;
        if (!v && (strcmp(a, "--width") == 0 || strcmp(a, "--height") == 0 ||
                   strcmp(a, "--threads") == 0 || strcmp(a, "--out") == 0 ||
                   strcmp(a, "--scene") == 0 || strcmp(a, "--plugin") == 0 ||
                   strcmp(a, "--material") == 0 || strcmp(a, "--ambient") == 0)) {
            fprintf(stderr, "scanline: %s needs a value\n", a);
            return EXIT_FAILURE;
        }
        if (strcmp(a, "--width") == 0 || strcmp(a, "--height") == 0) {
            if (host_parse_int(a, v, 1, 16384, &n) != 0)
                return EXIT_FAILURE;
            if (strcmp(a, "--width") == 0)
                set.width = (int)n;
            else
                set.height = (int)n;
            i++;
        } else if (strcmp(a, "--threads") == 0) {
            if (host_parse_int(a, v, 1, 256, &n) != 0)
                return EXIT_FAILURE;
            set.threads = (int)n;
            i++;
        } else if (strcmp(a, "--ambient") == 0) {
            if (i + 3 >= argc || parse_float(a, argv[i + 1], &set.ambient.x) != 0 ||
                parse_float(a, argv[i + 2], &set.ambient.y) != 0 ||
                parse_float(a, argv[i + 3], &set.ambient.z) != 0) {
                if (i + 3 >= argc)
                    fprintf(stderr, "scanline: --ambient needs three numbers\n");
                return EXIT_FAILURE;
            }
            set.ambient_given = 1;
            i += 3;
        } else if (strcmp(a, "--out") == 0) {
            out = v;
            i++;
        } else if (strcmp(a, "--scene") == 0) {
            scene_file = v;
            i++;
        } else if (strcmp(a, "--plugin") == 0) {
            plugin = v;
            i++;
        } else if (strcmp(a, "--material") == 0) {
            material = v;
            i++;
        } else if (strcmp(a, "--furnace") == 0) {
            furnace = 1;
        } else if (strcmp(a, "--quiet") == 0) {
            set.quiet = 1;
        } else if (strcmp(a, "--list-materials") == 0) {
            material_list();
            return EXIT_SUCCESS;
        } else if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return EXIT_SUCCESS;
        } else {
            fprintf(stderr, "scanline: unknown option \"%s\"\n", a);
            usage(stderr);
            return EXIT_FAILURE;
        }
    }
    if (host_open(&rt, &scene, plugin, scene_file, furnace, material) != 0)
        goto done;
    for (i = 0; i < scene.light_count; i++) { /* quad lights as point lights */
        const ex_quad_light *l = &scene.lights[i];
        const vec3 center = v_add(l->corner, v_scale(v_add(l->e1, l->e2), 0.5f));
        scene_add_point_light(&scene, center, v_scale(l->radiance, l->area));
    }
    if (scene_build(&scene, rt) != 0)
        goto done;

    npix = (size_t)set.width * (size_t)set.height;
    sh.scene = &scene;
    sh.rt = rt;
    sh.set = &set;
    sh.view = camera_view(&scene.camera, set.width, set.height);
    sh.ambient = set.ambient_given ? set.ambient : env_mean(&scene.env);
    sh.gbuf = calloc(npix, sizeof *sh.gbuf);
    sh.rgb = calloc(npix * 3, sizeof(float));
    workers = calloc((size_t)set.threads, sizeof *workers);
    if (!sh.gbuf || !sh.rgb || !workers) {
        fprintf(stderr, "scanline: out of memory\n");
        goto done;
    }
    for (ready = 0; ready < set.threads; ready++)
        if (worker_init(&workers[ready], &sh, set.width) != 0) {
            fprintf(stderr, "scanline: out of memory\n");
            worker_free(&workers[ready]);
            goto done;
        }
    if (!set.quiet)
        fprintf(stderr,
                "scanline: %s, %dx%d, %d thread%s, %d point and %d directional light%s, "
                "ambient (%.3g, %.3g, %.3g)\n",
                scene_file ? scene_file : furnace ? "white furnace" : "material showcase",
                set.width, set.height, set.threads, set.threads == 1 ? "" : "s",
                scene.point_light_count, scene.dir_light_count,
                scene.dir_light_count == 1 ? "" : "s", sh.ambient.x, sh.ambient.y,
                sh.ambient.z);
    for (i = 0; i < 2; i++)
        if ((seconds[i] = run_pass(&sh, workers, set.threads, i)) < 0.0)
            goto done;

    for (i = 0; i < set.threads; i++) {
        const worker *w = &workers[i];
        rays += w->rays;
        closures += w->closures_built;
        material_lanes += w->material_lanes;
        for (k = 0; k < GLINT_KINDS; k++) {
            glint_calls[k] += w->glint_calls[k];
            glint_s[k] += (double)w->glint_ns[k] * 1e-9;
        }
        thread_s += w->seconds[1];
        if (w->errors && !errors)
            memcpy(first_error, w->first_error, sizeof first_error);
        errors += w->errors;
    }
    for (i = 0; i < (int)(npix * 3); i++)
        if (!isfinite(sh.rgb[i]))
            nonfinite++;
    if (write_image(out, &set, sh.rgb,
                    scene_file ? scene_file : furnace ? "furnace" : "showcase") != 0)
        goto done;

    printf("G-buffer: %.1f ms, %.2f M primary rays/s\n"
           "shading:  %.1f ms (%.1f us per row), %.2f M pixels/s, %.3f M closures, %.3f M "
           "compiled-material lanes, %.1f M rays in all\n",
           seconds[0] * 1e3, (double)npix * 1e-6 / seconds[0], seconds[1] * 1e3,
           seconds[1] * 1e6 / set.height, (double)npix * 1e-6 / seconds[1],
           (double)closures * 1e-6, (double)material_lanes * 1e-6, (double)rays * 1e-6);
    for (k = 0; k < GLINT_KINDS; k++) {
        static const char *const kinds[GLINT_KINDS] = {
            "closure builds (arena reset + lobe blocks)", "batch calls on closures",
            "material batch calls"};
        printf("  %-42s %5.1f%% of shading-thread time, %7.0f calls, %6.0f ns each\n",
               kinds[k], thread_s > 0.0 ? 100.0 * glint_s[k] / thread_s : 0.0,
               (double)glint_calls[k], glint_calls[k] ? glint_s[k] * 1e9 / glint_calls[k] : 0.0);
    }
    if (nonfinite)
        printf("warning: %zu pixel values are NaN or infinite\n", nonfinite);
    if (errors)
        printf("warning: %llu glint errors, the first: %s\n", (unsigned long long)errors,
               first_error);
    printf("wrote %s.exr and %s.png\n", out, out);
    status = errors || nonfinite ? EXIT_FAILURE : EXIT_SUCCESS;

done:
    for (i = 0; i < ready; i++)
        worker_free(&workers[i]);
    free(workers);
    free(sh.gbuf);
    free(sh.rgb);
    scene_free(&scene);
    glint_runtime_destroy(rt);
    return status;
}
