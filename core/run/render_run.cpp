#include "core/run/render_run.h"

#include <algorithm>
#include <filesystem>
#include <iterator>
#include <set>
#include <utility>

#include "core/io/atomic_file.h"
#include "core/io/frame_memory.h"
#include "core/render/render_setup.h"
#include "core/run/render_stats.h"
#include "core/run/warning_tally.h"
#include "core/scene/scene.h"
#include "core/version.h"

namespace kdray {
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

/// A frame larger than the host's memory is refused with the figures, before it starts.
void check_host_memory(const RenderRunSettings& settings) {
    const RenderSettings& render = settings.render;
    const FrameMemory frame_memory = estimate_frame_memory(
        render.width, render.height, settings.frame.aov || settings.frame.heatmap);
    if (const std::uint64_t physical = physical_memory_bytes();
        physical > 0 && frame_memory.host_bytes > physical / 2)
        throw Error(
            (settings.render_file.empty() ? std::string("the image") : settings.render_file) +
            ": a " + std::to_string(render.width) + " x " + std::to_string(render.height) +
            " frame needs about " + std::to_string(frame_memory.host_bytes >> 20) +
            " MiB of host memory, more than half of this machine's " +
            std::to_string(physical >> 20) + " MiB");
}

/// The frames of `selected` that an earlier run into the folder completed (a record in its
/// stats.json, no failure since) and whose files are all there: what --skip-existing skips. A
/// frame whose image a killed run left without a record is rendered again. Without a stats.json
/// (`records` false), the files alone.
std::vector<std::size_t> frames_done(const std::vector<std::string>& inputs,
                                     const std::vector<std::size_t>& selected,
                                     const nlohmann::json& previous, bool records,
                                     const FrameOptions& frame,
                                     const std::set<std::string>& stale) {
    std::set<std::string> completed = completed_images(previous);
    for (const std::string& image : stale) completed.erase(image);
    std::vector<std::size_t> done;
    const std::filesystem::path& dir = frame.out_dir;
    for (const std::size_t i : selected) {
        const std::string stem = frame.name(inputs[i], i);
        if (records && completed.count(stem + "." + frame.format) == 0) continue;
        std::error_code ec;
        bool present = std::filesystem::is_regular_file(dir / (stem + "." + frame.format), ec);
        if (frame.aov)
            present = present && std::filesystem::is_regular_file(dir / (stem + ".aov.exr"), ec);
        if (frame.heatmap)
            present = present && std::filesystem::is_regular_file(dir / (stem + ".cost.png"), ec);
        if (present) done.push_back(i);
    }
    return done;
}

/// The run's settings that decide its images, as its stats.json record states them: the keys
/// image_settings reads.
nlohmann::json image_keys(const RenderRunSettings& settings) {
    const RenderSettings& render = settings.render;
    nlohmann::json keys = {
        {"image", {{"width", render.width}, {"height", render.height}, {"spp", render.spp}}},
        {"integrator", integrator_name(render.integrator)},
        // The render file's max_depth, after --ray-depth: one name per depth in stats.json.
        {"ray_depth", render.max_depth},
        {"exposure", render.exposure},
        // The 8-bit images' transform (EXR images are linear whatever it is).
        {"display", display_name(render.display)},
        {"intersect", intersect_name(settings.frame.intersect)}};
    if (!settings.quality.empty()) keys["quality"] = settings.quality;
    return keys;
}

/// The images (file names) of `previous`'s records made with image settings other than `own`.
std::set<std::string> images_of_other_settings(const nlohmann::json& previous,
                                               const nlohmann::json& own) {
    std::set<std::string> images;
    const std::vector<nlohmann::json> settings = record_settings(previous);
    for (std::size_t k = 0; k < settings.size(); ++k)
        if (settings_differ(settings[k], own))
            images.insert(previous["frames"][k].value("image", std::string()));
    return images;
}

}  // namespace

void RenderRunObserver::skipping(std::size_t, std::size_t) {}
void RenderRunObserver::framing_failed(const Error&, std::size_t) {}
void RenderRunObserver::first_scene(const nlohmann::json&) {}
void RenderRunObserver::frame_rendered(std::size_t, std::size_t, const nlohmann::json&) {}
void RenderRunObserver::warned(const std::string&) {}
void RenderRunObserver::frame_failed(std::size_t, const Error&) {}
void RenderRunObserver::tracing(std::size_t, std::size_t, std::size_t, std::uint64_t,
                                std::uint64_t) {}
