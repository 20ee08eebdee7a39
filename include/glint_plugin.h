/*
 * glint_plugin.h: the plugin ABI of Glint. Plain C99, no other Glint header needed.
 *
 * A plugin is a shared library that exports one function, `glint_plugin_entry`. Glint
 * calls it once when the plugin is loaded (glint_runtime_load_plugin or the `plugins=`
 * config key) and registers the lobe types it declares; they are then used exactly like
 * built-in lobes (by name in JSON and glint_closure_add_lobe, in closures with built-in
 * lobes, in batches). Plugins are never unloaded.
 *
 * Versioning. Each ABI version is frozen: a later version adds new structs and tables
 * (glint_plugin_v2, ...) instead of editing these. Glint passes the newest version it
 * speaks; the plugin answers with the version it implements (at most Glint's) and the
 * table of that version, or refuses. Every struct that may grow starts with
 * `struct_size`, set to sizeof by whoever fills it in.
 *
 * The lobe contract (identical to the built-in lobes', see glint.h):
 *  - Directions are unit vectors in the lobe's local frame: z is the shading normal,
 *    both `wo` (toward the viewer) and `wi` (toward the light) point away from the
 *    surface; "below" means z < 0.
 *  - eval writes value = f(wo, wi) |cos theta_i| (RGB) and the pdf (solid angle) with
 *    which `sample` draws wi from wo. Delta lobes (perfect specular) write 0 for both.
 *  - sample draws wi from wo with the random numbers u[0] (a discrete choice, e.g.
 *    reflect or refract), u[1], u[2], all in [0, 1). It returns 1 and fills the sample,
 *    or returns 0 when nothing can be scattered. value = f |cos theta_i| and pdf must
 *    equal what eval returns for that wi; for delta events set GLINT_PLUGIN_EVENT_DELTA,
 *    value = the reflected/transmitted fraction and pdf = the discrete probability.
 *  - albedo writes the directional albedo: the integral of eval's value over all wi.
 *  - Never return NaN, infinities or negative values or pdfs, values, pdfs or albedos
 *    above 1e16, or samples with a pdf below 1e-12. Glint repairs such outputs so that
 *    no closure output becomes NaN or infinite: NaN, infinite and negative ones become
 *    0, finite ones above 1e16 become 1e16, and a sample with a pdf below 1e-12 (whose
 *    weight value / pdf could overflow; such samples have total probability below
 *    5e-11) is no sample. Each repair is counted (glint_lobe_sanitized_count in
 *    glint.h; glint-verify fails a lobe that needed it), so one bad plugin cannot
 *    poison a render, but a lobe that needs this is broken.
 *  - Callbacks are called concurrently from many threads: they must be reentrant and
 *    must not keep state between calls.
 *  - `params` points to the lobe's parameter block: `block_size` bytes of floats laid
 *    out as the parameter table says (a C struct of float fields, in table order, is
 *    the natural way to declare it). An enum parameter is a float holding the index of
 *    the choice. Glint validates every value against the table before a callback sees it.
 *    The block is const: each call gets its own copy of the closure's block, so a
 *    callback that writes to it changes nothing beyond that call (and is counted as a
 *    repair, see above).
 *  - `transport` is GLINT_PLUGIN_RADIANCE (paths from the camera) or
 *    GLINT_PLUGIN_IMPORTANCE (from lights); only non-symmetric scattering (refraction)
 *    differs.
 */
#ifndef GLINT_PLUGIN_H
#define GLINT_PLUGIN_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The ABI versions this header describes. */
#define GLINT_PLUGIN_ABI_V1 1u
#define GLINT_PLUGIN_ABI_V2 2u

/* The name of the one symbol a plugin exports. */
#define GLINT_PLUGIN_ENTRY_SYMBOL "glint_plugin_entry"

#if defined(_WIN32)
#define GLINT_PLUGIN_EXPORT __declspec(dllexport)
#else
#define GLINT_PLUGIN_EXPORT __attribute__((visibility("default")))
#endif

/* Lobe flags (the same values as glint.h's GLINT_FLAG_*). */
#define GLINT_PLUGIN_FLAG_REFLECTION 1u
#define GLINT_PLUGIN_FLAG_TRANSMISSION 2u
#define GLINT_PLUGIN_FLAG_DIFFUSE 4u
#define GLINT_PLUGIN_FLAG_GLOSSY 8u
#define GLINT_PLUGIN_FLAG_SPECULAR 16u

