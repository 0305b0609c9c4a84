// image_codec_small.cpp — core/io/image_codec.h through Debian's stb (stb_image_write for PNG
// and JPEG,
// stb_image for textures) and tinyexr (EXR), KDRAY_IMAGE_CODEC=small: a dependency closure of a
// few MiB (zlib) against OpenImageIO's hundreds (boost, ffmpeg, OpenCV, ...), for the device
// bundle (scripts/device-bundle.sh). Textures: PNG, JPEG, BMP, TGA, GIF, PSD, HDR, PNM and EXR.
// Files are read as every input is (core/io/input_file.h) and decoded from memory, their declared
// size checked (check_image_size) before a pixel is decoded.
#include <stb_image.h>
#include <stb_image_write.h>
#include <tinyexr.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>

#include "core/error.h"
#include "core/io/image_codec.h"
#include "core/io/input_file.h"

namespace kdray {
namespace {

/// tinyexr's error message, freed, or `fallback` when it gave none.
std::string take_exr_error(const char* err, const std::string& fallback) {
    if (!err) return fallback;
    std::string message = err;
    FreeEXRErrorMessage(err);
    return message;
}

/// The EXR header and image that tinyexr fills, freed whatever happens.
struct ParsedExr {
    EXRHeader header;
    EXRImage image;
    bool header_parsed = false, image_loaded = false;
    ParsedExr() {
        InitEXRHeader(&header);
        InitEXRImage(&image);
    }
    ~ParsedExr() {
        if (image_loaded) FreeEXRImage(&image);
        if (header_parsed) FreeEXRHeader(&header);
    }
    ParsedExr(const ParsedExr&) = delete;
    ParsedExr& operator=(const ParsedExr&) = delete;
};

/// The bytes of `bytes` as the unsigned bytes the decoders take.
const unsigned char* data_of(const std::string& bytes) {
    return reinterpret_cast<const unsigned char*>(bytes.data());
}

/// The EXR image in `bytes` (the file `name`), every channel as 32-bit words.
ExrImage decode_exr(const std::string& name, const std::string& bytes) {
    auto fail = [&](const std::string& why) { throw Error("cannot read " + name + ": " + why); };
    EXRVersion version;
    if (ParseEXRVersionFromMemory(&version, data_of(bytes), bytes.size()) != TINYEXR_SUCCESS)
        fail("not an OpenEXR file");
    if (version.multipart || version.non_image) fail("a multi-part or deep EXR file");
    ParsedExr exr;
    const char* err = nullptr;
    if (ParseEXRHeaderFromMemory(&exr.header, &version, data_of(bytes), bytes.size(), &err) !=
        TINYEXR_SUCCESS)
        fail(take_exr_error(err, "a bad EXR header"));
    exr.header_parsed = true;
    if (exr.header.tiled) fail("a tiled EXR file (kdray reads scanline files)");
    const EXRBox2i& window = exr.header.data_window;
    check_image_size(name, std::int64_t(window.max_x) - window.min_x + 1,
                     std::int64_t(window.max_y) - window.min_y + 1, exr.header.num_channels,
                     bytes.size());
    for (int c = 0; c < exr.header.num_channels; ++c)
        if (exr.header.pixel_types[c] == TINYEXR_PIXELTYPE_HALF)
            exr.header.requested_pixel_types[c] = TINYEXR_PIXELTYPE_FLOAT;
    if (LoadEXRImageFromMemory(&exr.image, &exr.header, data_of(bytes), bytes.size(), &err) !=
        TINYEXR_SUCCESS)
        fail(take_exr_error(err, "bad EXR data"));
    exr.image_loaded = true;

    ExrImage result;
    result.width = exr.image.width;
    result.height = exr.image.height;
    const std::size_t pixels = std::size_t(result.width) * std::size_t(result.height);
    for (int c = 0; c < exr.header.num_channels; ++c) {
        ExrChannel channel;
        channel.name = exr.header.channels[c].name;
        channel.is_uint = exr.header.requested_pixel_types[c] == TINYEXR_PIXELTYPE_UINT;
        channel.words.resize(pixels);
        std::memcpy(channel.words.data(), exr.image.images[c], 4 * pixels);
        result.channels.push_back(std::move(channel));
    }
    return result;
}

}  // namespace

const char* image_codec_name() {
    return "small";
}

std::string encode_png_rgb8(int width, int height, const std::vector<std::uint8_t>& rgb) {
    std::string encoded;
    auto append = [](void* context, void* data, int size) {
        static_cast<std::string*>(context)->append(static_cast<const char*>(data), size);
    };
    // stb_image_write writes no sRGB chunk; PNG readers take 8-bit data as sRGB without one.
    if (!stbi_write_png_to_func(append, &encoded, width, height, 3, rgb.data(), 3 * width))
        throw Error("cannot encode a " + std::to_string(width) + "x" + std::to_string(height) +
                    " PNG image (stb_image_write)");
    return encoded;
}

std::string encode_rgb8(const std::string& format, int width, int height,
                        const std::vector<std::uint8_t>& rgb) {
    if (format != "jpg")
        throw Error("cannot encode a " + format +
                    " image: this kdray's image codec (small: stb and tinyexr) writes PNG, JPEG "
                    "and EXR only; build with KDRAY_IMAGE_CODEC=oiio for TIFF");
    std::string encoded;
    auto append = [](void* context, void* data, int size) {
        static_cast<std::string*>(context)->append(static_cast<const char*>(data), size);
    };
    if (!stbi_write_jpg_to_func(append, &encoded, width, height, 3, rgb.data(), 95))
        throw Error("cannot encode a " + std::to_string(width) + "x" + std::to_string(height) +
                    " JPEG image (stb_image_write)");
    return encoded;
}

std::string encode_exr(const ExrImage& image) {
    // OpenEXR requires the channel list in name order, and the scanlines' data in that order.
    std::vector<std::size_t> order(image.channels.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return image.channels[a].name < image.channels[b].name;
    });
    const int channels = int(order.size());
    std::vector<EXRChannelInfo> infos(channels);
    std::vector<int> types(channels);
    std::vector<unsigned char*> planes(channels);
    for (int c = 0; c < channels; ++c) {
        const ExrChannel& channel = image.channels[order[c]];
        if (channel.name.size() > 255)
            throw Error("cannot encode EXR channel '" + channel.name + "': name too long");
        std::memset(&infos[c], 0, sizeof infos[c]);
        std::strncpy(infos[c].name, channel.name.c_str(), 255);
        types[c] = channel.is_uint ? TINYEXR_PIXELTYPE_UINT : TINYEXR_PIXELTYPE_FLOAT;
        // tinyexr reads the planes and does not write them.
        planes[c] =
            reinterpret_cast<unsigned char*>(const_cast<std::uint32_t*>(channel.words.data()));
    }
    EXRHeader header;
    InitEXRHeader(&header);
    header.num_channels = channels;
    header.channels = infos.data();
    header.pixel_types = types.data();
    header.requested_pixel_types = types.data();
    header.compression_type = TINYEXR_COMPRESSIONTYPE_ZIP;
    EXRImage exr;
    InitEXRImage(&exr);
    exr.num_channels = channels;
    exr.width = image.width;
    exr.height = image.height;
    exr.images = planes.data();

