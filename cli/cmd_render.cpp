// `kdray render FRAME.obj... -o OUTDIR`: the command line turned into a render run
// (core/run/render_run.h: per frame, load, build, trace and write the image and the hit AOV, then
// the run merged into OUTDIR/stats.json), with the builder and the tracer it names (cl/backends.h);
// the run's messages and progress line on stderr, Ctrl-C, and the exit status.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <utility>

#include "cl/backends.h"
#include "cl/runtime/program_cache.h"
#include "cli/commands.h"
#include "cli/devices.h"
#include "cli/frame_selection.h"
#include "cli/inputs.h"
#include "cli/log.h"
#include "cli/output_target.h"
#include "cli/resume_command.h"
#include "cli/trace_progress.h"
#include "core/error.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/run/frame_pipeline.h"
#include "core/run/render_run.h"
#include "core/tree/build_quality.h"
#include "core/tree/reference_builder.h"

namespace kdray::cli {
namespace {

/// The frame options the command line gives: output folder, names and format (-o, --name,
/// --format: `target`), --aov, --intersect, --packets; and the clock of compilation that a
/// frame's compile_ms reads.
FrameOptions frame_options(const RenderCommand& command, const OutputTarget& target,
                           const OutputName& name) {
    FrameOptions options;
    options.name = name;
    options.compile_ms_so_far = compile_ms_total;
    options.out_dir = target.dir;
    options.format = target.format;
    options.aov = command.aov;
    options.heatmap = command.heatmap;
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
                        const RenderCommand& command, const OutputTarget& target) {
    std::map<std::string, std::size_t> writer;
    auto lower = [](std::string s) {
        std::transform(s.begin(), s.end(), s.begin(),
                       [](unsigned char c) { return std::tolower(c); });
        return s;
    };
    for (const std::size_t i : selected) {
        const std::string stem = output_name(inputs[i], i);
        std::vector<std::string> names = {stem + "." + target.format};
        if (command.aov) names.push_back(stem + ".aov.exr");
        if (command.heatmap) names.push_back(stem + ".cost.png");
        for (const std::string& name : names) {
            const auto [it, fresh] = writer.emplace(lower(name), i);
            if (!fresh)
                throw UsageError("inputs '" + inputs[it->second] + "' and '" + inputs[i] +
                                 "' would both write " +
                                 (std::filesystem::path(target.dir) / name).string() +
                                 "; render them into different folders");
        }
    }
}

/// Set by SIGINT/SIGTERM/SIGHUP: the run stops after the frame in progress, whose files are written
/// whole. A second signal ends the process at once; files are renamed into place only when
/// complete, so even then no truncated image exists under its final name.
volatile std::sig_atomic_t interrupted = 0;
/// Whether stderr is a terminal, read by the handler: a progress line there is cleared first.
volatile std::sig_atomic_t stderr_terminal = 0;

/// `text` on stderr from a signal handler: write(2) is async-signal-safe, stdio and spdlog are not.
void say_from_handler(const char* text, std::size_t length) {
    if (stderr_terminal) (void)!::write(STDERR_FILENO, "\r\033[K", 4);
    (void)!::write(STDERR_FILENO, text, length);
}

extern "C" void on_interrupt(int signal) {
    const int saved_errno = errno;
    if (interrupted == 0) {
        // Said at once: a frame can trace for minutes, and a silent Ctrl-C reads as ignored.
        interrupted = 1;
        constexpr char kStopping[] =
            "kdray: stopping after this frame; Ctrl-C again to abort now\n";
        say_from_handler(kStopping, sizeof kStopping - 1);
        errno = saved_errno;
        return;
    }
    constexpr char kAborted[] = "kdray: aborted\n";
    say_from_handler(kAborted, sizeof kAborted - 1);
    // Ended by the signal itself, so that the shell sees what ended it (status 128 + signal).
    std::signal(signal, SIG_DFL);
    std::raise(signal);
    errno = saved_errno;
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
    if (command.ray_depth) {
        const int depth = *command.ray_depth;
        if (settings.integrator == Integrator::path ? depth == 0 || depth < -1
                                                    : depth < 1 || depth > KDRAY_MAX_BOUNCES)
            throw UsageError("--ray-depth " + std::to_string(depth) +
                             (settings.integrator == Integrator::path
                                  ? ": the path integrator takes -1 (unbounded) or 1 to " +
                                        std::to_string(kMaxPathDepth) + " path segments"
                                  : ": Whitted's integrator takes 1 to " +
                                        std::to_string(KDRAY_MAX_BOUNCES) + " ray generations"));
        used["ray_depth"] = settings.max_depth = depth;
    }
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
                                    {"textures", "textures"},
                                    {"path", "path tracing"}})
        if (effects.value(key, false)) text += (text.empty() ? "" : ", ") + std::string(name);
    return text.empty() ? "direct shading only" : text;
}

