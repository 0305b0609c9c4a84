// image.h — images and hit buffers, and their files through OpenImageIO: PNG (8-bit sRGB), EXR
// (linear float), and the hit AOV of conventions.md (Z float32, prim_id uint32, optional N.XYZ).
// Files are written to a temporary name and renamed, so an interrupted run never leaves half a
// file.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/kd_shared.h"
#include "core/math.h"

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
};

/// Writes PNG (sRGB-encoded, 8 bit) or EXR (linear float) by the file's extension, the radiance
/// multiplied by 2^exposure_stops (conventions.md: PNG clamp(2^e x radiance, 0, 1), EXR 2^e x
/// radiance).
void write_image(const std::filesystem::path& path, const Image& image,
                 float exposure_stops = 0.0f);
void write_aov(const std::filesystem::path& path, const HitBuffer& hits);
/// The bytes write_image and write_aov would write to `path` (its extension picks the format),
/// for a caller that writes several files as one (write_files_atomically).
std::string encode_image(const std::filesystem::path& path, const Image& image,
                         float exposure_stops = 0.0f);
std::string encode_aov(const std::filesystem::path& path, const HitBuffer& hits);
HitBuffer read_aov(const std::filesystem::path& path);

}  // namespace kdray
