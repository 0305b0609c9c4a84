// test_frame_pipeline.cpp — the frame pipeline and the backends behind it: the factory hands out
// the builder and tracer a name asks for; the OpenCL tracer keeps one plan per combination and
// traces the OpenCL builder's device-resident tree to the hits of the host tree; a frame rendered
// for the warm-up (Output::Discard) is the frame the run renders, only unwritten; a render run
// driven through the library (core/run/render_run.h) renders, reports and records its frames as
// render_frame renders each on its own.
#include <doctest/doctest.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cl/backends.h"
#include "cl/builder/opencl_tree_builder.h"
#include "cl/renderer/opencl_tracer.h"
#include "cl/runtime/program_cache.h"
#include "core/error.h"
#include "core/render/camera.h"
#include "core/render/reference_tracer.h"
#include "core/render/render_setup.h"
#include "core/run/frame_pipeline.h"
#include "core/run/render_run.h"
#include "core/run/render_stats.h"
#include "core/run/stats_json.h"
#include "core/tree/reference_builder.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

namespace fs = std::filesystem;
using namespace kdray;

namespace {

RenderSettings small_settings() {
    RenderSettings s;
    s.width = 24;
    s.height = 16;
    return s;
}

}  // namespace

TEST_CASE("backends: the factory picks the builder and the tracer by name") {
    DeviceSession session("");
    const BuildParams params;
    auto reference = make_tree_builder("reference", params, session);
    CHECK(dynamic_cast<ReferenceTreeBuilder*>(reference.get()) != nullptr);
    CHECK(reference->description() == "reference (CPU, full SAH)");
    CHECK(reference->computes_on_host());
    // Neither reference backend opens the device.
    auto reference_tracer = make_tracer("reference", 1, session);
    CHECK(reference_tracer->name() == "reference");
    CHECK(reference_tracer->computes_on_host());
    CHECK_FALSE(session.is_open());

    auto opencl = make_tree_builder("opencl", params, session);
    CHECK(dynamic_cast<OpenClTreeBuilder*>(opencl.get()) != nullptr);
    CHECK_FALSE(session.is_open());  // on first need only
    auto opencl_tracer = make_tracer("opencl", 0, session);
    CHECK(dynamic_cast<OpenClTracer*>(opencl_tracer.get()) != nullptr);
    CHECK(opencl_tracer->name() == "opencl");
    CHECK(session.is_open());  // a bad device fails before the run makes anything
    CHECK(opencl_tracer->computes_on_host() == session.device().is_cpu());
    CHECK(opencl->description() == "opencl on " + session.device().info().name);

    CHECK_THROWS_AS(make_tree_builder("embree", params, session), UsageError);
    CHECK_THROWS_AS(make_tracer("embree", 0, session), UsageError);
}

TEST_CASE("backends: the OpenCL tracer traces the builder's device-resident tree") {
    // The resident buffers must give the hits the host tree gives when uploaded: a tracer that
    // ignored them, or read another build's, would differ.
    ClDevice& device = test::opencl_test_device();
    const Scene scene = test::random_triangles(300, 31);
    const BuiltTree built = [&] {
        BuiltTree b;
        auto resident = std::make_shared<OpenClResidentTree>();
        b.tree = build_opencl(device, scene, {}, &b.report, &resident->buffers);
        b.on_device = resident;
        return b;
    }();
    REQUIRE(built.on_device != nullptr);
    BuiltTree host_only;
    host_only.tree = built.tree;
    const RenderInputs inputs =
        prepare_render(scene, small_settings(), frame_bounds(scene.bounds()), 0);
    OpenClTracer tracer(device);
    const FrameResult resident = tracer.trace(built, scene, inputs);
    const FrameResult uploaded = tracer.trace(host_only, scene, inputs);
    REQUIRE(resident.hits.hits.size() == uploaded.hits.hits.size());
    for (std::size_t i = 0; i < resident.hits.hits.size(); ++i) {
        CHECK(resident.hits.hits[i].prim == uploaded.hits.hits[i].prim);
        CHECK(resident.hits.hits[i].t == uploaded.hits.hits[i].t);
    }
    CHECK(resident.image.rgb == uploaded.image.rgb);
}

