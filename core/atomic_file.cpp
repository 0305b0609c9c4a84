#include "core/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>

#include "core/error.h"

namespace kdray {

namespace fs = std::filesystem;

fs::path temporary_path(const fs::path& path) {
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "." + std::string.
    std::string name = ".";
    name += path.filename().string();
    name += ".tmp" + std::to_string(::getpid());
    name += path.extension().string();
    return path.parent_path() / name;
}

void write_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
    const fs::path temp = temporary_path(path);
    try {
        write(temp);
        std::error_code ec;
        fs::rename(temp, path, ec);
        if (ec)
            throw Error(path.string() +
                        ": cannot rename the finished file into place: " + ec.message());
    } catch (...) {
        std::error_code ignored;
        fs::remove(temp, ignored);
        throw;
    }
}

void write_file_atomically(const fs::path& path, std::string_view bytes) {
    write_atomically(path, [&](const fs::path& temp) {
        std::ofstream out(temp, std::ios::binary | std::ios::trunc);
        if (!out) throw Error(path.string() + ": cannot write: " + std::strerror(errno));
        out.write(bytes.data(), std::streamsize(bytes.size()));
        out.flush();
        if (!out) throw Error(path.string() + ": write failed: " + std::strerror(errno));
    });
}

}  // namespace kdray
