// atomic_file.h — files that appear whole or not at all: written to a temporary name beside the
// target and renamed into place, so an interrupted or failed run never leaves half a file.
#pragma once

#include <filesystem>
#include <string_view>

namespace kdray {

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace kdray
