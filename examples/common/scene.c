/* scene.c: scene containers, Embree setup, the environment, named materials and the
 * built-in scenes (the material showcase and the white furnace). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene.h"

const char *scene_program = "glint-example";

/* ---- named materials ------------------------------------------------------------------ */

typedef struct named_material {
    const char *name;
    const char *json;
} named_material;

static const named_material MATERIALS[] = {
    /* The white furnace's reference: albedo exactly 1. */
    {"white", "{\"lobes\":[{\"type\":\"lambert\",\"weight\":1,\"color\":[1,1,1]}]}"},
    {"clay", "{\"lobes\":[{\"type\":\"lambert\",\"color\":[0.70,0.26,0.13]}]}"},
    {"gold", "{\"lobes\":[{\"type\":\"conductor\",\"roughness\":0.3,\"fresnel\":\"artistic\","
             "\"reflectivity\":[1.0,0.77,0.33],\"edge_tint\":[1.0,0.96,0.78]}]}"},
    {"aluminium", "{\"lobes\":[{\"type\":\"conductor\",\"roughness\":0.5,\"fresnel\":"
                  "\"conductor\",\"eta\":[1.66,0.88,0.52],\"k\":[9.22,6.27,4.84]}]}"},
    {"rough_glass", "{\"lobes\":[{\"type\":\"dielectric\",\"roughness\":0.3,\"eta\":1.5}]}"},
    {"glass", "{\"lobes\":[{\"type\":\"dielectric\",\"roughness\":0,\"eta\":1.5}]}"},
    {"mirror", "{\"lobes\":[{\"type\":\"mirror\",\"fresnel\":\"schlick\",\"f0\":[0.96,0.96,0.96],"
               "\"f90\":1}]}"},
    /* Layered-looking: a blue diffuse base under a glossy silver coat, as one mix. */
    {"coated", "{\"lobes\":[{\"type\":\"lambert\",\"weight\":0.75,\"color\":[0.06,0.22,0.75]},"
               "{\"type\":\"conductor\",\"weight\":0.25,\"roughness\":0.15,\"fresnel\":\"schlick\","
               "\"f0\":[1,1,1],\"f90\":[1,1,1]}]}"},
    /* Velvet: dark diffuse base plus the Charlie sheen plugin (needs glint_charlie.so). */
    {"sheen", "{\"lobes\":[{\"type\":\"lambert\",\"weight\":0.85,\"color\":[0.16,0.01,0.05]},"
              "{\"type\":\"charlie\",\"weight\":1,\"color\":[1.0,0.75,0.85],\"roughness\":0.3}]}"},
    /* For the furnace tests: the whitest versions (albedo as close to 1 as each model gets). */
    {"white_conductor", "{\"lobes\":[{\"type\":\"conductor\",\"roughness\":0.6,\"fresnel\":"
                        "\"schlick\",\"f0\":1,\"f90\":1}]}"},
    {"white_mirror", "{\"lobes\":[{\"type\":\"mirror\"}]}"},
    {"white_mix", "{\"lobes\":[{\"type\":\"lambert\",\"weight\":0.5,\"color\":[1,1,1]},"
                  "{\"type\":\"conductor\",\"weight\":0.5,\"roughness\":0.2,"
                  "\"fresnel\":\"schlick\",\"f0\":1,\"f90\":1}]}"},
    {"white_sheen", "{\"lobes\":[{\"type\":\"lambert\",\"weight\":0.6,\"color\":[1,1,1]},"
                    "{\"type\":\"charlie\",\"weight\":0.4,\"color\":[1,1,1],\"roughness\":0.3}]}"},
    /* Disney (Burley 2012) material documents, compiled once per scene. Metallic sweep:
     * a copper-colored base from dielectric to metal. */
    {"disney_metallic_0", "{\"material\":\"disney\",\"base_color\":[0.95,0.55,0.35],"
                          "\"metallic\":0,\"roughness\":0.3}"},
    {"disney_metallic_50", "{\"material\":\"disney\",\"base_color\":[0.95,0.55,0.35],"
                           "\"metallic\":0.5,\"roughness\":0.3}"},
    {"disney_metallic_100", "{\"material\":\"disney\",\"base_color\":[0.95,0.55,0.35],"
                            "\"metallic\":1,\"roughness\":0.3}"},
    /* Roughness sweep: a green plastic. */
    {"disney_rough_10", "{\"material\":\"disney\",\"base_color\":[0.10,0.45,0.25],"
                        "\"roughness\":0.1}"},
    {"disney_rough_45", "{\"material\":\"disney\",\"base_color\":[0.10,0.45,0.25],"
                        "\"roughness\":0.45}"},
    {"disney_rough_80", "{\"material\":\"disney\",\"base_color\":[0.10,0.45,0.25],"
                        "\"roughness\":0.8}"},
    /* Car paint: a red half-metallic base under a glossy clearcoat. */
    {"disney_paint", "{\"material\":\"disney\",\"base_color\":[0.70,0.04,0.04],"
                     "\"metallic\":0.5,\"roughness\":0.4,\"clearcoat\":1,"
                     "\"clearcoat_gloss\":0.9}"},
    /* Fabric: rough diffuse with a tinted sheen at grazing angles. */
    {"disney_fabric", "{\"material\":\"disney\",\"base_color\":[0.30,0.18,0.55],"
                      "\"roughness\":0.9,\"sheen\":1,\"sheen_tint\":0.5}"},
    {"ground_light", "{\"lobes\":[{\"type\":\"lambert\",\"color\":[0.50,0.50,0.48]}]}"},
    {"ground_dark", "{\"lobes\":[{\"type\":\"lambert\",\"color\":[0.22,0.22,0.23]}]}"},
};

