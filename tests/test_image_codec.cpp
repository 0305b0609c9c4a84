// The image codec (core/io/image_codec.h), compiled once for each implementation: in kdray_tests
// with the codec kdray links (CTest image_codec), and with image_codec_small.cpp alone in
// kdray_tests_small_codec (CTest image_codec_small) when libstb-dev and libtinyexr-dev are
// installed. Every value must survive a round trip bit for bit, including the AOV's +inf and
// 0xFFFFFFFF misses and values that a half-float or a gamma would change, and every file must read
// the same through OpenImageIO itself, the library that the Embree peer and image viewers use.
#include <doctest/doctest.h>

#include <OpenImageIO/imageio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/io/image_codec.h"
#include "tests/hostile_png.h"

namespace {

namespace fs = std::filesystem;
using namespace kdray;

fs::path temp_file(const std::string& name) {
    const fs::path dir =
        fs::temp_directory_path() /
        ("kdray-codec-" + std::string(image_codec_name()) + "-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir / name;
}

void write_bytes(const fs::path& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    REQUIRE(out.good());
}

std::uint32_t bits(float v) {
    std::uint32_t w;
    std::memcpy(&w, &v, 4);
    return w;
}

// 7 x 5: odd sizes, so that a codec that pads rows or swaps width and height shows.
constexpr int kWidth = 7, kHeight = 5;
constexpr std::size_t kPixels = std::size_t(kWidth) * kHeight;

/// The AOV of conventions.md with the values that break lossy or converting codecs: +inf (a
/// miss), 0xFFFFFFFF (no triangle), ids above 2^24 (which a float channel would round), Z values
/// no half-float holds, denormals and negative zero in the normals.
ExrImage nasty_aov() {
    ExrImage image{kWidth, kHeight, {{"Z"}, {"prim_id", true}, {"N.X"}, {"N.Y"}, {"N.Z"}}};
    for (ExrChannel& c : image.channels) c.words.resize(kPixels);
    for (std::size_t i = 0; i < kPixels; ++i) {
        const bool miss = i % 4 == 3;
        image.channels[0].words[i] = bits(miss ? std::numeric_limits<float>::infinity()
                                               : 1.0f + 1e-7f * float(i) + 1234.567f * float(i));
        image.channels[1].words[i] = miss ? 0xFFFFFFFFu : std::uint32_t(16777217u + 3u * i);
        image.channels[2].words[i] = bits(i == 0 ? -0.0f : 1e-40f * float(i));
        image.channels[3].words[i] = bits(std::sin(float(i)));
        image.channels[4].words[i] = bits(-std::cos(float(i)));
    }
    return image;
}

}  // namespace

TEST_CASE("an EXR of named float32 and uint32 channels reads back bit for bit") {
    const ExrImage aov = nasty_aov();
    const fs::path path = temp_file("aov.exr");
    write_bytes(path, encode_exr(aov));

    const ExrImage back = read_exr(path);
    CHECK(back.width == kWidth);
    CHECK(back.height == kHeight);
    REQUIRE(back.channels.size() == aov.channels.size());
    for (const ExrChannel& want : aov.channels) {
        CAPTURE(want.name);
        const ExrChannel* got = back.find(want.name);
        REQUIRE(got != nullptr);
        CHECK(got->is_uint == want.is_uint);
        CHECK(got->words == want.words);
    }

    // OpenImageIO (OpenEXR underneath) finds the same channels with the same types and values.
    auto in = OIIO::ImageInput::open(path.string());
    REQUIRE(in);
    const OIIO::ImageSpec& spec = in->spec();
    CHECK(spec.width == kWidth);
    CHECK(spec.height == kHeight);
    for (const ExrChannel& want : aov.channels) {
        CAPTURE(want.name);
        const int c = spec.channelindex(want.name);
        REQUIRE(c >= 0);
        CHECK((spec.channelformat(c) == OIIO::TypeDesc::UINT) == want.is_uint);
        std::vector<std::uint32_t> words(kPixels);
        REQUIRE(in->read_image(0, 0, c, c + 1,
                               want.is_uint ? OIIO::TypeDesc::UINT : OIIO::TypeDesc::FLOAT,
                               words.data()));
        CHECK(words == want.words);
    }
    // No time stamp: a frame rendered twice must give the same bytes (OpenImageIO stamps an
    // EXR's DateTime unless told not to, and a test that compared AOVs across a second failed).
    CHECK(spec.find_attribute("DateTime") == nullptr);
    CHECK(spec.find_attribute("capDate") == nullptr);
}

TEST_CASE("an RGB EXR reads back through read_image as linear floats, R, G, B in order") {
    ExrImage rgb{kWidth, kHeight, {{"R"}, {"G"}, {"B"}}};
    for (int c = 0; c < 3; ++c)
        for (std::size_t i = 0; i < kPixels; ++i)
            rgb.channels[c].words.push_back(bits(0.001f * float(i) + float(c) + 1e-6f));
    const fs::path path = temp_file("rgb.exr");
    write_bytes(path, encode_exr(rgb));
    const DecodedImage back = read_image(path);
    CHECK(back.width == kWidth);
    CHECK(back.height == kHeight);
    REQUIRE(back.channels == 3);
    CHECK_FALSE(back.integer);
    for (int c = 0; c < 3; ++c)
        for (std::size_t i = 0; i < kPixels; ++i)
            CHECK(bits(back.values[i * 3 + c]) == rgb.channels[c].words[i]);
}

TEST_CASE("a PNG keeps every 8-bit value, and OpenImageIO reads the same bytes") {
    std::vector<std::uint8_t> pixels(3 * kPixels);
    for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = std::uint8_t((i * 37 + 11) % 256);
    pixels[0] = 0;
    pixels[1] = 255;
    const fs::path path = temp_file("image.png");
    write_bytes(path, encode_png_rgb8(kWidth, kHeight, pixels));

    const DecodedImage back = read_image(path);
    CHECK(back.width == kWidth);
    CHECK(back.height == kHeight);
    REQUIRE(back.channels == 3);
    CHECK(back.integer);
    for (std::size_t i = 0; i < pixels.size(); ++i)
        CHECK(std::lround(back.values[i] * 255.0f) == pixels[i]);

    auto in = OIIO::ImageInput::open(path.string());
    REQUIRE(in);
    std::vector<std::uint8_t> read(pixels.size());
    REQUIRE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, read.data()));
    CHECK(read == pixels);
}

