// `kdray render FRAME.obj... -o OUTDIR`: per frame, load, build, trace and write the image (and
// the hit AOV), then OUTDIR/stats.json for the run. Every file appears whole or not at all.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <future>
#include <iostream>
#include <utility>

#include "cl/render/opencl_renderer.h"
#include "cli/commands.h"
#include "cli/device_session.h"
#include "cli/frame_selection.h"
#include "cli/inputs.h"
#include "cli/report.h"
#include "cli/tree_builder.h"
#include "core/atomic_file.h"
#include "core/camera.h"
#include "core/error.h"
#include "core/reference_tracer.h"
#include "core/render_file.h"
#include "core/render_setup.h"
#include "core/scene.h"
#include "core/version.h"

namespace kdray::cli {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

void create_output_dir(const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir))
        throw Error(dir.string() + ": cannot create the output folder: " +
                    (ec ? ec.message() : std::string("a file of that name exists")));
    // What a killed run (SIGKILL mid-write) left behind would otherwise stay for ever.
    remove_stale_temporaries(dir);
}

/// One line on a terminal, rewritten in place: frame i/n, frames per second, time left.
void show_progress(std::size_t done, std::size_t total, double elapsed_ms) {
    double fps = elapsed_ms > 0 ? 1000.0 * double(done) / elapsed_ms : 0.0;
    double eta_s = fps > 0 ? double(total - done) / fps : 0.0;
    std::fprintf(stderr, "\rkdray: frame %zu/%zu  %.2f fps  ETA %.0f s   ", done, total, fps,
                 eta_s);
    if (done == total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
}

/// Everything a run shares between its frames.
struct RenderRun {
    const RenderCommand& command;
    std::vector<std::string> inputs;
    RenderSettings settings;
    std::filesystem::path out_dir;
    DeviceSession& session;
    TreeBuilder& builder;
    Camera framed;  // without a camera in the render file: frame the first rendered scene
};

/// The tracer's choices the command line makes: --intersect, --packets, and normals for --aov.
void set_trace_options(const RenderCommand& command, RenderInputs& inputs) {
    inputs.normals = command.aov;
    inputs.intersect =
        command.intersect == "moller" ? KDRAY_INTERSECT_MOLLER : KDRAY_INTERSECT_WATERTIGHT;
    inputs.packets = command.packets == "on"    ? RenderInputs::Packets::On
                     : command.packets == "off" ? RenderInputs::Packets::Off
                                                : RenderInputs::Packets::Auto;
}

/// Builds, traces and writes frame i; returns its stats.json record. `computed` runs once the
/// build and the trace are done, before the files are written.
nlohmann::json render_frame(RenderRun& run, std::size_t i, const Scene& scene, double load_ms,
                            Clock::time_point frame_start, const std::function<void()>& computed) {
    const RenderCommand& command = run.command;
    Camera camera = run.settings.camera_given ? run.settings.camera_at(int(i)) : run.framed;
    BuiltTree built = run.builder.build(scene);
    RenderInputs render_inputs = prepare_render(scene, run.settings, camera, kd_u32(i));
    set_trace_options(command, render_inputs);
    // The render program of this frame's effects is built (once per run) outside trace_ms.
    if (command.tracer == "opencl") prepare_opencl_renderer(run.session.device(), render_inputs);
    auto trace_start = Clock::now();
    FrameResult result = command.tracer == "opencl"
                             ? render_opencl(run.session.device(), built.tree, scene, render_inputs,
                                             &built.on_device)
                             : render_reference(built.tree, scene, render_inputs, command.threads);
    double trace_ms = ms_since(trace_start);
    computed();

    std::string stem = std::filesystem::path(run.inputs[i]).stem().string();
    std::filesystem::path image_path = run.out_dir / (stem + "." + command.format);
    write_image(image_path, result.image);
    std::filesystem::path aov_path = run.out_dir / (stem + ".aov.exr");
    if (command.aov) write_aov(aov_path, result.hits);

    const RayTotals& rays = result.rays;
    // Centre rays that hit: with a camera inside a closed mesh, every miss is a leak.
    const auto hit_pixels = std::count_if(result.hits.hits.begin(), result.hits.hits.end(),
                                          [](const KdHit& h) { return h.prim != KDRAY_NO_HIT; });
    nlohmann::json frame = {
        {"frame", i},
        {"input", run.inputs[i]},
        {"image", image_path.filename().string()},
        {"scene", scene_json(scene)},
        {"tree", tree_json(built, scene.triangle_count())},
        {"tracer", command.tracer},
        {"effects", render_inputs.effects.to_json()},
        {"load_ms", load_ms},
        {"build_ms", built.report.build_ms},
        {"trace_ms", trace_ms},
        {"frame_ms", ms_since(frame_start)},
        {"rays",
         {{"primary", rays.primary},
          {"shadow", rays.shadow},
          {"reflection", rays.reflection},
          {"refraction", rays.refraction}}},
        {"hit_pixels", hit_pixels},
        {"mrays_per_s", trace_ms > 0 ? double(rays.total()) / (trace_ms * 1e3) : 0.0}};
    if (command.aov) frame["aov"] = aov_path.filename().string();
    return frame;
}

nlohmann::json summary_json(const nlohmann::json& frames) {
    double total_ms = 0, worst_ms = 0;
    for (const nlohmann::json& f : frames) {
        total_ms += f["frame_ms"].get<double>();
        worst_ms = std::max(worst_ms, f["frame_ms"].get<double>());
    }
    double mean_ms = frames.empty() ? 0.0 : total_ms / double(frames.size());
    return {{"frames", frames.size()},
            {"mean_frame_ms", mean_ms},
            {"worst_frame_ms", worst_ms},
            {"frames_per_second", mean_ms > 0 ? 1000.0 / mean_ms : 0.0}};
}

/// Set by SIGINT/SIGTERM: the run stops after the frame in progress, whose files are written
/// whole. A second signal ends the process at once; files are renamed into place only when
/// complete, so even then no truncated image exists under its final name.
volatile std::sig_atomic_t interrupted = 0;

extern "C" void on_interrupt(int signal) {
    interrupted = 1;
    std::signal(signal, SIG_DFL);
}

}  // namespace

