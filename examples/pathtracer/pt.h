/* pt.h: the path tracer's settings and renderer (the scene is common/scene.h). */
#ifndef PT_H
#define PT_H

#include <stdint.h>

#include "scene.h"

/* ---- rendering --------------------------------------------------------------------- */

enum { STRATEGY_MIS, STRATEGY_BSDF, STRATEGY_LIGHT };

typedef struct pt_settings {
    int width, height, spp, max_depth, rr_depth, threads, strategy, quiet;
    int pixel_center; /* camera rays through pixel centers, no jitter */
    int timing; /* time every Glint call (clock_gettime) */
    uint64_t seed;
} pt_settings;

/* Per-pixel accumulators over the samples (radiance estimates), in double. */
typedef struct pt_accum {
    double *sum;    /* 3 per pixel */
    double *sum_sq; /* 3 per pixel */
    uint32_t *hits; /* camera samples whose first ray hit geometry */
} pt_accum;

/* Kinds of timed Glint calls: building a closure (glint_arena_reset, then the lobe-by-lobe
 * calls for a closure given as lobes or glint_material_closure for a compiled material; one
 * interval), glint_eval, glint_sample. */
enum { GLINT_BUILD_LOBES, GLINT_BUILD_MATERIAL, GLINT_EVAL, GLINT_SAMPLE, GLINT_KINDS };

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
int render(const ex_scene *scene, const glint_runtime *rt, const pt_settings *settings,
           pt_accum *acc, pt_stats *stats);

#endif
