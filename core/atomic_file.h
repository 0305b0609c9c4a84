// atomic_file.h — files that appear whole or not at all: written to a temporary name beside the
// target and renamed into place, so an interrupted or failed run never leaves half a file. The one
// writer of every file kdray outputs (images, AOVs, tree files, stats.json).
#pragma once

#include <filesystem>
#include <functional>
#include <string_view>

namespace kdray {

/// The temporary name for `path`: hidden, in the same folder (so the rename is atomic on one file
/// system), unique per process, and ending in the real extension so that a writer choosing the
/// format by extension (OpenImageIO) picks the right one: dir/frame.png ->
/// dir/.frame.png.tmp123.png.
std::filesystem::path temporary_path(const std::filesystem::path& path);

/// Calls `write` with the temporary name of `path`; `write` creates and fills that file and
/// throws Error when it cannot. Then the file is renamed onto `path`. On any failure the
/// temporary file is removed and the Error propagates.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& temp)>& write);

/// `bytes` as the whole content of `path`, atomically.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace kdray
