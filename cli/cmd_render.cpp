// `kdray render FRAME.obj... -o OUTDIR`: per frame, load, build, trace and write the image (and
// the hit AOV), then the run merged into OUTDIR/stats.json. Every file appears whole or not at all.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <future>
#include <iostream>
#include <iterator>
#include <map>
#include <memory>
#include <utility>

#include "cl/backends.h"
#include "cl/runtime/program_cache.h"
#include "cli/commands.h"
#include "cli/frame_selection.h"
#include "cli/inputs.h"
#include "cli/log.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/frame_memory.h"
#include "core/frame_pipeline.h"
#include "core/render_file.h"
#include "core/render_setup.h"
#include "core/render_stats.h"
#include "core/scene.h"
#include "core/version.h"

namespace kdray::cli {
namespace {

void create_output_dir(const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir))
        throw Error(dir.string() + ": cannot create the output folder: " +
                    (ec ? ec.message() : std::string("a file of that name exists")));
    // What a killed run (SIGKILL mid-write) left behind would otherwise stay for ever.
    remove_stale_temporaries(dir);
}

/// The frame options the command line gives: output folder, names and format, --aov,
/// --intersect, --packets; and the clock of compilation that a frame's compile_ms reads.
FrameOptions frame_options(const RenderCommand& command, const OutputName& name) {
    FrameOptions options;
    options.name = name;
    options.compile_ms_so_far = compile_ms_total;
    options.out_dir = command.output_dir;
    options.format = command.format;
    options.aov = command.aov;
    options.intersect =
        command.intersect == "moller" ? KDRAY_INTERSECT_MOLLER : KDRAY_INTERSECT_WATERTIGHT;
    options.packets = command.packets == "on"    ? RenderInputs::Packets::On
                      : command.packets == "off" ? RenderInputs::Packets::Off
                                                 : RenderInputs::Packets::Auto;
    return options;
}

/// Two selected inputs that would write the same file (the same stem from two folders, x.obj and
/// x.OBJ, a path given twice, a.obj's AOV and a.aov.obj's EXR image) are a usage error naming
/// both, before anything renders. Names are compared without case, as a case-insensitive file
/// system (macOS, Windows shares) would.
void check_output_names(const std::vector<std::string>& inputs,
                        const std::vector<std::size_t>& selected, const OutputName& output_name,
                        const RenderCommand& command) {
    std::map<std::string, std::size_t> writer;
    auto lower = [](std::string s) {
        std::transform(s.begin(), s.end(), s.begin(),
                       [](unsigned char c) { return std::tolower(c); });
        return s;
    };
    for (const std::size_t i : selected) {
        const std::string stem = output_name(inputs[i], i);
        std::vector<std::string> names = {stem + "." + command.format};
        if (command.aov) names.push_back(stem + ".aov.exr");
        for (const std::string& name : names) {
            const auto [it, fresh] = writer.emplace(lower(name), i);
            if (!fresh)
                throw UsageError("inputs '" + inputs[it->second] + "' and '" + inputs[i] +
                                 "' would both write " +
                                 (std::filesystem::path(command.output_dir) / name).string() +
                                 "; render them into different folders");
        }
    }
}

/// Set by SIGINT/SIGTERM/SIGHUP: the run stops after the frame in progress, whose files are written
/// whole. A second signal ends the process at once; files are renamed into place only when
/// complete, so even then no truncated image exists under its final name.
volatile std::sig_atomic_t interrupted = 0;

extern "C" void on_interrupt(int signal) {
    interrupted = 1;
    std::signal(signal, SIG_DFL);
}