const char *material_by_name(const char *name)
{
    size_t i;
    for (i = 0; i < sizeof MATERIALS / sizeof MATERIALS[0]; i++)
        if (strcmp(MATERIALS[i].name, name) == 0)
            return MATERIALS[i].json;
    return NULL;
}

void material_list(void)
{
    size_t i;
    for (i = 0; i < sizeof MATERIALS / sizeof MATERIALS[0]; i++)
        fprintf(stderr, "  %-16s %s\n", MATERIALS[i].name, MATERIALS[i].json);
}

/* ---- containers ----------------------------------------------------------------------- */

static void *grow(void *array, int *cap, int count, size_t elem)
{
    if (count < *cap)
        return array;
    *cap = *cap ? *cap * 2 : 8;
    array = realloc(array, (size_t)*cap * elem);
    if (!array) {
        fprintf(stderr, "%s: out of memory\n", scene_program);
        exit(EXIT_FAILURE);
    }
    return array;
}

static void *xmalloc(size_t n)
{
    void *p = malloc(n ? n : 1);
    if (!p) {
        fprintf(stderr, "%s: out of memory\n", scene_program);
        exit(EXIT_FAILURE);
    }
    return p;
}

void scene_init(ex_scene *s)
{
    memset(s, 0, sizeof *s);
    s->camera.eye = v3(0, 0, 5);
    s->camera.target = v3(0, 0, 0);
    s->camera.up = v3(0, 1, 0);
    s->camera.vfov_deg = 40.0f;
    s->env.kind = ENV_NONE;
    s->env.intensity = 1.0f;
}

void scene_free(ex_scene *s)
{
    int i;
    for (i = 0; i < s->material_count; i++) {
        free(s->materials[i].json);
        material_release(&s->materials[i]);
    }
    for (i = 0; i < s->object_count; i++) {
        free(s->objects[i].positions);
        free(s->objects[i].normals);
        free(s->objects[i].indices);
    }
    free(s->materials);
    free(s->objects);
    free(s->lights);
    free(s->point_lights);
    free(s->dir_lights);
    if (s->rtc)
        rtcReleaseScene(s->rtc);
    if (s->device)
        rtcReleaseDevice(s->device);
    memset(s, 0, sizeof *s);
}

