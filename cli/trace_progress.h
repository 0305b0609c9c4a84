// trace_progress.h — what `kdray render` says while a frame traces (core/run/render_run.h's
// RenderRunObserver::tracing): on a terminal the progress line, redrawn at most every 0.2 s with
// the share of the frame's primary rays traced, their rate and the run's time left; elsewhere (a
// file, a batch job's log) a plain info line at intervals, every 10 s by default
// (KDRAY_PROGRESS_INTERVAL_S), so that a long frame is not silent.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "cli/log.h"
#include "core/run/frame_pipeline.h"

namespace kdray::cli {

class TraceProgress {
  public:
    /// `line`: the terminal's progress line, or null off a terminal.
    explicit TraceProgress(ProgressLine* line);

    /// The run's `position`-th frame (number `frame`) of `count`: `done` of `total` primary rays
    /// traced. `frames_ms`: the time the run's earlier frames took, for the time left.
    void tracing(std::size_t position, std::size_t count, std::size_t frame, std::uint64_t done,
                 std::uint64_t total, double frames_ms);

  private:
    ProgressLine* line_;
    double interval_s_;  // between lines off a terminal
    FrameClock::time_point start_, last_;
};

/// The progress line while a frame traces: "kdray: frame 1/3  tracing 45%  2.10 Mrays/s  ETA 12 s".
std::string tracing_text(std::size_t position, std::size_t count, double fraction,
                         double rays_per_s, double eta_s);

}  // namespace kdray::cli