/* Transport modes. */
#define GLINT_PLUGIN_RADIANCE 0u
#define GLINT_PLUGIN_IMPORTANCE 1u

/* Parameter types: one float, three floats (RGB), or a float holding a choice index. */
#define GLINT_PLUGIN_PARAM_FLOAT 0u
#define GLINT_PLUGIN_PARAM_RGB 1u
#define GLINT_PLUGIN_PARAM_ENUM 2u

/* One parameter of a lobe type (as in OSL's closure parameter tables). */
typedef struct glint_plugin_param {
    const char *name;          /* unique within the lobe type */
    uint32_t type;             /* GLINT_PLUGIN_PARAM_* */
    uint32_t offset;           /* byte offset in the parameter block */
    float default_value[3];    /* float: [0]; rgb: all three; enum: [0] = choice index */
    float min, max;            /* valid range of each component (float, rgb) */
    const char *const *choices; /* enum: choice_count names; otherwise NULL */
    uint32_t choice_count;
    const char *doc;           /* one line, may be NULL */
} glint_plugin_param;

/* Bits of glint_plugin_sample.events. */
#define GLINT_PLUGIN_EVENT_TRANSMITTED 1u /* wi is on the other side of the surface */
#define GLINT_PLUGIN_EVENT_DELTA 2u       /* a perfect specular event */

/* What sample fills in. */
typedef struct glint_plugin_sample {
    float wi[3];     /* unit, local frame */
    float value[3];  /* f |cos theta_i| (delta: the scattered fraction) */
    float pdf;       /* solid-angle pdf (delta: the discrete probability) */
    uint32_t events; /* GLINT_PLUGIN_EVENT_* */
    float eta;       /* relative IOR crossed by a transmitted sample, else 1 */
    float roughness; /* in [0, 1], 0 for delta events: a hint for path regularization */
} glint_plugin_sample;

/* Arguments of the optional batch eval: `count` lanes of SoA arrays. */
typedef struct glint_plugin_eval_batch {
    uint32_t struct_size;
    uint32_t transport;
    size_t count;
    const void *const *params; /* each lane's parameter block */
    const float *wo_x, *wo_y, *wo_z;
    const float *wi_x, *wi_y, *wi_z;
    float *value_r, *value_g, *value_b, *pdf; /* written, not accumulated */
} glint_plugin_eval_batch;

/* A lobe type, ABI version 1. */
typedef struct glint_plugin_lobe_v1 {
    uint32_t struct_size; /* sizeof(glint_plugin_lobe_v1) */
    const char *name;     /* unique among all lobe types: [a-z0-9_]+ */
    const char *summary;  /* one line */
    uint32_t flags;       /* every GLINT_PLUGIN_FLAG_* a sample may carry */
    uint32_t reciprocal;  /* 1 when f(wo, wi) == f(wi, wo) in radiance transport */
    const glint_plugin_param *params;
    uint32_t param_count;
    uint32_t block_size;  /* bytes of the parameter block (sizeof your struct) */
    uint32_t block_align; /* its alignment (4: floats) */
    void (*eval)(const void *params, const float wo[3], const float wi[3], uint32_t transport,
                 float value[3], float *pdf);
    int32_t (*sample)(const void *params, const float wo[3], const float u[3],
                      uint32_t transport, glint_plugin_sample *out);
    void (*albedo)(const void *params, const float wo[3], uint32_t transport, float albedo[3]);
    /* Optional (NULL: Glint loops over eval). */
    void (*eval_batch)(const glint_plugin_eval_batch *batch);
} glint_plugin_lobe_v1;

/* The table a version-1 plugin hands to Glint; it must stay valid forever. */
typedef struct glint_plugin_v1 {
    uint32_t struct_size; /* sizeof(glint_plugin_v1) */
    const char *name;     /* the plugin's name, for messages */
    uint32_t lobe_count;
    const glint_plugin_lobe_v1 *lobes;
} glint_plugin_v1;

/* ---- ABI version 2: samples report their class and component ----------------------- */

/* The class of a sample (glint_plugin_sample_v2.sample_class): the same values as
 * glint.h's GLINT_FLAG_DIFFUSE, _GLOSSY and _SPECULAR, and as GLINT_PLUGIN_FLAG_*. */
#define GLINT_PLUGIN_CLASS_DIFFUSE 4u
#define GLINT_PLUGIN_CLASS_GLOSSY 8u
#define GLINT_PLUGIN_CLASS_SPECULAR 16u

