#include "core/io/library_output.h"

#include <sys/mman.h>
#include <unistd.h>

#include <cstdio>
#include <exception>

#include "core/error.h"

namespace kdray {
namespace {

/// The most bytes of a library's output kept for a message.
constexpr std::size_t kKeptBytes = 4096;

/// Restores descriptor 2 from `saved` and closes it.
void restore(int saved) {
    std::fflush(stderr);
    ::dup2(saved, STDERR_FILENO);
    ::close(saved);
}

/// What `fd` holds from its start, at most kKeptBytes, without trailing newlines.
std::string read_back(int fd) {
    std::string text(kKeptBytes, '\0');
    const ssize_t n = ::pread(fd, text.data(), text.size(), 0);
    text.resize(n > 0 ? std::size_t(n) : 0);
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    return text;
}

/// Whether `message` already says what each line of `said` says (after libpng's prefix).
bool already_said(const std::string& message, const std::string& said) {
    std::size_t start = 0;
    while (start < said.size()) {
        std::size_t end = said.find('\n', start);
        if (end == std::string::npos) end = said.size();
        std::string line = said.substr(start, end - start);
        for (const char* prefix : {"libpng error: ", "libpng warning: "})
            if (line.rfind(prefix, 0) == 0) line.erase(0, std::string(prefix).size());
        if (!line.empty() && message.find(line) == std::string::npos) return false;
        start = end + 1;
    }
    return true;
}

}  // namespace

std::mutex& stderr_lock() {
    static std::mutex lock;
    return lock;
}

std::string capture_stderr(const std::function<void()>& call) {
    const std::lock_guard<std::mutex> lock(stderr_lock());
    std::fflush(stderr);
    const int buffer = ::memfd_create("kdray-library-output", MFD_CLOEXEC);
    const int saved = buffer >= 0 ? ::dup(STDERR_FILENO) : -1;
    if (saved < 0 || ::dup2(buffer, STDERR_FILENO) < 0) {
        if (saved >= 0) ::close(saved);
        if (buffer >= 0) ::close(buffer);
        call();
        return "";
    }
    std::exception_ptr failure;
    try {
        call();
    } catch (...) {
        failure = std::current_exception();
    }
    restore(saved);
    const std::string said = read_back(buffer);
    ::close(buffer);
    if (failure) {
        try {
            std::rethrow_exception(failure);
        } catch (const Error& e) {
            if (said.empty() || already_said(e.what(), said)) throw;
            throw Error(std::string(e.what()) + "; the image library printed: " + said);
        }
    }
    return said;
}

}  // namespace kdray
