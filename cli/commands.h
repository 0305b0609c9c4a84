// commands.h — the options of each kdray command as parsed by cli/main.cpp, and the commands.
// Commands return the process exit status; they throw kdray::Error for main to report.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/tree/build_quality.h"
#include "core/tree/tree.h"

namespace kdray::cli {

/// Which builder, on which device, with which parameters: shared by build, render and stats.
struct BuilderOptions {
    std::string builder = "opencl";  // "opencl" or "reference"
    std::string device;              // index or name substring; empty: first GPU, else first device
    BuildParams params;              // the ladder's three below come from the quality
    std::string quality;             // low, medium, high; empty: the command's default
    // Set by the user apart from the quality (--large-split-bins, --small-reclip-refs,
    // --small-leaf-refs).
    std::optional<int> large_split_bins, small_reclip_refs, small_leaf_refs, small_split_bins;
    std::string small_stage = "auto";  // --small-stage: small_stage_name's names (main.cpp checks)
    std::string large_stage = "auto";  // --large-stage: large_stage_name's names (main.cpp checks)
    std::string retired_max_depth;     // `--max-depth`, refused by its check (main.cpp)

    /// params at `quality` (default_quality when none was given), with the ladder options the
    /// user set kept.
    BuildParams build_params(BuildQuality default_quality) const;
};

struct BuildCommand {
    std::string scene;
    std::string output;  // tree file, optional
    bool json = false;
    int repeat = 1;       // > 1: one warm-up build, then this many timed builds, median reported
    bool strict = false;  // any warning is an error
    BuilderOptions builder;
};

struct RenderCommand {
    std::vector<std::string> command_line;  // argv as typed: an interrupted run's resume command
    std::vector<std::string> inputs;
    std::string output_dir;
    std::string render_file;
    // Overrides of the render file: image.spp, image.width x image.height, max_depth, exposure.
    std::optional<int> spp, ray_depth;
    std::optional<double> exposure;
    std::string size;  // WIDTHxHEIGHT
    bool aov = false;
    bool heatmap = false;  // <stem>.cost.png: the centre rays' walk cost in false colour
    std::string format = "png";
    bool format_given = false;    // --format was on the command line (cli/output_target.h)
    std::string name = "{stem}";  // a frame's file names (core/io/output_name.h)
    bool stats_json = false;      // -o FILE: merge into stats.json beside it all the same
    bool skip_existing = false;   // render only the frames whose files are missing
    // The folder's records made with other image settings: replaced, or kept beside (default:
    // the run refuses).
    bool overwrite = false, mixed = false;
    std::string tracer = "opencl";
    int threads = 0;
    bool quiet = false;
    std::string frames;       // START:END[:STEP], END included
    std::string shard;        // I/N
    bool keep_going = false;  // render the remaining frames after a bad one
    bool warm_up = false;     // benchmarks: render the first frame once, untimed, before the run
    bool strict = false;      // any warning is an error, before the frame builds where it can
    std::string intersect = "watertight";  // ray-triangle test: "watertight" or "moller"
    std::string packets = "auto";  // primary rays as packets: "auto" (CPU devices), "on", "off"
    BuilderOptions builder;
};

struct StatsCommand {
    std::vector<std::string> paths;
    bool json = false;
    BuilderOptions builder;
};

/// `kdray compare A B`: two hit AOVs or two images.
struct CompareCommand {
    std::string a, b;
    bool json = false;
    double tolerance = 1e-3;             // images: a channel differing by more is "over"
    std::optional<double> max_fraction;  // default: 1e-4 for AOVs (conventions.md), 0 for images
};

int run_build(const BuildCommand& command);
int run_render(const RenderCommand& command);
int run_stats(const StatsCommand& command);
int run_compare(const CompareCommand& command);

}  // namespace kdray::cli
