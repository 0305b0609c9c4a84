// frame_loader.h — the scenes of a run's frames, each OBJ read on another thread while the frame
// before it renders: render_frame's load step (core/run/frame_pipeline.h) takes the next scene from
// here, and waits only for the part of its load that did not overlap the frame before.
//
// When the next load starts depends on where the frame computes. With the build and the trace on
// a GPU, the load overlaps them; when they run on the host's own cores (a CPU device, the
// reference code) a loader beside them only preempts their workers (the Kitchen's large stage:
// 33 -> 48 ms on 2 cores), so it overlaps writing the files instead.
#pragma once

#include <cstddef>
#include <future>
#include <optional>
#include <string>
#include <vector>

#include "core/scene/scene.h"

namespace kdray {

/// A scene and its load's own duration (a frame's load_ms).
struct LoadedScene {
    Scene scene;
    double load_ms = 0;
};

class FrameLoader {
  public:
    /// When the next frame's load starts: as the frame begins, beside its build and trace
    /// (Compute: a GPU computes them), or once they are done, beside writing the files (Write:
    /// the host's own cores compute them).
    enum class Overlap { Compute, Write };

    /// `paths`: the OBJ of each frame, in the order the run renders them. The first one starts
    /// loading now.
    FrameLoader(std::vector<std::string> paths, Overlap overlap);

    /// The next frame's scene, waiting for its load (started now if none is pending: a frame that
    /// failed before its trace started none for this one). With Overlap::Compute the load of the
    /// frame after it starts first. The frame counts as taken even when its load throws (Error
    /// naming the file), so that the run can go on with the next one.
    LoadedScene take();

    /// The next frame's scene, kept for its take(): the warm-up renders the run's first frame from
    /// the scene the frame itself then renders, so each OBJ is read once and that frame waits for
    /// none of its load.
    const LoadedScene& peek();

    /// The frame taken last is built and traced: the next load starts now, unless it has already.
    void computed();

  private:
    /// Starts loading the next frame's OBJ, when there is one and it is not loading or loaded.
    void start_next();

    std::vector<std::string> paths_;
    Overlap overlap_;
    std::size_t next_ = 0;              // the frame take() hands out next
    std::future<LoadedScene> loading_;  // next_'s load, when started
    std::optional<LoadedScene> kept_;   // next_'s scene, when peek() waited for it
};

}  // namespace kdray
