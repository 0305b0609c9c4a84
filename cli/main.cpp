// kdray — builds kd-trees over triangle scenes on an OpenCL device and ray traces them.
// This file parses the command line, dispatches to the commands, and is the one place errors are
// caught: `kdray: error: ...` on stderr, exit status 2 for usage errors and 1 for everything else.
#include <CLI/CLI.hpp>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <new>
#include <optional>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/log.h"
#include "core/error.h"
#include "core/io/image_codec.h"
#include "core/render/render_file.h"
#include "core/text/nearest_name.h"
#include "core/version.h"

namespace {

using namespace kdray::cli;

/// A number option that must be finite: CLI11's Range and NonNegativeNumber let nan through (every
/// comparison with it is false), and `compare --tolerance nan` said an all-0 and an all-1 image
/// agree.
const CLI::Validator kFiniteNumber(
    [](std::string& text) -> std::string {
        double value = 0;
        if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value))
            return "'" + text + "' is not a finite number";
        return {};
    },
    "FINITE");

/// The tree's options (group "Tree") and the device's ("Device"). Each option is named as its
/// key in stats.json's "params" (`--large-node-threshold`, large_node_threshold), the short name
/// it had before kept as an alias. `--max-depth` is refused with the names that replace it: on
/// render it read as the ray depth and set the tree's.
void add_builder_options(CLI::App& app, BuilderOptions& o) {
    app.option_defaults()->group("Device");
    app.add_option("--device", o.device,
                   "OpenCL device: gpu, cpu (the first of that type), an index from `kdray "
                   "stats` or a part of its name (default: the first GPU, else the first "
                   "device)");
    app.option_defaults()->group("Tree");
    app.add_option("--builder", o.builder, "kd-tree builder")
        ->check(CLI::IsMember({"opencl", "reference"}))
        ->capture_default_str();
    app.add_option("--cost-traversal,--ct", o.params.costs.traversal,
                   "SAH cost of a traversal step, C_t")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    app.add_option("--cost-intersection,--ci", o.params.costs.intersection,
                   "SAH cost of a triangle test, C_i")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    app.add_option("--large-node-threshold,--large-threshold", o.params.large_node_threshold,
                   "OpenCL builder: nodes with more triangles are 'large' (empty-space cuts, then "
                   "a binned-SAH or median split); the rest get the full SAH (Zhou et al.'s T, "
                   "at most " +
                       std::to_string(KDRAY_SMALL_ROOT_MAX_REFS) + ")")
        ->check(CLI::Range(1, KDRAY_SMALL_ROOT_MAX_REFS))
        ->capture_default_str();
    app.add_option("--empty-space-ratio,--empty-ratio", o.params.empty_space_ratio,
                   "OpenCL builder: cut off empty space larger than this share of a large "
                   "node's extent (Zhou et al.'s C_e)")
        ->check(CLI::Range(0.0f, 1.0f))
        ->capture_default_str();
    app.add_option("--empty-bonus", o.params.empty_bonus,
                   "a split with an empty side has its SAH cost scaled by (1 - this), in "
                   "[0, 1): both builders")
        ->check(kFiniteNumber)
        ->check(CLI::Range(0.0f, 1.0f))
        ->capture_default_str();
    app.add_option("--quality", o.quality,
                   "OpenCL builder: tree quality against build time (docs/quality-ladder.md): "
                   "high (exact SAH everywhere), medium, low (fastest build). Default: " +
                       std::string(kdray::build_quality_name(kdray::kAnimationBuildQuality)) +
                       " for a render of several frames, else " +
                       kdray::build_quality_name(kdray::kStaticBuildQuality))
        ->check(CLI::IsMember({"low", "medium", "high"}));
    app.add_option("--large-split-bins,--large-bins", o.large_split_bins,
                   "OpenCL builder: split a large node at the cheapest by the SAH of this many "
                   "bins per axis of its tight box; 0: at the spatial median (Zhou et al.). "
                   "Default: by --quality")
        ->check(CLI::Range(0, kdray::kMaxLargeSplitBins));
    app.add_option("--small-reclip-refs,--reclip-refs", o.small_reclip_refs,
                   "OpenCL builder: a small node of at most this many triangles re-clips those "
                   "reaching past its box before its SAH search (0: never). Default: by --quality")
        ->check(CLI::Range(0, int(KDRAY_RECLIP_REFS)));
    app.add_option("--small-leaf-refs,--leaf-refs", o.small_leaf_refs,
                   "OpenCL builder: a small node of at most this many triangles is a leaf "
                   "without an SAH search (0: search every node). Default: by --quality")
        ->check(CLI::Range(0, KDRAY_SMALL_ROOT_MAX_REFS));
    app.add_option("--small-split-bins,--small-bins", o.small_split_bins,
                   "OpenCL builder: split a small node at the cheapest by the SAH of this many "
                   "bins per axis of its tight box, without split-candidate masks; 0: price every "
                   "candidate exactly (Zhou et al.). Default: by --quality")
        ->check(CLI::Range(0, int(KDRAY_SMALL_MAX_BINS)));
    app.add_option("--small-stage", o.small_stage,
                   "OpenCL builder: how the small-node stage runs, for the same tree: per-root "
                   "(a work-item builds a small root's whole subtree; CPU devices), per-level "
                   "(Zhou et al.'s shape: one work-group per node, level by level; GPUs), or auto "
                   "(per-level on a GPU, else per-root)")
        ->check(CLI::IsMember({"auto", "per-root", "per-level"}))
        ->capture_default_str();
    app.add_option("--large-stage", o.large_stage,
                   "OpenCL builder: how the large-node stage runs, for the same tree: level "
                   "(Zhou et al.'s shape: a work-item per reference, a work-group per 256; GPUs), "
                   "chunked (levels too, a work-item walking 256 references of a node in order), "
                   "depth-first (chunked levels until there are a few nodes per compute unit, then "
                   "a work-item per node builds its subtree depth first, in cache; CPUs), or auto "
                   "(level on a GPU, else depth-first)")
        ->check(CLI::IsMember({"auto", "chunked", "level", "depth-first"}))
        ->capture_default_str();
    app.add_option("--tree-depth", o.params.max_depth,
                   "the kd-tree's depth limit (stats: params.tree_depth; the depth a tree "
                   "reached is tree_depth_reached)")
        ->check(CLI::Range(1, KDRAY_MAX_DEPTH))
        ->capture_default_str();
    app.add_option("--max-depth", o.retired_max_depth)->group("");  // refused after parsing
    app.option_defaults()->group("Options");
}

}  // namespace

