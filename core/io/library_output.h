// library_output.h — what image libraries print on stderr by themselves, taken into kdray's own
// messages. libpng prints "libpng error: ..." (and "libpng warning: ...") on stderr, through
// OpenImageIO, which has no way to turn it off: those lines appeared even with --log-level quiet,
// beside kdray's one-line warning about the same file.
#pragma once

#include <functional>
#include <mutex>
#include <string>

namespace kdray {

/// The lock of the process's stderr: kdray's messages (cli/log.cpp) and capture_stderr hold it,
/// so that no message of kdray's is captured and no library line splits one.
std::mutex& stderr_lock();

/// Runs `call` with stderr (descriptor 2) sent to a buffer, under stderr_lock(), and returns what
/// was written there (at most 4 KiB, trailing newlines dropped). When `call` throws Error, it is
/// thrown again with the text appended ("; the image library printed: ..."), unless the message
/// already says it; any other exception propagates as it was. Where the buffer cannot be made
/// (no memfd), `call` runs with stderr as it is.
std::string capture_stderr(const std::function<void()>& call);

}  // namespace kdray
