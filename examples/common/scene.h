/* scene.h: the scene both example hosts render (materials, objects, lights, environment,
 * camera, the Embree scene) and the geometry code they share, so that the path tracer and
 * the scanline host see the same surfaces, frames and shadow rays. */
#ifndef EX_SCENE_H
#define EX_SCENE_H

#include <stddef.h>
#include <stdint.h>

#include <embree3/rtcore.h>

#include "glint.h"
#include "vec.h"

/* The program name that prefixes the scene code's messages ("pathtracer", "scanline"). */
extern const char *scene_program;

/* ---- materials ---------------------------------------------------------------------- */

/* One lobe decoded for glint_closure_add_lobe (materials.c). */
typedef struct ex_lobe_block {
    uint32_t type;
    float weight[3];
    glint_frame frame;
    float *params;
    uint32_t param_count;
} ex_lobe_block;

typedef struct ex_material {
    char name[64];
    /* The description: a closure ({"lobes": [...]}) or a material document
     * ({"material": "disney", ...}). Read only while the scene is built. */
    char *json;
    int transmits; /* has a lobe that transmits: closed surfaces, the normal is not flipped */
    /* A material document compiled once (glint_material_create), NULL for a closure given
     * as lobes. Its closures are built from a shading context in world space. */
    glint_material *compiled;
    /* A closure given as lobes, built lobe by lobe from blocks decoded once, in the shading
     * frame (z = the shading normal). */
    ex_lobe_block *lobes;
    int lobe_count;
    uint32_t closure_flags;
} ex_material;

/* Make m ready to shade: compile a material document, or decode a closure's lobes into
 * blocks and check them against glint_closure_from_json. 0, or -1 with a message on
 * stderr naming the material. */
int material_prepare(ex_material *m, const glint_runtime *rt);
/* Build the closure of a material given as lobes from its decoded blocks. */
glint_status material_build(const ex_material *m, const glint_runtime *rt, glint_arena *arena,
                            const glint_vec3 *wo, glint_closure **out);
/* Release what material_prepare made. */
void material_release(ex_material *m);

/* The named materials of the showcase and tests ("gold", "glass", ...): JSON or NULL. */
const char *material_by_name(const char *name);
/* Writes the list of material names to stderr. */
void material_list(void);

/* ---- objects and lights ------------------------------------------------------------- */

enum { OBJ_SPHERE, OBJ_MESH, OBJ_LIGHT };

typedef struct ex_object {
    int kind;
    int material;        /* index in ex_scene.materials (not for OBJ_LIGHT) */
    int material2;       /* a checkerboard's second material, or -1 */
    float checker_scale; /* checker square size (world units) */
    int light;           /* OBJ_LIGHT: index in ex_scene.lights */
    vec3 center;         /* OBJ_SPHERE */
    float radius;
    size_t vertex_count, triangle_count; /* OBJ_MESH, OBJ_LIGHT */
    float *positions;                    /* 3 floats per vertex, world space */
    float *normals;                      /* 3 floats per vertex, or NULL (flat shading) */
    uint32_t *indices;                   /* 3 per triangle, counter-clockwise = front */
} ex_object;

/* A one-sided emissive parallelogram corner + s e1 + t e2, emitting toward e1 x e2. */
typedef struct ex_quad_light {
    vec3 corner, e1, e2, normal;
    float area;
    vec3 radiance;
    float select_prob; /* probability of picking this light for next-event estimation */
    float cdf;         /* running sum of select_prob */
} ex_quad_light;

/* Delta lights (seed 001's light sources): an isotropic point light of radiant intensity
 * `intensity` (irradiance I cos / d^2), and a directional light from `direction` (unit,
 * toward the light) of irradiance `irradiance` on a surface facing it. */
typedef struct ex_point_light {
    vec3 position, intensity;
} ex_point_light;

typedef struct ex_dir_light {
    vec3 direction, irradiance;
} ex_dir_light;

enum { ENV_NONE, ENV_UNIFORM, ENV_SKY };

/* Environment radiance: uniform, or a sky (zenith-horizon gradient above, a ground
 * color below, blended across the horizon; no sun). Sampled with probability
 * `up_fraction` by cosine around +y, otherwise uniformly on the sphere. */
typedef struct ex_env {
    int kind;
    vec3 color; /* ENV_UNIFORM */
    vec3 zenith, horizon, ground;
    float up_fraction;
    float intensity; /* scales everything */
} ex_env;

typedef struct ex_camera {
    vec3 eye, target, up;
    float vfov_deg;
} ex_camera;

typedef struct ex_scene {
    ex_material *materials;
    int material_count, material_cap;
    ex_object *objects;
    int object_count, object_cap;
    ex_quad_light *lights;
    int light_count, light_cap;
    ex_point_light *point_lights;
    int point_light_count, point_light_cap;
    ex_dir_light *dir_lights;
    int dir_light_count, dir_light_cap;
    ex_env env;
    ex_camera camera;
    RTCDevice device;
    RTCScene rtc;
} ex_scene;

