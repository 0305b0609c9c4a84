// image.cpp — images and hit AOVs to and from files through the image codec
// (core/io/image_codec.h). Every file is encoded in memory, then written to a temporary name beside
// its target and renamed into place with every write checked (core/io/atomic_file.h), so a reader
// never sees half a file, a failed write leaves nothing behind, and a full disk is an error
// (OpenImageIO's PNG writer does not report one).
#include "core/io/image.h"

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/io/atomic_file.h"
#include "core/io/image_codec.h"

namespace kdray {
namespace {

namespace fs = std::filesystem;

std::string lower_extension(const fs::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

/// What the codec's `encode()` makes of the image for `path`; an Error names `path`.
std::string encoded(const fs::path& path, const std::function<std::string()>& encode) {
    try {
        return encode();
    } catch (const Error& e) {
        throw Error("cannot write " + path.string() + ": " + e.what());
    }
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

std::string image_format_of(const fs::path& path) {
    const std::string ext = lower_extension(path);
    if (ext == ".png" || ext == ".exr") return ext.substr(1);
    if (ext == ".jpg" || ext == ".jpeg") return "jpg";
    if (ext == ".tif" || ext == ".tiff") return "tif";
    return "";
}

float display_transform(float linear, DisplayTransform transform) {
    if (!(linear > 0.0f)) return 0.0f;
    if (transform == DisplayTransform::clamp) return std::min(linear, 1.0f);
    // Narkowicz, "ACES Filmic Tone Mapping Curve" (2015): a rational fit of the ACES reference
    // rendering and output transforms, applied per channel, without the fit's 0.6 pre-scale so
    // that mid grey stays near mid grey (0.18 -> 0.267).
    // The fit passes 1 at x = 7.24 and stays above it; inf / inf would be NaN.
    if (linear >= 8.0f) return 1.0f;
    const double x = linear;
    const double y = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    return float(std::min(y, 1.0));
}

const char* display_name(DisplayTransform transform) {
    return transform == DisplayTransform::filmic ? "filmic" : "clamp";
}

void write_image(const fs::path& path, const Image& image, float exposure_stops,
                 DisplayTransform display) {
    write_file_atomically(path, encode_image(path, image, exposure_stops, display));
}

void write_aov(const fs::path& path, const HitBuffer& hits) {
    write_file_atomically(path, encode_aov(path, hits));
}

std::string encode_image(const fs::path& path, const Image& image, float exposure_stops,
                         DisplayTransform display) {
    check_size(path, image.width, image.height, image.rgb.size(), 3, "image");
    // conventions.md: every radiance that reaches an image is multiplied by 2^exposure.
    const float scale = std::exp2(exposure_stops);
    const std::string format = image_format_of(path);
    if (format == "png" || format == "jpg" || format == "tif") {
        std::vector<std::uint8_t> pixels(image.rgb.size());
        for (std::size_t i = 0; i < pixels.size(); ++i)
            pixels[i] = std::uint8_t(std::lround(
                srgb_encode(display_transform(scale * image.rgb[i], display)) * 255.0f));
        return encoded(path, [&] {
            return format == "png" ? encode_png_rgb8(image.width, image.height, pixels)
                                   : encode_rgb8(format, image.width, image.height, pixels);
        });
    }
    if (format == "exr") {
        ExrImage exr{image.width, image.height, {{"R"}, {"G"}, {"B"}}};
        const std::size_t pixels = std::size_t(image.width) * std::size_t(image.height);
        for (int c = 0; c < 3; ++c) {
            std::vector<std::uint32_t>& words = exr.channels[c].words;
            words.resize(pixels);
            for (std::size_t i = 0; i < pixels; ++i) {
                // The renderers' radiance is finite (kd_render.h); an exposure must not
                // multiply it past the largest float either.
                const float v = std::min(scale * image.rgb[3 * i + c], FLT_MAX);
                std::memcpy(&words[i], &v, 4);
            }
        }
        return encoded(path, [&] { return encode_exr(exr); });
    }
    throw Error("cannot write " + path.string() + ": unknown image extension '" +
                path.extension().string() + "' (use .png, .jpg, .tif or .exr)");
}

std::string encode_aov(const fs::path& path, const HitBuffer& hits) {
    check_size(path, hits.width, hits.height, hits.hits.size(), 1, "hit buffer");
    if (!hits.normals.empty() && hits.normals.size() != hits.hits.size())
        throw Error("cannot write " + path.string() + ": " + std::to_string(hits.normals.size()) +
                    " normals for " + std::to_string(hits.hits.size()) + " pixels");
    if (lower_extension(path) != ".exr")
        throw Error("cannot write " + path.string() + ": a hit AOV is an OpenEXR file (.exr)");

    // Per-channel formats exactly as peers/embree/embree_ref.cpp writes them (Z float32, prim_id
    // uint32), so that `embree_ref --compare` reads our files; the normals follow as float32.
    const std::size_t pixels = hits.hits.size();
    ExrImage exr{hits.width, hits.height, {{"Z"}, {"prim_id", true}}};
    for (ExrChannel& c : exr.channels) c.words.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) {
        std::memcpy(&exr.channels[0].words[i], &hits.hits[i].t, 4);
        exr.channels[1].words[i] = hits.hits[i].prim;
    }
    if (!hits.normals.empty()) {
        for (const char* name : {"N.X", "N.Y", "N.Z"})
            exr.channels.push_back({name, false, std::vector<std::uint32_t>(pixels)});
        for (std::size_t i = 0; i < pixels; ++i) {
            const float n[3] = {hits.normals[i].x, hits.normals[i].y, hits.normals[i].z};
            for (int a = 0; a < 3; ++a) std::memcpy(&exr.channels[2 + a].words[i], &n[a], 4);
        }
    }
    if (!hits.costs.empty()) {
        if (hits.costs.size() != pixels)
            throw Error("cannot write " + path.string() + ": " + std::to_string(hits.costs.size()) +
                        " walk costs for " + std::to_string(pixels) + " pixels");
        const std::size_t first = exr.channels.size();
        for (const char* name : {"cost.nodes", "cost.triangles"})
            exr.channels.push_back({name, true, std::vector<std::uint32_t>(pixels)});
        for (std::size_t i = 0; i < pixels; ++i) {
            exr.channels[first].words[i] = hits.costs[i].nodes;
            exr.channels[first + 1].words[i] = hits.costs[i].triangles;
        }
    }
    return encoded(path, [&] { return encode_exr(exr); });
}

Vec3 heatmap_colour(float x) {
    // viridis (van der Walt and Smith, matplotlib, CC0) at entries 0, 32, ..., 224 and 255 of its
    // 256, taken as evenly spaced.
    static constexpr float kViridis[9][3] = {
        {0.267004f, 0.004874f, 0.329415f}, {0.278826f, 0.175490f, 0.483397f},
        {0.229739f, 0.322361f, 0.545706f}, {0.172719f, 0.448791f, 0.557885f},
        {0.127568f, 0.566949f, 0.550556f}, {0.157851f, 0.683765f, 0.501686f},
        {0.369214f, 0.788888f, 0.382914f}, {0.678489f, 0.863742f, 0.189503f},
        {0.993248f, 0.906157f, 0.143936f}};
    const float at = (x > 0.0f ? std::min(x, 1.0f) : 0.0f) * 8.0f;
    const int i = std::min(int(at), 7);
    const float f = at - float(i);
    const float* a = kViridis[i];
    const float* b = kViridis[i + 1];
    return {a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])};
}

Heatmap encode_heatmap(const fs::path& path, const HitBuffer& hits, float cost_traversal,
                       float cost_intersection) {
    check_size(path, hits.width, hits.height, hits.costs.size(), 1, "walk cost buffer");
    if (lower_extension(path) != ".png")
        throw Error("cannot write " + path.string() + ": a heat map is a PNG file (.png)");
    std::vector<double> cost(hits.costs.size()), walked;
    Heatmap out;
    for (std::size_t i = 0; i < cost.size(); ++i) {
        cost[i] = double(cost_traversal) * hits.costs[i].nodes +
                  double(cost_intersection) * hits.costs[i].triangles;
        out.max_cost = std::max(out.max_cost, cost[i]);
        if (hits.costs[i].nodes > 0) walked.push_back(cost[i]);
    }
    if (!walked.empty()) {
        const auto at = walked.begin() + std::ptrdiff_t((walked.size() - 1) * 99 / 100);
        std::nth_element(walked.begin(), at, walked.end());
        out.scale_cost = *at;
    }
    std::vector<std::uint8_t> pixels(3 * cost.size());
    for (std::size_t i = 0; i < cost.size(); ++i) {
        const Vec3 c = heatmap_colour(out.scale_cost > 0 ? float(cost[i] / out.scale_cost) : 0.0f);
        pixels[3 * i] = std::uint8_t(std::lround(c.x * 255.0f));
        pixels[3 * i + 1] = std::uint8_t(std::lround(c.y * 255.0f));
        pixels[3 * i + 2] = std::uint8_t(std::lround(c.z * 255.0f));
    }
    out.png = encoded(path, [&] { return encode_png_rgb8(hits.width, hits.height, pixels); });
    return out;
}

HitBuffer read_aov(const fs::path& path) {
    const ExrImage exr = read_exr(path);
    const ExrChannel* z = exr.find("Z");
    const ExrChannel* prim = exr.find("prim_id");
    if (!z || !prim) throw Error("cannot read " + path.string() + ": no Z or prim_id channel");
    if (z->is_uint || !prim->is_uint)
        throw Error("cannot read " + path.string() +
                    ": Z must be float32 and prim_id uint32 (docs/conventions.md)");
    const ExrChannel* n[3] = {exr.find("N.X"), exr.find("N.Y"), exr.find("N.Z")};

    HitBuffer result;
    result.width = exr.width;
    result.height = exr.height;
    const std::size_t pixels = std::size_t(exr.width) * std::size_t(exr.height);
    result.hits.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) {
        float t;
        std::memcpy(&t, &z->words[i], 4);
        result.hits[i] = KdHit{t, prim->words[i], 0.0f, 0.0f};
    }
    if (n[0] && n[1] && n[2] && !n[0]->is_uint && !n[1]->is_uint && !n[2]->is_uint) {
        result.normals.resize(pixels);
        for (std::size_t i = 0; i < pixels; ++i) {
            float v[3];
            for (int a = 0; a < 3; ++a) std::memcpy(&v[a], &n[a]->words[i], 4);
            result.normals[i] = {v[0], v[1], v[2]};
        }
    }
    const ExrChannel* nodes = exr.find("cost.nodes");
    const ExrChannel* tested = exr.find("cost.triangles");
    if (nodes && tested && nodes->is_uint && tested->is_uint) {
        result.costs.resize(pixels);
        for (std::size_t i = 0; i < pixels; ++i)
            result.costs[i] = KdTraceCost{nodes->words[i], tested->words[i]};
    }
    return result;
}

}  // namespace kdray