int scene_add_material(ex_scene *s, const char *name, const char *json)
{
    ex_material *m;
    size_t n = strlen(json);
    s->materials = grow(s->materials, &s->material_cap, s->material_count, sizeof *m);
    m = &s->materials[s->material_count];
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "%s", name);
    m->json = xmalloc(n + 1);
    memcpy(m->json, json, n + 1);
    return s->material_count++;
}

int scene_find_material(const ex_scene *s, const char *name)
{
    int i;
    for (i = 0; i < s->material_count; i++)
        if (strcmp(s->materials[i].name, name) == 0)
            return i;
    return -1;
}

static ex_object *new_object(ex_scene *s, int kind, int material)
{
    ex_object *o;
    s->objects = grow(s->objects, &s->object_cap, s->object_count, sizeof *o);
    o = &s->objects[s->object_count++];
    memset(o, 0, sizeof *o);
    o->kind = kind;
    o->material = material;
    o->material2 = -1;
    o->checker_scale = 1.0f;
    o->light = -1;
    return o;
}

void scene_add_sphere(ex_scene *s, vec3 center, float radius, int material)
{
    ex_object *o = new_object(s, OBJ_SPHERE, material);
    o->center = center;
    o->radius = radius;
}

static void quad_mesh(ex_object *o, vec3 c, vec3 e1, vec3 e2)
{
    const vec3 p[4] = {c, v_add(c, e1), v_add(v_add(c, e1), e2), v_add(c, e2)};
    static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    int i;
    o->vertex_count = 4;
    o->triangle_count = 2;
    o->positions = xmalloc(12 * sizeof(float));
    o->indices = xmalloc(6 * sizeof(uint32_t));
    for (i = 0; i < 4; i++) {
        o->positions[3 * i + 0] = p[i].x;
        o->positions[3 * i + 1] = p[i].y;
        o->positions[3 * i + 2] = p[i].z;
    }
    memcpy(o->indices, idx, sizeof idx);
}

void scene_add_quad(ex_scene *s, vec3 corner, vec3 e1, vec3 e2, int material)
{
    quad_mesh(new_object(s, OBJ_MESH, material), corner, e1, e2);
}

void scene_add_mesh(ex_scene *s, float *positions, float *normals, size_t vertex_count,
                    uint32_t *indices, size_t triangle_count, int material)
{
    ex_object *o = new_object(s, OBJ_MESH, material);
    o->positions = positions;
    o->normals = normals;
    o->vertex_count = vertex_count;
    o->indices = indices;
    o->triangle_count = triangle_count;
}

void scene_add_quad_light(ex_scene *s, vec3 corner, vec3 e1, vec3 e2, vec3 radiance)
{
    ex_quad_light *l;
    ex_object *o;
    const vec3 n = v_cross(e1, e2);
    s->lights = grow(s->lights, &s->light_cap, s->light_count, sizeof *l);
    l = &s->lights[s->light_count];
    memset(l, 0, sizeof *l);
    l->corner = corner;
    l->e1 = e1;
    l->e2 = e2;
    l->area = v_len(n);
    l->normal = v_norm(n);
    l->radiance = radiance;
    o = new_object(s, OBJ_LIGHT, -1);
    o->light = s->light_count++;
    quad_mesh(o, corner, e1, e2);
}

void scene_add_point_light(ex_scene *s, vec3 position, vec3 intensity)
{
    ex_point_light *l;
    s->point_lights =
        grow(s->point_lights, &s->point_light_cap, s->point_light_count, sizeof *l);
    l = &s->point_lights[s->point_light_count++];
    l->position = position;
    l->intensity = intensity;
}

