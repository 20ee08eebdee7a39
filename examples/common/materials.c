/* materials.c: scene materials prepared once, so that no JSON is read per shading point.
 *
 * A material document ({"material": "disney", ...}) is compiled with glint_material_create;
 * its closure at a hit comes from glint_material_closure with the hit's shading context
 * (surface_closure), and the scanline host shades it with the material batch calls.
 *
 * A closure given as lobes ({"lobes": [...]}) is decoded into Glint parameter blocks and
 * built lobe by lobe per hit (glint_closure_begin / glint_closure_add_lobe /
 * glint_closure_finish). The decoding follows the JSON closure format of the README through
 * Glint's registry (glint_lobe_type_find, glint_lobe_param_defaults, glint_lobe_param_find,
 * glint_lobe_param_info, glint_lobe_param_choice), and material_prepare checks the result
 * against glint_closure_from_json: both closures must give identical eval results. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene.h"

#include <cjson/cJSON.h>

static int bad(const ex_material *m, int lobe, const char *what)
{
    fprintf(stderr, "%s: material \"%s\": lobes[%d]: %s\n", scene_program, m->name, lobe, what);
    return -1;
}

/* A number, or (when `n` is 3) also [a, b, c]; a single number fills all three. */
static int read_floats(const cJSON *v, float *out, int n)
{
    int i;
    if (cJSON_IsNumber(v)) {
        for (i = 0; i < n; i++)
            out[i] = (float)v->valuedouble;
        return 0;
    }
    if (n != 3 || !cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3)
        return -1;
    for (i = 0; i < 3; i++) {
        const cJSON *e = cJSON_GetArrayItem(v, i);
        if (!cJSON_IsNumber(e))
            return -1;
        out[i] = (float)e->valuedouble;
    }
    return 0;
}

static int decode_lobe(ex_material *m, const glint_runtime *rt, const cJSON *lobe, int index,
                       ex_lobe_block *out)
{
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(lobe, "type"), *item;
    glint_lobe_info info;
    memset(out, 0, sizeof *out);
    out->weight[0] = out->weight[1] = out->weight[2] = 1.0f;
    out->frame.normal = v3(0, 0, 1);
    if (cJSON_IsObject(lobe) && cJSON_GetObjectItemCaseSensitive(lobe, "material"))
        return bad(m, index, "a material entry cannot be built lobe by lobe; give the material "
                             "as a document of its own ({\"material\": ...})");
    if (!cJSON_IsObject(lobe) || !cJSON_IsString(type))
        return bad(m, index, "needs a \"type\" string");
    if (glint_lobe_type_find(rt, type->valuestring, &out->type) != GLINT_OK)
        return bad(m, index, glint_last_error());
    memset(&info, 0, sizeof info);
    info.struct_size = sizeof info;
    if (glint_lobe_type_info(rt, out->type, &info) != GLINT_OK)
        return bad(m, index, glint_last_error());
    out->param_count = info.param_block_size;
    out->params = calloc(info.param_block_size ? info.param_block_size : 1, sizeof(float));
    if (!out->params)
        return bad(m, index, "out of memory");
    if (glint_lobe_param_defaults(rt, out->type, out->params, out->param_count) != GLINT_OK)
        return bad(m, index, glint_last_error());
    cJSON_ArrayForEach(item, lobe)
    {
        const char *key = item->string;
        uint32_t p;
        glint_param_info pi;
        if (strcmp(key, "type") == 0)
            continue;
        if (strcmp(key, "weight") == 0) {
            if (read_floats(item, out->weight, 3) != 0)
                return bad(m, index, "\"weight\" must be a number or [r, g, b]");
            continue;
        }
        if (strcmp(key, "normal") == 0 || strcmp(key, "tangent") == 0) {
            float v[3];
            if (!cJSON_IsArray(item) || read_floats(item, v, 3) != 0)
                return bad(m, index, "\"normal\" and \"tangent\" must be [x, y, z]");
            if (key[0] == 'n')
                out->frame.normal = v3(v[0], v[1], v[2]);
            else
                out->frame.tangent = v3(v[0], v[1], v[2]);
            continue;
        }
        if (glint_lobe_param_find(rt, out->type, key, &p) != GLINT_OK)
            return bad(m, index, glint_last_error());
        memset(&pi, 0, sizeof pi);
        pi.struct_size = sizeof pi;
        if (glint_lobe_param_info(rt, out->type, p, &pi) != GLINT_OK)
            return bad(m, index, glint_last_error());
        if (pi.param_type == GLINT_PARAM_ENUM) {
            if (!cJSON_IsString(item) ||
                glint_lobe_param_choice(rt, out->type, p, item->valuestring,
                                        &out->params[pi.offset]) != GLINT_OK)
                return bad(m, index, cJSON_IsString(item) ? glint_last_error()
                                                          : "a choice must be a string");
        } else if (read_floats(item, &out->params[pi.offset], (int)pi.size) != 0) {
            return bad(m, index, pi.size == 3 ? "expected a number or [r, g, b]"
                                              : "expected a number");
        }
    }
    return 0;
}

