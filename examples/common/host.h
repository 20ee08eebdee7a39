/* host.h: command-line plumbing both example hosts share: integer options, plugins, and
 * picking the scene (showcase, white furnace or a scene file). */
#ifndef EX_HOST_H
#define EX_HOST_H

#include "scene.h"

#define CHARLIE_FILE "glint_charlie.so"

/* Parse an integer option value in [lo, hi]: 0, or -1 with a message on stderr. */
int host_parse_int(const char *opt, const char *s, long lo, long hi, long *out);

/* Load `plugin`, or when NULL the Charlie sheen plugin beside the executable if it is there.
 * Returns whether a "charlie" lobe type is registered (0 or 1), or -1 with a message on
 * stderr when `plugin` fails to load. */
int host_load_plugins(glint_runtime *rt, const char *plugin);

/* Fill an initialized scene: the scene file when `scene_file`, else the white furnace with
 * `material` (a name or closure JSON) when `furnace`, else the showcase. 0, or -1 with a
 * message on stderr. */
int host_pick_scene(ex_scene *s, const char *scene_file, int furnace, const char *material,
                    int have_charlie);

#endif