void scene_add_dir_light(ex_scene *s, vec3 direction, vec3 irradiance)
{
    ex_dir_light *l;
    s->dir_lights = grow(s->dir_lights, &s->dir_light_cap, s->dir_light_count, sizeof *l);
    l = &s->dir_lights[s->dir_light_count++];
    l->direction = v_norm(direction);
    l->irradiance = irradiance;
}

/* ---- build ----------------------------------------------------------------------------- */

static void embree_error(void *user, enum RTCError code, const char *message)
{
    (void)user;
    fprintf(stderr, "%s: embree error %d: %s\n", scene_program, (int)code, message);
}

static int check_materials(ex_scene *s, const glint_runtime *rt)
{
    glint_arena *arena = NULL;
    int i, ok = 1;
    if (glint_arena_create(1, &arena) != GLINT_OK) {
        fprintf(stderr, "%s: glint_arena_create: %s\n", scene_program, glint_last_error());
        return -1;
    }
    for (i = 0; i < s->material_count && ok; i++) {
        ex_material *m = &s->materials[i];
        glint_closure *c = NULL;
        uint32_t n = 0, k;
        glint_arena_reset(arena);
        if (glint_closure_from_json(rt, arena, m->json, NULL, &c) != GLINT_OK ||
            glint_closure_lobe_count(c, &n) != GLINT_OK) {
            fprintf(stderr, "%s: material \"%s\": %s\n", scene_program, m->name, glint_last_error());
            ok = 0;
            break;
        }
        m->transmits = 0;
        for (k = 0; k < n; k++) {
            uint32_t type = 0;
            float prob = 0.0f;
            glint_lobe_info info;
            memset(&info, 0, sizeof info);
            info.struct_size = sizeof info;
            if (glint_closure_lobe(c, k, &type, &prob) != GLINT_OK ||
                glint_lobe_type_info(rt, type, &info) != GLINT_OK) {
                fprintf(stderr, "%s: material \"%s\": %s\n", scene_program, m->name, glint_last_error());
                ok = 0;
                break;
            }
            if (info.flags & GLINT_FLAG_TRANSMISSION)
                m->transmits = 1;
        }
    }
    glint_arena_destroy(arena);
    return ok ? 0 : -1;
}

int scene_build(ex_scene *s, const glint_runtime *rt)
{
    int i;
    float total = 0.0f, run = 0.0f;
    if (check_materials(s, rt) != 0)
        return -1;
    for (i = 0; i < s->material_count; i++)
        if (material_prepare(&s->materials[i], rt) != 0)
            return -1;
    for (i = 0; i < s->object_count; i++) {
        const ex_object *o = &s->objects[i];
        if (o->kind != OBJ_LIGHT &&
            (o->material < 0 || o->material >= s->material_count ||
             o->material2 >= s->material_count)) {
            fprintf(stderr, "%s: object %d has no valid material\n", scene_program, i);
            return -1;
        }
    }
    /* Lights are picked in proportion to their power (luminance x area). */
    for (i = 0; i < s->light_count; i++)
        total += v_luminance(s->lights[i].radiance) * s->lights[i].area;
    for (i = 0; i < s->light_count; i++) {
        ex_quad_light *l = &s->lights[i];
        l->select_prob = total > 0.0f ? v_luminance(l->radiance) * l->area / total
                                      : 1.0f / (float)s->light_count;
        run += l->select_prob;
        l->cdf = i + 1 == s->light_count ? 1.0f : run;
    }

    s->device = rtcNewDevice(NULL);
    if (!s->device) {
        fprintf(stderr, "%s: rtcNewDevice failed (error %d)\n", scene_program,
                (int)rtcGetDeviceError(NULL));
        return -1;
    }
    rtcSetDeviceErrorFunction(s->device, embree_error, NULL);
    s->rtc = rtcNewScene(s->device);
    rtcSetSceneFlags(s->rtc, RTC_SCENE_FLAG_ROBUST);
    for (i = 0; i < s->object_count; i++) {
        const ex_object *o = &s->objects[i];
        RTCGeometry g;
        if (o->kind == OBJ_SPHERE) {
            float *v;
            g = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
            v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                        4 * sizeof(float), 1);
            v[0] = o->center.x;
            v[1] = o->center.y;
            v[2] = o->center.z;
            v[3] = o->radius;
        } else {
            float *v;
            uint32_t *idx;
            g = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
            v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                        3 * sizeof(float), o->vertex_count);
            idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                          3 * sizeof(uint32_t), o->triangle_count);
            memcpy(v, o->positions, o->vertex_count * 3 * sizeof(float));
            memcpy(idx, o->indices, o->triangle_count * 3 * sizeof(uint32_t));
        }
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(s->rtc, g, (unsigned)i);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(s->rtc);
    if (rtcGetDeviceError(s->device) != RTC_ERROR_NONE) {
        fprintf(stderr, "%s: building the Embree scene failed\n", scene_program);
        return -1;
    }
    return 0;
}