namespace {

/// On a CPU device (PoCL) device buffers are host memory from malloc, and a build or a frame
/// allocates and frees a few hundred of them. glibc maps large blocks afresh and trims the heap
/// behind freed ones, so every build touched new pages: 11,500 page faults per BART Kitchen
/// build. Keeping blocks of up to 32 MiB in the heap, and not trimming it below 512 MiB, lets
/// later builds and frames reuse them: 3,900 faults per build, CPU time per build -10% (perf
/// stat, 12 builds, 2 cores). GPU drivers allocate device memory apart and are unaffected.
void keep_freed_memory_for_reuse() {
#ifdef __GLIBC__
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
#endif
}

/// Every long option name of `app`, with its dashes.
std::vector<std::string> long_option_names(const CLI::App& app) {
    std::vector<std::string> names;
    for (const CLI::Option* o : app.get_options())
        for (const std::string& n : o->get_lnames()) names.push_back("--" + n);
    return names;
}

}  // namespace

/// Flushes what the command printed on stdout; throws Error when any of it could not be written
/// (`kdray build x.obj --json > /dev/full` said nothing and exited 0).
void finish_stdout() {
    // std::cout writes through stdio's stdout: its flush is stdout's, whose errno says why.
    errno = 0;
    std::cout.flush();
    const bool flushed = std::fflush(stdout) == 0;
    const int error = errno;
    if (flushed && !std::ferror(stdout) && !std::cout.fail()) return;
    throw kdray::Error(std::string("cannot write to standard output: ") +
                       (error != 0 ? std::strerror(error) : "write error"));
}