TEST_CASE("backends: the OpenCL tracer makes a frame's kernels once per combination") {
    ClDevice& device = test::opencl_test_device();
    const Scene scene = test::random_triangles(40, 32);
    RenderSettings settings = small_settings();
    const RenderInputs headlight = prepare_render(scene, settings, frame_bounds(scene.bounds()), 0);
    settings.lights.push_back(Light{Light::Type::point, {0.5f, 3.0f, 0.5f}, {}, {5, 5, 5}});
    const RenderInputs lit = prepare_render(scene, settings, frame_bounds(scene.bounds()), 0);
    REQUIRE(headlight.effects.bits() != lit.effects.bits());

    OpenClTracer tracer(device);
    tracer.prepare(headlight);
    const int builds = program_build_count();
    tracer.prepare(headlight);
    CHECK(tracer.plan_count() == 1);
    BuiltTree built;
    built.tree = build_reference(scene);
    const FrameResult first = tracer.trace(built, scene, headlight);
    const FrameResult again = tracer.trace(built, scene, headlight);
    CHECK(tracer.plan_count() == 1);
    CHECK(program_build_count() == builds);
    CHECK(first.image.rgb == again.image.rgb);
    tracer.trace(built, scene, lit);  // a frame not prepared plans on the spot
    CHECK(tracer.plan_count() == 2);
}

TEST_CASE("frame pipeline: the warm-up's frame is the run's frame, unwritten") {
    const fs::path dir = test::fresh_temp_dir("frame-pipeline");
    const Scene scene = test::random_triangles(200, 33);
    ReferenceTreeBuilder builder({});
    ReferenceTracer tracer(1);
    FrameOptions options;
    options.out_dir = dir;
    options.aov = true;
    FramePipeline pipeline(builder, tracer, small_settings(), options);
    const FrameJob job{3, (dir / "in" / "frame_3.obj").string(), &scene};

    const nlohmann::json warm = pipeline.render_frame(job, FramePipeline::Output::Discard);
    CHECK(fs::is_empty(dir));
    bool computed = false;
    const nlohmann::json run =
        pipeline.render_frame(job, FramePipeline::Output::Write, [&] { computed = true; });
    CHECK(computed);
    CHECK(fs::exists(dir / "frame_3.png"));
    CHECK(fs::exists(dir / "frame_3.aov.exr"));
    // The same record but for the timings: the same frame, tree, effects and rays.
    for (const char* key :
         {"frame", "input", "image", "aov", "scene", "tracer", "effects", "rays", "hit_pixels"})
        CHECK_MESSAGE(warm[key] == run[key], key);
    CHECK(warm["tree"]["nodes"] == run["tree"]["nodes"]);
    CHECK(run["tracer"] == "reference");
    CHECK(run["frame"] == 3);
    CHECK(run["rays"]["primary"] == 24 * 16);
    fs::remove_all(dir);
}

