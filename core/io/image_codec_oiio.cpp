// image_codec_oiio.cpp — core/io/image_codec.h through OpenImageIO (KDRAY_IMAGE_CODEC=oiio, the
// default): every format OpenImageIO reads is a texture kdray can load. Files are read as every
// input is (core/io/input_file.h) and decoded from memory.
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cstring>
#include <functional>
#include <memory>

#include "core/error.h"
#include "core/io/image_codec.h"
#include "core/io/input_file.h"
#include "core/io/library_output.h"

namespace kdray {
namespace {

/// The file `name` (its extension picks the format) that `write` fills, encoded in memory. An
/// Error names OIIO's message.
std::string encode(const std::string& name, const OIIO::ImageSpec& spec,
                   const std::function<bool(OIIO::ImageOutput&)>& write) {
    auto fail = [&](const std::string& why) { throw Error("cannot encode " + name + ": " + why); };
    std::vector<unsigned char> encoded;
    {
        OIIO::Filesystem::IOVecOutput memory(encoded);
        auto out = OIIO::ImageOutput::create(name, &memory);
        if (!out) fail(OIIO::geterror());
        if (!out->open(name, spec)) fail(out->geterror());
        if (!write(*out)) {
            std::string why = out->geterror();
            out->close();
            fail(why);
        }
        if (!out->close()) fail(out->geterror());
    }
    return std::string(reinterpret_cast<const char*>(encoded.data()), encoded.size());
}

/// An image file opened for decoding, its header read and its declared size checked
/// (check_image_size) before a pixel is decoded. Its bytes were read as every input is: a FIFO,
/// a device or a file past the size budget is an Error naming it, where OpenImageIO blocked on a
/// FIFO and read /dev/zero or a sparse terabyte for ever.
struct OpenedImage {
    std::string bytes;
    std::unique_ptr<OIIO::Filesystem::IOMemReader> memory;
    std::unique_ptr<OIIO::ImageInput> in;  // declared last: closed before `memory` goes

