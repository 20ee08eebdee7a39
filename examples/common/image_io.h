/* image_io.h: image files for the Glint examples, through OpenImageIO (C++), callable
 * from C.
 *
 * Pixels are interleaved 32-bit floats, rows top to bottom. The OpenEXR writer stores
 * linear values at full float precision with any channel names (R, G, B, then AOVs) and
 * string metadata; the PNG writer takes linear RGB and stores 8-bit sRGB, clamped to
 * [0, 1]. Every function returns 0 on success and otherwise -1 with a message in `err`.
 */
#ifndef GLINT_EXAMPLES_IMAGE_IO_H
#define GLINT_EXAMPLES_IMAGE_IO_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define IMAGE_MAX_CHANNELS 16
#define IMAGE_MAX_ATTRS 16
#define IMAGE_NAME_LEN 64

typedef struct image_attr {
    char name[IMAGE_NAME_LEN];
    char value[IMAGE_NAME_LEN];
} image_attr;

typedef struct image {
    int width, height, channels;
    char channel_names[IMAGE_MAX_CHANNELS][IMAGE_NAME_LEN];
    float *pixels; /* width * height * channels floats; free with image_free */
    int attr_count;
    image_attr attrs[IMAGE_MAX_ATTRS]; /* string metadata read back (only "glint:*" keys) */
} image;

/* Write an OpenEXR file (32-bit float, zip). `names` holds `channels` channel names;
 * `attrs` (may be NULL when attr_count is 0) are stored as string attributes. */
int image_write_exr(const char *path, int width, int height, int channels,
                    const char *const *names, const float *pixels, const image_attr *attrs,
                    int attr_count, char *err, size_t err_len);

/* Write an 8-bit sRGB PNG from `stride` interleaved linear floats per pixel, of which the
 * first three are R, G, B. */
int image_write_png(const char *path, int width, int height, int stride, const float *pixels,
                    char *err, size_t err_len);

/* Read any image OpenImageIO reads (as float) into `out` (every channel). */
int image_read(const char *path, image *out, char *err, size_t err_len);

/* The index of channel `name` in `img`, or -1. */
int image_channel(const image *img, const char *name);

/* The value of string attribute `name`, or NULL. */
const char *image_attr_value(const image *img, const char *name);

void image_free(image *img);

#ifdef __cplusplus
}
#endif

#endif