/// The command line's overrides of the render file (--spp, --size, --ray-depth, --exposure)
/// applied to `settings`; returns what each set, for stats.json.
nlohmann::json apply_overrides(const RenderCommand& command, RenderSettings& settings) {
    nlohmann::json used = nlohmann::json::object();
    if (command.spp) used["spp"] = settings.spp = *command.spp;
    if (command.exposure) {
        if (!(std::fabs(*command.exposure) <= kMaxExposureStops))
            throw UsageError("--exposure: " + fmt::format("{:g}", *command.exposure) +
                             " is not between -" + fmt::format("{:g}", kMaxExposureStops) +
                             " and " + fmt::format("{:g}", kMaxExposureStops) + " stops");
        settings.exposure = float(*command.exposure);
        used["exposure"] = settings.exposure;
    }
    if (command.ray_depth) used["ray_depth"] = settings.max_depth = *command.ray_depth;
    if (!command.size.empty()) {
        int width = 0, height = 0;
        char x = 0, rest = 0;
        if (std::sscanf(command.size.c_str(), "%d%c%d%c", &width, &x, &height, &rest) != 3 ||
            (x != 'x' && x != 'X') || width < 1 || height < 1 || width > 65536 || height > 65536)
            throw UsageError("--size " + command.size +
                             ": expected WIDTHxHEIGHT, each from 1 to 65536 (e.g. 320x240)");
        settings.width = width;
        settings.height = height;
        used["size"] = command.size;
    }
    return used;
}

/// The effects a frame simulates (its record's "effects"), for the log: "shadow rays, textures".
std::string effects_text(const nlohmann::json& effects) {
    std::string text;
    for (const auto& [key, name] : {std::pair{"shadows", "shadow rays"},
                                    {"reflection", "reflection"},
                                    {"refraction", "refraction"},
                                    {"ambient", "ambient"},
                                    {"area_lights", "area lights"},
                                    {"textures", "textures"}})
        if (effects.value(key, false)) text += (text.empty() ? "" : ", ") + std::string(name);
    return text.empty() ? "direct shading only" : text;
}

/// The frames of `selected` that an earlier run into the folder completed (a record in its
/// stats.json, no failure since) and whose files are all there: what --skip-existing skips. A
/// frame whose image a killed run left without a record is rendered again.
std::vector<std::size_t> frames_done(const std::vector<std::string>& inputs,
                                     const std::vector<std::size_t>& selected,
                                     const nlohmann::json& previous, const OutputName& name,
                                     const RenderCommand& command) {
    const std::set<std::string> completed = completed_images(previous);
    std::vector<std::size_t> done;
    const std::filesystem::path dir = command.output_dir;
    for (const std::size_t i : selected) {
        const std::string stem = name(inputs[i], i);
        if (completed.count(stem + "." + command.format) == 0) continue;
        std::error_code ec;
        bool present = std::filesystem::is_regular_file(dir / (stem + "." + command.format), ec);
        if (command.aov)
            present = present && std::filesystem::is_regular_file(dir / (stem + ".aov.exr"), ec);
        if (present) done.push_back(i);
    }
    return done;
}

}  // namespace