/* ---- environment ---------------------------------------------------------------------- */

static vec3 lerp3(vec3 a, vec3 b, float t) { return v_add(a, v_scale(v_sub(b, a), t)); }

vec3 env_radiance(const ex_env *e, vec3 d)
{
    switch (e->kind) {
    case ENV_UNIFORM:
        return v_scale(e->color, e->intensity);
    case ENV_SKY: {
        const float y = d.y / v_len(d);
        vec3 c;
        if (y >= 0.0f)
            c = lerp3(e->horizon, e->zenith, sqrtf(y));
        else
            c = lerp3(e->horizon, e->ground, fminf(1.0f, -y * 8.0f));
        return v_scale(c, e->intensity);
    }
    default:
        return v3(0, 0, 0);
    }
}

float env_pdf(const ex_env *e, vec3 d)
{
    const float y = d.y / v_len(d);
    if (e->kind == ENV_NONE)
        return 0.0f;
    return e->up_fraction * fmaxf(y, 0.0f) / EX_PI + (1.0f - e->up_fraction) / (4.0f * EX_PI);
}

vec3 env_sample(const ex_env *e, float u0, float u1, float u2, float *pdf)
{
    vec3 d;
    if (u0 < e->up_fraction) { /* cosine around +y */
        const float r = sqrtf(u1), phi = 2.0f * EX_PI * u2;
        d = v3(r * cosf(phi), sqrtf(fmaxf(0.0f, 1.0f - u1)), r * sinf(phi));
    } else { /* uniform sphere */
        const float y = 1.0f - 2.0f * u1, r = sqrtf(fmaxf(0.0f, 1.0f - y * y));
        const float phi = 2.0f * EX_PI * u2;
        d = v3(r * cosf(phi), y, r * sinf(phi));
    }
    *pdf = env_pdf(e, d);
    return d;
}

vec3 env_mean(const ex_env *e)
{
    /* Both kinds depend on the height y only, and y is uniform in [-1, 1] over the sphere:
     * the mean is (1/2) of the integral over y (midpoint rule). */
    enum { STEPS = 4096 };
    vec3 sum = v3(0, 0, 0);
    int i;
    for (i = 0; i < STEPS; i++) {
        const float y = -1.0f + 2.0f * ((float)i + 0.5f) / (float)STEPS;
        const float r = sqrtf(fmaxf(0.0f, 1.0f - y * y));
        sum = v_add(sum, env_radiance(e, v3(r, y, 0.0f)));
    }
    return v_scale(sum, 1.0f / (float)STEPS);
}

/* ---- camera, rays and surfaces ---------------------------------------------------------- */