int main(int argc, char** argv) {
    keep_freed_memory_for_reuse();
    // A reader that goes away (`kdray render ... 2>&1 | head -3`) must not kill a run by SIGPIPE
    // mid-frame, leaving images without their stats.json: a write to it fails with EPIPE
    // instead, which the log treats as the end of logging (cli/log.cpp) and finish_stdout as an
    // error.
    std::signal(SIGPIPE, SIG_IGN);
    CLI::App app{"kdray: kd-trees built on an OpenCL device (Zhou et al. 2008), ray traced"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("kdray ") + kdray::kVersion +
                                          " (image codec: " + kdray::image_codec_name() + ")");
    init_logging("info");
    std::optional<std::string> log_level;
    app.add_option("--log-level", log_level,
                   "quiet (warnings and errors), info (what happens: device, compiles, one line "
                   "per frame off a terminal) or debug; default info")
        ->check(CLI::IsMember({"quiet", "info", "debug"}));
    // --log-level after the command too: `kdray render ... --log-level debug`.
    app.fallthrough();

    BuildCommand build;
    auto* build_app = app.add_subcommand("build", "Build a kd-tree and print its statistics");
    build_app->add_option("scene", build.scene, "OBJ scene")->required();
    build_app->add_option("-o,--output", build.output, "write the tree to this file");
    build_app->add_flag("--json", build.json, "print one JSON object instead of a table");
    build_app
        ->add_option("--repeat", build.repeat,
                     "benchmark: one warm-up build, then this many timed builds; the median is "
                     "reported as build_ms and every time as build_ms_samples")
        ->check(CLI::Range(1, 1000));
    build_app->add_flag("--strict", build.strict,
                        "any warning (the scene's, the tree's) is an error: exit 1, no tree "
                        "written");
    add_builder_options(*build_app, build.builder);

    RenderCommand render;
    render.command_line.assign(argv, argv + argc);
    auto* render_app =
        app.add_subcommand("render", "Build and trace every frame; write images and stats.json");
    render_app->add_option("frames", render.inputs, "OBJ frames (files or globs), natural order")
        ->required();
    render_app->option_defaults()->group("Image");
    render_app->add_option("--render-file,--camera", render.render_file,
                           "render file (JSON, docs/conventions.md): camera, image, integrator, "
                           "lights; --camera is its old name. Default: frame the scene");
    render_app->add_option("--spp", render.spp, "samples per pixel (overrides the render file)")
        ->check(CLI::Range(1, 65536));
    render_app->add_option("--size", render.size,
                           "image size WIDTHxHEIGHT, e.g. 320x240 (overrides the render file)");
    render_app
        ->add_option("--ray-depth", render.ray_depth,
                     "the render file's max_depth (overrides it): Whitted's ray generations, 1 "
                     "to 16, or the path integrator's segments, -1 (unbounded) or 1 to 65536")
        ->check(CLI::Range(-1, kdray::kMaxPathDepth));
    render_app->add_option("--exposure", render.exposure,
                           "in stops: radiance x 2^STOPS before the image is written, from -64 to "
                           "64 (overrides the render file)");
    render_app->option_defaults()->group("Output");
    render_app
        ->add_option("-o,--output", render.output_dir,
                     "output folder (DIR/, an existing folder, or a name without an image "
                     "extension), or one frame's image file FILE.png|.jpg|.tif|.exr, its "
                     "extension picking the format: its AOV and heat map go beside it as "
                     "FILE-stem.aov.exr and FILE-stem.cost.png, and no stats.json unless "
                     "--stats-json")
        ->required();
    render_app
        ->add_option("--name", render.name,
                     "a frame's file names, from {stem} (the OBJ's name), {frame} and "
                     "{frame:04} (its number, zero-padded), e.g. frame_{frame:04}; an image "
                     "extension (shot.jpg) picks the format")
        ->capture_default_str();
    render_app->add_flag("--skip-existing", render.skip_existing,
                         "render only the frames whose image (and AOV) are not in the folder yet; "
                         "stats.json keeps the earlier runs' records of the others. Ctrl-C stops "
                         "after the frame in progress and prints the command that resumes the "
                         "run (with this option); a second Ctrl-C aborts at once");
    auto* overwrite = render_app->add_flag(
        "--overwrite", render.overwrite,
        "when the folder's stats.json records frames rendered with other image settings (size, "
        "spp, ray depth, integrator, exposure, display, build quality, triangle test), which "
        "refuses the run: replace those records (with --skip-existing, their frames are "
        "rendered again)");
    render_app
        ->add_flag("--mixed", render.mixed,
                   "... or render beside them into a folder of mixed settings (stats.json's "
                   "image lists each group's frames)")
        ->excludes(overwrite);
    render_app->add_flag("--aov", render.aov,
                         "also write <stem>.aov.exr (Z, prim_id, N, cost.nodes, cost.triangles)");
    render_app->add_flag("--heatmap", render.heatmap,
                         "also write <stem>.cost.png: each centre ray's kd-tree walk cost "
                         "(C_t x nodes + C_i x triangles) in false colour (viridis), from 0 "
                         "to the 99th percentile of the rays that enter the tree");
    render_app->add_flag("--stats-json", render.stats_json,
                         "with -o FILE: merge the run into stats.json in FILE's folder too, as "
                         "a folder's run always does");
    render_app
        ->add_option("--format", render.format,
                     "image format: png, jpg, tif (8-bit sRGB) or exr (linear float)")
        ->check(CLI::IsMember({"png", "exr", "jpg", "tif"}))
        ->capture_default_str();
    render_app->option_defaults()->group("Tracer");
    render_app->add_option("--tracer", render.tracer, "ray tracer")
        ->check(CLI::IsMember({"opencl", "reference"}))
        ->capture_default_str();
    render_app
        ->add_option("--threads", render.threads, "CPU threads for the reference tracer (0: all)")
        ->check(CLI::NonNegativeNumber);
    render_app->option_defaults()->group("Output");
    render_app->add_flag("-q,--quiet", render.quiet,
                         "no progress line (on a terminal it is drawn while each frame traces; "
                         "elsewhere an info line says how far a long frame is every 10 s, or "
                         "KDRAY_PROGRESS_INTERVAL_S), and only warnings and errors (unless "
                         "--log-level)");
    render_app->add_flag("--keep-going", render.keep_going,
                         "after a bad frame, render the rest; exit 1 with the failed frames "
                         "listed (default: stop at the first bad frame)");
    render_app->add_flag("--warm-up", render.warm_up,
                         "benchmarks: build and trace the first frame once, untimed, so that "
                         "program builds and first launches stay out of the frame times");
    render_app->add_flag("--strict", render.strict,
                         "any warning is an error (exit 1): a scene's fails its frame before the "
                         "frame builds, a tree's after it; for farms that must not publish "
                         "frames that warned");
    render_app->option_defaults()->group("Tracer");
    render_app
        ->add_option("--intersect", render.intersect,
                     "ray-triangle test: watertight (Woop et al. 2013: no ray slips through a "
                     "shared edge) or moller (Moller-Trumbore 1997: faster, may leak through "
                     "edges and vertices of closed meshes)")
        ->check(CLI::IsMember({"watertight", "moller"}))
        ->capture_default_str();
    render_app
        ->add_option("--packets", render.packets,
                     "OpenCL tracer: trace primary rays in packets of the device's float width "
                     "(16 rays, 4x4 pixels, on AVX-512; 8, 4x2, on AVX2; KDRAY_PACKET_LANES=8|16 "
                     "overrides) on its SIMD lanes; auto: on CPU devices (watertight test only; "
                     "the hits are the same)")
        ->check(CLI::IsMember({"auto", "on", "off"}))
        ->capture_default_str();
    render_app->option_defaults()->group("Frames");
    render_app->add_option("--frames", render.frames,
                           "render only frames START:END[:STEP] (END included), N (one frame) "
                           "or START-END; frame numbers are positions in the naturally sorted "
                           "inputs, from 0");
    render_app->add_option("--shard", render.shard,
                           "render every N-th of the selected frames, starting at the I-th (I/N), "
                           "e.g. --shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT");
    add_builder_options(*render_app, render.builder);

    StatsCommand stats;
    auto* stats_app = app.add_subcommand(
        "stats",
        "Statistics of OBJ scenes, tree files or render folders; with none, the OpenCL devices "
        "and the defaults kdray would build with");
    stats_app->add_option("paths", stats.paths, "OBJ files, tree files or render output folders");
    stats_app->add_flag("--json", stats.json, "machine-readable output");
    add_builder_options(*stats_app, stats.builder);

    CompareCommand compare;
    auto* compare_app = app.add_subcommand(
        "compare",
        "Compare two hit AOVs (docs/conventions.md: both miss, or both hit with |Z_a - Z_b| <= "
        "1e-4 max(1, Z_b); B is the reference) or two images; exit 1 when they disagree");
    compare_app->add_option("a", compare.a, "AOV (.aov.exr) or image (PNG, EXR, JPEG, TIFF)")
        ->required();
    compare_app->add_option("b", compare.b, "the reference AOV or image")->required();
    compare_app->add_flag("--json", compare.json, "machine-readable output");
    compare_app
        ->add_option("--tolerance", compare.tolerance,
                     "images: a pixel with a channel differing by more than this is 'over' "
                     "(PNG values in [0, 1], EXR linear)")
        ->check(kFiniteNumber)
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    compare_app
        ->add_option("--max-fraction", compare.max_fraction,
                     "the largest share of pixels that may disagree (AOVs: mismatch_fraction; "
                     "images: pixels over the tolerance). Default: 1e-4 for AOVs, 0 for images")
        ->check(kFiniteNumber)
        ->check(CLI::Range(0.0, 1.0));

    // A usage error points at the help of the command it was given to: `kdray render --help`
    // lists render's options, `kdray --help` only the commands.
    const auto see_help = [&] {
        for (const CLI::App* sub : {build_app, render_app, stats_app, compare_app})
            if (sub->parsed()) return " (see kdray " + sub->get_name() + " --help)";
        return std::string(" (see kdray --help)");
    };

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // --help and --version are "errors" that succeed; every other one is a usage error.
        if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
        // A mistyped subcommand or option gets the nearest valid name.
        std::string hint;
        const std::string first = argc > 1 ? argv[1] : "";
        if (!first.empty() && first[0] != '-' && first != "build" && first != "render" &&
            first != "stats" && first != "compare")
            hint = "'" + first + "' is not a command" +
                   kdray::did_you_mean(first, {"build", "render", "stats", "compare"});
        for (const CLI::App* sub : {build_app, render_app, stats_app, compare_app})
            if (sub->parsed())
                for (int i = 2; i < argc && hint.empty(); ++i) {
                    std::string arg = argv[i];
                    arg = arg.substr(0, arg.find('='));
                    if (arg.rfind("--", 0) == 0 && !sub->get_option_no_throw(arg))
                        if (const std::string near =
                                kdray::did_you_mean(arg, long_option_names(*sub));
                            !near.empty())
                            hint = "unknown option '" + arg + "'" + near;
                }
        // CLI11 names an option by its first name: one typed by its alias (`--camera`,
        // `--large-threshold`) is named as typed.
        std::string message = e.what();
        for (const CLI::App* sub : {build_app, render_app, stats_app, compare_app})
            if (sub->parsed())
                for (int i = 2; i < argc; ++i) {
                    std::string arg = argv[i];
                    arg = arg.substr(0, arg.find('='));
                    const CLI::Option* o =
                        arg.rfind("--", 0) == 0 ? sub->get_option_no_throw(arg) : nullptr;
                    if (!o || o->get_lnames().empty()) continue;
                    const std::string first = "--" + o->get_lnames()[0];
                    if (first != arg && message.rfind(first + ":", 0) == 0)
                        message = arg + message.substr(first.size());
                }
        print_error((hint.empty() ? message : hint) + see_help());
        return 2;
    }

    init_logging(log_level.value_or(*render_app && render.quiet ? "quiet" : "info"));
    render.format_given = render_app->count("--format") > 0;
    log_kernel_compiles();

    for (const BuilderOptions* o : {&build.builder, &render.builder, &stats.builder})
        if (!o->retired_max_depth.empty()) {
            print_error(
                "--max-depth is gone: --tree-depth sets the kd-tree's depth limit; on "
                "render, --ray-depth the render file's max_depth" +
                see_help());
            return 2;
        }

    // `build -o ""` exited 0 having written nothing, and `render -o ""` blamed a folder named "".
    if (build_app->count("--output") > 0 && build.output.empty()) {
        print_error("build -o/--output: the tree file's name is empty" + see_help());
        return 2;
    }
    if (*render_app && render.output_dir.empty()) {
        print_error("render -o/--output: the output folder's name is empty" + see_help());
        return 2;
    }

    // CLI11's checks let nan through (every comparison with it is false) and a float option
    // overflows to inf: the one parameter check decides, as a usage error.
    try {
        for (const BuilderOptions* o : {&build.builder, &render.builder, &stats.builder})
            kdray::validate_build_params(o->build_params(kdray::kStaticBuildQuality));
    } catch (const kdray::Error& e) {
        print_error(std::string(e.what()) + see_help());
        return 2;
    }

    try {
        int status = 0;
        if (*build_app) status = run_build(build);
        if (*render_app) status = run_render(render);
        if (*stats_app) status = run_stats(stats);
        if (*compare_app) status = run_compare(compare);
        finish_stdout();
        return status;
    } catch (const kdray::UsageError& e) {
        print_error(e.what() + see_help());
        return 2;
    } catch (const kdray::Error& e) {
        print_error(e.what());
        return 1;
    } catch (const std::bad_alloc&) {
        print_error("out of host memory");
        return 1;
    } catch (const std::exception& e) {
        print_error(e.what());
        return 1;
    }
    return 0;
}
