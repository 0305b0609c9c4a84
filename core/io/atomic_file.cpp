#include "core/io/atomic_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <memory>
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

/// Whether `name` is a temporary that temporary_path made on this host: not the user's
/// `.holiday.tmp2023.tar`, nor another node's temporary in a folder that nodes share (a lock
/// there may be one that only its node sees: NFS mounted with local_lock).
bool is_own_hosts_temporary(const std::string& name) {
    if (name.empty() || name[0] != '.') return false;
    const std::size_t at = name.rfind(kTemporaryMarker);
    if (at == std::string::npos || at == 0) return false;
    std::string_view rest = std::string_view(name).substr(at + kTemporaryMarker.size());
    const std::string& host = host_tag();
    if (rest.substr(0, host.size()) != host || rest.size() <= host.size() ||
        rest[host.size()] != '@')
        return false;
    rest.remove_prefix(host.size() + 1);
    long pid = 0;
    const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), pid);
    if (ec != std::errc() || end == rest.data() || end == rest.data() + rest.size() ||
        *end != '@' || pid <= 0)
        return false;
    rest.remove_prefix(std::size_t(end - rest.data()) + 1);
    // 16 hex digits, then the target's extension or nothing.
    if (rest.size() < 16) return false;
    for (char c : rest.substr(0, 16))
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
    return rest.size() == 16 || rest[16] == '.';
}

/// Whether `fd` and `path` are one file: the name still holds what was opened.
bool same_file(int fd, const fs::path& path) {
    struct stat opened {
    }, named{};
    return ::fstat(fd, &opened) == 0 && ::lstat(path.c_str(), &named) == 0 &&
           opened.st_dev == named.st_dev && opened.st_ino == named.st_ino;
}

/// flock(LOCK_EX | LOCK_NB) on `fd`: 1 taken, 0 held by another, -1 the file system has no locks.
int try_lock(int fd) {
    while (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        if (errno == EINTR) continue;
        return errno == EWOULDBLOCK ? 0 : -1;
    }
    return 1;
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

/// A temporary file of `path`'s, created new and locked (flock) for as long as this lives: the
/// lock, not a process id, is what tells another kdray that it is live. Shards in two PID
/// namespaces of one host (containers, Slurm's job containers) share the host name, and a
/// process id of one means nothing in the other: a shard starting in one deleted the live
/// temporaries of the other, whose frame then failed ("cannot rename the finished file into
/// place"). A lock is the kernel's, whichever namespace holds it, and goes when its holder dies.
class LockedTemporary {
  public:
    explicit LockedTemporary(const fs::path& path) {
        // A cleaner may lock the new file in the moment before this does, and remove it; then
        // the name no longer holds this file, and another name is tried.
        for (int attempt = 0; attempt < 100; ++attempt) {
            path_ = temporary_path(path);
            // O_EXCL|O_NOFOLLOW: the temporary is new, never something already there or a link.
            fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
            if (fd_ < 0) throw Error(path.string() + ": cannot write: " + std::strerror(errno));
            // A file system without locks: no cleaner can lock it either, so none removes it.
            const int locked = try_lock(fd_);
            if (locked != 0 && same_file(fd_, path_)) return;
            if (locked == 1) ::unlink(path_.c_str());
            ::close(fd_);
            fd_ = -1;
        }
        throw Error(path.string() + ": cannot write: no temporary name of its own beside it");
    }
    ~LockedTemporary() {
        if (fd_ >= 0) ::close(fd_);  // the lock goes with the last descriptor
    }
    LockedTemporary(const LockedTemporary&) = delete;
    LockedTemporary& operator=(const LockedTemporary&) = delete;

    const fs::path& path() const { return path_; }
    /// A second descriptor of the file for writing: closing it keeps the lock, held by the
    /// first, until the temporary is renamed into place.
    int writer() const { return ::fcntl(fd_, F_DUPFD_CLOEXEC, 0); }

  private:
    fs::path path_;
    int fd_ = -1;
};

/// `bytes` into the new file `temp`, every write and the close checked; errors name `path`.
void write_new_file(const LockedTemporary& temp, const fs::path& path, std::string_view bytes) {
    const int fd = temp.writer();
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
    // Created and locked here; `write` opens it by name and truncates it, the same file.
    const LockedTemporary temp(path);
    try {
        write(temp.path());
        rename_into_place(temp.path(), path);
    } catch (...) {
        std::error_code ignored;
        fs::remove(temp.path(), ignored);
        throw;
    }
}

void write_file_atomically(const fs::path& path, std::string_view bytes) {
    write_files_atomically({{path, bytes}});
}

void write_files_atomically(const std::vector<FileContent>& files) {
    for (const FileContent& file : files) check_replaceable(file.path);
    std::vector<std::unique_ptr<LockedTemporary>> locked;
    std::vector<fs::path> temps;
    try {
        for (const FileContent& file : files) {
            locked.push_back(std::make_unique<LockedTemporary>(file.path));
            temps.push_back(locked.back()->path());
            write_new_file(*locked.back(), file.path, file.bytes);
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
    // Each second name is locked as a temporary is, so that a cleaner leaves it (a lock on the
    // earlier file itself, which no other kdray locks); checked to still name the earlier file
    // once locked.
    std::vector<int> backup_locks(files.size(), -1);
    // One file's rename is all or nothing by itself.
    for (std::size_t i = 0; files.size() > 1 && i < files.size(); ++i) {
        backups[i] = temporary_path(files[i].path);
        if (::link(files[i].path.c_str(), backups[i].c_str()) != 0) {
            if (errno != ENOENT) earlier[i] = Earlier::Unkept;  // a file system without hard links
            continue;
        }
        backup_locks[i] = ::open(backups[i].c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
        const bool held = backup_locks[i] >= 0 && try_lock(backup_locks[i]) != 0 &&
                          same_file(backup_locks[i], files[i].path);
        earlier[i] =
            held && same_file(backup_locks[i], backups[i]) ? Earlier::Kept : Earlier::Unkept;
        if (earlier[i] == Earlier::Unkept) {
            std::error_code ignored;
            fs::remove(backups[i], ignored);
        }
    }
    auto drop_backups = [&] {
        std::error_code ignored;
        for (std::size_t i = 0; i < files.size(); ++i) {
            if (earlier[i] == Earlier::Kept) fs::remove(backups[i], ignored);
            if (backup_locks[i] >= 0) ::close(backup_locks[i]);
            backup_locks[i] = -1;
        }
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
        if (!is_own_hosts_temporary(it->path().filename().string())) continue;
        // Read-write where it may: NFS emulates flock with a POSIX write lock, which a descriptor
        // open only for reading cannot take (there it fails, and the file stays).
        const int flags = O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC;
        int fd = ::open(it->path().c_str(), O_RDWR | flags);
        if (fd < 0) fd = ::open(it->path().c_str(), O_RDONLY | flags);
        if (fd < 0) continue;
        struct stat info {};
        // Stale when no one holds its lock: its writer died (SIGKILL, a power cut), in whichever
        // PID namespace it ran. Removed while this holds the lock, if the name still holds it.
        if (::fstat(fd, &info) == 0 && S_ISREG(info.st_mode) && try_lock(fd) == 1 &&
            same_file(fd, it->path()))
            ::unlink(it->path().c_str());
        ::close(fd);
    }
}

}  // namespace kdray