/* What a version-2 sample fills in: version 1's fields, then the sample's own class and
 * the component (sub-lobe) it came from, which Glint reports to the host as it does for
 * built-in lobes (glint_sample_result's flags and component, the sample batch's
 * component array). Rules, each repaired and counted like the outputs above when broken
 * (the class becomes the one a version-1 sample of the type reports, the component 0):
 *  - sample_class is exactly one GLINT_PLUGIN_CLASS_*, and one the lobe's flags declare;
 *  - GLINT_PLUGIN_CLASS_SPECULAR exactly when events has GLINT_PLUGIN_EVENT_DELTA;
 *  - component < the lobe's component_count. */
typedef struct glint_plugin_sample_v2 {
    uint32_t struct_size;  /* set by Glint to sizeof(glint_plugin_sample_v2) before the call */
    float wi[3];           /* unit, local frame */
    float value[3];        /* f |cos theta_i| (delta: the scattered fraction) */
    float pdf;             /* solid-angle pdf (delta: the discrete probability) */
    uint32_t events;       /* GLINT_PLUGIN_EVENT_* */
    float eta;             /* relative IOR crossed by a transmitted sample, else 1 */
    float roughness;       /* in [0, 1], 0 for delta events: a hint for path regularization */
    uint32_t sample_class; /* GLINT_PLUGIN_CLASS_* (not `class`: a C++ keyword) */
    uint32_t component;    /* the sub-lobe sampled, < the lobe's component_count */
} glint_plugin_sample_v2;

/* A lobe type, ABI version 2: version 1's fields (sample writes the version-2 sample),
 * then the number of components. `flags` must include at least one class bit (DIFFUSE,
 * GLOSSY or SPECULAR), the classes samples may report. */
typedef struct glint_plugin_lobe_v2 {
    uint32_t struct_size; /* sizeof(glint_plugin_lobe_v2) */
    const char *name;     /* unique among all lobe types: [a-z0-9_]+ */
    const char *summary;  /* one line */
    uint32_t flags;       /* every GLINT_PLUGIN_FLAG_* a sample may carry */
    uint32_t reciprocal;  /* 1 when f(wo, wi) == f(wi, wo) in radiance transport */
    const glint_plugin_param *params;
    uint32_t param_count;
    uint32_t block_size;  /* bytes of the parameter block (sizeof your struct) */
    uint32_t block_align; /* its alignment (4: floats) */
    void (*eval)(const void *params, const float wo[3], const float wi[3], uint32_t transport,
                 float value[3], float *pdf);
    int32_t (*sample)(const void *params, const float wo[3], const float u[3],
                      uint32_t transport, glint_plugin_sample_v2 *out);
    void (*albedo)(const void *params, const float wo[3], uint32_t transport, float albedo[3]);
    /* Optional (NULL: Glint loops over eval). */
    void (*eval_batch)(const glint_plugin_eval_batch *batch);
    uint32_t component_count; /* 1 ..= 65536: components are 0 .. component_count - 1 */
} glint_plugin_lobe_v2;

/* The table a version-2 plugin hands to Glint; it must stay valid forever. */
typedef struct glint_plugin_v2 {
    uint32_t struct_size; /* sizeof(glint_plugin_v2) */
    const char *name;     /* the plugin's name, for messages */
    uint32_t lobe_count;
    const glint_plugin_lobe_v2 *lobes;
} glint_plugin_v2;

/*
 * The entry point. `host_abi_version` is the newest ABI version Glint speaks. Return 0
 * after setting `*plugin_abi_version` to the version you implement (at most the host's)
 * and `*table` to that version's table (a `const glint_plugin_v1 *` for version 1, a
 * `const glint_plugin_v2 *` for version 2); return nonzero to refuse (for example when the
 * host is too old). Glint passes GLINT_PLUGIN_ABI_V2 and accepts either answer; a
 * version-1 plugin's samples report the lobe type's class and component 0.
 */
typedef int32_t (*glint_plugin_entry_fn)(uint32_t host_abi_version,
                                         uint32_t *plugin_abi_version, const void **table);

GLINT_PLUGIN_EXPORT int32_t glint_plugin_entry(uint32_t host_abi_version,
                                               uint32_t *plugin_abi_version,
                                               const void **table);

#ifdef __cplusplus
}
#endif

#endif /* GLINT_PLUGIN_H */