int run_render(const RenderCommand& command) {
    const auto setup_start = FrameClock::now();
    // Check everything that can be checked before the first frame costs time.
    std::vector<std::string> inputs = expand_inputs(command.inputs);
    std::vector<std::size_t> selected = select_frames(inputs.size(), command.frames, command.shard);
    if (selected.empty())
        throw UsageError("--frames/--shard select no frame of the " +
                         std::to_string(inputs.size()) + " inputs");
    const OutputName output_name(command.name);
    check_output_names(inputs, selected, output_name, command);
    RenderSettings settings;
    if (!command.render_file.empty()) settings = load_render_file(command.render_file);
    const nlohmann::json overrides = apply_overrides(command, settings);
    // Every frame's camera, interpolated between valid keys, must have a basis too: checked
    // before the first frame costs time.
    if (settings.camera_given)
        for (const std::size_t i : selected) settings.check_camera_at(int(i));
    // A frame larger than the host's memory is refused with the figures, before it starts.
    const FrameMemory frame_memory =
        estimate_frame_memory(settings.width, settings.height, command.aov);
    if (const std::uint64_t physical = physical_memory_bytes();
        physical > 0 && frame_memory.host_bytes > physical / 2)
        throw Error((command.render_file.empty() ? std::string("the image") : command.render_file) +
                    ": a " + std::to_string(settings.width) + " x " +
                    std::to_string(settings.height) + " frame needs about " +
                    std::to_string(frame_memory.host_bytes >> 20) +
                    " MiB of host memory, more than half of this machine's " +
                    std::to_string(physical >> 20) + " MiB");
    const std::filesystem::path out_dir = command.output_dir;
    // The run's frames merge into the folder's stats.json: one that cannot be merged into fails
    // the run before it renders.
    const nlohmann::json previous = read_folder_stats(out_dir);
    if (command.skip_existing) {
        const std::vector<std::size_t> done =
            frames_done(inputs, selected, previous, output_name, command);
        if (!done.empty()) {
            spdlog::info("skipping {} of {} frame(s): rendered into {} already", done.size(),
                         selected.size(), out_dir.string());
            std::vector<std::size_t> rest;
            std::set_difference(selected.begin(), selected.end(), done.begin(), done.end(),
                                std::back_inserter(rest));
            selected = std::move(rest);
        }
        if (selected.empty()) return 0;
    }
    DeviceSession session(command.builder.device);
    // A dynamic scene is rebuilt every frame: the ladder's fastest frame; one frame: the best tree.
    // Decided by the inputs, not the selection: a --frames range, a shard or a resumed run
    // builds the trees the whole run builds.
    const BuildQuality default_quality =
        inputs.size() > 1 ? kAnimationBuildQuality : kStaticBuildQuality;
    const std::unique_ptr<TreeBuilder> builder = make_tree_builder(
        command.builder.builder, command.builder.build_params(default_quality), session);
    const std::unique_ptr<Tracer> tracer = make_tracer(command.tracer, command.threads, session);
    // The builder's programs are built in the first frame (its compile_ms), not here.
    FramePipeline pipeline(*builder, *tracer, settings, frame_options(command, output_name));
    create_output_dir(out_dir);
    const bool progress =
        !command.quiet && stderr_is_terminal() && spdlog::should_log(spdlog::level::info);
    ProgressLine progress_line;
    // A closed terminal or a killed ssh session (SIGHUP) stops the run as Ctrl-C does.
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) std::signal(signal, on_interrupt);

    // The next frame's OBJ loads on another thread. With the build and the trace on a GPU it
    // overlaps them; when they run on the host's own cores (a CPU device, the reference code) a
    // loader beside them only preempts their workers (the Kitchen's large stage: 33 -> 48 ms on
    // 2 cores), so it overlaps writing the files instead.
    const bool compute_on_host = builder->computes_on_host() || tracer->computes_on_host();
    using LoadedScene = std::pair<Scene, double>;  // the scene and its load's own duration
    auto load_async = [&](std::size_t frame) {
        return std::async(std::launch::async, [path = inputs[frame]] {
            auto start = FrameClock::now();
            Scene scene = load_obj(path);
            return LoadedScene(std::move(scene), ms_since(start));
        });
    };
    // Without a camera in the render file, every run into a folder frames the scene of the first
    // input: a resumed run, a --frames range or a shard sees what a whole run sees. Loaded
    // before the run's first frame starts loading: one scene in memory at a time.
    if (!settings.camera_given && selected[0] != 0) {
        try {
            pipeline.frame_on(load_obj(inputs[0]));
        } catch (const Error& e) {
            spdlog::warn("{}; this run frames its own first frame, {}, instead", e.what(),
                         selected[0]);
        }
    }
    std::future<LoadedScene> next_scene = load_async(selected[0]);
    const double setup_ms = ms_since(setup_start);

    double warm_up_ms = 0;
    if (command.warm_up) {
        // Benchmarks: the first frame once through the same pipeline, untimed and unwritten, so
        // that program builds and first-launch costs stay out of every frame's figures. Its
        // scene is the run's first frame's: the OBJ is read once, and that frame waits for none.
        const auto warm_up_start = FrameClock::now();
        const std::size_t first = selected[0];
        LoadedScene loaded = next_scene.get();
        pipeline.render_frame({first, inputs[first], &loaded.first},
                              FramePipeline::Output::Discard);
        std::promise<LoadedScene> ready;
        ready.set_value(std::move(loaded));
        next_scene = ready.get_future();
        warm_up_ms = ms_since(warm_up_start);
    }

    nlohmann::json frames = nlohmann::json::array(), failures = nlohmann::json::array();
    std::string effects_said;  // the effects the log last named
    const std::string builder_quality = builder->quality();
    auto run_start = FrameClock::now();
    std::size_t done = 0;
    for (; done < selected.size() && !interrupted; ++done) {
        const std::size_t i = selected[done];
        auto frame_start = FrameClock::now();
        try {
            // A frame that failed before its trace started no load for this one.
            auto pending = next_scene.valid() ? std::move(next_scene) : load_async(i);
            auto load_next = [&] {
                if (done + 1 < selected.size() && !next_scene.valid())
                    next_scene = load_async(selected[done + 1]);
            };
            if (!compute_on_host) load_next();
            auto [scene, load_ms] = pending.get();
            const double load_wait_ms = ms_since(frame_start);
            if (effects_said.empty()) {
                // Once, when the first scene is in: the device is open, the effects known.
                effects_said = effects_text(decide_effects(scene, pipeline.settings()).to_json());
                spdlog::info(
                    "rendering {} frame(s) into {}: builder {} (quality {}), tracer {}; "
                    "effects: {}",
                    selected.size(), out_dir.string(), builder->description(), builder_quality,
                    tracer->name(), effects_said);
            }
            frames.push_back(
                pipeline.render_frame({i, inputs[i], &scene, load_ms, load_wait_ms, frame_start},
                                      FramePipeline::Output::Write, load_next));
            for (const std::string& warning : scene.warnings) spdlog::warn("{}", warning);
            for (const auto& warning :
                 frames.back()["tree"].value("warnings", nlohmann::json::array()))
                spdlog::warn("{}: {}", inputs[i], warning.get<std::string>());
            const nlohmann::json& record = frames.back();
            if (const std::string text = effects_text(record["effects"]); text != effects_said) {
                spdlog::info("frame {}: effects now: {}", i, text);
                effects_said = text;
            }
            const double frame_ms = record["frame_ms"].get<double>();
            if (!progress)
                spdlog::info(
                    "frame {} ({}/{}, {}): {:.1f} ms ({:.2f} fps): build {:.1f}, trace "
                    "{:.1f}{}",
                    i, done + 1, selected.size(), inputs[i], frame_ms,
                    frame_ms > 0 ? 1000.0 / frame_ms : 0.0, record["build_ms"].get<double>(),
                    record["trace_ms"].get<double>(),
                    record["compile_ms"].get<double>() > 0.5
                        ? fmt::format(", compile {:.0f}", record["compile_ms"].get<double>())
                        : std::string());
        } catch (const Error& e) {
            // Without --keep-going the first bad frame ends the run; the frames before it
            // are complete, and stats.json below records them.
            if (!command.keep_going && frames.empty()) throw;
            failures.push_back({{"frame", i},
                                {"input", inputs[i]},
                                {"image", output_name(inputs[i], i) + "." + command.format},
                                {"error", e.what()}});
            spdlog::error("{}", e.what());
            if (!command.keep_going) break;
        }
        if (progress) progress_line.show(done + 1, selected.size(), ms_since(run_start));
    }
    progress_line.finish();

    nlohmann::json run = {
        {"kdray_version", kVersion},
        {"name", output_name.pattern()},
        {"builder", builder->description()},
        {"tracer", tracer->name()},
        {"render_file", command.render_file},
        {"image", {{"width", settings.width}, {"height", settings.height}, {"spp", settings.spp}}},
        {"max_depth", settings.max_depth},
        {"overrides", overrides},
        {"intersect", command.intersect},
        {"packets_requested", command.packets},  // each frame's "packets": what ran
        // Before the first frame: the inputs checked, the device opened, the first load started.
        {"setup_ms", setup_ms},
        {"frames", frames}};
    if (command.warm_up) run["warm_up_ms"] = warm_up_ms;
    if (!failures.empty()) run["failed_frames"] = failures;
    if (interrupted) run["interrupted_after_frames"] = frames.size();
    if (!frames.empty() || !failures.empty()) {
        // Other runs into the folder (shards, earlier runs) keep their records.
        const FolderMerge merge = merge_into_folder(out_dir, std::move(run));
        if (!merge.locked)
            spdlog::warn(
                "{}: merged stats.json without a lock (runs finishing into the folder "
                "at the same moment may lose each other's records)",
                merge.lock_problem);
    }

    if (interrupted) {
        std::cerr << "kdray: interrupted: " << frames.size() << " frame(s) complete in "
                  << out_dir.string() << "\n";
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