TEST_CASE("a TIFF keeps every 8-bit value and a JPEG stays near them, as OpenImageIO reads them") {
    // A smooth gradient: JPEG's blocks keep it to a few steps, where noise would not survive.
    std::vector<std::uint8_t> pixels(3 * kPixels);
    for (std::size_t i = 0; i < kPixels; ++i)
        for (int c = 0; c < 3; ++c) pixels[3 * i + c] = std::uint8_t(40 + 20 * c + 4 * i);
    for (const std::string format : {"tif", "jpg"}) {
        CAPTURE(format);
        if (format == "tif" && std::string(image_codec_name()) == "small") {
            CHECK_THROWS_WITH_AS(encode_rgb8(format, kWidth, kHeight, pixels),
                                 doctest::Contains("KDRAY_IMAGE_CODEC=oiio"), Error);
            continue;
        }
        const fs::path path = temp_file("image." + format);
        write_bytes(path, encode_rgb8(format, kWidth, kHeight, pixels));
        auto in = OIIO::ImageInput::open(path.string());
        REQUIRE(in);
        CHECK(std::string(in->format_name()) == (format == "tif" ? "tiff" : "jpeg"));
        CHECK(in->spec().width == kWidth);
        CHECK(in->spec().height == kHeight);
        std::vector<std::uint8_t> read(pixels.size());
        REQUIRE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, read.data()));
        for (std::size_t i = 0; i < pixels.size(); ++i)
            CHECK(std::abs(int(read[i]) - int(pixels[i])) <= (format == "tif" ? 0 : 6));
    }
}