void scene_init(ex_scene *s);
void scene_free(ex_scene *s);
/* Returns the material's index; `json` is copied. */
int scene_add_material(ex_scene *s, const char *name, const char *json);
int scene_find_material(const ex_scene *s, const char *name);
void scene_add_sphere(ex_scene *s, vec3 center, float radius, int material);
/* A parallelogram corner + s e1 + t e2 facing e1 x e2, as two triangles. */
void scene_add_quad(ex_scene *s, vec3 corner, vec3 e1, vec3 e2, int material);
/* Takes ownership of the arrays (malloc'd). */
void scene_add_mesh(ex_scene *s, float *positions, float *normals, size_t vertex_count,
                    uint32_t *indices, size_t triangle_count, int material);
void scene_add_quad_light(ex_scene *s, vec3 corner, vec3 e1, vec3 e2, vec3 radiance);
void scene_add_point_light(ex_scene *s, vec3 position, vec3 intensity);
/* `direction` points toward the light; it is normalized. */
void scene_add_dir_light(ex_scene *s, vec3 direction, vec3 irradiance);
/* Checks every material against the runtime and prepares it (material_prepare; errors name
 * the material), builds the Embree scene and the light selection table. Returns 0, or -1
 * with a message on stderr. */
int scene_build(ex_scene *s, const glint_runtime *rt);

/* Built-in scenes. The showcase: a checker ground and a sphere per material under a soft box
 * and a sky. */
void scene_showcase(ex_scene *s, int with_sheen);
void scene_furnace(ex_scene *s, const char *material_json);

/* Scene files (scene_file.c): 0, or -1 with a message on stderr. */
int scene_load_file(ex_scene *s, const char *path);

/* Environment radiance, sampling and pdf (solid angle). */
vec3 env_radiance(const ex_env *e, vec3 dir);
vec3 env_sample(const ex_env *e, float u0, float u1, float u2, float *pdf);
float env_pdf(const ex_env *e, vec3 dir);
/* The environment's mean radiance over the sphere of directions. */
vec3 env_mean(const ex_env *e);

/* ---- camera, rays and surfaces ------------------------------------------------------ */

/* A pinhole camera set up for an image size. */
typedef struct ex_view {
    vec3 eye, forward, right, up;
    float tan_half, aspect;
    int width, height;
} ex_view;

ex_view camera_view(const ex_camera *c, int width, int height);
/* The unit direction through image position (x, y) in pixels, (0, 0) the top left corner
 * (a pixel's center is at + 0.5). */
vec3 camera_ray(const ex_view *v, float x, float y);

typedef struct ex_hit {
    float t, u, v;
    unsigned geom, prim;
} ex_hit;

/* The closest hit along o + t d, t > 0: 1, or 0 on a miss. */
int scene_intersect(const ex_scene *s, struct RTCIntersectContext *ctx, vec3 o, vec3 d,
                    ex_hit *h);
/* Is anything on o + t d for 0 < t < tfar? */
int scene_occluded(const ex_scene *s, struct RTCIntersectContext *ctx, vec3 o, vec3 d,
                   float tfar);

/* A shading point: position, geometric and shading normals facing the viewer unless the
 * material transmits, the shading frame (z = ns, tangent t), wo, and the space Glint's
 * directions live in for this material: the shading frame for a closure given as lobes (its
 * lobes keep their default normal, z), world space (the identity) for a compiled material,
 * whose closure is built in the context's frame. */
typedef struct ex_surface {
    vec3 p, ng, ns, wo;
    frame fr;
    frame space;
    vec3 wo_space; /* wo in `space` */
    int material;
} ex_surface;

/* The shading point of a hit of the ray o + t d on a surface (not a light). */
void surface_at(const ex_scene *s, const ex_hit *h, vec3 o, vec3 d, ex_surface *out);

/* The closure of surface point `sf` in `arena`: glint_material_closure with the point's
 * shading context for a compiled material, material_build otherwise. No JSON is read. */
glint_status surface_closure(const ex_scene *s, const glint_runtime *rt, glint_arena *arena,
                             const ex_surface *sf, glint_closure **out);

/* Move a surface point off the surface, to the side of `dir`. */
vec3 offset_point(vec3 p, vec3 ng, vec3 dir);

/* Is `wi` on the same side of the geometric normal as of the shading normal? With
 * interpolated normals (meshes) they can disagree near silhouettes; such directions would
 * leak light through the surface, so they are dropped. Always true on spheres and quads. */
static inline int side_ok(vec3 wi, vec3 ng, vec3 ns)
{
    return (v_dot(wi, ng) > 0.0f) == (v_dot(wi, ns) > 0.0f);
}

/* Delta lights, point lights first then directional: how many, and light `index` seen from
 * the surface point: the unit direction to it, the shadow ray (origin off the surface,
 * unit direction, length) and the irradiance on a surface facing it (no cosine). Returns 0
 * when the light cannot reach the point (behind the surface, or at the point). */
int delta_light_count(const ex_scene *s);
int delta_light_at(const ex_scene *s, int index, const ex_surface *sf, vec3 *wi,
                   vec3 *shadow_origin, vec3 *shadow_dir, float *shadow_len, vec3 *irradiance);

#endif