bool RenderRunObserver::wants_tracing() const {
    return false;
}
void RenderRunObserver::progress(std::size_t, std::size_t, double) {}
void RenderRunObserver::frames_finished() {}
void RenderRunObserver::merged_without_lock(const std::string&) {}
bool RenderRunObserver::interrupted() {
    return false;
}

RenderRun::RenderRun(RenderRunSettings settings, RenderRunObserver& observer)
    : settings_(std::move(settings)), observer_(observer), selected_(settings_.selected) {
    check_host_memory(settings_);
    const std::filesystem::path& out_dir = settings_.frame.out_dir;
    // The run's frames merge into the folder's stats.json: one that cannot be merged into fails
    // the run before it renders.
    const bool records = settings_.folder_stats;
    const nlohmann::json previous = records ? read_folder_stats(out_dir) : nlohmann::json();
    // A folder holds the images of one set of settings unless told otherwise: a resume at
    // another size, or one frame re-rendered into an animation's folder, mixed them silently.
    const nlohmann::json own = image_settings(image_keys(settings_));
    if (settings_.other_settings == OtherSettings::Refuse)
        check_folder_settings(out_dir.string(), previous, own);
    if (settings_.skip_existing) {
        const std::set<std::string> stale = settings_.other_settings == OtherSettings::Overwrite
                                                ? images_of_other_settings(previous, own)
                                                : std::set<std::string>();
        const std::vector<std::size_t> done =
            frames_done(settings_.inputs, selected_, previous, records, settings_.frame, stale);
        if (!done.empty()) {
            observer_.skipping(done.size(), selected_.size());
            std::vector<std::size_t> rest;
            std::set_difference(selected_.begin(), selected_.end(), done.begin(), done.end(),
                                std::back_inserter(rest));
            selected_ = std::move(rest);
        }
    }
}

RenderRun::~RenderRun() = default;

