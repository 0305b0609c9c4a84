#include "cli/log.h"

#include <unistd.h>

#include <cstdio>
#include <memory>
#include <mutex>

#include <spdlog/details/null_mutex.h>
#include <spdlog/sinks/base_sink.h>

#include "cl/runtime/program_cache.h"

namespace kdray::cli {
namespace {

// One lock for the sink and the progress line: a message and a redraw never interleave.
std::mutex stderr_mutex;
std::string progress_text;  // what the progress line shows now; empty when none is shown
// Set once a write to stderr failed (its reader went away: EPIPE, SIGPIPE being ignored; or a
// full disk): the run goes on and finishes its outputs, without logging.
bool stderr_lost = false;

/// Flushes stderr after a message or a redraw; a failed flush ends logging for the run.
void flush_or_stop() {
    if (std::fflush(stderr) != 0 || std::ferror(stderr)) stderr_lost = true;
}

const char* prefix(spdlog::level::level_enum level) {
    switch (level) {
        case spdlog::level::warn:
            return "kdray: warning: ";
        case spdlog::level::err:
        case spdlog::level::critical:
            return "kdray: error: ";
        case spdlog::level::debug:
        case spdlog::level::trace:
            return "kdray: debug: ";
        default:
            return "kdray: ";
    }
}

/// stderr, unbuffered, one whole line a message, around the progress line.
class StderrSink final : public spdlog::sinks::base_sink<spdlog::details::null_mutex> {
  protected:
    void sink_it_(const spdlog::details::log_msg& msg) override {
        std::lock_guard<std::mutex> lock(stderr_mutex);
        if (stderr_lost) return;
        // "\r\033[K": back to the start of the progress line and clear it.
        if (!progress_text.empty()) std::fputs("\r\033[K", stderr);
        std::fputs(prefix(msg.level), stderr);
        std::fwrite(msg.payload.data(), 1, msg.payload.size(), stderr);
        std::fputc('\n', stderr);
        if (!progress_text.empty()) std::fputs(progress_text.c_str(), stderr);
        flush_or_stop();
    }
    void flush_() override {
        std::lock_guard<std::mutex> lock(stderr_mutex);
        if (!stderr_lost) flush_or_stop();
    }
};

}  // namespace

void init_logging(const std::string& level) {
    static const std::shared_ptr<spdlog::logger> logger = [] {
        auto made = std::make_shared<spdlog::logger>("kdray", std::make_shared<StderrSink>());
        spdlog::set_default_logger(made);
        return made;
    }();
    logger->set_level(level == "debug"   ? spdlog::level::debug
                      : level == "quiet" ? spdlog::level::warn
                                         : spdlog::level::info);
}

void log_kernel_compiles() {
    set_program_build_listener([said = false](const ProgramBuildEvent& event) mutable {
        if (!event.done && !said) {
            spdlog::info(
                "compiling OpenCL kernels for '{}' (a first run on a device compiles "
                "them; later runs read the driver's cache)",
                event.device);
            said = true;
        }
        if (event.done) spdlog::debug("built {} in {:.0f} ms", event.file, event.ms);
    });
}

bool stderr_is_terminal() {
    return ::isatty(STDERR_FILENO) == 1;
}

void ProgressLine::show(std::size_t done, std::size_t total, double elapsed_ms) {
    const double fps = elapsed_ms > 0 ? 1000.0 * double(done) / elapsed_ms : 0.0;
    const double eta_s = fps > 0 ? double(total - done) / fps : 0.0;
    char text[128];
    std::snprintf(text, sizeof text, "kdray: frame %zu/%zu  %.2f fps  ETA %.0f s", done, total, fps,
                  eta_s);
    std::lock_guard<std::mutex> lock(stderr_mutex);
    if (stderr_lost) return;
    progress_text = text;
    std::fprintf(stderr, "\r\033[K%s", text);
    flush_or_stop();
}

void ProgressLine::finish() {
    std::lock_guard<std::mutex> lock(stderr_mutex);
    if (progress_text.empty() || stderr_lost) return;
    progress_text.clear();
    std::fputc('\n', stderr);
    flush_or_stop();
}

}  // namespace kdray::cli
