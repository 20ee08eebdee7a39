/* pt.h: the path tracer's scene, settings and renderer. */
#ifndef PT_H
#define PT_H

#include <stddef.h>
#include <stdint.h>

#include <embree3/rtcore.h>

#include "glint.h"
#include "vec.h"

/* ---- scene ------------------------------------------------------------------------- */

/* One lobe decoded for glint_closure_add_lobe (material_blocks.c). */
typedef struct pt_lobe_block {
    uint32_t type;
    float weight[3];
    glint_frame frame;
    float *params;
    uint32_t param_count;
} pt_lobe_block;

typedef struct pt_material {
    char name[64];
    char *json;    /* the closure description given to glint_closure_from_json */
    int transmits; /* has a lobe that transmits: closed surfaces, the normal is not flipped */
    /* --closures blocks: the same closure decoded once (material_decode). */
    pt_lobe_block *lobes;
    int lobe_count;
    uint32_t closure_flags;
} pt_material;

/* Decode m->json into lobe blocks and check them against glint_closure_from_json.
 * 0, or -1 with a message on stderr. */
int material_decode(pt_material *m, const glint_runtime *rt);
/* Build m's closure lobe by lobe from its decoded blocks. */
glint_status material_build(const pt_material *m, const glint_runtime *rt, glint_arena *arena,
                            const glint_vec3 *wo, glint_closure **out);
void material_free_blocks(pt_material *m);

enum { OBJ_SPHERE, OBJ_MESH, OBJ_LIGHT };

typedef struct pt_object {
    int kind;
    int material;        /* index in pt_scene.materials (not for OBJ_LIGHT) */
    int material2;       /* a checkerboard's second material, or -1 */
    float checker_scale; /* checker square size (world units) */
    int light;           /* OBJ_LIGHT: index in pt_scene.lights */
    vec3 center;         /* OBJ_SPHERE */
    float radius;
    size_t vertex_count, triangle_count; /* OBJ_MESH, OBJ_LIGHT */
    float *positions;                    /* 3 floats per vertex, world space */
    float *normals;                      /* 3 floats per vertex, or NULL (flat shading) */
    uint32_t *indices;                   /* 3 per triangle, counter-clockwise = front */
} pt_object;

/* A one-sided emissive parallelogram corner + s e1 + t e2, emitting toward e1 x e2. */
typedef struct pt_quad_light {
    vec3 corner, e1, e2, normal;
    float area;
    vec3 radiance;
    float select_prob; /* probability of picking this light for next-event estimation */
    float cdf;         /* running sum of select_prob */
} pt_quad_light;

enum { ENV_NONE, ENV_UNIFORM, ENV_SKY };

/* Environment radiance: uniform, or a sky (zenith-horizon gradient above, a ground
 * color below, blended across the horizon; no sun). Sampled with probability
 * `up_fraction` by cosine around +y, otherwise uniformly on the sphere. */
typedef struct pt_env {
    int kind;
    vec3 color; /* ENV_UNIFORM */
    vec3 zenith, horizon, ground;
    float up_fraction;
    float intensity; /* scales everything */
} pt_env;

typedef struct pt_camera {
    vec3 eye, target, up;
    float vfov_deg;
} pt_camera;

typedef struct pt_scene {
    pt_material *materials;
    int material_count, material_cap;
    pt_object *objects;
    int object_count, object_cap;
    pt_quad_light *lights;
    int light_count, light_cap;
    pt_env env;
    pt_camera camera;
    RTCDevice device;
    RTCScene rtc;
} pt_scene;

void scene_init(pt_scene *s);
void scene_free(pt_scene *s);
/* Returns the material's index; `json` is copied. */
int scene_add_material(pt_scene *s, const char *name, const char *json);
int scene_find_material(const pt_scene *s, const char *name);
void scene_add_sphere(pt_scene *s, vec3 center, float radius, int material);
/* A parallelogram corner + s e1 + t e2 facing e1 x e2, as two triangles. */
void scene_add_quad(pt_scene *s, vec3 corner, vec3 e1, vec3 e2, int material);
/* Takes ownership of the arrays (malloc'd). */
void scene_add_mesh(pt_scene *s, float *positions, float *normals, size_t vertex_count,
                    uint32_t *indices, size_t triangle_count, int material);
void scene_add_quad_light(pt_scene *s, vec3 corner, vec3 e1, vec3 e2, vec3 radiance);
/* Checks every material against the runtime (errors name the material), decodes them into
 * parameter blocks when `decode_blocks`, builds the Embree scene and the light selection
 * table. Returns 0, or -1 with a message on stderr. */
int scene_build(pt_scene *s, const glint_runtime *rt, int decode_blocks);

/* Built-in scenes. */
void scene_showcase(pt_scene *s, int with_sheen);
void scene_furnace(pt_scene *s, const char *material_json);
/* The named materials of the showcase and tests ("gold", "glass", ...): JSON or NULL. */
const char *material_by_name(const char *name);
/* Writes the list of material names to stderr. */
void material_list(void);

/* Scene files (scene_file.c): 0, or -1 with a message on stderr. */
int scene_load_file(pt_scene *s, const char *path);

/* Environment radiance, sampling and pdf (solid angle). */
vec3 env_radiance(const pt_env *e, vec3 dir);
vec3 env_sample(const pt_env *e, float u0, float u1, float u2, float *pdf);
float env_pdf(const pt_env *e, vec3 dir);

/* ---- rendering --------------------------------------------------------------------- */

enum { STRATEGY_MIS, STRATEGY_BSDF, STRATEGY_LIGHT };
/* How the per-hit closure is built: glint_closure_from_json, or lobe by lobe. */
enum { CLOSURES_JSON, CLOSURES_BLOCKS };

typedef struct pt_settings {
    int width, height, spp, max_depth, rr_depth, threads, strategy, closures, quiet;
    int timing; /* time every Glint call (clock_gettime) */
    uint64_t seed;
} pt_settings;

/* Per-pixel accumulators over the samples (radiance estimates), in double. */
typedef struct pt_accum {
    double *sum;    /* 3 per pixel */
    double *sum_sq; /* 3 per pixel */
    uint32_t *hits; /* camera samples whose first ray hit geometry */
} pt_accum;

/* Kinds of timed Glint calls: building a closure (glint_arena_reset then
 * glint_closure_from_json or the lobe-by-lobe calls, one interval), glint_eval,
 * glint_sample. */
enum { GLINT_BUILD, GLINT_EVAL, GLINT_SAMPLE, GLINT_KINDS };

typedef struct pt_stats {
    double seconds;        /* wall clock of the render */
    double thread_seconds; /* summed over threads */
    double glint_seconds;  /* summed over threads: inside glint_* calls */
    uint64_t rays;         /* rtcIntersect1 + rtcOccluded1 */
    uint64_t samples;      /* camera samples */
    uint64_t glint_calls;
    double glint_kind_seconds[GLINT_KINDS];
    uint64_t glint_kind_calls[GLINT_KINDS];
    double timer_inside_ns; /* what one timed interval measures of the timer itself */
    double timer_pair_ns;   /* what the two clock reads of a timed call cost the thread */
    uint64_t closures;
    uint64_t nonfinite; /* samples whose estimate was NaN or infinite (kept in the image) */
    uint64_t glint_errors;
    char first_error[256];
} pt_stats;

/* Renders into `acc` (allocated by the caller, zeroed). Returns 0 on success. */
int render(const pt_scene *scene, const glint_runtime *rt, const pt_settings *settings,
           pt_accum *acc, pt_stats *stats);

#endif
