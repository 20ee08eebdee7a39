/* scene_file.c: JSON scene files (cJSON) with meshes loaded through Assimp's C API.
 * The format is described in README.md next to this file; errors name the file and the
 * JSON path of the offending value. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene.h"

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <cjson/cJSON.h>

typedef struct loader {
    ex_scene *scene;
    const char *path; /* the scene file */
    char dir[4096];   /* its directory, for relative mesh paths */
} loader;

static int fail(const loader *ld, const char *where, const char *message)
{
    fprintf(stderr, "%s: %s: %s: %s\n", scene_program, ld->path, where, message);
    return -1;
}

/* Every key of `obj` must be one of the NULL-terminated `keys`. */
static int check_keys(const loader *ld, const char *where, const cJSON *obj,
                      const char *const *keys)
{
    const cJSON *item;
    cJSON_ArrayForEach(item, obj)
    {
        int k, known = 0;
        for (k = 0; keys[k]; k++)
            if (strcmp(item->string, keys[k]) == 0)
                known = 1;
        if (!known) {
            char msg[512];
            size_t n = (size_t)snprintf(msg, sizeof msg, "unknown key \"%s\"; valid keys:",
                                        item->string);
            for (k = 0; keys[k] && n < sizeof msg; k++)
                n += (size_t)snprintf(msg + n, sizeof msg - n, " %s", keys[k]);
            return fail(ld, where, msg);
        }
    }
    return 0;
}

static int get_number(const loader *ld, const char *where, const cJSON *obj, const char *key,
                      int required, float *out)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    char msg[128];
    if (!v) {
        if (!required)
            return 0;
        snprintf(msg, sizeof msg, "missing \"%s\" (a number)", key);
        return fail(ld, where, msg);
    }
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) {
        snprintf(msg, sizeof msg, "\"%s\" must be a number", key);
        return fail(ld, where, msg);
    }
    *out = (float)v->valuedouble;
    return 0;
}

/* A vector: [x, y, z]; a single number n means [n, n, n] when `splat`. */
static int get_vec3(const loader *ld, const char *where, const cJSON *obj, const char *key,
                    int required, int splat, vec3 *out)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    char msg[128];
    float c[3];
    int i;
    if (!v) {
        if (!required)
            return 0;
        snprintf(msg, sizeof msg, "missing \"%s\" ([x, y, z])", key);
        return fail(ld, where, msg);
    }
    if (splat && cJSON_IsNumber(v)) {
        *out = v3((float)v->valuedouble, (float)v->valuedouble, (float)v->valuedouble);
        return 0;
    }
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) {
        snprintf(msg, sizeof msg, "\"%s\" must be an array of 3 numbers", key);
        return fail(ld, where, msg);
    }
    for (i = 0; i < 3; i++) {
        const cJSON *e = cJSON_GetArrayItem(v, i);
        if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble)) {
            snprintf(msg, sizeof msg, "\"%s\" must be an array of 3 numbers", key);
            return fail(ld, where, msg);
        }
        c[i] = (float)e->valuedouble;
    }
    *out = v3(c[0], c[1], c[2]);
    return 0;
}

/* "corner", "edge1", "edge2" of a parallelogram that spans an area. */
static int get_parallelogram(const loader *ld, const char *where, const cJSON *obj, vec3 *corner,
                             vec3 *e1, vec3 *e2)
{
    if (get_vec3(ld, where, obj, "corner", 1, 0, corner) ||
        get_vec3(ld, where, obj, "edge1", 1, 0, e1) || get_vec3(ld, where, obj, "edge2", 1, 0, e2))
        return -1;
    if (!(v_len(v_cross(*e1, *e2)) > 0.0f))
        return fail(ld, where, "\"edge1\" and \"edge2\" must span an area");
    return 0;
}

static const char *get_string(const cJSON *obj, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    return cJSON_IsString(v) ? v->valuestring : NULL;
}

/* A material reference: a name from "materials", a built-in name, or an inline closure
 * ({"lobes": [...]}) or material document ({"material": "disney", ...}). Returns the index
 * or -1. */