RenderRunOutcome RenderRun::run(TreeBuilder& builder, Tracer& tracer) {
    const std::vector<std::string>& inputs = settings_.inputs;
    const std::filesystem::path& out_dir = settings_.frame.out_dir;
    // The builder's programs are built in the first frame (its compile_ms), not here.
    FramePipeline pipeline(builder, tracer, settings_.render, settings_.frame);
    create_output_dir(out_dir);

    // Without a camera in the render file, every run into a folder frames the scene of the first
    // input: a resumed run, a --frames range or a shard sees what a whole run sees. Loaded
    // before the run's first frame starts loading: one scene in memory at a time.
    if (!settings_.render.camera_given && selected_[0] != 0) {
        try {
            pipeline.frame_on(load_obj(inputs[0]));
        } catch (const Error& e) {
            observer_.framing_failed(e, selected_[0]);
        }
    }
    // The next frame's OBJ loads on another thread (frame_loader.h says when).
    const bool compute_on_host = builder.computes_on_host() || tracer.computes_on_host();
    std::vector<std::string> paths;
    for (const std::size_t i : selected_) paths.push_back(inputs[i]);
    loader_ = std::make_unique<FrameLoader>(std::move(paths), compute_on_host
                                                                  ? FrameLoader::Overlap::Write
                                                                  : FrameLoader::Overlap::Compute);
    const double setup_ms = ms_since(settings_.setup_start);

    double warm_up_ms = 0;
    if (settings_.warm_up) {
        // Benchmarks: the first frame once through the same pipeline, untimed and unwritten, so
        // that program builds and first-launch costs stay out of every frame's figures. Its
        // scene is the run's first frame's: the OBJ is read once, and that frame waits for none.
        const auto warm_up_start = FrameClock::now();
        FrameJob warm_up;
        warm_up.number = selected_[0];
        warm_up.input = inputs[selected_[0]];
        warm_up.loader = loader_.get();
        warm_up.loaded = [&](const Scene& scene) {
            throw_if_strict(settings_.strict, scene.warnings);
        };
        pipeline.render_frame(warm_up, FramePipeline::Output::Discard);
        warm_up_ms = ms_since(warm_up_start);
    }

    nlohmann::json frames = nlohmann::json::array(), failures = nlohmann::json::array();
    bool announced = false;  // the first scene's effects told the observer
    auto announce = [&](const Scene& scene) {
        if (announced) return;
        // Once, when the first scene is in: the device is open, the effects known.
        observer_.first_scene(decide_effects(scene, pipeline.settings()).to_json());
        announced = true;
    };
    // Each cause printed once; under --strict a scene's warnings fail its frame before it builds.
    WarningTally warnings;
    auto warn = [&](std::size_t frame, const std::vector<std::string>& texts) {
        for (const std::string& text : texts)
            if (warnings.add(frame, inputs[frame], text)) observer_.warned(text);
        throw_if_strict(settings_.strict, texts);
    };
    auto run_start = FrameClock::now();
    std::size_t done = 0;
    for (; done < selected_.size() && !observer_.interrupted(); ++done) {
        const std::size_t i = selected_[done];
        FrameJob job;  // the frame starts now
        job.number = i;
        job.input = inputs[i];
        job.loader = loader_.get();
        job.loaded = [&, i](const Scene& scene) {
            announce(scene);
            warn(i, scene.warnings);
        };
        if (observer_.wants_tracing())
            job.traced = [this, i, done](std::uint64_t rays, std::uint64_t total) {
                observer_.tracing(i, done, selected_.size(), rays, total);
            };
        try {
            nlohmann::json frame = pipeline.render_frame(job, FramePipeline::Output::Write);
            std::vector<std::string> tree_warnings;
            for (const auto& w : frame["tree"].value("warnings", nlohmann::json::array()))
                tree_warnings.push_back(inputs[i] + ": " + w.get<std::string>());
            warn(i, tree_warnings);
            frames.push_back(std::move(frame));
            observer_.frame_rendered(done, selected_.size(), frames.back());
        } catch (const Error& e) {
            // Without keep_going the first bad frame ends the run; the frames before it
            // are complete, and stats.json below records them.
            if (!settings_.keep_going && frames.empty()) throw;
            failures.push_back(
                {{"frame", i},
                 {"input", inputs[i]},
                 {"image", settings_.frame.name(inputs[i], i) + "." + settings_.frame.format},
                 {"error", e.what()}});
            observer_.frame_failed(i, e);
            if (!settings_.keep_going) break;
        }
        observer_.progress(done + 1, selected_.size(), ms_since(run_start));
    }
    observer_.frames_finished();

    RenderRunOutcome outcome;
    outcome.frames = selected_.size();
    outcome.rendered = frames.size();
    outcome.failed = failures.size();
    outcome.interrupted = observer_.interrupted();
    outcome.warnings = warnings.summary();
    nlohmann::json run = image_keys(settings_);
    if (!run.contains("quality")) run["quality"] = builder.quality();
    run.update(
        {{"kdray_version", kVersion},
         {"name", settings_.frame.name.pattern()},
         {"builder", builder.description()},
         {"tracer", tracer.name()},
         {"exact_arithmetic", tracer.exact_arithmetic()},
         {"render_file", settings_.render_file},
         {"overrides", settings_.overrides},
         // Each frame's "packets": what ran.
         {"packets_requested", packets_name(settings_.frame.packets)},
         // Before the first frame: the inputs checked, the device opened, the first load started.
         {"setup_ms", setup_ms},
         {"frames", frames}});
    if (settings_.warm_up) run["warm_up_ms"] = warm_up_ms;
    if (warnings.total() > 0) run["warnings"] = warnings.to_json();
    if (!failures.empty()) run["failed_frames"] = failures;
    if (outcome.interrupted) run["interrupted_after_frames"] = frames.size();
    if (settings_.folder_stats && (!frames.empty() || !failures.empty())) {
        // Other runs into the folder (shards, earlier runs) keep their records.
        const FolderMerge merge = merge_into_folder(
            out_dir, std::move(run), settings_.other_settings == OtherSettings::Overwrite);
        if (!merge.locked) observer_.merged_without_lock(merge.lock_problem);
    }
    return outcome;
}

}  // namespace kdray