ex_view camera_view(const ex_camera *c, int width, int height)
{
    ex_view v;
    v.eye = c->eye;
    v.forward = v_norm(v_sub(c->target, c->eye));
    v.right = v_norm(v_cross(v.forward, c->up));
    v.up = v_cross(v.right, v.forward);
    v.tan_half = tanf(0.5f * c->vfov_deg * EX_PI / 180.0f);
    v.aspect = (float)width / (float)height;
    v.width = width;
    v.height = height;
    return v;
}

vec3 camera_ray(const ex_view *v, float x, float y)
{
    const float px = x / (float)v->width * 2.0f - 1.0f;
    const float py = 1.0f - y / (float)v->height * 2.0f;
    return v_norm(v_add(v->forward, v_add(v_scale(v->right, px * v->tan_half * v->aspect),
                                          v_scale(v->up, py * v->tan_half))));
}

int scene_intersect(const ex_scene *s, struct RTCIntersectContext *ctx, vec3 o, vec3 d,
                    ex_hit *h)
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
    rtcIntersect1(s->rtc, ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return 0;
    h->t = rh.ray.tfar;
    h->u = rh.hit.u;
    h->v = rh.hit.v;
    h->geom = rh.hit.geomID;
    h->prim = rh.hit.primID;
    return 1;
}

int scene_occluded(const ex_scene *s, struct RTCIntersectContext *ctx, vec3 o, vec3 d,
                   float tfar)
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
    rtcOccluded1(s->rtc, ctx, &r);
    return r.tfar < 0.0f; /* set to -inf on a hit */
}

vec3 offset_point(vec3 p, vec3 ng, vec3 dir)
{
    const float eps = 2e-4f * (1.0f + v_max_abs(p));
    return v_madd(p, ng, v_dot(dir, ng) > 0.0f ? eps : -eps);
}

void surface_at(const ex_scene *s, const ex_hit *h, vec3 o, vec3 d, ex_surface *out)
{
    static const frame world = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const ex_object *obj = &s->objects[h->geom];
    const vec3 wo = v_neg(d);
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
    if (!s->materials[out->material].transmits && v_dot(wo, out->ng) < 0.0f) {
        /* Two-sided reflection: a surface that does not transmit faces the viewer. */
        out->ng = v_neg(out->ng);
        out->ns = v_neg(out->ns);
    }
    if (v_dot(wo, out->ns) * v_dot(wo, out->ng) <= 0.0f)
        out->ns = out->ng;
    out->wo = wo;
    out->fr = frame_from_normal(out->ns);
    out->space = s->materials[out->material].compiled ? world : out->fr;
    out->wo_space = frame_to_local(&out->space, wo);
}

int delta_light_count(const ex_scene *s) { return s->point_light_count + s->dir_light_count; }

int delta_light_at(const ex_scene *s, int index, const ex_surface *sf, vec3 *wi,
                   vec3 *shadow_origin, vec3 *shadow_dir, float *shadow_len, vec3 *irradiance)
{
    if (index < s->point_light_count) {
        const ex_point_light *l = &s->point_lights[index];
        const vec3 to = v_sub(l->position, sf->p);
        const float d2 = v_dot(to, to);
        vec3 seg;
        float seg_len;
        if (!(d2 > 0.0f))
            return 0;
        *wi = v_scale(to, 1.0f / sqrtf(d2));
        if (!side_ok(*wi, sf->ng, sf->ns))
            return 0;
        /* As for area lights: the shadow ray ends at the light, from the moved origin. */
        *shadow_origin = offset_point(sf->p, sf->ng, *wi);
        seg = v_sub(l->position, *shadow_origin);
        seg_len = v_len(seg);
        *shadow_dir = v_scale(seg, 1.0f / seg_len);
        *shadow_len = seg_len * (1.0f - 1e-4f);
        *irradiance = v_scale(l->intensity, 1.0f / d2);
        return 1;
    } else {
        const ex_dir_light *l = &s->dir_lights[index - s->point_light_count];
        *wi = l->direction;
        if (!side_ok(*wi, sf->ng, sf->ns))
            return 0;
        *shadow_origin = offset_point(sf->p, sf->ng, *wi);
        *shadow_dir = *wi;
        *shadow_len = INFINITY;
        *irradiance = l->irradiance;
        return 1;
    }
}

