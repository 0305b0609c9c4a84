// image.h — images and hit buffers, and their files through OpenImageIO: PNG (8-bit sRGB), EXR
// (linear float), the hit AOV of conventions.md (Z float32, prim_id uint32, optional N.XYZ and
// cost.nodes, cost.triangles uint32), and the walk cost's heat map (PNG).
// Files are written to a temporary name and renamed, so an interrupted run never leaves half a
// file.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/device/kd_shared.h"
#include "core/geometry/math.h"

namespace kdray {

/// Linear RGB, row 0 at the top.
struct Image {
    int width = 0, height = 0;
    std::vector<float> rgb;  // 3 floats per pixel
};

struct HitBuffer {
    int width = 0, height = 0;
    std::vector<KdHit> hits;    // one per pixel; t = +inf and prim = KDRAY_NO_HIT on a miss
    std::vector<Vec3> normals;  // optional: geometric normal facing the ray, per pixel
    /// optional: the centre ray's walk, per pixel (the AOV's cost.nodes and cost.triangles)
    std::vector<KdTraceCost> costs;
};

/// How an 8-bit image maps radiance (after exposure) to [0, 1] before the sRGB encoding: the
/// render file's "display" (conventions.md). EXR images are never transformed.
///   clamp   min(x, 1): exact below 1, everything brighter white
///   filmic  the ACES filmic curve as fitted by Narkowicz (2015), per channel: a toe, mid grey
///           0.18 -> 0.267, 1 -> 0.80, and a shoulder that reaches white only at about 7.2, so
///           that highlights keep their gradations instead of clipping
enum class DisplayTransform { clamp, filmic };
/// The transform of one linear value; NaN and negative values give 0.
float display_transform(float linear, DisplayTransform transform);
/// "clamp" or "filmic", as the render file and stats.json spell them.
const char* display_name(DisplayTransform transform);

/// The image format a file name's extension picks, as --format names it: "png", "jpg" (.jpg,
/// .jpeg), "tif" (.tif, .tiff) or "exr", in any case; "" for any other extension.
std::string image_format_of(const std::filesystem::path& path);

/// Writes PNG, JPEG or TIFF (sRGB-encoded, 8 bit) or EXR (linear float) by the file's extension,
/// the radiance multiplied by 2^exposure_stops (conventions.md: 8-bit display(2^e x radiance),
/// EXR 2^e x radiance).
void write_image(const std::filesystem::path& path, const Image& image, float exposure_stops = 0.0f,
                 DisplayTransform display = DisplayTransform::clamp);
void write_aov(const std::filesystem::path& path, const HitBuffer& hits);
/// The bytes write_image and write_aov would write to `path` (its extension picks the format),
/// for a caller that writes several files as one (write_files_atomically).
std::string encode_image(const std::filesystem::path& path, const Image& image,
                         float exposure_stops = 0.0f,
                         DisplayTransform display = DisplayTransform::clamp);
std::string encode_aov(const std::filesystem::path& path, const HitBuffer& hits);
HitBuffer read_aov(const std::filesystem::path& path);

/// The heat map of `--heatmap`: each pixel's walk cost C_t x nodes + C_i x triangles (the SAH's
/// own model of a ray's cost, with the tree's C_t and C_i) of hits.costs, divided by `scale_cost`
/// and coloured by heatmap_colour, as an 8-bit PNG. scale_cost is the 99th percentile of the costs
/// of the rays that entered the tree (0 when none did): the frame's few costliest rays (grazing a
/// silhouette, along a wall) saturate rather than darken everything else; max_cost is the
/// largest.
struct Heatmap {
    std::string png;
    double scale_cost = 0, max_cost = 0;
};
Heatmap encode_heatmap(const std::filesystem::path& path, const HitBuffer& hits,
                       float cost_traversal, float cost_intersection);
/// The colour of x in [0, 1] (clamped; NaN is 0): matplotlib's viridis (perceptually uniform,
/// readable in grey and by colour-blind readers), linear between 9 of its 256 entries, as
/// sRGB-encoded values in [0, 1].
Vec3 heatmap_colour(float x);

}  // namespace kdray