int run_render(const RenderCommand& command) {
    // Check everything that can be checked before the first frame costs time.
    std::vector<std::string> inputs = expand_inputs(command.inputs);
    const std::vector<std::size_t> selected =
        select_frames(inputs.size(), command.frames, command.shard);
    if (selected.empty())
        throw UsageError("--frames/--shard select no frame of the " +
                         std::to_string(inputs.size()) + " inputs");
    RenderSettings settings;
    if (!command.render_file.empty()) settings = load_render_file(command.render_file);
    DeviceSession session(command.builder.device);
    TreeBuilder builder(command.builder, session);
    if (command.tracer == "opencl") session.device();
    builder.prepare();
    RenderRun run{command, inputs, settings, command.output_dir, session, builder, {}};
    create_output_dir(run.out_dir);
    const bool progress = !command.quiet && ::isatty(STDERR_FILENO);
    std::signal(SIGINT, on_interrupt);
    std::signal(SIGTERM, on_interrupt);

    if (command.warm_up) {
        // Benchmarks: build and trace the first frame once, untimed and unwritten, so that
        // program builds and first-launch costs stay out of every frame's figures.
        Scene scene = load_obj(inputs[selected[0]]);
        Camera camera = settings.camera_given ? settings.camera_at(int(selected[0]))
                                              : frame_bounds(scene.bounds());
        BuiltTree built = builder.build(scene);
        RenderInputs render_inputs = prepare_render(scene, settings, camera, 0);
        set_trace_options(command, render_inputs);
        if (command.tracer == "opencl")
            render_opencl(session.device(), built.tree, scene, render_inputs);
        else
            render_reference(built.tree, scene, render_inputs, command.threads);
    }

    // The next frame's OBJ loads on another thread. With the build and the trace on a GPU it
    // overlaps them; when they run on the host's own cores (a CPU device, the reference code) a
    // loader beside them only preempts their workers (the Kitchen's large stage: 33 -> 48 ms on
    // 2 cores), so it overlaps writing the files instead.
    const bool compute_on_host = command.builder.builder == "reference" ||
                                 command.tracer == "reference" || session.device().is_cpu();
    auto load_async = [&](std::size_t frame) {
        return std::async(std::launch::async, [path = inputs[frame]] {
            auto start = Clock::now();
            Scene scene = load_obj(path);
            return std::make_pair(std::move(scene), ms_since(start));
        });
    };
    nlohmann::json frames = nlohmann::json::array(), failures = nlohmann::json::array();
    auto run_start = Clock::now();
    auto next_scene = load_async(selected[0]);
    std::size_t done = 0;
    for (; done < selected.size() && !interrupted; ++done) {
        const std::size_t i = selected[done];
        auto frame_start = Clock::now();
        try {
            // A frame that failed before its trace started no load for this one.
            auto pending = next_scene.valid() ? std::move(next_scene) : load_async(i);
            auto load_next = [&] {
                if (done + 1 < selected.size() && !next_scene.valid())
                    next_scene = load_async(selected[done + 1]);
            };
            if (!compute_on_host) load_next();
            auto [scene, load_ms] = pending.get();
            if (frames.empty()) run.framed = frame_bounds(scene.bounds());
            frames.push_back(render_frame(run, i, scene, load_ms, frame_start, load_next));
            for (const std::string& warning : scene.warnings)
                std::cerr << "kdray: warning: " << warning << "\n";
        } catch (const Error& e) {
            // Without --keep-going the first bad frame ends the run; the frames before it
            // are complete, and stats.json below records them.
            if (!command.keep_going && frames.empty()) throw;
            failures.push_back({{"frame", i}, {"input", inputs[i]}, {"error", e.what()}});
            std::cerr << "kdray: error: " << e.what() << "\n";
            if (!command.keep_going) break;
        }
        if (progress) show_progress(done + 1, selected.size(), ms_since(run_start));
    }

    nlohmann::json stats = {
        {"kdray_version", kVersion},
        {"builder", builder.description()},
        {"tracer", command.tracer},
        {"render_file", command.render_file},
        {"image", {{"width", settings.width}, {"height", settings.height}, {"spp", settings.spp}}},
        {"max_depth", settings.max_depth},
        {"intersect", command.intersect},
        {"packets", command.packets},
        {"frames", frames},
        {"summary", summary_json(frames)}};
    if (!failures.empty()) stats["failed_frames"] = failures;
    if (interrupted) stats["interrupted_after_frames"] = frames.size();
    if (!frames.empty()) write_file_atomically(run.out_dir / "stats.json", stats.dump(2) + "\n");

    if (interrupted) {
        std::cerr << "kdray: interrupted: " << frames.size() << " frame(s) complete in "
                  << run.out_dir.string() << "\n";
        return 130;
    }
    if (!failures.empty()) {
        std::cerr << "kdray: " << failures.size() << " of " << selected.size() << " frame(s) failed"
                  << (command.keep_going ? "" : "; stopped at the first") << "\n";
        return 1;
    }
    return 0;
}

}  // namespace kdray::cli
