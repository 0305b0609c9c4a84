// image_codec.h — the one seam between kdray's images and an image library: PNG encoding, EXR
// encoding and decoding by named channels, and decoding any image a texture may be. Two
// implementations, one linked (CMake's KDRAY_IMAGE_CODEC): image_codec_oiio.cpp (OpenImageIO, the
// default) and image_codec_small.cpp (stb_image, stb_image_write and tinyexr, whose dependency
// closure is a few MiB: the device bundle's, scripts/device-bundle.sh). Both write files that the
// other, OpenImageIO and OpenEXR read with the same values (tests/test_image_codec.cpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace kdray {

/// One channel of an EXR image: width x height 32-bit words, row 0 at the top, each the bits of a
/// float32 or, when `is_uint`, a uint32.
struct ExrChannel {
    ExrChannel() = default;
    ExrChannel(std::string name_, bool is_uint_ = false, std::vector<std::uint32_t> words_ = {})
        : name(std::move(name_)), is_uint(is_uint_), words(std::move(words_)) {}

    std::string name;
    bool is_uint = false;
    std::vector<std::uint32_t> words;
};

struct ExrImage {
    int width = 0, height = 0;
    std::vector<ExrChannel> channels;

    /// The channel called `name`, or nullptr.
    const ExrChannel* find(const std::string& name) const {
        for (const ExrChannel& c : channels)
            if (c.name == name) return &c;
        return nullptr;
    }
};

/// A decoded image: `channels` floats per pixel, row 0 at the top. Integer formats (`integer`:
/// 8 or 16 bit, sRGB-encoded by convention) are normalised to [0, 1]; float formats are as stored.
struct DecodedImage {
    int width = 0, height = 0, channels = 0;
    bool integer = false;
    std::vector<float> values;
    /// What the image library printed on stderr while it decoded the image (libpng's warnings),
    /// captured for kdray's own message; empty when it printed nothing.
    std::string library_messages;
};

/// "oiio" or "small": the implementation linked.
const char* image_codec_name();

/// The PNG file of an 8-bit sRGB image, 3 bytes per pixel (`rgb.size()` is 3 x width x height).
std::string encode_png_rgb8(int width, int height, const std::vector<std::uint8_t>& rgb);

/// The JPEG (quality 95) or TIFF (8-bit, uncompressed) file of an 8-bit sRGB image, as
/// encode_png_rgb8; `format` is "jpg" or "tif". Throws Error when the codec cannot write it (the
/// small codec writes no TIFF).
std::string encode_rgb8(const std::string& format, int width, int height,
                        const std::vector<std::uint8_t>& rgb);

/// The EXR file (ZIP-compressed scanlines) of `image`; float32 channels stay float32. The file
/// lists its channels in name order, as OpenEXR requires; readers find them by name.
std::string encode_exr(const ExrImage& image);

/// Every channel of the EXR file at `path` (half channels widened to float32). Throws Error
/// naming `path` and the reason.
ExrImage read_exr(const std::filesystem::path& path);

/// Any image file the codec decodes (PNG, JPEG, EXR, ...: textures, images to compare); an EXR
/// gives every channel, R, G, B and A first when it has them. Throws Error naming `path` and the
/// reason.
DecodedImage read_image(const std::filesystem::path& path);

}  // namespace kdray
