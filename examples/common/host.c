/* host.c: see host.h. */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "host.h"

int host_parse_int(const char *opt, const char *s, long lo, long hi, long *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (errno || *end || end == s || v < lo || v > hi) {
        fprintf(stderr, "%s: %s expects an integer in [%ld, %ld], got \"%s\"\n", scene_program,
                opt, lo, hi, s);
        return -1;
    }
    *out = v;
    return 0;
}

/* The directory of the running executable (for plugins placed beside it). */
static int exe_dir(char *buf, size_t len)
{
    ssize_t n = readlink("/proc/self/exe", buf, len - 1);
    char *slash;
    if (n <= 0)
        return -1;
    buf[n] = '\0';
    slash = strrchr(buf, '/');
    if (!slash)
        return -1;
    *slash = '\0';
    return 0;
}

/* Whether a "charlie" lobe type is registered afterwards (0 or 1), or -1 when `plugin`
 * fails to load. */
static int load_plugins(glint_runtime *rt, const char *plugin)
{
    uint32_t id;
    if (plugin) {
        if (glint_runtime_load_plugin(rt, plugin) != GLINT_OK) {
            fprintf(stderr, "%s: %s\n", scene_program, glint_last_error());
            return -1;
        }
    } else {
        char dir[PATH_MAX], path[PATH_MAX + 32];
        if (exe_dir(dir, sizeof dir) == 0) {
            snprintf(path, sizeof path, "%s/%s", dir, CHARLIE_FILE);
            if (access(path, R_OK) == 0 && glint_runtime_load_plugin(rt, path) != GLINT_OK)
                fprintf(stderr, "%s: warning: %s\n", scene_program, glint_last_error());
        }
    }
    return glint_lobe_type_find(rt, "charlie", &id) == GLINT_OK;
}

static int pick_scene(ex_scene *s, const char *scene_file, int furnace, const char *material,
                      int have_charlie)
{
    if (scene_file)
        return scene_load_file(s, scene_file);
    if (furnace) {
        const char *json = material[0] == '{' ? material : material_by_name(material);
        if (!json) {
            fprintf(stderr, "%s: unknown material \"%s\"; the named ones:\n", scene_program,
                    material);
            material_list();
            return -1;
        }
        scene_furnace(s, json);
        return 0;
    }
    if (!have_charlie)
        fprintf(stderr, "%s: no charlie lobe (plugin " CHARLIE_FILE " not found, see --plugin): "
                        "the sheen sphere is left out\n",
                scene_program);
    scene_showcase(s, have_charlie);
    return 0;
}

int host_open(glint_runtime **rt, ex_scene *s, const char *plugin, const char *scene_file,
              int furnace, const char *material)
{
    int have_charlie;
    *rt = NULL;
    scene_init(s);
    if (furnace && scene_file) {
        fprintf(stderr, "%s: --furnace and --scene exclude each other\n", scene_program);
        return -1;
    }
    if (glint_runtime_create("threads=1", rt) != GLINT_OK) {
        fprintf(stderr, "%s: glint_runtime_create: %s\n", scene_program, glint_last_error());
        *rt = NULL;
        return -1;
    }
    have_charlie = load_plugins(*rt, plugin);
    if (have_charlie < 0)
        return -1;
    return pick_scene(s, scene_file, furnace, material, have_charlie);
}
