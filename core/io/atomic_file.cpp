#include "core/io/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <string_view>
#include <system_error>

#include "core/error.h"
#include "core/io/input_file.h"

namespace kdray {

namespace fs = std::filesystem;

namespace {

/// The longest file name most file systems hold (NAME_MAX on Linux).
constexpr std::size_t kNameMax = 255;

/// What marks a temporary as kdray's, and separates its fields: `@` is in no host name, and no
/// user names a file `.NAME.kdray.tmp@HOST@PID@RANDOM`.
constexpr std::string_view kTemporaryMarker = ".kdray.tmp@";

/// This machine's host name as a temporary name holds it: at most 64 bytes of letters, digits,
/// '.', '-' and '_' (anything else, '@' included, becomes '_').
const std::string& host_tag() {
    static const std::string tag = [] {
        char host[256] = {};
        if (::gethostname(host, sizeof host - 1) != 0 || host[0] == '\0')
            std::snprintf(host, sizeof host, "unknown-host");
        std::string t;
        for (const char* c = host; *c != '\0' && t.size() < 64; ++c) {
            const bool plain = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                               (*c >= '0' && *c <= '9') || *c == '.' || *c == '-' || *c == '_';
            t += plain ? *c : '_';
        }
        return t;
    }();
    return tag;
}

/// The process id in a temporary name that temporary_path made on this host, or 0 when `name`
/// is anything else: the user's `.holiday.tmp2023.tar`, or another node's temporary in a folder
/// that nodes share (its process id means nothing here).
long temporary_owner(const std::string& name) {
    if (name.empty() || name[0] != '.') return 0;
    const std::size_t at = name.rfind(kTemporaryMarker);
    if (at == std::string::npos || at == 0) return 0;
    std::string_view rest = std::string_view(name).substr(at + kTemporaryMarker.size());
    const std::string& host = host_tag();
    if (rest.substr(0, host.size()) != host || rest.size() <= host.size() ||
        rest[host.size()] != '@')
        return 0;
    rest.remove_prefix(host.size() + 1);
    long pid = 0;
    const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), pid);
    if (ec != std::errc() || end == rest.data() || end == rest.data() + rest.size() || *end != '@')
        return 0;
    rest.remove_prefix(std::size_t(end - rest.data()) + 1);
    // 16 hex digits, then the target's extension or nothing.
    if (rest.size() < 16) return 0;
    for (char c : rest.substr(0, 16))
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return 0;
    if (rest.size() > 16 && rest[16] != '.') return 0;
    return pid;
}

}  // namespace

fs::path temporary_path(const fs::path& path) {
    // A random part as well as the process id: two hosts (or PID namespaces) writing one shared
    // folder cannot pick the same name, and O_EXCL refuses a clash rather than sharing a file.
    static thread_local std::mt19937_64 random{std::random_device{}()};
    char unique[17];
    std::snprintf(unique, sizeof unique, "%016llx", static_cast<unsigned long long>(random()));
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "." + std::string.
    std::string suffix(kTemporaryMarker);
    suffix += host_tag();
    suffix += '@';
    suffix += std::to_string(::getpid());
    suffix += '@';
    suffix += unique;
    suffix += path.extension().string();
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
    // A name the folder cannot hold (too long, a path through a file) fails here, before
    // anything is written, rather than at its rename with the set's other files in place.
    if (ec && ec != std::errc::no_such_file_or_directory)
        throw Error(path.string() + ": cannot write there: " + ec.message());
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
    try {
        for (const FileContent& file : files) {
            temps.push_back(temporary_path(file.path));
            write_new_file(temps.back(), file.path, file.bytes);
        }
    } catch (...) {
        std::error_code ignored;
        for (const fs::path& temp : temps) fs::remove(temp, ignored);
        throw;
    }

    // The targets' earlier files, each kept under a second name (a hard link, no copy) until
    // every rename is done: a rename that fails after others succeeded (the folder changed under
    // the run) puts the earlier files back, instead of leaving a set of mixed runs, or deleting
    // a file that a stats.json lists.
    enum class Earlier { None, Kept, Unkept };
    std::vector<Earlier> earlier(files.size(), Earlier::None);
    std::vector<fs::path> backups(files.size());
    // One file's rename is all or nothing by itself.
    for (std::size_t i = 0; files.size() > 1 && i < files.size(); ++i) {
        backups[i] = temporary_path(files[i].path);
        if (::link(files[i].path.c_str(), backups[i].c_str()) == 0)
            earlier[i] = Earlier::Kept;
        else if (errno != ENOENT)
            earlier[i] = Earlier::Unkept;  // a file system without hard links, say
    }
    auto drop_backups = [&] {
        std::error_code ignored;
        for (std::size_t i = 0; i < files.size(); ++i)
            if (earlier[i] == Earlier::Kept) fs::remove(backups[i], ignored);
    };

    std::size_t renamed = 0;
    try {
        for (; renamed < files.size(); ++renamed)
            rename_into_place(temps[renamed], files[renamed].path);
    } catch (const Error& e) {
        std::error_code ignored;
        for (std::size_t i = renamed; i < files.size(); ++i) fs::remove(temps[i], ignored);
        std::string outcome;
        for (std::size_t i = 0; i < renamed; ++i) {
            const fs::path& path = files[i].path;
            std::error_code ec;
            if (earlier[i] == Earlier::Kept)
                fs::rename(backups[i], path, ec);
            else if (earlier[i] == Earlier::None)
                fs::remove(path, ec);  // this run's own file, where there was none
            // Never a deletion of what the folder held: a file that cannot be put back stays
            // this run's, and the message says so.
            if (earlier[i] == Earlier::Unkept || ec)
                outcome += "; " + path.string() + " is this run's new file (the earlier one " +
                           (ec ? "could not be put back: " + ec.message()
                               : std::string("could not be kept")) +
                           ")";
            else
                outcome += "; " + path.string() + " is as it was";
        }
        drop_backups();
        throw Error(e.what() + outcome);
    }
    drop_backups();
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