glint_status material_build(const ex_material *m, const glint_runtime *rt, glint_arena *arena,
                            const glint_vec3 *wo, glint_closure **out)
{
    glint_closure *c = NULL;
    glint_status st = glint_closure_begin(rt, arena, wo, m->closure_flags, &c);
    int i;
    for (i = 0; st == GLINT_OK && i < m->lobe_count; i++) {
        const ex_lobe_block *b = &m->lobes[i];
        st = glint_closure_add_lobe(c, b->type, b->weight, &b->frame, b->params,
                                    b->param_count, NULL);
    }
    if (st == GLINT_OK)
        st = glint_closure_finish(c);
    *out = st == GLINT_OK ? c : NULL;
    return st;
}

/* Both ways of building must give the same closure: compare evals over a few directions. */
static int self_check(ex_material *m, const glint_runtime *rt)
{
    glint_arena *arena = NULL;
    int i, ok = 1;
    if (glint_arena_create(2, &arena) != GLINT_OK)
        return -1;
    for (i = 0; i < 64 && ok; i++) {
        const float a = 0.37f * (float)i, b = 0.91f * (float)i + 0.3f;
        const glint_vec3 wo = {cosf(a) * 0.8f, sinf(a) * 0.8f, 0.1f + 0.9f * (float)(i % 8) / 8.0f};
        const glint_vec3 wi = {cosf(b) * 0.6f, sinf(b) * 0.6f, (float)((i * 5) % 9) / 4.0f - 1.0f};
        glint_closure *cj = NULL, *cb = NULL;
        glint_eval_result ej, eb;
        memset(&ej, 0, sizeof ej);
        memset(&eb, 0, sizeof eb);
        ej.struct_size = eb.struct_size = sizeof ej;
        glint_arena_reset(arena);
        if (glint_closure_from_json(rt, arena, m->json, &wo, &cj) != GLINT_OK ||
            material_build(m, rt, arena, &wo, &cb) != GLINT_OK ||
            glint_eval(cj, wo, wi, &ej) != GLINT_OK || glint_eval(cb, wo, wi, &eb) != GLINT_OK) {
            fprintf(stderr, "%s: material \"%s\": %s\n", scene_program, m->name, glint_last_error());
            ok = 0;
        } else if (memcmp(ej.value, eb.value, sizeof ej.value) != 0 || ej.pdf != eb.pdf) {
            fprintf(stderr, "%s: material \"%s\": the decoded parameter blocks do not match "
                    "glint_closure_from_json\n", scene_program,
                    m->name);
            ok = 0;
        }
    }
    glint_arena_destroy(arena);
    return ok ? 0 : -1;
}

int material_prepare(ex_material *m, const glint_runtime *rt)
{
    cJSON *root = cJSON_Parse(m->json);
    const cJSON *lobes, *lobe, *transport;
    int n = 0, rc = -1;
    if (!root) {
        fprintf(stderr, "%s: material \"%s\": malformed JSON\n", scene_program, m->name);
        return -1;
    }
    if (cJSON_GetObjectItemCaseSensitive(root, "material")) {
        if (glint_material_create(rt, m->json, &m->compiled) == GLINT_OK)
            rc = 0;
        else
            fprintf(stderr, "%s: material \"%s\": %s\n", scene_program, m->name,
                    glint_last_error());
        goto out;
    }
    lobes = cJSON_GetObjectItemCaseSensitive(root, "lobes");
    transport = cJSON_GetObjectItemCaseSensitive(root, "transport");
    m->closure_flags = 0;
    if (cJSON_IsString(transport) && strcmp(transport->valuestring, "importance") == 0)
        m->closure_flags = GLINT_CLOSURE_IMPORTANCE;
    if (!cJSON_IsArray(lobes) || cJSON_GetArraySize(lobes) > GLINT_MAX_LOBES) {
        fprintf(stderr, "%s: material \"%s\": needs a \"lobes\" array or a \"material\" type\n",
                scene_program, m->name);
        goto out;
    }
    m->lobes = calloc((size_t)cJSON_GetArraySize(lobes) + 1, sizeof *m->lobes);
    if (!m->lobes)
        goto out;
    cJSON_ArrayForEach(lobe, lobes)
    {
        m->lobe_count = n + 1; /* so material_release frees a partly decoded lobe */
        if (decode_lobe(m, rt, lobe, n, &m->lobes[n]) != 0)
            goto out;
        n++;
    }
    rc = self_check(m, rt);
out:
    cJSON_Delete(root);
    return rc;
}

void material_release(ex_material *m)
{
    int i;
    glint_material_destroy(m->compiled);
    m->compiled = NULL;
    for (i = 0; i < m->lobe_count; i++)
        free(m->lobes[i].params);
    free(m->lobes);
    m->lobes = NULL;
    m->lobe_count = 0;
}

glint_status surface_closure(const ex_scene *s, const glint_runtime *rt, glint_arena *arena,
                             const ex_surface *sf, glint_closure **out)
{
    const ex_material *m = &s->materials[sf->material];
    glint_shading_context ctx;
    if (!m->compiled)
        return material_build(m, rt, arena, &sf->wo_space, out);
    /* Objects do not move, so the rest position is the world one. The scenes have no
     * texture coordinates, and the hosts track no ray footprint: uv and footprint stay 0. */
    memset(&ctx, 0, sizeof ctx);
    ctx.struct_size = sizeof ctx;
    ctx.wo = sf->wo;
    ctx.normal = sf->ns;
    ctx.tangent = sf->fr.t; /* the host's frame, as closures given as lobes get it */
    ctx.geometric_normal = sf->ng;
    ctx.position = sf->p;
    ctx.reference_position = sf->p;
    return glint_material_closure(m->compiled, arena, &ctx, NULL, 0, out);
}
