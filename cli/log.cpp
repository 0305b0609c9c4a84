#include "cli/log.h"

#include <unistd.h>

#include <cctype>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>

#include <spdlog/details/null_mutex.h>
#include <spdlog/sinks/base_sink.h>

#include "cl/runtime/program_cache.h"
#include "core/io/library_output.h"

namespace kdray::cli {
namespace {

// One lock for the sink and the progress line: a message and a redraw never interleave, and
// none is taken into an image library's captured output (core/io/library_output.h).
std::mutex& stderr_mutex = stderr_lock();
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
        print_message(prefix(msg.level), std::string_view(msg.payload.data(), msg.payload.size()));
    }
    void flush_() override {
        std::lock_guard<std::mutex> lock(stderr_mutex);
        if (!stderr_lost) flush_or_stop();
    }
};

constexpr std::size_t kQuotedBytes = 200, kMessageBytes = 4096;

bool is_word(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0;
}

/// The length of the well-formed UTF-8 sequence at text[i] (a lead byte >= 0x80), 0 if none,
/// and its code point in `cp`.
std::size_t utf8_length(std::string_view text, std::size_t i, std::uint32_t& cp) {
    const auto c = static_cast<unsigned char>(text[i]);
    const std::size_t n = c >= 0xf5 ? 0 : c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : c >= 0xc2 ? 2 : 0;
    if (n == 0 || i + n > text.size()) return 0;
    cp = c & (0x7fu >> n);
    for (std::size_t k = 1; k < n; ++k) {
        const auto b = static_cast<unsigned char>(text[i + k]);
        if ((b & 0xc0) != 0x80) return 0;
        cp = (cp << 6) | (b & 0x3f);
    }
    // Overlong forms, surrogates and code points past U+10FFFF are not UTF-8.
    const bool valid = (n == 3 && cp >= 0x800 && (cp < 0xd800 || cp > 0xdfff)) ||
                       (n == 4 && cp >= 0x10000 && cp <= 0x10ffff) || n == 2;
    return valid ? n : 0;
}

std::string hex_escape(unsigned v, const char* format) {
    char text[12];
    std::snprintf(text, sizeof text, format, v);
    return text;
}

}  // namespace

std::string printable(std::string_view text) {
    std::string out;
    bool quoted = false, cut = false;
    std::size_t quoted_bytes = 0;
    for (std::size_t i = 0; i < text.size();) {
        const char c = text[i];
        std::string unit;
        std::size_t length = 1;
        // An apostrophe inside a word ("file's") neither opens nor closes a quoted value.
        if (c == '\'' && !quoted && (i == 0 || !is_word(text[i - 1]))) {
            quoted = true;
            cut = false;
            quoted_bytes = 0;
            unit = "'";
        } else if (c == '\'' && quoted && (i + 1 == text.size() || !is_word(text[i + 1]))) {
            quoted = false;
            unit = cut ? "...'" : "'";
        } else {
            const auto byte = static_cast<unsigned char>(c);
            std::uint32_t cp = 0;
            if (c == '\n')
                unit = "\\n";
            else if (c == '\r')
                unit = "\\r";
            else if (c == '\t')
                unit = "\\t";
            else if (byte < 0x20 || byte == 0x7f)
                unit = hex_escape(byte, "\\x%02x");
            else if (byte < 0x80)
                unit = std::string(1, c);
            else if ((length = utf8_length(text, i, cp)) == 0)
                unit = hex_escape(byte, "\\x%02x"), length = 1;
            else if (cp < 0xa0)  // C1 controls: U+009B is a CSI to some terminals
                unit = hex_escape(cp, "\\u%04x");
            else
                unit = std::string(text.substr(i, length));
            if (quoted && !cut) {
                cut = quoted_bytes + unit.size() > kQuotedBytes;
                quoted_bytes += unit.size();
            }
            if (quoted && cut) unit.clear();
        }
        i += length;
        if (out.size() + unit.size() > kMessageBytes) return out + "...";
        out += unit;
    }
    if (quoted && cut) out += "...";
    return out;
}

void print_message(const char* prefix, std::string_view text) {
    print_line_as_is(prefix, printable(text));
}

void print_line_as_is(const char* prefix, std::string_view line) {
    std::lock_guard<std::mutex> lock(stderr_mutex);
    if (stderr_lost) return;
    // "\r\033[K": back to the start of the progress line and clear it.
    if (!progress_text.empty()) std::fputs("\r\033[K", stderr);
    std::fputs(prefix, stderr);
    std::fwrite(line.data(), 1, line.size(), stderr);
    std::fputc('\n', stderr);
    if (!progress_text.empty()) std::fputs(progress_text.c_str(), stderr);
    flush_or_stop();
}

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
    show_text(text);
}

void ProgressLine::show_text(const std::string& text) {
    std::lock_guard<std::mutex> lock(stderr_mutex);
    if (stderr_lost) return;
    progress_text = text;
    std::fprintf(stderr, "\r\033[K%s", text.c_str());
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