/// The run's messages on stderr (cli/log.h): on a terminal the progress line, elsewhere a line per
/// frame; the first scene's effects and every change of them; the frames' warnings and errors.
class RenderLog final : public RenderRunObserver {
  public:
    explicit RenderLog(const RenderCommand& command)
        : out_dir_(command.output_dir),
          progress_(!command.quiet && stderr_is_terminal() &&
                    spdlog::should_log(spdlog::level::info)) {}

    /// What the line said when the first scene is in names, set once the builder and the tracer
    /// are made; the builder's description is asked for only then (it opens the device).
    std::size_t frames = 0;
    TreeBuilder* builder = nullptr;
    std::string builder_quality;
    const Tracer* tracer = nullptr;

    void skipping(std::size_t skipped, std::size_t selected) override {
        spdlog::info("skipping {} of {} frame(s): rendered into {} already", skipped, selected,
                     out_dir_);
    }

    void framing_failed(const Error& e, std::size_t first) override {
        spdlog::warn("{}; this run frames its own first frame, {}, instead", e.what(), first);
    }

    void first_scene(const nlohmann::json& effects) override {
        effects_said_ = effects_text(effects);
        spdlog::info(
            "rendering {} frame(s) into {}: builder {} (quality {}), tracer {}; "
            "effects: {}",
            frames, out_dir_, builder->description(), builder_quality, tracer->name(),
            effects_said_);
        // The scene asks for an ambient term the render file does not give: its shadows will be
        // black, which a user would otherwise take for a bug (#30).
        if (effects.value("ambient_unlit", false))
            spdlog::info(
                "no ambient term: {}; an \"ambient\" in the render file lights the "
                "shadows (docs/effects.md)",
                effects["reasons"].value("ambient", std::string()));
        // The hits are as exact either way (to a near-tie of floats); said once, since a user
        // comparing devices may ask why stats.json's exact_arithmetic differs.
        if (tracer->exact_arithmetic() != "fp64")
            spdlog::info(
                "tracer {}: no fp64 (the device has none, or KDRAY_FORCE_NO_FP64 is set): the "
                "triangle test's edge fallback and refined distance run in {} arithmetic",
                tracer->name(), tracer->exact_arithmetic());
    }

    void frame_rendered(std::size_t done, std::size_t count,
                        const nlohmann::json& record) override {
        const std::size_t i = record["frame"].get<std::size_t>();
        const std::string input = record["input"].get<std::string>();
        if (const std::string text = effects_text(record["effects"]); text != effects_said_) {
            spdlog::info("frame {}: effects now: {}", i, text);
            effects_said_ = text;
        }
        const double frame_ms = record["frame_ms"].get<double>();
        if (!progress_)
            spdlog::info(
                "frame {} ({}/{}, {}): {:.1f} ms ({:.2f} fps): build {:.1f}, trace "
                "{:.1f}{}",
                i, done + 1, count, input, frame_ms, frame_ms > 0 ? 1000.0 / frame_ms : 0.0,
                record["build_ms"].get<double>(), record["trace_ms"].get<double>(),
                record["compile_ms"].get<double>() > 0.5
                    ? fmt::format(", compile {:.0f}", record["compile_ms"].get<double>())
                    : std::string());
    }

    void warned(const std::string& text) override { spdlog::warn("{}", text); }

    void frame_failed(std::size_t, const Error& e) override { spdlog::error("{}", e.what()); }

    bool wants_tracing() const override { return trace_log_; }

    void tracing(std::size_t frame, std::size_t position, std::size_t count, std::uint64_t done,
                 std::uint64_t total) override {
        if (trace_log_) trace_progress_.tracing(position, count, frame, done, total, frames_ms_);
    }

    void progress(std::size_t done, std::size_t count, double elapsed_ms) override {
        frames_ms_ = elapsed_ms;
        if (progress_) progress_line_.show(done, count, elapsed_ms);
    }

    void frames_finished() override { progress_line_.finish(); }

    void merged_without_lock(const std::string& problem) override {
        spdlog::warn(
            "{}: merged stats.json without a lock (runs finishing into the folder "
            "at the same moment may lose each other's records)",
            problem);
    }

    bool interrupted() override { return cli::interrupted != 0; }

  private:
    std::string out_dir_;
    bool progress_;
    ProgressLine progress_line_;
    // Off a terminal, the lines while a frame traces are info lines.
    bool trace_log_ = progress_ || spdlog::should_log(spdlog::level::info);
    TraceProgress trace_progress_{progress_ ? &progress_line_ : nullptr};
    double frames_ms_ = 0;      // the run's frames so far, for the time left
    std::string effects_said_;  // the effects the log last named
};

}  // namespace

