#include "cli/output_target.h"

#include <filesystem>

#include "core/error.h"
#include "core/io/image.h"

namespace kdray::cli {
namespace {

namespace fs = std::filesystem;

/// `--format` against the format an extension picks: both name one, or a usage error.
void check_format(const std::string& what, const std::string& picked, const std::string& format,
                  bool format_given) {
    if (format_given && picked != format)
        throw UsageError(what + " picks the " + picked + " format but --format says " + format +
                         "; give one of them");
}

}  // namespace

OutputTarget output_target(const RenderCommand& command, bool format_given) {
    const std::string& o = command.output_dir;
    const fs::path path(o);
    std::error_code ec;
    // A trailing separator or an existing folder keeps a name like `shots.png/` a folder.
    const bool folder = o.back() == '/' || fs::is_directory(path, ec);
    if (const std::string picked = image_format_of(path); !folder && !picked.empty()) {
        check_format("-o " + o, picked, command.format, format_given);
        if (command.name != "{stem}")
            throw UsageError("-o " + o +
                             " names the image file itself; --name names a frame's files in a "
                             "folder (-o DIR/)");
        const std::string extension = path.extension().string();
        return {path.has_parent_path() ? path.parent_path().string() : ".", path.stem().string(),
                extension.substr(1), true};
    }
    OutputTarget target{o, command.name, command.format, false};
    // `--name shot.jpg` writes shot.jpg, where it wrote shot.jpg.png.
    if (const std::string picked = image_format_of(command.name); !picked.empty()) {
        check_format("--name " + command.name, picked, command.format, format_given);
        const fs::path name(command.name);
        target.name = name.stem().string();
        target.format = name.extension().string().substr(1);
    }
    return target;
}

void check_one_frame(const OutputTarget& target, const std::string& output, std::size_t selected,
                     std::size_t inputs) {
    if (target.file && selected > 1)
        throw UsageError("-o " + output + " is one image, but " + std::to_string(selected) +
                         " of the " + std::to_string(inputs) +
                         " inputs' frames are selected; give a folder (-o DIR/) for several, or "
                         "one frame (--frames N:N)");
}

}  // namespace kdray::cli
