// image.cpp — images and hit AOVs to and from files through OpenImageIO. Every file is written to a
// temporary name beside its target and renamed into place, so a reader never sees half a file and
// a failed write leaves nothing behind.
#include "core/image.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <system_error>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"

namespace kdray {
namespace {

namespace fs = std::filesystem;

std::string lower_extension(const fs::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

/// Writes `spec` to `path` through OpenImageIO: the file is encoded in memory (`write` fills the
/// opened image), then written atomically with every write checked (core/atomic_file.h), since
/// OpenImageIO's PNG writer does not report a write that a full disk cut short. An Error names
/// `path` and OIIO's message.
void write_image_file(const fs::path& path, const OIIO::ImageSpec& spec,
                      const std::function<bool(OIIO::ImageOutput&)>& write) {
    auto fail = [&](const std::string& why) {
        throw Error("cannot write " + path.string() + ": " + why);
    };
    std::vector<unsigned char> encoded;
    {
        OIIO::Filesystem::IOVecOutput memory(encoded);
        // The format comes from the file name's extension, as for a file on disk.
        auto out = OIIO::ImageOutput::create(path.string(), &memory);
        if (!out) fail(OIIO::geterror());
        if (!out->open(path.string(), spec)) fail(out->geterror());
        if (!write(*out)) {
            std::string why = out->geterror();
            out->close();
            fail(why);
        }
        if (!out->close()) fail(out->geterror());
    }
    write_file_atomically(
        path, std::string_view(reinterpret_cast<const char*>(encoded.data()), encoded.size()));
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value, clamped to [0, 1] first; NaN
/// becomes black so that one bad pixel cannot poison the encoding.
float srgb_encode(float linear) {
    if (!(linear > 0.0f)) return 0.0f;
    if (linear >= 1.0f) return 1.0f;
    return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

void check_size(const fs::path& path, int width, int height, std::size_t values,
                std::size_t per_pixel, const char* what) {
    if (width <= 0 || height <= 0)
        throw Error("cannot write " + path.string() + ": empty " + what + " (" +
                    std::to_string(width) + "x" + std::to_string(height) + ")");
    if (values != std::size_t(width) * std::size_t(height) * per_pixel)
        throw Error("cannot write " + path.string() + ": " + what + " of " + std::to_string(width) +
                    "x" + std::to_string(height) + " holds " + std::to_string(values) +
                    " values, not " + std::to_string(std::size_t(width) * height * per_pixel));
}

}  // namespace

void write_image(const fs::path& path, const Image& image, float exposure_stops) {
    check_size(path, image.width, image.height, image.rgb.size(), 3, "image");
    const std::string ext = lower_extension(path);
    // conventions.md: every radiance that reaches an image is multiplied by 2^exposure.
    const float scale = std::exp2(exposure_stops);
    if (ext == ".png") {
        std::vector<std::uint8_t> pixels(image.rgb.size());
        for (std::size_t i = 0; i < pixels.size(); ++i)
            pixels[i] = std::uint8_t(std::lround(srgb_encode(scale * image.rgb[i]) * 255.0f));
        OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::UINT8);
        spec.attribute("oiio:ColorSpace", "sRGB");
        write_image_file(path, spec, [&](OIIO::ImageOutput& out) {
            return out.write_image(OIIO::TypeDesc::UINT8, pixels.data());
        });
    } else if (ext == ".exr") {
        OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::FLOAT);
        spec.attribute("oiio:ColorSpace", "linear");
        std::vector<float> exposed;
        if (scale != 1.0f) {
            exposed.resize(image.rgb.size());
            for (std::size_t i = 0; i < exposed.size(); ++i) exposed[i] = scale * image.rgb[i];
        }
        const float* linear = scale != 1.0f ? exposed.data() : image.rgb.data();
        write_image_file(path, spec, [&](OIIO::ImageOutput& out) {
            return out.write_image(OIIO::TypeDesc::FLOAT, linear);
        });
    } else {
        throw Error("cannot write " + path.string() + ": unknown image extension '" +
                    path.extension().string() + "' (use .png or .exr)");
    }
}

void write_aov(const fs::path& path, const HitBuffer& hits) {
    check_size(path, hits.width, hits.height, hits.hits.size(), 1, "hit buffer");
    if (!hits.normals.empty() && hits.normals.size() != hits.hits.size())
        throw Error("cannot write " + path.string() + ": " + std::to_string(hits.normals.size()) +
                    " normals for " + std::to_string(hits.hits.size()) + " pixels");
    if (lower_extension(path) != ".exr")
        throw Error("cannot write " + path.string() + ": a hit AOV is an OpenEXR file (.exr)");

    // Per-channel formats exactly as peers/embree/embree_ref.cpp writes them (Z float32, prim_id
    // uint32), so that `embree_ref --compare` reads our files; the normals follow as float32.
    const bool with_normals = !hits.normals.empty();
    const int channels = with_normals ? 5 : 2;
    OIIO::ImageSpec spec(hits.width, hits.height, channels, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {"Z", "prim_id"};
    spec.channelformats = {OIIO::TypeDesc::FLOAT, OIIO::TypeDesc::UINT};
    if (with_normals) {
        spec.channelnames.insert(spec.channelnames.end(), {"N.X", "N.Y", "N.Z"});
        spec.channelformats.insert(spec.channelformats.end(), 3, OIIO::TypeDesc::FLOAT);
    }

    // Native layout: every channel is 4 bytes, packed per pixel in the spec's channel order.
    const std::size_t stride = 4 * std::size_t(channels);
    std::vector<unsigned char> buffer(hits.hits.size() * stride);
    for (std::size_t i = 0; i < hits.hits.size(); ++i) {
        unsigned char* pixel = &buffer[i * stride];
        std::memcpy(pixel, &hits.hits[i].t, 4);
        std::memcpy(pixel + 4, &hits.hits[i].prim, 4);
        if (with_normals) {
            const float n[3] = {hits.normals[i].x, hits.normals[i].y, hits.normals[i].z};
            std::memcpy(pixel + 8, n, 12);
        }
    }
    write_image_file(path, spec, [&](OIIO::ImageOutput& out) {
        return out.write_image(OIIO::TypeDesc::UNKNOWN, buffer.data(), OIIO::stride_t(stride));
    });
}

HitBuffer read_aov(const fs::path& path) {
    auto in = OIIO::ImageInput::open(path.string());
    if (!in) throw Error("cannot read " + path.string() + ": " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    const int z = spec.channelindex("Z"), prim = spec.channelindex("prim_id");
    if (z < 0 || prim < 0)
        throw Error("cannot read " + path.string() + ": no Z or prim_id channel");
    const int nx = spec.channelindex("N.X"), ny = spec.channelindex("N.Y"),
              nz = spec.channelindex("N.Z");

    HitBuffer result;
    result.width = spec.width;
    result.height = spec.height;
    const std::size_t pixels = std::size_t(spec.width) * std::size_t(spec.height);
    auto read_channel = [&](int channel, OIIO::TypeDesc type, void* data) {
        if (!in->read_image(0, 0, channel, channel + 1, type, data))
            throw Error("cannot read channel " + spec.channelnames[channel] + " of " +
                        path.string() + ": " + in->geterror());
    };
    std::vector<float> t(pixels);
    std::vector<std::uint32_t> ids(pixels);
    read_channel(z, OIIO::TypeDesc::FLOAT, t.data());
    read_channel(prim, OIIO::TypeDesc::UINT, ids.data());
    result.hits.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) result.hits[i] = KdHit{t[i], ids[i], 0.0f, 0.0f};

    if (nx >= 0 && ny >= 0 && nz >= 0) {
        std::vector<float> n[3];
        const int channel[3] = {nx, ny, nz};
        for (int a = 0; a < 3; ++a) {
            n[a].resize(pixels);
            read_channel(channel[a], OIIO::TypeDesc::FLOAT, n[a].data());
        }
        result.normals.resize(pixels);
        for (std::size_t i = 0; i < pixels; ++i) result.normals[i] = {n[0][i], n[1][i], n[2][i]};
    }
    return result;
}

}  // namespace kdray
