// log.h — kdray's messages on stderr, through spdlog: "kdray: ..." at info, "kdray: warning: ...",
// "kdray: error: ..." and "kdray: debug: ...". The progress line a terminal shows is cleared
// before a message and drawn again after it, so that the two never share a line.
#pragma once

#include <string>
#include <string_view>

#include <spdlog/spdlog.h>

namespace kdray::cli {

/// `text` made one bounded, printable line: control characters (C0 and DEL, C1 in UTF-8, and bytes
/// that are not UTF-8) written as escapes (\n, \r, \t, \x1b), a quoted value ('...') cut after
/// 200 bytes and the whole after 4096, each with "...". Messages quote what files say: a render
/// file's key holding "\nkdray: error: ..." or an ANSI escape forged lines and recoloured the
/// terminal, and a 30 MB string gave a 30 MB line.
std::string printable(std::string_view text);

/// Prints `prefix` ("kdray: error: ") and printable(text) as one line on stderr, around the
/// progress line. Every message kdray prints goes through here, spdlog's included.
void print_message(const char* prefix, std::string_view text);
/// Prints `prefix` and `text` as one line, as they are, around the progress line: for text that
/// is one printable line already and that printable() would cut (a shell-quoted command to paste
/// back, cli/resume_command.h).
void print_line_as_is(const char* prefix, std::string_view text);
inline void print_error(std::string_view text) {
    print_message("kdray: error: ", text);
}
inline void print_warning(std::string_view text) {
    print_message("kdray: warning: ", text);
}

/// Makes spdlog's default logger kdray's stderr logger at `level`, one of --log-level's: quiet
/// (warnings and errors only), info or debug. Safe to call again: main sets info before it parses
/// the command line.
void init_logging(const std::string& level);

/// Says, once per process at info, that OpenCL kernels are compiling (why a first frame or build
/// waits seconds), and at debug each program's build time.
void log_kernel_compiles();

/// Whether stderr is a terminal: the progress line is drawn only there; elsewhere (a file, a
/// Slurm job's log) a frame is one plain info line.
bool stderr_is_terminal();

/// The progress line on a terminal, rewritten in place: frame i/n, frames per second, time
/// left. Messages logged while it is shown appear above it.
class ProgressLine {
  public:
    void show(std::size_t done, std::size_t total, double elapsed_ms);
    /// Shows `text` (one printable line) as the progress line.
    void show_text(const std::string& text);
    /// Ends the line (a newline) so that what follows starts on a line of its own.
    void finish();
    ~ProgressLine() { finish(); }
};

}  // namespace kdray::cli