TEST_CASE("frame pipeline: one summary for a run and for folders") {
    // Records in the order the run rendered them: frame 4 first (the one that compiled).
    const nlohmann::json frames = nlohmann::json::array({{{"frame", 4},
                                                          {"frame_ms", 30.0},
                                                          {"load_wait_ms", 2.0},
                                                          {"compile_ms", 12.0},
                                                          {"build_ms", 10.0},
                                                          {"trace_ms", 5.0},
                                                          {"write_ms", 1.0}},
                                                         {{"frame", 2},
                                                          {"frame_ms", 10.0},
                                                          {"load_wait_ms", 0.0},
                                                          {"compile_ms", 0.0},
                                                          {"build_ms", 4.0},
                                                          {"trace_ms", 3.0},
                                                          {"write_ms", 2.0}}});
    const nlohmann::json s = summarise_frames(frames);
    CHECK(s["frames"] == 2);
    CHECK(s["mean_frame_ms"].get<double>() == doctest::Approx(20.0));
    CHECK(s["worst_frame_ms"].get<double>() == doctest::Approx(30.0));
    CHECK(s["mean_load_wait_ms"].get<double>() == doctest::Approx(1.0));
    CHECK(s["mean_compile_ms"].get<double>() == doctest::Approx(6.0));
    CHECK(s["mean_build_ms"].get<double>() == doctest::Approx(7.0));
    CHECK(s["mean_trace_ms"].get<double>() == doctest::Approx(4.0));
    CHECK(s["mean_write_ms"].get<double>() == doctest::Approx(1.5));
    CHECK(s["frames_per_second"].get<double>() == doctest::Approx(1000.0 / 20.0));
    CHECK(s["frames_per_second_after_first"].get<double>() == doctest::Approx(1000.0 / 10.0));
    CHECK(s["frame_numbers"] == nlohmann::json::array({2, 4}));
    CHECK_FALSE(s.contains("warning"));
    nlohmann::json twice = frames;
    twice.push_back(frames[0]);
    CHECK(summarise_frames(twice).contains("warning"));
    const nlohmann::json none = summarise_frames(nlohmann::json::array());
    CHECK(none["frames_per_second"] == 0.0);
    CHECK(none["frames_per_second_after_first"].is_null());
    CHECK(summarise_frames(nlohmann::json::array({frames[0]}))["frames_per_second_after_first"]
              .is_null());

    // Two shards: each has a first frame of its own. After the firsts: 10 and 60 ms.
    const nlohmann::json shard = nlohmann::json::array(
        {{{"frame", 1}, {"frame_ms", 20.0}}, {{"frame", 3}, {"frame_ms", 60.0}}});
    const nlohmann::json both = summarise_runs({frames, shard});
    CHECK(both["frames"] == 4);
    CHECK(both["frames_per_second"].get<double>() == doctest::Approx(1000.0 / 30.0));
    CHECK(both["frames_per_second_after_first"].get<double>() == doctest::Approx(1000.0 / 35.0));
    CHECK(both["mean_compile_ms"].get<double>() == doctest::Approx(3.0));  // absent: 0
    CHECK(both["frame_numbers"] == nlohmann::json::array({1, 2, 3, 4}));
}

namespace {

/// What a run told its observer, in order; it interrupts the run after `stop_after` frames.
struct RecordingObserver final : RenderRunObserver {
    std::vector<std::string> events;
    std::size_t rendered = 0;
    std::size_t stop_after = SIZE_MAX;

    void skipping(std::size_t skipped, std::size_t selected) override {
        events.push_back("skipping " + std::to_string(skipped) + "/" + std::to_string(selected));
    }
    void first_scene(const nlohmann::json& effects) override {
        events.push_back(std::string("first scene, shadows ") +
                         (effects.value("shadows", false) ? "on" : "off"));
    }
    void frame_rendered(std::size_t position, std::size_t count,
                        const nlohmann::json& record) override {
        ++rendered;
        events.push_back("frame " + std::to_string(record["frame"].get<std::size_t>()) + " (" +
                         std::to_string(position + 1) + "/" + std::to_string(count) + ")");
    }
    void frame_failed(std::size_t frame, const Error&) override {
        events.push_back("failed " + std::to_string(frame));
    }
    void progress(std::size_t done, std::size_t count, double) override {
        events.push_back("progress " + std::to_string(done) + "/" + std::to_string(count));
    }
    void frames_finished() override { events.push_back("finished"); }
    bool interrupted() override { return rendered >= stop_after; }
};

/// Two frames of testdata/anim with its render file (keyframed camera, two lights), small.
RenderRunSettings anim_run(const fs::path& out_dir) {
    const fs::path anim = test::source_dir() / "testdata" / "anim";
    RenderRunSettings run;
    run.inputs = {(anim / "frame_000.obj").string(), (anim / "frame_001.obj").string()};
    run.selected = {0, 1};
    run.render_file = (anim / "render.json").string();
    run.render = load_render_file(run.render_file);
    run.render.width = 48;
    run.render.height = 27;
    run.overrides = {{"size", "48x27"}};
    run.frame.out_dir = out_dir;
    run.frame.aov = true;
    return run;
}

}  // namespace

