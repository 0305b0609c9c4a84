// input_file.h — how kdray reads every file a user names as input (OBJ and MTL files, render
// files, tree files, stats.json, textures and images to compare): only a regular file is read, its
// size is checked before the read, nothing can block (a FIFO) or grow without bound (/dev/zero, a
// link to it), an image's declared size is checked before it is decoded, and JSON is parsed to a
// bounded depth. Errors name the file and the problem.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

namespace kdray {

/// What a file that is not a regular file is, for messages: "a FIFO", "a character device", ...
/// (the one wording of input_file and atomic_file's refusals).
const char* file_type_name(std::filesystem::file_type type);

/// The most bytes kdray reads of one input file of any kind: a quarter of the machine's physical
/// memory, since a parsed scene takes several times its text.
std::uint64_t input_size_limit();

/// The whole of `path` in memory. `what` names the kind of file in messages ("OBJ file"). Throws
/// Error "PATH: cannot open: REASON" when it cannot be opened, "PATH: not a regular file (a FIFO)"
/// for anything but a regular file (devices, FIFOs, sockets; a symbolic link is followed to what
/// it names; a directory is "cannot open: Is a directory"), and "PATH: N bytes, more than the M
/// bytes kdray reads of one WHAT here" when it exceeds max_bytes.
std::string read_input_file(const std::filesystem::path& path, std::string_view what,
                            std::uint64_t max_bytes = input_size_limit());

/// The most pixels kdray decodes of one image (a texture, an image to compare): 16384 x 16384,
/// the largest texture in common use. An image's header declares its size in a few bytes and the
/// decoder allocates it before reading any pixel, so that a 68-byte PNG declaring 60000 x 60000
/// cost 58 GB ("out of host memory", naming no file).
inline constexpr std::uint64_t kMaxImagePixels = std::uint64_t(1) << 28;

/// An image file's bytes bound the pixels it can hold: deflate (PNG, TIFF, EXR's ZIP) packs at
/// most 1032 bytes into one, 8 pixels a byte at 1 bit a pixel; JPEG needs bits for every 8 x 8
/// block; GIF's codes grow a pixel at a time. A header declaring more is damaged or hostile: a
/// 1,121-byte JPEG declaring 16000 x 16000 cost 4.1 GB before its first scanline failed (found by
/// fuzz_texture). Images of up to kPlausibleImagePixels pass whatever their size.
inline constexpr std::uint64_t kMaxPixelsPerFileByte = 16384;
inline constexpr std::uint64_t kPlausibleImagePixels = std::uint64_t(1) << 22;

/// Throws Error "NAME: an image of W x H pixels and C channels, more than ..." unless the image
/// declares at most kMaxImagePixels pixels and its decoded floats (4 bytes a channel) fit in
/// input_size_limit(); "NAME: an empty image (W x H, C channels)" when a dimension is not
/// positive; "NAME: ... in a file of B bytes, more than ..." when it declares more than
/// kPlausibleImagePixels pixels and more than kMaxPixelsPerFileByte a byte of its file
/// (`file_bytes`). Called with the header's figures, before anything is decoded.
void check_image_size(const std::string& name, std::int64_t width, std::int64_t height,
                      std::int64_t channels, std::uint64_t file_bytes);

/// The deepest nesting of arrays and objects kdray parses: kdray's own files nest 5 deep, and
/// every consumer of a parsed value (dump(), destruction, a message quoting it) recurses once a
/// level, so that 100,000 nested `[` in a 200 KB file overflowed the stack.
inline constexpr int kMaxJsonDepth = 64;

/// `text` parsed as JSON. Throws Error "NAME: invalid JSON at byte N: WHAT" on a syntax error,
/// "NAME: invalid JSON: WHAT" on a value JSON cannot hold, "NAME: JSON nested more than 64
/// levels deep" past kMaxJsonDepth, before anything deeper is built, and "NAME: field 'PATH' is
/// given twice" for a key that appears twice in one object (PATH as `lights[1].type`).
nlohmann::json parse_json(std::string_view text, const std::string& name);

}  // namespace kdray
