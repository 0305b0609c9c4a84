// output_target.h — what `kdray render -o` names: a folder of frames (`-o DIR/`, an existing
// folder, or a name without an image extension), or one image file (`-o shot.png|.jpg|.tif|.exr`)
// whose extension picks its format. `--name shot.jpg` picks the format the same way.
#pragma once

#include <cstddef>
#include <string>

#include "cli/commands.h"

namespace kdray::cli {

struct OutputTarget {
    std::string dir;     // the folder the files go into
    std::string name;    // the --name pattern (OutputName); for a file, the file's stem
    std::string format;  // the image's extension without the dot, as given: png, JPG, tiff, ...
    bool file = false;   // -o named one image file
};

/// The target of `command`'s -o, --name and --format (`format_given`: --format was on the
/// command line). Throws UsageError when they disagree: a file's extension and --format, a file
/// and --name, --name's extension and --format.
OutputTarget output_target(const RenderCommand& command, bool format_given);

/// Throws UsageError when `target` is one image file (`-o output`) but `selected` frames (more
/// than one) of `inputs` are to be rendered.
void check_one_frame(const OutputTarget& target, const std::string& output, std::size_t selected,
                     std::size_t inputs);

}  // namespace kdray::cli