static int material_ref(const loader *ld, const char *where, const cJSON *v)
{
    ex_scene *s = ld->scene;
    if (cJSON_IsString(v)) {
        int m = scene_find_material(s, v->valuestring);
        const char *builtin;
        if (m >= 0)
            return m;
        builtin = material_by_name(v->valuestring);
        if (builtin)
            return scene_add_material(s, v->valuestring, builtin);
        {
            char msg[256];
            snprintf(msg, sizeof msg,
                     "unknown material \"%s\" (not in \"materials\" nor built in; "
                     "pathtracer --list-materials lists the built-in ones)",
                     v->valuestring);
            fail(ld, where, msg);
        }
        return -1;
    }
    if (cJSON_IsObject(v)) {
        char *json = cJSON_PrintUnformatted(v);
        int m;
        if (!json)
            return -1;
        m = scene_add_material(s, where, json);
        cJSON_free(json);
        return m;
    }
    fail(ld, where, "\"material\" must be a material name, a closure description "
                    "({\"lobes\": [...]}) or a material document ({\"material\": ...})");
    return -1;
}

static vec3 rotate_xyz(vec3 p, vec3 deg)
{
    const float rx = deg.x * EX_PI / 180.0f, ry = deg.y * EX_PI / 180.0f,
                rz = deg.z * EX_PI / 180.0f;
    vec3 q;
    q = v3(p.x, p.y * cosf(rx) - p.z * sinf(rx), p.y * sinf(rx) + p.z * cosf(rx));
    q = v3(q.x * cosf(ry) + q.z * sinf(ry), q.y, -q.x * sinf(ry) + q.z * cosf(ry));
    q = v3(q.x * cosf(rz) - q.y * sinf(rz), q.x * sinf(rz) + q.y * cosf(rz), q.z);
    return q;
}

