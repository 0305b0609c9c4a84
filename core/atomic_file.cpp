#include "core/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <string>
#include <system_error>

#include "core/error.h"
#include "core/input_file.h"

namespace kdray {

namespace fs = std::filesystem;

namespace {

/// The longest file name most file systems hold (NAME_MAX on Linux).
constexpr std::size_t kNameMax = 255;

/// The process id in a temporary name made by temporary_path, or 0 when `name` is not one.
long temporary_owner(const std::string& name) {
    if (name.empty() || name[0] != '.') return 0;
    const std::size_t at = name.rfind(".tmp");
    if (at == std::string::npos || at == 0) return 0;
    long pid = 0;
    const char* begin = name.data() + at + 4;
    const auto [end, ec] = std::from_chars(begin, name.data() + name.size(), pid);
    if (ec != std::errc() || end == begin || (*end != '\0' && *end != '.')) return 0;
    return pid;
}

}  // namespace

fs::path temporary_path(const fs::path& path) {
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "." + std::string.
    const std::string suffix = ".tmp" + std::to_string(::getpid()) + path.extension().string();
    std::string name = ".";
    name += path.filename().string();
    if (name.size() + suffix.size() > kNameMax) {
        // A legal final name near the limit: a short stand-in that still says what it is for.
        char hash[17];
        std::snprintf(hash, sizeof hash, "%016zx", std::hash<std::string>{}(name));
        name = ".kdray-";
        name += hash;
    }
    name += suffix;
    return path.parent_path() / name;
}

namespace {

/// Refuses a target that exists and is not a regular file: a device node, a FIFO, a directory or
/// a symbolic link where the output should go is the user's, and renaming over it would destroy
/// it.
void check_replaceable(const fs::path& path) {
    std::error_code ec;
    const fs::file_status existing = fs::symlink_status(path, ec);
    if (fs::exists(existing) && !fs::is_regular_file(existing))
        throw Error(path.string() + ": exists and is " + file_type_name(existing.type()) +
                    "; kdray replaces only regular files");
}

void rename_into_place(const fs::path& temp, const fs::path& path) {
    std::error_code ec;
    fs::rename(temp, path, ec);
    if (ec)
        throw Error(path.string() +
                    ": cannot rename the finished file into place: " + ec.message());
}

/// `bytes` into the new file `temp`, every write and the close checked; errors name `path`.
void write_new_file(const fs::path& temp, const fs::path& path, std::string_view bytes) {
    // O_EXCL|O_NOFOLLOW: the temporary is new, never something already there or a link.
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd < 0) throw Error(path.string() + ": cannot write: " + std::strerror(errno));
    std::size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            const int error = errno;
            ::close(fd);
            throw Error(path.string() + ": write failed: " + std::strerror(error));
        }
        done += std::size_t(n);
    }
    // close() is where some file systems (NFS, full quotas) report a failed write.
    if (::close(fd) != 0) throw Error(path.string() + ": write failed: " + std::strerror(errno));
}

}  // namespace

void write_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
    check_replaceable(path);
    const fs::path temp = temporary_path(path);
    try {
        write(temp);
        rename_into_place(temp, path);
    } catch (...) {
        std::error_code ignored;
        fs::remove(temp, ignored);
        throw;
    }
}

void write_file_atomically(const fs::path& path, std::string_view bytes) {
    write_files_atomically({{path, bytes}});
}

void write_files_atomically(const std::vector<FileContent>& files) {
    for (const FileContent& file : files) check_replaceable(file.path);
    std::vector<fs::path> temps;
    std::size_t renamed = 0;
    try {
        for (const FileContent& file : files) {
            temps.push_back(temporary_path(file.path));
            write_new_file(temps.back(), file.path, file.bytes);
        }
        for (; renamed < files.size(); ++renamed)
            rename_into_place(temps[renamed], files[renamed].path);
    } catch (...) {
        std::error_code ignored;
        for (std::size_t i = 0; i < temps.size(); ++i)
            fs::remove(i < renamed ? files[i].path : temps[i], ignored);
        throw;
    }
}

void remove_stale_temporaries(const fs::path& dir) {
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        const long owner = temporary_owner(name);
        if (owner <= 0 || owner == long(::getpid())) continue;
        // A process that still runs may be writing it (another kdray into the same folder).
        if (::kill(pid_t(owner), 0) == 0 || errno != ESRCH) continue;
        std::error_code ignored;
        if (it->is_regular_file(ignored)) fs::remove(it->path(), ignored);
    }
}

}  // namespace kdray
