// render_run.h — a `kdray render` run, whichever builder and tracer it is given: the checks that
// come before the device opens (the frame fits in host memory, the folder's stats.json can be
// merged into, --skip-existing's frames dropped), then the frames through one FramePipeline
// (the next frame's OBJ loading while one renders, core/run/frame_loader.h), the warm-up through
// the same render_frame, a bad frame stopping the run or, with keep_going, recorded, and at the end
// the run's settings and records merged into the folder's stats.json (core/run/render_stats.h).
//
// What a user sees of it (log lines, the progress line) and when it stops early (Ctrl-C) are the
// caller's: the run reports to a RenderRunObserver and asks it whether it was interrupted.
// cli/cmd_render.cpp is the caller: it turns the command line into RenderRunSettings, makes the
// builder and the tracer (cl/backends.h), and turns the outcome into an exit status.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/render/render_file.h"
#include "core/render/tracer.h"
#include "core/run/frame_loader.h"
#include "core/run/frame_pipeline.h"
#include "core/run/image_settings.h"
#include "core/tree/tree_builder.h"

namespace kdray {

/// What a run renders and how, as the command line gave it.
struct RenderRunSettings {
    /// Every input, naturally sorted: a frame's number is its position here.
    std::vector<std::string> inputs;
    /// The frame numbers this run renders (--frames, --shard), in order; not empty.
    std::vector<std::size_t> selected;
    RenderSettings render;       // the render file with the command line's overrides applied
    std::string render_file;     // its path; empty: none (stats.json's "render_file")
    nlohmann::json overrides;    // what the overrides set (stats.json's "overrides")
    FrameOptions frame;          // the output folder, the files' names and format, the AOV, ...
    bool skip_existing = false;  // leave out the frames the folder holds already
    /// Merge the run into the folder's stats.json; false (`render -o FILE` unless --stats-json)
    /// writes none, and --skip-existing then goes by the files alone.
    bool folder_stats = true;
    bool keep_going = false;     // render the remaining frames after a bad one
    bool warm_up = false;        // render the first frame once, untimed and unwritten, first
    bool strict = false;         // any warning fails the frame, before it builds where it can
    /// Records in the folder made with other image settings (core/run/image_settings.h).
    OtherSettings other_settings = OtherSettings::Refuse;
    /// The builder's quality (TreeBuilder::quality), known before the device opens so that the
    /// folder's records are checked against it; empty: not checked, taken from the builder.
    std::string quality;
    /// When the run began checking its inputs: stats.json's setup_ms counts from there.
    FrameClock::time_point setup_start = FrameClock::now();
};

/// What a run reports while it renders. Every call has a default that does nothing.
class RenderRunObserver {
  public:
    virtual ~RenderRunObserver() = default;
    /// --skip-existing: `skipped` of the `selected` frames are in the folder already.
    virtual void skipping(std::size_t skipped, std::size_t selected);
    /// The first input, which frames a run without a camera, did not load (`error`); the run
    /// frames its own first frame, `first`, instead.
    virtual void framing_failed(const Error& error, std::size_t first);
    /// Once, when the run's first scene is in (the device open): the effects its frame decided
    /// (Effects::to_json).
    virtual void first_scene(const nlohmann::json& effects);
    /// The run's `position`-th frame (from 0) of `count` rendered: its stats.json record.
    virtual void frame_rendered(std::size_t position, std::size_t count,
                                const nlohmann::json& record);
    /// A warning whose cause (core/run/warning_tally.h) the run had not seen: printed once.
    virtual void warned(const std::string& text);
    /// Frame `frame` failed with `error`; the run goes on only with keep_going.
    virtual void frame_failed(std::size_t frame, const Error& error);
    /// While frame `frame`, the run's `position`-th (from 0) of `count`, traces: `done` of
    /// `total` primary rays traced, first 0 as the trace starts, then between chunks of the
    /// tracer's work (RenderInputs::progress); on the run's thread.
    virtual void tracing(std::size_t frame, std::size_t position, std::size_t count,
                         std::uint64_t done, std::uint64_t total);
    /// Whether tracing() shows anything: when not, the tracers are given no progress callback
    /// (the OpenCL tracer then queues a frame's launches without waiting between them).
    virtual bool wants_tracing() const;
    /// After each frame, rendered or failed: `done` of `count`, `elapsed_ms` since the first
    /// began.
    virtual void progress(std::size_t done, std::size_t count, double elapsed_ms);
    /// The frames are over; stats.json is merged next.
    virtual void frames_finished();
    /// The folder's stats.json was merged without its lock, because of `problem`.
    virtual void merged_without_lock(const std::string& problem);
    /// Asked before each frame and once after the last: true stops the run after the frame in
    /// progress (its files are written whole) and marks it interrupted in stats.json.
    virtual bool interrupted();
};

/// How a run ended, for the exit status.
struct RenderRunOutcome {
    std::size_t frames = 0;    // the run's frames (after --skip-existing)
    std::size_t rendered = 0;  // frames rendered and written
    std::size_t failed = 0;    // frames that failed (keep_going, or the one that stopped the run)
    bool interrupted = false;  // stopped by RenderRunObserver::interrupted
    std::string warnings;      // WarningTally::summary(); empty when nothing was warned
};

class RenderRun {
  public:
    /// Checks what can be checked before the device opens, in this order: a frame of the image
    /// size fits in half the host's memory; the output folder's stats.json, when there is one,
    /// can be merged into and (other_settings Refuse) holds no record made with other image
    /// settings (UsageError naming them); with skip_existing, the frames the folder holds are
    /// dropped (with Overwrite, only those recorded with the run's settings; the observer told
    /// how many). Throws Error naming the file or the figures.
    RenderRun(RenderRunSettings settings, RenderRunObserver& observer);
    ~RenderRun();

    /// The frame numbers left to render; empty when --skip-existing found every one done.
    const std::vector<std::size_t>& frames() const { return selected_; }

    /// Renders the frames with `builder` and `tracer` into the output folder (made if missing)
    /// and merges the run into its stats.json. The first frame's Error ends the run with it
    /// unless keep_going; a later one is recorded (and, without keep_going, stops the run).
    RenderRunOutcome run(TreeBuilder& builder, Tracer& tracer);

  private:
    RenderRunSettings settings_;
    RenderRunObserver& observer_;
    std::vector<std::size_t> selected_;
    // Outlives run(): a load still running when the run stops is waited for as the run's
    // owner lets it go.
    std::unique_ptr<FrameLoader> loader_;
};

}  // namespace kdray