static int load_mesh(const loader *ld, const char *where, const cJSON *o, int material)
{
    static const char *const keys[] = {"type", "file", "material", "scale", "rotate",
                                       "translate", "smooth", NULL};
    const char *file = get_string(o, "file");
    char path[8192];
    const struct aiScene *sc;
    vec3 rot = v3(0, 0, 0), tr = v3(0, 0, 0);
    float scale = 1.0f;
    const cJSON *smooth = cJSON_GetObjectItemCaseSensitive(o, "smooth");
    size_t nv = 0, nt = 0, vbase = 0, tbase = 0;
    float *pos, *nrm;
    uint32_t *idx;
    unsigned m, k;
    if (check_keys(ld, where, o, keys) || get_number(ld, where, o, "scale", 0, &scale) ||
        get_vec3(ld, where, o, "rotate", 0, 0, &rot) ||
        get_vec3(ld, where, o, "translate", 0, 0, &tr))
        return -1;
    if (!file)
        return fail(ld, where, "a mesh needs \"file\" (a path relative to the scene file)");
    if (smooth && !cJSON_IsBool(smooth))
        return fail(ld, where, "\"smooth\" must be true or false");
    if (file[0] == '/')
        snprintf(path, sizeof path, "%s", file);
    else
        snprintf(path, sizeof path, "%s%s", ld->dir, file);
    sc = aiImportFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                aiProcess_GenSmoothNormals | aiProcess_PreTransformVertices |
                                aiProcess_SortByPType);
    if (!sc) {
        fprintf(stderr, "%s: %s: %s: %s: %s\n", scene_program, ld->path, where, path,
                aiGetErrorString());
        return -1;
    }
    for (m = 0; m < sc->mNumMeshes; m++) {
        const struct aiMesh *me = sc->mMeshes[m];
        if (!(me->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
            continue;
        nv += me->mNumVertices;
        nt += me->mNumFaces;
    }
    if (nt == 0) {
        aiReleaseImport(sc);
        return fail(ld, where, "the mesh file has no triangles");
    }
    pos = malloc(nv * 3 * sizeof(float));
    nrm = malloc(nv * 3 * sizeof(float));
    idx = malloc(nt * 3 * sizeof(uint32_t));
    if (!pos || !nrm || !idx) {
        free(pos);
        free(nrm);
        free(idx);
        aiReleaseImport(sc);
        return fail(ld, where, "out of memory");
    }
    for (m = 0; m < sc->mNumMeshes; m++) {
        const struct aiMesh *me = sc->mMeshes[m];
        size_t used = 0;
        if (!(me->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
            continue;
        for (k = 0; k < me->mNumVertices; k++) {
            const vec3 p = v_add(rotate_xyz(v_scale(v3(me->mVertices[k].x, me->mVertices[k].y,
                                                       me->mVertices[k].z),
                                                    scale),
                                            rot),
                                 tr);
            vec3 n = v3(0, 0, 0);
            if (me->mNormals)
                n = v_norm(rotate_xyz(
                    v3(me->mNormals[k].x, me->mNormals[k].y, me->mNormals[k].z), rot));
            pos[3 * (vbase + k) + 0] = p.x;
            pos[3 * (vbase + k) + 1] = p.y;
            pos[3 * (vbase + k) + 2] = p.z;
            nrm[3 * (vbase + k) + 0] = n.x;
            nrm[3 * (vbase + k) + 1] = n.y;
            nrm[3 * (vbase + k) + 2] = n.z;
        }
        for (k = 0; k < me->mNumFaces; k++) {
            const struct aiFace *f = &me->mFaces[k];
            if (f->mNumIndices != 3)
                continue; /* points and lines sorted into other meshes; be safe */
            idx[3 * (tbase + used) + 0] = (uint32_t)(vbase + f->mIndices[0]);
            idx[3 * (tbase + used) + 1] = (uint32_t)(vbase + f->mIndices[1]);
            idx[3 * (tbase + used) + 2] = (uint32_t)(vbase + f->mIndices[2]);
            used++;
        }
        vbase += me->mNumVertices;
        tbase += used;
    }
    aiReleaseImport(sc);
    if (smooth && cJSON_IsFalse(smooth)) {
        free(nrm);
        nrm = NULL;
    }
    if (scale < 0.0f && nrm) /* a mirrored mesh: normals follow the flipped geometry */
        for (k = 0; k < nv * 3; k++)
            nrm[k] = -nrm[k];
    scene_add_mesh(ld->scene, pos, nrm, vbase, idx, tbase, material);
    return 0;
}

static int load_objects(const loader *ld, const cJSON *objects)
{
    const cJSON *o;
    int i = 0;
    if (!cJSON_IsArray(objects))
        return fail(ld, "objects", "must be an array");
    cJSON_ArrayForEach(o, objects)
    {
        char where[64];
        const char *type = get_string(o, "type");
        int material;
        snprintf(where, sizeof where, "objects[%d]", i++);
        if (!cJSON_IsObject(o) || !type)
            return fail(ld, where, "an object needs \"type\": sphere, quad or mesh");
        if (!cJSON_GetObjectItemCaseSensitive(o, "material"))
            return fail(ld, where, "missing \"material\"");
        material = material_ref(ld, where, cJSON_GetObjectItemCaseSensitive(o, "material"));
        if (material < 0)
            return -1;
        if (strcmp(type, "sphere") == 0) {
            static const char *const keys[] = {"type", "center", "radius", "material", NULL};
            vec3 c;
            float r;
            if (check_keys(ld, where, o, keys) || get_vec3(ld, where, o, "center", 1, 0, &c) ||
                get_number(ld, where, o, "radius", 1, &r))
                return -1;
            if (!(r > 0.0f))
                return fail(ld, where, "\"radius\" must be positive");
            scene_add_sphere(ld->scene, c, r, material);
        } else if (strcmp(type, "quad") == 0) {
            static const char *const keys[] = {"type", "corner", "edge1", "edge2", "material",
                                               "checker", "checker_scale", NULL};
            vec3 c, e1, e2;
            float scale = 1.0f;
            const cJSON *checker = cJSON_GetObjectItemCaseSensitive(o, "checker");
            if (check_keys(ld, where, o, keys) || get_parallelogram(ld, where, o, &c, &e1, &e2) ||
                get_number(ld, where, o, "checker_scale", 0, &scale))
                return -1;
            scene_add_quad(ld->scene, c, e1, e2, material);
            if (checker) {
                ex_object *q;
                const int m2 = material_ref(ld, where, checker);
                if (m2 < 0)
                    return -1;
                if (!(scale > 0.0f))
                    return fail(ld, where, "\"checker_scale\" must be positive");
                q = &ld->scene->objects[ld->scene->object_count - 1];
                q->material2 = m2;
                q->checker_scale = scale;
            }
        } else if (strcmp(type, "mesh") == 0) {
            if (load_mesh(ld, where, o, material) != 0)
                return -1;
        } else {
            return fail(ld, where, "unknown \"type\"; valid types: sphere quad mesh");
        }
    }
    return 0;
}

static int get_nonnegative_vec3(const loader *ld, const char *where, const cJSON *obj,
                                const char *key, vec3 *out)
{
    char msg[128];
    if (get_vec3(ld, where, obj, key, 1, 1, out))
        return -1;
    if (out->x < 0.0f || out->y < 0.0f || out->z < 0.0f) {
        snprintf(msg, sizeof msg, "\"%s\" must not be negative", key);
        return fail(ld, where, msg);
    }
    return 0;
}

static int load_lights(const loader *ld, const cJSON *lights)
{
    const cJSON *l;
    int i = 0;
    if (!cJSON_IsArray(lights))
        return fail(ld, "lights", "must be an array");
    cJSON_ArrayForEach(l, lights)
    {
        char where[64];
        const char *type = get_string(l, "type");
        snprintf(where, sizeof where, "lights[%d]", i++);
        if (!cJSON_IsObject(l) || !type)
            return fail(ld, where, "a light needs \"type\": quad, point or directional");
        if (strcmp(type, "quad") == 0) {
            static const char *const keys[] = {"type", "corner", "edge1", "edge2", "radiance",
                                               NULL};
            vec3 c, e1, e2, radiance;
            if (check_keys(ld, where, l, keys) || get_parallelogram(ld, where, l, &c, &e1, &e2) ||
                get_nonnegative_vec3(ld, where, l, "radiance", &radiance))
                return -1;
            scene_add_quad_light(ld->scene, c, e1, e2, radiance);
        } else if (strcmp(type, "point") == 0) {
            static const char *const keys[] = {"type", "position", "intensity", NULL};
            vec3 p, intensity;
            if (check_keys(ld, where, l, keys) || get_vec3(ld, where, l, "position", 1, 0, &p) ||
                get_nonnegative_vec3(ld, where, l, "intensity", &intensity))
                return -1;
            scene_add_point_light(ld->scene, p, intensity);
        } else if (strcmp(type, "directional") == 0) {
            static const char *const keys[] = {"type", "direction", "irradiance", NULL};
            vec3 d, irradiance;
            if (check_keys(ld, where, l, keys) ||
                get_vec3(ld, where, l, "direction", 1, 0, &d) ||
                get_nonnegative_vec3(ld, where, l, "irradiance", &irradiance))
                return -1;
            if (!(v_len(d) > 0.0f))
                return fail(ld, where, "\"direction\" must not be zero");
            scene_add_dir_light(ld->scene, d, irradiance);
        } else {
            return fail(ld, where, "unknown \"type\"; valid types: quad point directional");
        }
    }
    return 0;
}

static int load_environment(const loader *ld, const cJSON *e)
{
    static const char *const keys[] = {"type",   "color",     "zenith",      "horizon",
                                       "ground", "intensity", "up_fraction", NULL};
    ex_env *env = &ld->scene->env;
    const char *type = get_string(e, "type");
    if (!cJSON_IsObject(e) || !type)
        return fail(ld, "environment", "needs \"type\": sky, uniform or none");
    if (check_keys(ld, "environment", e, keys))
        return -1;
    env->intensity = 1.0f;
    if (strcmp(type, "none") == 0) {
        env->kind = ENV_NONE;
        return 0;
    }
    if (strcmp(type, "uniform") == 0) {
        env->kind = ENV_UNIFORM;
        env->color = v3(1, 1, 1);
        env->up_fraction = 0.0f;
        if (get_vec3(ld, "environment", e, "color", 0, 1, &env->color))
            return -1;
    } else if (strcmp(type, "sky") == 0) {
        env->kind = ENV_SKY;
        env->zenith = v3(0.22f, 0.38f, 0.80f);
        env->horizon = v3(0.85f, 0.88f, 0.95f);
        env->ground = v3(0.20f, 0.18f, 0.16f);
        env->up_fraction = 0.8f;
        if (get_vec3(ld, "environment", e, "zenith", 0, 1, &env->zenith) ||
            get_vec3(ld, "environment", e, "horizon", 0, 1, &env->horizon) ||
            get_vec3(ld, "environment", e, "ground", 0, 1, &env->ground))
            return -1;
    } else {
        return fail(ld, "environment", "unknown \"type\"; valid types: sky uniform none");
    }
    if (get_number(ld, "environment", e, "intensity", 0, &env->intensity) ||
        get_number(ld, "environment", e, "up_fraction", 0, &env->up_fraction))
        return -1;
    if (!(env->up_fraction >= 0.0f && env->up_fraction <= 1.0f))
        return fail(ld, "environment", "\"up_fraction\" must be in [0, 1]");
    if (!(env->intensity >= 0.0f))
        return fail(ld, "environment", "\"intensity\" must not be negative");
    return 0;
}

static int load_camera(const loader *ld, const cJSON *c)
{
    static const char *const keys[] = {"eye", "target", "up", "fov", NULL};
    ex_camera *cam = &ld->scene->camera;
    if (!cJSON_IsObject(c))
        return fail(ld, "camera", "must be an object");
    if (check_keys(ld, "camera", c, keys) || get_vec3(ld, "camera", c, "eye", 1, 0, &cam->eye) ||
        get_vec3(ld, "camera", c, "target", 1, 0, &cam->target) ||
        get_vec3(ld, "camera", c, "up", 0, 0, &cam->up) ||
        get_number(ld, "camera", c, "fov", 0, &cam->vfov_deg))
        return -1;
    if (!(cam->vfov_deg > 0.0f && cam->vfov_deg < 180.0f))
        return fail(ld, "camera", "\"fov\" (vertical, degrees) must be in (0, 180)");
    if (!(v_len(v_cross(v_sub(cam->target, cam->eye), cam->up)) > 0.0f))
        return fail(ld, "camera", "\"eye\", \"target\" and \"up\" must not be collinear");
    return 0;
}

int scene_load_file(ex_scene *s, const char *path)
{
    static const char *const keys[] = {"camera", "environment", "materials", "lights",
                                       "objects", NULL};
    loader ld;
    FILE *f = fopen(path, "rb");
    char *text;
    long size;
    cJSON *root, *item;
    const char *slash;
    int rc = -1;
    memset(&ld, 0, sizeof ld);
    ld.scene = s;
    ld.path = path;
    slash = strrchr(path, '/');
    if (slash)
        snprintf(ld.dir, sizeof ld.dir, "%.*s/", (int)(slash - path), path);
    if (!f) {
        fprintf(stderr, "%s: cannot open %s\n", scene_program, path);
        return -1;
    }
    fseek(f, 0, SEEK_END);
    size = ftell(f);
    fseek(f, 0, SEEK_SET);
    text = malloc((size_t)(size > 0 ? size : 0) + 1);
    if (!text || size < 0 || fread(text, 1, (size_t)size, f) != (size_t)size) {
        fclose(f);
        free(text);
        fprintf(stderr, "%s: cannot read %s\n", scene_program, path);
        return -1;
    }
    fclose(f);
    text[size] = '\0';
    root = cJSON_Parse(text);
    if (!root) {
        const char *at = cJSON_GetErrorPtr();
        fprintf(stderr, "%s: %s: JSON syntax error near byte %ld\n", scene_program, path,
                at ? (long)(at - text) : -1L);
        free(text);
        return -1;
    }
    if (!cJSON_IsObject(root)) {
        fail(&ld, "top level", "must be an object");
        goto out;
    }
    if (check_keys(&ld, "top level", root, keys))
        goto out;
    /* Named materials first, so objects can refer to them. */
    item = cJSON_GetObjectItemCaseSensitive(root, "materials");
    if (item) {
        const cJSON *m;
        if (!cJSON_IsObject(item)) {
            fail(&ld, "materials", "must be an object of name: closure description or material "
                                   "document");
            goto out;
        }
        cJSON_ArrayForEach(m, item)
        {
            char *json;
            if (!cJSON_IsObject(m)) {
                fail(&ld, "materials", "each material must be a closure description "
                                       "({\"lobes\": [...]}) or a material document "
                                       "({\"material\": ...})");
                goto out;
            }
            json = cJSON_PrintUnformatted(m);
            if (!json)
                goto out;
            scene_add_material(s, m->string, json);
            cJSON_free(json);
        }
    }
    if ((item = cJSON_GetObjectItemCaseSensitive(root, "camera")) && load_camera(&ld, item))
        goto out;
    if ((item = cJSON_GetObjectItemCaseSensitive(root, "environment")) &&
        load_environment(&ld, item))
        goto out;
    if ((item = cJSON_GetObjectItemCaseSensitive(root, "lights")) && load_lights(&ld, item))
        goto out;
    item = cJSON_GetObjectItemCaseSensitive(root, "objects");
    if (!item) {
        fail(&ld, "top level", "missing \"objects\"");
        goto out;
    }
    if (load_objects(&ld, item))
        goto out;
    if (s->light_count == 0 && delta_light_count(s) == 0 && s->env.kind == ENV_NONE)
        fprintf(stderr, "%s: warning: %s has no light and no environment\n", scene_program, path);
    rc = 0;
out:
    cJSON_Delete(root);
    free(text);
    return rc;
}
