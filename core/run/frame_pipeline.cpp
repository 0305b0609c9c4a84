#include "core/run/frame_pipeline.h"

#include <algorithm>
#include <optional>
#include <utility>

#include "core/error.h"
#include "core/io/atomic_file.h"
#include "core/io/image.h"
#include "core/run/stats_json.h"

namespace kdray {

double ms_since(FrameClock::time_point start) {
    return std::chrono::duration<double, std::milli>(FrameClock::now() - start).count();
}

FramePipeline::FramePipeline(TreeBuilder& builder, Tracer& tracer, RenderSettings settings,
                             FrameOptions options)
    : builder_(builder),
      tracer_(tracer),
      settings_(std::move(settings)),
      options_(std::move(options)) {}

void FramePipeline::frame_on(const Scene& scene) {
    if (settings_.camera_given) return;
    settings_.camera_keys = {
        CameraKey{0, in_scene_units(frame_bounds(scene.bounds()), scene.frame)}};
    framed_ = true;
}

nlohmann::json FramePipeline::render_frame(const FrameJob& job, Output output,
                                           const std::function<void()>& computed) {
    // Load: the scene the caller holds, else the loader's next one. The warm-up's scene stays in
    // the loader for the frame it renders ahead of time.
    std::optional<LoadedScene> loaded;
    const Scene* scene_in = job.scene;
    double load_ms = job.load_ms, load_wait_ms = job.load_wait_ms;
    if (!scene_in && job.loader) {
        if (output == Output::Discard) {
            scene_in = &job.loader->peek().scene;
        } else {
            loaded = job.loader->take();
            scene_in = &loaded->scene;
            load_ms = loaded->load_ms;
            load_wait_ms = ms_since(job.start);
        }
    }
    if (!scene_in) throw Error(job.input + ": render_frame without a scene");
    const Scene& scene = *scene_in;
    if (job.loaded) job.loaded(scene);
    // Choose the camera: the render file's at this frame, else the first completed frame's view,
    // kept in the scene's units: each frame of an animation has a frame of its own.
    if (!settings_.camera_given && !framed_) {
        frame_on(scene);
        // A warm-up's framing is the run's first frame's too, but it is only kept once a frame
        // is written: until then every frame frames its own scene.
        framed_ = output == Output::Write;
    }
    const Camera camera = settings_.camera_at(int(job.number), scene.frame);

    // Prepare, build, then trace: the programs that the builder and the tracer for these effects
    // need are built (in the first frame; compile_ms) outside build_ms and trace_ms.
    const double compiled_before = options_.compile_ms_so_far ? options_.compile_ms_so_far() : 0;
    // The first frame's build then finds its memory made and its kernels launched once, as
    // `kdray build`'s does (build_prewarm.h); the builder does that once per run.
    builder_.expect_triangles(scene.triangle_count());
    builder_.prepare();
    RenderInputs inputs = prepare_render(scene, settings_, camera, kd_u32(job.number));
    inputs.normals = options_.aov;
    inputs.cost = options_.aov || options_.heatmap;
    inputs.intersect = options_.intersect;
    inputs.packets = options_.packets;
    inputs.progress = job.traced;
    tracer_.prepare(inputs);
    const double compile_ms =
        options_.compile_ms_so_far ? options_.compile_ms_so_far() - compiled_before : 0;
    BuiltTree built = builder_.build(scene);
    const auto trace_start = FrameClock::now();
    FrameResult result = tracer_.trace(built, scene, inputs);
    const double trace_ms = ms_since(trace_start);
    // The AOV's distances in the scene's units.
    if (!scene.frame.is_identity())
        for (KdHit& hit : result.hits.hits) hit.t = scene.frame.scene_length(hit.t);
    if (job.loader) job.loader->computed();
    if (computed) computed();

    // Write the image and the AOV, each whole or not at all.
    const std::string stem = options_.name(job.input, job.number);
    const std::filesystem::path image_path = options_.out_dir / (stem + "." + options_.format);
    const std::filesystem::path aov_path = options_.out_dir / (stem + ".aov.exr");
    const std::filesystem::path heatmap_path = options_.out_dir / (stem + ".cost.png");
    Heatmap heatmap;
    const auto write_start = FrameClock::now();
    if (output == Output::Write) {
        // A frame is its image, its AOV and its heat map: all are encoded before any is put into
        // place, so that a failed one (a full disk, a directory where it goes) fails the frame
        // with the folder as it was, an earlier run's files of the frame included.
        const std::string image_bytes =
            encode_image(image_path, result.image, settings_.exposure, settings_.display);
        const std::string aov_bytes = options_.aov ? encode_aov(aov_path, result.hits) : "";
        std::vector<FileContent> files = {{image_path, image_bytes}};
        if (options_.aov) files.push_back({aov_path, aov_bytes});
        if (options_.heatmap) {
            heatmap = encode_heatmap(heatmap_path, result.hits, built.tree.params.costs.traversal,
                                     built.tree.params.costs.intersection);
            files.push_back({heatmap_path, heatmap.png});
        }
        write_files_atomically(files);
    }
    const double write_ms = output == Output::Write ? ms_since(write_start) : 0.0;

    // The frame's record; its statistics (the tree's walked) are part of the frame's time.
    const RayTotals& rays = result.rays;
    // Centre rays that hit: with a camera inside a closed mesh, every miss is a leak.
    const auto hit_pixels = std::count_if(result.hits.hits.begin(), result.hits.hits.end(),
                                          [](const KdHit& h) { return h.prim != KDRAY_NO_HIT; });
    nlohmann::json scene_record = scene_json(scene);
    nlohmann::json tree_record = tree_json(built, scene.triangle_count());
    const double frame_ms = ms_since(job.start);
    const double build_ms = built.report.build_ms;
    nlohmann::json frame = {
        {"frame", job.number},
        {"input", job.input},
        {"image", image_path.filename().string()},
        {"scene", std::move(scene_record)},
        {"tree", std::move(tree_record)},
        {"tracer", tracer_.name()},
        {"effects", inputs.effects.to_json()},
        // What traced in packets, not what --packets asked for (stats.json's packets_requested).
        {"packets",
         {{"primary", result.primary_packets},
          {"shadow", result.shadow_packets},
          {"lanes", result.packet_lanes}}},
        {"load_ms", load_ms},
        {"load_wait_ms", load_wait_ms},
        {"compile_ms", compile_ms},
        {"build_ms", build_ms},
        {"trace_ms", trace_ms},
        {"write_ms", write_ms},
        // The stretches between the named ones: the render inputs, kernels made on first use,
        // the next frame's load started, the record's statistics.
        {"other_ms", frame_ms - (load_wait_ms + compile_ms + build_ms + trace_ms + write_ms)},
        {"frame_ms", frame_ms},
        {"rays",
         {{"primary", rays.primary},
          {"shadow", rays.shadow},
          {"reflection", rays.reflection},
          {"refraction", rays.refraction},
          {"area_shadow", rays.area_shadow}}},
        {"hit_pixels", hit_pixels},
        {"mrays_per_s", trace_ms > 0 ? double(rays.total()) / (trace_ms * 1e3) : 0.0}};
    if (options_.aov) frame["aov"] = aov_path.filename().string();
    if (options_.heatmap && output == Output::Write)
        frame["heatmap"] = {{"file", heatmap_path.filename().string()},
                            {"scale_cost", heatmap.scale_cost},
                            {"max_cost", heatmap.max_cost},
                            {"cost_traversal", built.tree.params.costs.traversal},
                            {"cost_intersection", built.tree.params.costs.intersection}};
    builder_.recycle(std::move(built.tree));
    return frame;
}

}  // namespace kdray