TEST_CASE("render run: an animation through the library, observed and merged into stats.json") {
    // The run's load step (the loader, one frame ahead) against a scene loaded by hand: a loader
    // that handed a frame the wrong scene, or a run that framed it with another camera, would
    // write another image.
    const fs::path dir = test::fresh_temp_dir("render-run");
    RecordingObserver seen;
    ReferenceTreeBuilder builder({});
    ReferenceTracer tracer(1);
    RenderRun run(anim_run(dir / "run"), seen);
    REQUIRE(run.frames() == std::vector<std::size_t>{0, 1});
    const RenderRunOutcome outcome = run.run(builder, tracer);
    CHECK(outcome.frames == 2);
    CHECK(outcome.rendered == 2);
    CHECK(outcome.failed == 0);
    CHECK_FALSE(outcome.interrupted);
    CHECK(seen.events == std::vector<std::string>{"first scene, shadows on", "frame 0 (1/2)",
                                                  "progress 1/2", "frame 1 (2/2)", "progress 2/2",
                                                  "finished"});

    const nlohmann::json stats = read_render_stats(dir / "run" / "stats.json");
    REQUIRE(stats["frames"].size() == 2);
    for (std::size_t i = 0; i < 2; ++i) {
        const nlohmann::json& record = stats["frames"][i];
        CHECK(record["frame"] == i);
        CHECK(record["image"] == "frame_00" + std::to_string(i) + ".png");
        CHECK(record["aov"] == "frame_00" + std::to_string(i) + ".aov.exr");
        CHECK(record["tracer"] == "reference");
        CHECK(record["run"] == 0);
        CHECK(record["load_ms"].get<double>() > 0);
    }
    CHECK(stats["builder"] == "reference (CPU, full SAH)");
    CHECK(stats["image"]["width"] == 48);
    CHECK(stats["overrides"]["size"] == "48x27");
    CHECK(stats["intersect"] == "watertight");
    CHECK(stats["packets_requested"] == "auto");
    CHECK(stats["runs"].size() == 1);
    CHECK(stats["runs"][0]["frames_rendered"] == nlohmann::json::array({0, 1}));
    CHECK(stats["summary"]["frames"] == 2);
    CHECK_FALSE(stats.contains("failed_frames"));
    CHECK_FALSE(stats.contains("interrupted_after_frames"));

    // Frame 1 by render_frame alone, from a scene loaded here, into another folder.
    RenderRunSettings alone = anim_run(dir / "alone");
    fs::create_directories(alone.frame.out_dir);
    ReferenceTreeBuilder alone_builder({});
    ReferenceTracer alone_tracer(1);
    FramePipeline pipeline(alone_builder, alone_tracer, alone.render, alone.frame);
    const Scene scene = load_obj(alone.inputs[1]);
    pipeline.render_frame({1, alone.inputs[1], &scene});
    for (const char* file : {"frame_001.png", "frame_001.aov.exr"}) {
        const std::string bytes = test::read_file(dir / "alone" / file);
        CHECK_FALSE(bytes.empty());
        CHECK_MESSAGE(test::read_file(dir / "run" / file) == bytes, file);
    }

    // Resumed with --skip-existing: both frames are in the folder, nothing is left to render.
    RecordingObserver resumed;
    RenderRunSettings again = anim_run(dir / "run");
    again.skip_existing = true;
    RenderRun nothing_left(std::move(again), resumed);
    CHECK(nothing_left.frames().empty());
    CHECK(resumed.events == std::vector<std::string>{"skipping 2/2"});

    // Interrupted after the first frame: that frame is complete and recorded, the second never
    // starts.
    RecordingObserver stopped;
    stopped.stop_after = 1;
    RenderRun interrupted(anim_run(dir / "interrupted"), stopped);
    const RenderRunOutcome cut = interrupted.run(builder, tracer);
    CHECK(cut.interrupted);
    CHECK(cut.rendered == 1);
    CHECK(stopped.events.back() == "finished");
    const nlohmann::json cut_stats = read_render_stats(dir / "interrupted" / "stats.json");
    CHECK(cut_stats["frames"].size() == 1);
    CHECK(cut_stats["interrupted_after_frames"] == 1);
    CHECK(fs::exists(dir / "interrupted" / "frame_000.png"));
    CHECK_FALSE(fs::exists(dir / "interrupted" / "frame_001.png"));
    fs::remove_all(dir);
}
