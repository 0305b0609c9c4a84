// hostile_png.h — the smallest PNG that declares a huge image: a valid signature and IHDR chunk
// (8-bit RGB, width x height) with correct CRCs, then an IDAT cut off after the zlib header and
// an IEND. 68 bytes whatever the size declared: a decoder that allocates the declared image
// before it reads a pixel (OpenImageIO, stb_image) spends width x height x channels on it.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace kdray::test {

/// PNG's CRC-32 (ISO 3309) of `bytes`.
inline std::uint32_t png_crc(const std::string& bytes) {
    std::uint32_t crc = 0xFFFFFFFFu;
    for (const unsigned char b : bytes) {
        crc ^= b;
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return crc ^ 0xFFFFFFFFu;
}

inline std::string png_declaring(std::uint32_t width, std::uint32_t height) {
    auto be32 = [](std::uint32_t v) {
        return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
    };
    auto chunk = [&](const std::string& type, const std::string& data) {
        return be32(std::uint32_t(data.size())) + type + data + be32(png_crc(type + data));
    };
    // Bit depth 8, colour type 2 (RGB), deflate, adaptive filtering, no interlace.
    const std::string ihdr = be32(width) + be32(height) + std::string{8, 2, 0, 0, 0};
    // A zlib header and the first bytes of a deflate stream that never ends.
    const std::string idat{'\x78', '\x9c', '\xec', '\xc1', '\x01', '\x0d',
                           '\x00', '\x00', '\x00', '\xc2', '\xa0'};
    return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + chunk("IDAT", idat) +
           chunk("IEND", "");
}

}  // namespace kdray::test