int run_render(const RenderCommand& command) {
    RenderRunSettings run_settings;  // setup_ms counts from now
    // Check everything that can be checked before the first frame costs time.
    std::vector<std::string> inputs = expand_inputs(command.inputs);
    std::string past;  // frames of --frames past the inputs
    std::vector<std::size_t> selected =
        select_frames(inputs.size(), command.frames, command.shard, &past);
    if (selected.empty())
        throw UsageError("--frames/--shard select no frame of the " +
                         std::to_string(inputs.size()) + " inputs");
    if (!past.empty() && command.strict) throw Error("--strict: " + past);
    if (!past.empty()) spdlog::warn("{}", past);
    const OutputTarget target = output_target(command, command.format_given);
    check_one_frame(target, command.output_dir, selected.size(), inputs.size());
    const OutputName output_name(target.name);
    check_output_names(inputs, selected, output_name, command, target);
    RenderSettings& settings = run_settings.render;
    if (!command.render_file.empty()) settings = load_render_file(command.render_file);
    const nlohmann::json overrides = apply_overrides(command, settings);
    // Every frame's camera, interpolated between valid keys, must have a basis too: checked
    // before the first frame costs time.
    if (settings.camera_given)
        for (const std::size_t i : selected) settings.check_camera_at(int(i));
    // A dynamic scene is rebuilt every frame: the ladder's fastest frame; one frame: the best tree.
    // Decided by the inputs, not the selection: a --frames range, a shard or a resumed run
    // builds the trees the whole run builds.
    const BuildQuality default_quality =
        inputs.size() > 1 ? kAnimationBuildQuality : kStaticBuildQuality;
    run_settings.inputs = std::move(inputs);
    run_settings.selected = std::move(selected);
    run_settings.render_file = command.render_file;
    run_settings.overrides = overrides;
    run_settings.frame = frame_options(command, target, output_name);
    run_settings.folder_stats = !target.file || command.stats_json;
    run_settings.skip_existing = command.skip_existing;
    run_settings.other_settings = command.overwrite ? OtherSettings::Overwrite
                                  : command.mixed   ? OtherSettings::Mixed
                                                    : OtherSettings::Refuse;
    const BuildParams build_params = command.builder.build_params(default_quality);
    run_settings.quality = command.builder.builder == "reference"
                               ? ReferenceTreeBuilder(build_params).quality()
                               : build_quality_of(build_params);
    run_settings.keep_going = command.keep_going;
    run_settings.warm_up = command.warm_up;
    run_settings.strict = command.strict;
    RenderLog log(command);
    // The host's memory, the folder's stats.json and --skip-existing, before the device opens.
    RenderRun run(std::move(run_settings), log);
    if (run.frames().empty()) return 0;

    DeviceSession session(command.builder.device);
    say_when_no_gpu(session, command.builder.device);
    if (command.tracer == "opencl" && command.packets == "on" && command.intersect == "watertight")
        say_packets_off_cpu(session);
    const std::unique_ptr<TreeBuilder> builder =
        make_tree_builder(command.builder.builder, build_params, session);
    const std::unique_ptr<Tracer> tracer = make_tracer(command.tracer, command.threads, session);
    log.frames = run.frames().size();
    log.builder = builder.get();
    log.builder_quality = builder->quality();
    log.tracer = tracer.get();
    // A closed terminal or a killed ssh session (SIGHUP) stops the run as Ctrl-C does.
    stderr_terminal = stderr_is_terminal() ? 1 : 0;
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) std::signal(signal, on_interrupt);

    const RenderRunOutcome outcome = run.run(*builder, *tracer);
    // At info: --quiet keeps only the warnings themselves; stats.json's run record counts them.
    if (!outcome.warnings.empty()) spdlog::info("{}", outcome.warnings);
    if (outcome.interrupted) {
        // The resume command is printed as it is: printable() would cut a long one.
        print_line_as_is("kdray: interrupted: ",
                         printable(std::to_string(outcome.rendered) + " frame(s) complete in " +
                                   command.output_dir) +
                             "; resume with: " + resume_command(command.command_line));
        return 130;
    }
    if (outcome.failed > 0) {
        print_message("kdray: ", std::to_string(outcome.failed) + " of " +
                                     std::to_string(outcome.frames) + " frame(s) failed" +
                                     (command.keep_going ? "" : "; stopped at the first"));
        return 1;
    }
    return 0;
}

}  // namespace kdray::cli
