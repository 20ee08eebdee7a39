/* host.h: command-line plumbing both example hosts share: integer options, the runtime,
 * plugins, and picking the scene (showcase, white furnace or a scene file). */
#ifndef EX_HOST_H
#define EX_HOST_H

#include <stdint.h>
#include <time.h>

#include "scene.h"

#define CHARLIE_FILE "glint_charlie.so"

/* Monotonic clock in nanoseconds, for the hosts' timings (needs _POSIX_C_SOURCE). */
static inline uint64_t host_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
}

/* Parse an integer option value in [lo, hi]: 0, or -1 with a message on stderr. */
int host_parse_int(const char *opt, const char *s, long lo, long hi, long *out);

/* Start a host: check the scene options, create a runtime with one Glint thread per call
 * (the hosts run their own threads), load `plugin` (or, when NULL, the Charlie sheen plugin
 * beside the executable if it is there), and initialize and fill `s`: the scene file when
 * `scene_file`, else the white furnace with `material` (a name, or the JSON of a closure or
 * a material document) when `furnace`, else the showcase (with the sheen sphere when a
 * "charlie" lobe exists).
 * 0, or -1 with a message on stderr; either way the caller frees `s` and `*rt`. */
int host_open(glint_runtime **rt, ex_scene *s, const char *plugin, const char *scene_file,
              int furnace, const char *material);

#endif