/* ---- built-in scenes -------------------------------------------------------------------- */

void scene_showcase(ex_scene *s, int with_sheen)
{
    /* Two staggered rows: the back row first. */
    static const char *const names[8] = {"clay",  "aluminium",   "coated", "sheen",
                                         "gold",  "glass", "rough_glass", "mirror"};
    static const float xs[8] = {-2.45f, -1.05f, 0.35f, 1.75f, -1.75f, -0.35f, 1.05f, 2.45f};
    static const char *const disney[8] = {
        "disney_metallic_0", "disney_metallic_50", "disney_metallic_100", "disney_paint",
        "disney_fabric",     "disney_rough_10",    "disney_rough_45",     "disney_rough_80"};
    const float radius = 0.6f, row_z = 0.8f;
    const float disney_radius = 0.4f, disney_step = 0.92f, disney_z = 2.2f;
    int i;
    const int light = scene_add_material(s, "ground_light", material_by_name("ground_light"));
    const int dark = scene_add_material(s, "ground_dark", material_by_name("ground_dark"));

    /* Ground: a large checkerboard. */
    scene_add_quad(s, v3(-40, 0, 40), v3(80, 0, 0), v3(0, 0, -80), light);
    s->objects[s->object_count - 1].material2 = dark;
    s->objects[s->object_count - 1].checker_scale = 1.0f;

    for (i = 0; i < 8; i++) {
        int m;
        float x = xs[i];
        if (i == 3 && !with_sheen)
            continue;
        if (i < 3 && !with_sheen)
            x += 0.7f; /* re-center the back row of three */
        m = scene_add_material(s, names[i], material_by_name(names[i]));
        scene_add_sphere(s, v3(x, radius, i < 4 ? -row_z : row_z), radius, m);
    }
    /* A front row of smaller Disney spheres: the metallic sweep, the car paint, the fabric,
     * the roughness sweep. */
    for (i = 0; i < 8; i++) {
        const int m = scene_add_material(s, disney[i], material_by_name(disney[i]));
        scene_add_sphere(s, v3(((float)i - 3.5f) * disney_step, disney_radius, disney_z),
                         disney_radius, m);
    }

    /* A soft box above, left and in front, emitting downward (e1 x e2 points down). */
    scene_add_quad_light(s, v3(-5.5f, 5.5f, 0.5f), v3(5.0f, 0, 0), v3(0, 0, 4.0f),
                         v3(5.8f, 5.5f, 5.1f));

    s->env.kind = ENV_SKY;
    s->env.zenith = v3(0.22f, 0.38f, 0.80f);
    s->env.horizon = v3(0.85f, 0.88f, 0.95f);
    s->env.ground = v3(0.20f, 0.18f, 0.16f);
    s->env.up_fraction = 0.8f;
    s->env.intensity = 0.55f;

    s->camera.eye = v3(0.0f, 3.6f, 10.2f);
    s->camera.target = v3(0.0f, 0.2f, -0.3f);
    s->camera.up = v3(0, 1, 0);
    s->camera.vfov_deg = 30.0f;
}

void scene_furnace(ex_scene *s, const char *material_json)
{
    const int m = scene_add_material(s, "furnace", material_json);
    scene_add_sphere(s, v3(0, 0, 0), 1.0f, m);
    s->env.kind = ENV_UNIFORM;
    s->env.color = v3(1, 1, 1);
    s->env.intensity = 1.0f;
    s->env.up_fraction = 0.0f; /* uniform on the sphere */
    s->camera.eye = v3(0, 0, 4.5f);
    s->camera.target = v3(0, 0, 0);
    s->camera.up = v3(0, 1, 0);
    s->camera.vfov_deg = 30.0f;
}