    unsigned char* memory = nullptr;
    const char* err = nullptr;
    const std::size_t size = SaveEXRImageToMemory(&exr, &header, &memory, &err);
    if (size == 0)
        throw Error("cannot encode a " + std::to_string(image.width) + "x" +
                    std::to_string(image.height) +
                    " EXR image: " + take_exr_error(err, "tinyexr failed"));
    std::string encoded(reinterpret_cast<const char*>(memory), size);
    std::free(memory);
    return encoded;
}

ExrImage read_exr(const std::filesystem::path& path) {
    return decode_exr(path.string(), read_input_file(path, "image file"));
}

DecodedImage read_image(const std::filesystem::path& path) {
    const std::string name = path.string();
    const std::string bytes = read_input_file(path, "image file");
    DecodedImage result;
    if (EXRVersion version;
        ParseEXRVersionFromMemory(&version, data_of(bytes), bytes.size()) == TINYEXR_SUCCESS) {
        const ExrImage exr = decode_exr(name, bytes);
        // R, G, B and A first, as OpenImageIO orders them; then the rest in name order.
        std::vector<const ExrChannel*> picked;
        for (const char* first : {"R", "G", "B", "A"})
            if (const ExrChannel* c = exr.find(first)) picked.push_back(c);
        for (const ExrChannel& c : exr.channels)
            if (std::find(picked.begin(), picked.end(), &c) == picked.end()) picked.push_back(&c);
        result.width = exr.width;
        result.height = exr.height;
        result.channels = int(picked.size());
        const std::size_t pixels = std::size_t(exr.width) * std::size_t(exr.height);
        result.values.resize(pixels * picked.size());
        for (std::size_t c = 0; c < picked.size(); ++c)
            for (std::size_t i = 0; i < pixels; ++i) {
                const std::uint32_t w = picked[c]->words[i];
                float v;
                if (picked[c]->is_uint)
                    v = float(w);
                else
                    std::memcpy(&v, &w, 4);
                result.values[i * picked.size() + c] = v;
            }
        return result;
    }

    // stb_image takes an int length.
    if (bytes.size() > std::size_t(std::numeric_limits<int>::max()))
        throw Error("cannot read " + name + ": " + std::to_string(bytes.size()) +
                    " bytes, more than stb_image reads");
    const unsigned char* const in = data_of(bytes);
    const int length = int(bytes.size());
    int width = 0, height = 0, channels = 0;
    // The header's size, checked before stb_image allocates it; what it cannot size it cannot
    // decode either.
    if (!stbi_info_from_memory(in, length, &width, &height, &channels))
        throw Error("cannot read " + name + ": " +
                    (stbi_failure_reason() ? stbi_failure_reason() : "stb_image failed"));
    check_image_size(name, width, height, channels, bytes.size());
    // stbi_loadf would apply a gamma to 8-bit data: integer images are read as integers and
    // normalised here, float (Radiance HDR) images as floats.
    std::unique_ptr<void, void (*)(void*)> data(nullptr, stbi_image_free);
    const bool hdr = stbi_is_hdr_from_memory(in, length);
    const bool sixteen = !hdr && stbi_is_16_bit_from_memory(in, length);
    if (hdr)
        data.reset(stbi_loadf_from_memory(in, length, &width, &height, &channels, 0));
    else if (sixteen)
        data.reset(stbi_load_16_from_memory(in, length, &width, &height, &channels, 0));
    else
        data.reset(stbi_load_from_memory(in, length, &width, &height, &channels, 0));
    result.integer = !hdr;
    if (!data || width <= 0 || height <= 0 || channels <= 0)
        throw Error("cannot read " + name + ": " +
                    (stbi_failure_reason() ? stbi_failure_reason() : "stb_image failed"));
    const std::size_t count = std::size_t(width) * std::size_t(height) * std::size_t(channels);
    result.width = width;
    result.height = height;
    result.channels = channels;
    result.values.resize(count);
    if (!result.integer)
        std::memcpy(result.values.data(), data.get(), 4 * count);
    else if (sixteen)
        for (std::size_t i = 0; i < count; ++i)
            result.values[i] = static_cast<const std::uint16_t*>(data.get())[i] / 65535.0f;
    else
        for (std::size_t i = 0; i < count; ++i)
            result.values[i] = static_cast<const std::uint8_t*>(data.get())[i] / 255.0f;
    return result;
}

}  // namespace kdray
