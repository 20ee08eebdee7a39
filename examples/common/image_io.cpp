// image_io.cpp: OpenImageIO behind the C interface of image_io.h.
#include "image_io.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace {

int fail(char *err, size_t err_len, const std::string &message)
{
    if (err && err_len)
        std::snprintf(err, err_len, "%s", message.c_str());
    return -1;
}

unsigned char to_srgb8(float linear)
{
    if (!(linear > 0.0f)) // also catches NaN
        return 0;
    if (linear >= 1.0f)
        return 255;
    const float s = linear <= 0.0031308f ? 12.92f * linear
                                         : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
    return static_cast<unsigned char>(std::lround(s * 255.0f));
}

void copy_name(char *dst, const std::string &src)
{
    std::snprintf(dst, IMAGE_NAME_LEN, "%s", src.c_str());
}

} // namespace

extern "C" int image_write_exr(const char *path, int width, int height, int channels,
                               const char *const *names, const float *pixels,
                               const image_attr *attrs, int attr_count, char *err,
                               size_t err_len)
{
    if (!path || !names || !pixels || width <= 0 || height <= 0 || channels <= 0)
        return fail(err, err_len, "image_write_exr: invalid arguments");
    auto out = OIIO::ImageOutput::create(path);
    if (!out)
        return fail(err, err_len, std::string(path) + ": " + OIIO::geterror());
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::FLOAT);
    spec.channelnames.clear();
    for (int c = 0; c < channels; c++)
        spec.channelnames.emplace_back(names[c]);
    spec.alpha_channel = -1;
    spec.attribute("compression", "zip");
    for (int i = 0; i < attr_count; i++)
        spec.attribute(attrs[i].name, attrs[i].value);
    if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels) ||
        !out->close())
        return fail(err, err_len, std::string(path) + ": " + out->geterror());
    return 0;
}

extern "C" int image_write_png(const char *path, int width, int height, int stride,
                               const float *pixels, char *err, size_t err_len)
{
    if (!path || !pixels || width <= 0 || height <= 0 || stride < 3)
        return fail(err, err_len, "image_write_png: invalid arguments");
    std::vector<unsigned char> bytes(static_cast<size_t>(width) * height * 3);
    for (size_t i = 0; i < static_cast<size_t>(width) * height; i++)
        for (size_t c = 0; c < 3; c++)
            bytes[i * 3 + c] = to_srgb8(pixels[i * stride + c]);
    auto out = OIIO::ImageOutput::create(path);
    if (!out)
        return fail(err, err_len, std::string(path) + ": " + OIIO::geterror());
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::UINT8, bytes.data()) ||
        !out->close())
        return fail(err, err_len, std::string(path) + ": " + out->geterror());
    return 0;
}

extern "C" int image_read(const char *path, image *out, char *err, size_t err_len)
{
    if (!path || !out)
        return fail(err, err_len, "image_read: invalid arguments");
    std::memset(out, 0, sizeof *out);
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        return fail(err, err_len, std::string(path) + ": " + OIIO::geterror());
    const OIIO::ImageSpec &spec = in->spec();
    if (spec.nchannels > IMAGE_MAX_CHANNELS)
        return fail(err, err_len, std::string(path) + ": too many channels");
    const size_t count = static_cast<size_t>(spec.width) * spec.height * spec.nchannels;
    float *data = static_cast<float *>(std::malloc(count * sizeof(float)));
    if (!data)
        return fail(err, err_len, "out of memory");
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, data)) {
        std::free(data);
        return fail(err, err_len, std::string(path) + ": " + in->geterror());
    }
    out->width = spec.width;
    out->height = spec.height;
    out->channels = spec.nchannels;
    out->pixels = data;
    for (int c = 0; c < spec.nchannels; c++)
        copy_name(out->channel_names[c], spec.channel_name(c));
    for (const auto &p : spec.extra_attribs) {
        const std::string name = p.name().string();
        if (name.rfind("glint:", 0) != 0 || out->attr_count == IMAGE_MAX_ATTRS)
            continue;
        copy_name(out->attrs[out->attr_count].name, name);
        copy_name(out->attrs[out->attr_count].value, p.get_string());
        out->attr_count++;
    }
    in->close();
    return 0;
}

extern "C" int image_channel(const image *img, const char *name)
{
    for (int c = 0; c < img->channels; c++)
        if (std::strcmp(img->channel_names[c], name) == 0)
            return c;
    return -1;
}

extern "C" const char *image_attr_value(const image *img, const char *name)
{
    for (int i = 0; i < img->attr_count; i++)
        if (std::strcmp(img->attrs[i].name, name) == 0)
            return img->attrs[i].value;
    return nullptr;
}

extern "C" void image_free(image *img)
{
    if (img) {
        std::free(img->pixels);
        img->pixels = nullptr;
    }
}
