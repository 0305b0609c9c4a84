// frame_pipeline.h — what a frame of `kdray render` is, whichever builder and tracer run it:
// the scene loaded, its tree built, the frame traced, the image (and the hit AOV) written, and
// the frame's stats.json record. The run (core/run/render_run.h) and its warm-up go through the
// same render_frame; the warm-up only writes nothing.
//
// A record's times add up: frame_ms = load_wait_ms + compile_ms + build_ms + trace_ms + write_ms
// + other_ms, each a separate stretch of the frame's own wall time. load_ms is not one of them:
// it is the load's own duration, mostly spent on another thread while the frame before rendered
// (core/run/frame_loader.h); what the frame itself waited for its scene is load_wait_ms.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "core/io/output_name.h"
#include "core/render/camera.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/render/tracer.h"
#include "core/run/frame_loader.h"
#include "core/scene/scene.h"
#include "core/tree/tree_builder.h"

namespace kdray {

using FrameClock = std::chrono::steady_clock;

/// Milliseconds from `start` to now.
double ms_since(FrameClock::time_point start);

/// What every frame of a run shares beside the builder, the tracer and the render file.
struct FrameOptions {
    std::filesystem::path out_dir;
    std::string format = "png";  // the image's format and extension: png or exr
    OutputName name;             // a frame's files: NAME.png (or .exr) and NAME.aov.exr
    bool aov = false;            // also <stem>.aov.exr; the hits then carry their normals
    bool heatmap = false;        // also <stem>.cost.png, the centre rays' walk cost (image.h)
    kd_u32 intersect = KDRAY_INTERSECT_WATERTIGHT;  // KDRAY_INTERSECT_*
    RenderInputs::Packets packets = RenderInputs::Packets::Auto;
    /// The process's milliseconds of compilation so far (the OpenCL program cache's
    /// compile_ms_total); a frame's compile_ms is how much it grew while the frame prepared the
    /// builder and the tracer. Empty: the backends compile nothing.
    std::function<double()> compile_ms_so_far;
};

/// One frame: its number (its position in the run's naturally sorted inputs), its OBJ, the scene
/// loaded from it, how long the load took and how much of that the frame waited for, and when
/// the frame began (frame_ms counts from there; the wait is its first load_wait_ms).
struct FrameJob {
    std::size_t number = 0;
    std::string input;
    /// A scene the caller loaded, with load_ms and load_wait_ms; or none, and `loader` holds it.
    const Scene* scene = nullptr;
    double load_ms = 0;
    double load_wait_ms = 0;
    FrameClock::time_point start = FrameClock::now();
    /// Without `scene`: the run's loader, whose next scene is this frame's (render_frame's load
    /// step measures load_ms and load_wait_ms).
    FrameLoader* loader = nullptr;
    /// Called once the scene is in, before the frame is framed and built (the run's first scene
    /// announced: the device is open, the effects known).
    std::function<void(const Scene&)> loaded = nullptr;
    /// Told how far the frame's trace is (RenderInputs::progress); may be empty.
    std::function<void(std::uint64_t done, std::uint64_t total)> traced = nullptr;
};

class FramePipeline {
  public:
    enum class Output { Write, Discard };

    FramePipeline(TreeBuilder& builder, Tracer& tracer, RenderSettings settings,
                  FrameOptions options);

    /// Loads (from `job.loader`, unless `job.scene` is given), builds and traces `job`'s frame
    /// and, with Output::Write, writes its files; returns its stats.json record. The builder and
    /// the tracer are prepared (their programs built, the first frame's compile_ms) outside
    /// build_ms and trace_ms. Once the build and the trace are done, before the files are
    /// written, the loader starts the next load (if it has not) and `computed`, when given, runs.
    /// A frame rendered with Output::Discard (the warm-up) is the loader's next frame rendered
    /// ahead of time: the loader keeps its scene for that frame. Without a camera in the render
    /// file, frames are framed on the scene of the first frame rendered with Write (unless
    /// frame_on chose another).
    /// Throws Error from any stage.
    nlohmann::json render_frame(const FrameJob& job, Output output = Output::Write,
                                const std::function<void()>& computed = {});

    /// Without a camera in the render file: frames every later frame on `scene`'s view (kept in
    /// its units). Unless it is called, the first frame rendered with Output::Write is framed.
    void frame_on(const Scene& scene);

    const RenderSettings& settings() const { return settings_; }

  private:
    TreeBuilder& builder_;
    Tracer& tracer_;
    RenderSettings settings_;
    FrameOptions options_;
    bool framed_ = false;  // the camera keys hold a framing (frame_on)
};

}  // namespace kdray