TEST_CASE("files OpenImageIO writes (8-bit grey PNG, half-float EXR) read as it wrote them") {
    // A grey PNG: one channel, as a texture may be.
    std::vector<std::uint8_t> grey(kPixels);
    for (std::size_t i = 0; i < kPixels; ++i) grey[i] = std::uint8_t(i * 7);
    const fs::path png = temp_file("grey.png");
    {
        auto out = OIIO::ImageOutput::create(png.string());
        REQUIRE(out);
        REQUIRE(
            out->open(png.string(), OIIO::ImageSpec(kWidth, kHeight, 1, OIIO::TypeDesc::UINT8)));
        REQUIRE(out->write_image(OIIO::TypeDesc::UINT8, grey.data()));
        REQUIRE(out->close());
    }
    const DecodedImage g = read_image(png);
    REQUIRE(g.channels == 1);
    CHECK(g.integer);
    for (std::size_t i = 0; i < kPixels; ++i) CHECK(std::lround(g.values[i] * 255.0f) == grey[i]);

    // A half-float EXR (what most tools write) widens to the same floats.
    std::vector<float> values(3 * kPixels);
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = 0.25f * float(i);  // exact in half
    const fs::path exr = temp_file("half.exr");
    {
        auto out = OIIO::ImageOutput::create(exr.string());
        REQUIRE(out);
        REQUIRE(out->open(exr.string(), OIIO::ImageSpec(kWidth, kHeight, 3, OIIO::TypeDesc::HALF)));
        REQUIRE(out->write_image(OIIO::TypeDesc::FLOAT, values.data()));
        REQUIRE(out->close());
    }
    const DecodedImage h = read_image(exr);
    REQUIRE(h.channels == 3);
    CHECK_FALSE(h.integer);
    CHECK(h.values == values);
    const ExrImage channels = read_exr(exr);
    REQUIRE(channels.find("G") != nullptr);
    CHECK_FALSE(channels.find("G")->is_uint);
    CHECK(channels.find("G")->words[2] == bits(values[2 * 3 + 1]));
}

TEST_CASE("files that are not images are errors that name them") {
    const fs::path path = temp_file("not-an-image.png");
    write_bytes(path, "not an image");
    const std::string name = path.string();
    CHECK_THROWS_WITH_AS(read_image(path), doctest::Contains(name.c_str()), Error);
    CHECK_THROWS_WITH_AS(read_exr(path), doctest::Contains(name.c_str()), Error);
    CHECK_THROWS_AS(read_image(temp_file("missing.png")), Error);
}

TEST_CASE("an image's declared size and its file are checked before anything is decoded") {
    // A 68-byte PNG whose header declares 60000 x 60000 made OpenImageIO allocate 43 GB before
    // reading a pixel: "out of host memory", naming no file. stb_image refuses past 2^30 bytes
    // itself; 17000 x 17000 (289 M pixels, 867 MB) is past kdray's 2^28 pixels but not stb's.
    for (const std::uint32_t side : {60000u, 17000u}) {
        CAPTURE(side);
        const fs::path huge = temp_file("huge.png");
        write_bytes(huge, test::png_declaring(side, side));
        REQUIRE(fs::file_size(huge) == 68u);
        CHECK_THROWS_WITH_AS(read_image(huge), doctest::Contains(huge.string().c_str()), Error);
        if (side == 17000u || std::string(image_codec_name()) == "oiio")
            CHECK_THROWS_WITH_AS(read_image(huge), doctest::Contains("pixels, 3 channels, more"),
                                 Error);
    }
    // A 2 x 2 declaration gets as far as the cut-off pixel data.
    const fs::path small = temp_file("small.png");
    write_bytes(small, test::png_declaring(2, 2));
    try {
        read_image(small);
        FAIL("a PNG without its pixel data was read");
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find("channels, more") == std::string::npos);
    }

    // An EXR whose dataWindow says 60000 x 60000: the encoded 7 x 5 AOV, its box patched.
    // OpenEXR refuses it at its offset table; tinyexr would allocate it.
    std::string exr = encode_exr(nasty_aov());
    const std::string attribute("dataWindow\0box2i\0", 17);
    const std::size_t at = exr.find(attribute);
    REQUIRE(at != std::string::npos);
    const std::int32_t box[4] = {0, 0, 59999, 59999};
    std::memcpy(&exr[at + attribute.size() + 4], box, 16);
    const fs::path huge_exr = temp_file("huge.exr");
    write_bytes(huge_exr, exr);
    CHECK_THROWS_WITH_AS(read_exr(huge_exr), doctest::Contains(huge_exr.string().c_str()), Error);
    CHECK_THROWS_WITH_AS(read_image(huge_exr), doctest::Contains(huge_exr.string().c_str()), Error);
    if (std::string(image_codec_name()) == "small")
        CHECK_THROWS_WITH_AS(read_exr(huge_exr), doctest::Contains("60000 x 60000 pixels"), Error);

    // Only a regular file is read: a FIFO blocked the decoders for ever, /dev/zero never ended.
    const fs::path fifo = temp_file("fifo.png");
    fs::remove(fifo);
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    CHECK_THROWS_WITH_AS(read_image(fifo), doctest::Contains("not a regular file (a FIFO)"), Error);
    CHECK_THROWS_WITH_AS(read_exr(fifo), doctest::Contains("not a regular file (a FIFO)"), Error);
    CHECK_THROWS_WITH_AS(read_image("/dev/zero"), doctest::Contains("/dev/zero"), Error);
    fs::remove(fifo);
}
