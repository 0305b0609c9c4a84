// `kdray render FRAME.obj... -o OUTDIR`: per frame, load, build, trace and write the image (and
// the hit AOV), then OUTDIR/stats.json for the run. Every file appears whole or not at all.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <future>
#include <iostream>
#include <utility>

#include "cl/opencl_renderer.h"
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

}  // namespace

int run_render(const RenderCommand& command) {
    // Check everything that can be checked before the first frame costs time.
    std::vector<std::string> inputs = expand_inputs(command.inputs);
    RenderSettings settings;
    if (!command.render_file.empty()) settings = load_render_file(command.render_file);
    const std::filesystem::path out_dir = command.output_dir;
    DeviceSession session(command.builder.device);
    TreeBuilder builder(command.builder, session);
    const bool opencl_tracer = command.tracer == "opencl";
    if (opencl_tracer || command.builder.builder == "opencl") session.device();
    create_output_dir(out_dir);
    const bool progress = !command.quiet && ::isatty(STDERR_FILENO);

    const std::vector<std::size_t> selected =
        select_frames(inputs.size(), command.frames, command.shard);
    if (selected.empty())
        throw UsageError("--frames/--shard select no frame of the " +
                         std::to_string(inputs.size()) + " inputs");

    // The next frame's OBJ loads on another thread while this one builds and traces.
    auto load_async = [&](std::size_t frame) {
        return std::async(std::launch::async, [path = inputs[frame]] {
            auto start = Clock::now();
            Scene scene = load_obj(path);
            return std::make_pair(std::move(scene), ms_since(start));
        });
    };
    nlohmann::json frames = nlohmann::json::array();
    std::vector<double> frame_times;
    Camera framed;  // without a camera in the render file: frame the first rendered scene
    auto run_start = Clock::now();
    auto next_scene = load_async(selected[0]);
    for (std::size_t k = 0; k < selected.size(); ++k) {
        const std::size_t i = selected[k];
        auto frame_start = Clock::now();
        auto [scene, load_ms] = next_scene.get();
        if (k + 1 < selected.size()) next_scene = load_async(selected[k + 1]);
        if (k == 0) framed = frame_bounds(scene.bounds());
        Camera camera = settings.camera_given ? settings.camera_at(int(i)) : framed;

        BuiltTree built = builder.build(scene);
        auto trace_start = Clock::now();
        RenderInputs render_inputs = prepare_render(scene, settings, camera, kd_u32(i));
        FrameResult result =
            opencl_tracer ? render_opencl(session.device(), built.tree, scene, render_inputs)
                          : render_reference(built.tree, scene, render_inputs, command.threads);
        double trace_ms = ms_since(trace_start);

        std::string stem = std::filesystem::path(inputs[i]).stem().string();
        std::filesystem::path image_path = out_dir / (stem + "." + command.format);
        write_image(image_path, result.image);
        std::filesystem::path aov_path;
        if (command.aov) {
            aov_path = out_dir / (stem + ".aov.exr");
            write_aov(aov_path, result.hits);
        }
        double frame_ms = ms_since(frame_start);
        frame_times.push_back(frame_ms);

        const RayTotals& rays = result.rays;
        nlohmann::json frame = {
            {"frame", i},
            {"input", inputs[i]},
            {"image", image_path.filename().string()},
            {"scene", scene_json(scene)},
            {"tree", tree_json(built, scene.triangle_count())},
            {"tracer", command.tracer},
            {"effects", render_inputs.effects.to_json()},
            {"load_ms", load_ms},
            {"build_ms", built.report.build_ms},
            {"trace_ms", trace_ms},
            {"frame_ms", frame_ms},
            {"rays",
             {{"primary", rays.primary},
              {"shadow", rays.shadow},
              {"reflection", rays.reflection},
              {"refraction", rays.refraction}}},
            {"mrays_per_s", trace_ms > 0 ? double(rays.total()) / (trace_ms * 1e3) : 0.0}};
        if (command.aov) frame["aov"] = aov_path.filename().string();
        frames.push_back(frame);
        for (const std::string& warning : scene.warnings)
            std::cerr << "kdray: warning: " << warning << "\n";
        if (progress) show_progress(k + 1, selected.size(), ms_since(run_start));
    }

    double total_ms = 0, worst_ms = 0;
    for (double ms : frame_times) total_ms += ms, worst_ms = std::max(worst_ms, ms);
    double mean_ms = frame_times.empty() ? 0.0 : total_ms / double(frame_times.size());
    nlohmann::json stats = {
        {"kdray_version", "0.1.0"},
        {"builder", builder.description()},
        {"tracer", command.tracer},
        {"render_file", command.render_file},
        {"image", {{"width", settings.width}, {"height", settings.height}, {"spp", settings.spp}}},
        {"frames", frames},
        {"summary",
         {{"frames", frame_times.size()},
          {"mean_frame_ms", mean_ms},
          {"worst_frame_ms", worst_ms},
          {"frames_per_second", mean_ms > 0 ? 1000.0 / mean_ms : 0.0}}}};
    write_file_atomically(out_dir / "stats.json", stats.dump(2) + "\n");
    return 0;
}

}  // namespace kdray::cli
