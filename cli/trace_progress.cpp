#include "cli/trace_progress.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <spdlog/spdlog.h>

namespace kdray::cli {
namespace {

/// Redraws of the terminal's line: often enough to look alive, rarely enough to cost nothing.
constexpr double kRedrawS = 0.2;
constexpr double kDefaultIntervalS = 10.0;

double interval_from_environment() {
    const char* text = std::getenv("KDRAY_PROGRESS_INTERVAL_S");
    if (!text || !*text) return kDefaultIntervalS;
    char* end = nullptr;
    const double value = std::strtod(text, &end);
    return end != text && *end == '\0' && value > 0 && value < 1e9 ? value : kDefaultIntervalS;
}

double seconds_between(FrameClock::time_point a, FrameClock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

}  // namespace

std::string tracing_text(std::size_t position, std::size_t count, double fraction,
                         double rays_per_s, double eta_s) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "kdray: frame %zu/%zu  tracing %.0f%%  %.2f Mrays/s  ETA %.0f s", position + 1,
                  count, std::floor(100.0 * fraction), rays_per_s / 1e6, eta_s);
    return text;
}

TraceProgress::TraceProgress(ProgressLine* line)
    : line_(line), interval_s_(interval_from_environment()) {}

void TraceProgress::tracing(std::size_t position, std::size_t count, std::size_t frame,
                            std::uint64_t done, std::uint64_t total, double frames_ms) {
    const auto now = FrameClock::now();
    if (done == 0) {
        start_ = last_ = now;
        return;
    }
    const double elapsed_s = seconds_between(start_, now);
    // Nothing once the trace is done: the frame's own line follows at once.
    if (seconds_between(last_, now) < (line_ ? kRedrawS : interval_s_) || total == 0 ||
        done >= total || elapsed_s <= 0)
        return;
    last_ = now;
    const double fraction = double(done) / double(total);
    const double rays_per_s = double(done) / elapsed_s;
    const double frame_left_s = elapsed_s * (1.0 - fraction) / fraction;
    // The frames after this one take what the earlier ones took on average, or, in the first
    // frame, what this one's trace will have taken.
    const double per_frame_s =
        position > 0 ? frames_ms / 1e3 / double(position) : elapsed_s / fraction;
    const double eta_s = frame_left_s + per_frame_s * double(count - position - 1);
    if (line_) {
        line_->show_text(tracing_text(position, count, fraction, rays_per_s, eta_s));
        return;
    }
    spdlog::info(
        "frame {} ({}/{}): traced {:.0f}% of its {} primary rays, {:.2f} Mrays/s; about "
        "{:.1f} s left in the frame, {:.1f} s in the run",
        frame, position + 1, count, std::floor(100.0 * fraction), total, rays_per_s / 1e6,
        frame_left_s, eta_s);
}

}  // namespace kdray::cli