    explicit OpenedImage(const std::filesystem::path& path) {
        const std::string name = path.string();
        bytes = read_input_file(path, "image file");
        memory = std::make_unique<OIIO::Filesystem::IOMemReader>(bytes.data(), bytes.size());
        in = OIIO::ImageInput::open(name, nullptr, memory.get());
        if (!in) {
            std::string why = OIIO::geterror();
            // A few rare formats (SGI, ICO, FITS, ...) read only from a path; the path was just
            // checked to be a regular file of bounded size.
            const auto probe = OIIO::ImageInput::create(name);
            if (probe && !probe->supports("ioproxy")) in = OIIO::ImageInput::open(name);
            if (!in)
                throw Error("cannot read " + name + ": " + (why.empty() ? OIIO::geterror() : why));
        }
        const OIIO::ImageSpec& spec = in->spec();
        check_image_size(name, spec.width, spec.height, spec.nchannels, bytes.size());
    }
};

}  // namespace

const char* image_codec_name() {
    return "oiio";
}

std::string encode_png_rgb8(int width, int height, const std::vector<std::uint8_t>& rgb) {
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    return encode("image.png", spec, [&](OIIO::ImageOutput& out) {
        return out.write_image(OIIO::TypeDesc::UINT8, rgb.data());
    });
}

std::string encode_rgb8(const std::string& format, int width, int height,
                        const std::vector<std::uint8_t>& rgb) {
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    // OpenImageIO 2.4 writes a TIFF tagged sRGB into memory with a broken first directory (no
    // ImageLength): readers take 8-bit TIFF as sRGB untagged, as they do PNG.
    if (format != "tif") spec.attribute("oiio:ColorSpace", "sRGB");
    // Without a DateTime OpenImageIO stamps a TIFF with the time it was written: the same frame
    // rendered twice must be the same bytes, as its PNG is.
    spec.attribute("DateTime", "");
    if (format == "jpg") spec.attribute("Compression", "jpeg:95");
    return encode("image." + format, spec, [&](OIIO::ImageOutput& out) {
        return out.write_image(OIIO::TypeDesc::UINT8, rgb.data());
    });
}

std::string encode_exr(const ExrImage& image) {
    const int channels = int(image.channels.size());
    OIIO::ImageSpec spec(image.width, image.height, channels, OIIO::TypeDesc::FLOAT);
    spec.channelnames.clear();
    bool any_uint = false;
    for (const ExrChannel& c : image.channels) {
        spec.channelnames.push_back(c.name);
        any_uint = any_uint || c.is_uint;
    }
    // Per-channel formats only when they differ (the AOV's prim_id, as peers/embree writes it).
    if (any_uint)
        for (const ExrChannel& c : image.channels)
            spec.channelformats.push_back(c.is_uint ? OIIO::TypeDesc::UINT : OIIO::TypeDesc::FLOAT);
    else
        spec.attribute("oiio:ColorSpace", "linear");
    // OpenImageIO stamps an EXR with the time it was written unless DateTime is given: the
    // same frame rendered twice must be the same bytes (check_same_output.sh, the tests that
    // compare AOVs file for file), so the AOV carries no time. PNGs never had one.
    spec.attribute("DateTime", "");

    // Native layout: every channel is 4 bytes, packed per pixel in the spec's channel order.
    const std::size_t pixels = std::size_t(image.width) * std::size_t(image.height);
    std::vector<std::uint32_t> buffer(pixels * std::size_t(channels));
    for (int c = 0; c < channels; ++c)
        for (std::size_t i = 0; i < pixels; ++i)
            buffer[i * channels + c] = image.channels[c].words[i];
    return encode("image.exr", spec, [&](OIIO::ImageOutput& out) {
        return out.write_image(OIIO::TypeDesc::UNKNOWN, buffer.data(),
                               OIIO::stride_t(4 * std::size_t(channels)));
    });
}

namespace {

ExrImage read_exr_file(const std::filesystem::path& path) {
    const OpenedImage opened(path);
    OIIO::ImageInput* in = opened.in.get();
    const OIIO::ImageSpec& spec = in->spec();
    if (std::string(in->format_name()) != "openexr")
        throw Error("cannot read " + path.string() + ": not an OpenEXR file");
    ExrImage result;
    result.width = spec.width;
    result.height = spec.height;
    const std::size_t pixels = std::size_t(spec.width) * std::size_t(spec.height);
    for (int c = 0; c < spec.nchannels; ++c) {
        ExrChannel channel;
        channel.name = spec.channelnames[c];
        channel.is_uint = spec.channelformat(c) == OIIO::TypeDesc::UINT;
        channel.words.resize(pixels);
        if (!in->read_image(0, 0, c, c + 1,
                            channel.is_uint ? OIIO::TypeDesc::UINT : OIIO::TypeDesc::FLOAT,
                            channel.words.data()))
            throw Error("cannot read channel " + channel.name + " of " + path.string() + ": " +
                        in->geterror());
        result.channels.push_back(std::move(channel));
    }
    return result;
}

}  // namespace

ExrImage read_exr(const std::filesystem::path& path) {
    ExrImage result;
    // An EXR library's lines on stderr (OpenEXR prints none that kdray has seen) join the Error.
    capture_stderr([&] { result = read_exr_file(path); });
    return result;
}

DecodedImage read_image(const std::filesystem::path& path) {
    DecodedImage result;
    // libpng's own "libpng error:" lines become part of the Error, or of library_messages.
    result.library_messages = capture_stderr([&] {
        const OpenedImage opened(path);
        OIIO::ImageInput* in = opened.in.get();
        const OIIO::ImageSpec spec = in->spec();
        result.width = spec.width;
        result.height = spec.height;
        result.channels = spec.nchannels;
        result.integer = !spec.format.is_floating_point();
        result.values.resize(std::size_t(spec.width) * spec.height * spec.nchannels);
        if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, result.values.data()))
            throw Error("cannot read " + path.string() + ": " + in->geterror());
    });
    return result;
}

}  // namespace kdray
